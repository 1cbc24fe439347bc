"""Textures sampled outside [0, 1] as their files say, against the closed form: a face-on quad whose uv
runs from -1 to 2 along both axes, a 4 x 4 texture, C_amb = 1 and no lights, so each pixel is the
bilinear texel at its uv with the wrap written in the file (glTF's sampler wrapS/wrapT, USD's
UsdUVTexture wrapS/wrapT, MTL's -clamp on): clamp to edge, mirrored repeat or repeat, per axis."""

import math

import numpy as np
import pytest
from PIL import Image

import warprt
from oracle import camera_rays, ray_plane

from formats.gltf_files import Gltf
from scenekit import write_scene

S = 2.0  # the quad spans [-2, 2]^2 in z = 0
LO, HI = -1.0, 2.0  # and uv [-1, 2]^2 across it
N = 4
TEXELS8 = np.random.default_rng(24).integers(0, 256, (N, N, 3), dtype=np.uint8)  # row 0: the image's top
GL = {"repeat": 10497, "clamp": 33071, "mirror": 33648}


def srgb(c8):
    c = np.asarray(c8, np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def texel_index(i, n, mode):
    """OpenGL's wrap of texel index i among n: repeat, clamp to edge, mirrored repeat."""
    if mode == "repeat":
        return i % n
    if mode == "clamp":
        return min(max(i, 0), n - 1)
    i = i % (2 * n)
    return i if i < n else 2 * n - 1 - i


def bilinear(u, v, wrap):
    """The texture at (u, v), v up from the image's bottom row, texel centres at (i + 1/2) / N."""
    texels = srgb(TEXELS8[::-1])  # row 0 at v = 0
    x, y = u * N - 0.5, v * N - 0.5
    i, j = math.floor(x), math.floor(y)
    a, b = x - i, y - j
    at = lambda di, dj: texels[texel_index(j + dj, N, wrap[1]), texel_index(i + di, N, wrap[0])]  # noqa: E731
    return (1 - a) * (1 - b) * at(0, 0) + a * (1 - b) * at(1, 0) + (1 - a) * b * at(0, 1) + a * b * at(1, 1)


def quad_scene_doc(mesh_name, lights=(), **render):
    """The scene-file dict of the mesh file ``mesh_name`` seen face on from z = 4, 96 x 96 pixels."""
    doc = {
        "camera": {"eye": [0.0, 0.0, 4.0], "center": [0.0, 0.0, 0.0], "fovy": 60.0, "width": 96, "height": 96},
        "render": dict(render),
        "objects": [{"mesh": mesh_name}],
    }
    if lights:
        doc["lights"] = [dict(l) for l in lights]
    return doc


def render_quad(tmp_path, mesh_name):
    write_scene(tmp_path, quad_scene_doc(mesh_name, ambient=[1.0, 1.0, 1.0], max_depth=1), "s.toml")
    scene = warprt.load_scene(tmp_path / "s.toml")
    image, _ = warprt.render(scene)
    eye, d = camera_rays(scene.camera)
    p = eye + ray_plane(eye, d, np.zeros(3), np.array([0.0, 0.0, 1.0]))[..., None] * d
    uv = LO + (HI - LO) * (p[..., :2] + S) / (2 * S)
    inside = (np.abs(p[..., :2]) < S * 0.995).all(-1)
    return image, uv, inside


def assert_wrap(image, uv, inside, wrap):
    rows, cols = np.nonzero(inside)
    assert len(rows) > 2000
    expected = np.array([bilinear(*uv[r, c], wrap) for r, c in zip(rows, cols)])
    np.testing.assert_allclose(image[rows, cols], expected, atol=1e-4)
    # the negative control: any other wrap is far off somewhere on the quad
    for other in {("repeat", "repeat"), ("clamp", "clamp"), ("mirror", "mirror"), wrap[::-1]} - {wrap}:
        wrong = np.array([bilinear(*uv[r, c], other) for r, c in zip(rows, cols)])
        assert np.abs(wrong - expected).max() > 0.05, other


def write_texture(path):
    Image.fromarray(TEXELS8).save(path)


def quad_gltf(path, wrap):
    g = Gltf()
    vertices = [[-S, -S, 0], [S, -S, 0], [S, S, 0], [-S, S, 0]]
    uv = [[LO, 1 - LO], [HI, 1 - LO], [HI, 1 - HI], [LO, 1 - HI]]  # glTF's v runs down the image
    sampler = g.add("samplers", {"magFilter": 9729, "minFilter": 9729, "wrapS": GL[wrap[0]], "wrapT": GL[wrap[1]]})
    g.add("images", {"uri": "t.png"})
    g.add("textures", {"source": 0, "sampler": sampler})
    material = g.add("materials", {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}})
    g.node(mesh=g.mesh(vertices, [[0, 1, 2], [0, 2, 3]], uv=uv, material=material))
    return g.write(path)


@pytest.mark.parametrize("wrap", [("clamp", "mirror"), ("mirror", "clamp"), ("repeat", "repeat")])
def test_gltf_sampler_wrap_modes(tmp_path, wrap):
    write_texture(tmp_path / "t.png")
    quad_gltf(tmp_path / "q.gltf", wrap)
    assert_wrap(*render_quad(tmp_path, "q.gltf"), wrap)


def test_mtl_clamp_on(tmp_path):
    write_texture(tmp_path / "t.png")
    (tmp_path / "q.obj").write_text(f"mtllib q.mtl\nv -2 -2 0\nv 2 -2 0\nv 2 2 0\nv -2 2 0\n"
                                    f"vt {LO} {LO}\nvt {HI} {LO}\nvt {HI} {HI}\nvt {LO} {HI}\nusemtl t\nf 1/1 2/2 3/3 4/4\n")
    (tmp_path / "q.mtl").write_text("newmtl t\nmap_Kd -clamp on t.png\n")
    assert_wrap(*render_quad(tmp_path, "q.obj"), ("clamp", "clamp"))


def test_usd_uv_texture_wrap(tmp_path):
    from pxr import Sdf, Usd, UsdGeom, UsdShade

    write_texture(tmp_path / "t.png")
    stage = Usd.Stage.CreateNew(str(tmp_path / "q.usda"))
    mesh = UsdGeom.Mesh.Define(stage, "/quad")
    mesh.CreatePointsAttr([(-S, -S, 0), (S, -S, 0), (S, S, 0), (-S, S, 0)])
    mesh.CreateFaceVertexCountsAttr([4])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2, 3])
    UsdGeom.PrimvarsAPI(mesh).CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex).Set(
        [(LO, LO), (HI, LO), (HI, HI), (LO, HI)])
    mat = UsdShade.Material.Define(stage, "/looks/m")
    surface = UsdShade.Shader.Define(stage, "/looks/m/surface")
    surface.CreateIdAttr("UsdPreviewSurface")
    tex = UsdShade.Shader.Define(stage, "/looks/m/texture")
    tex.CreateIdAttr("UsdUVTexture")
    tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(Sdf.AssetPath("t.png"))
    tex.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set("sRGB")
    tex.CreateInput("wrapS", Sdf.ValueTypeNames.Token).Set("mirror")
    tex.CreateInput("wrapT", Sdf.ValueTypeNames.Token).Set("clamp")
    tex.CreateOutput("rgb", Sdf.ValueTypeNames.Float3)
    surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(tex.ConnectableAPI(), "rgb")
    mat.CreateSurfaceOutput().ConnectToSource(surface.ConnectableAPI(), "surface")
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(mat)
    stage.GetRootLayer().Save()
    assert_wrap(*render_quad(tmp_path, "q.usda"), ("mirror", "clamp"))


def test_one_image_with_two_samplers_is_sampled_both_ways(tmp_path):
    """The texture table holds an image once per wrap: two quads, one image, clamp on one, mirror on the other."""
    write_texture(tmp_path / "t.png")
    g = Gltf()
    g.add("images", {"uri": "t.png"})
    for k, mode in enumerate(("clamp", "mirror")):
        sampler = g.add("samplers", {"wrapS": GL[mode], "wrapT": GL[mode]})
        g.add("textures", {"source": 0, "sampler": sampler})
        material = g.add("materials", {"pbrMetallicRoughness": {"baseColorTexture": {"index": k}}})
        x0 = -S if k == 0 else 0.0
        vertices = [[x0, -S, 0], [x0 + S, -S, 0], [x0 + S, S, 0], [x0, S, 0]]
        uv = [[LO, 1 - LO], [HI, 1 - LO], [HI, 1 - HI], [LO, 1 - HI]]
        g.node(mesh=g.mesh(vertices, [[0, 1, 2], [0, 2, 3]], uv=uv, material=material))
    g.write(tmp_path / "two.gltf")
    image, _, inside = render_quad(tmp_path, "two.gltf")
    scene = warprt.load_scene(tmp_path / "s.toml")
    eye, d = camera_rays(scene.camera)
    p = eye + ray_plane(eye, d, np.zeros(3), np.array([0.0, 0.0, 1.0]))[..., None] * d
    for k, mode in enumerate(("clamp", "mirror")):
        x0 = -S if k == 0 else 0.0
        local = (p[..., 0] - x0) / S
        on = inside & (local > 0.01) & (local < 0.99)
        uv = np.stack([LO + (HI - LO) * local, LO + (HI - LO) * (p[..., 1] + S) / (2 * S)], -1)
        rows, cols = np.nonzero(on)
        expected = np.array([bilinear(*uv[r, c], (mode, mode)) for r, c in zip(rows, cols)])
        np.testing.assert_allclose(image[rows, cols], expected, atol=1e-4)
