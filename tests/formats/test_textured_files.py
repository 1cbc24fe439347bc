"""Files that carry their look, written here and read back through a scene, each pixel checked against
the closed form: a face-on quad spans uv [0, 1]^2, so every pixel's uv follows from its camera ray;
its texture is 4 x 4 blocks of one colour each (8 x 8 texels), so away from the block edges bilinear
filtering returns the block's colour exactly, decoded from sRGB by the IEC formula. C_amb = 1 and no
lights: a pixel is ka, which is kd with kd's texture (times the file's factor) where the file names no Ka.
"""

import json
import struct

import numpy as np
import pytest
from PIL import Image

import warprt
from oracle import camera_rays, ray_plane
from scenekit import write_scene

S = 2.0  # the quad's half size: it spans [-2, 2]^2 in z = 0 and uv [0, 1]^2
BLOCKS, TEXELS = 4, 8  # 4 x 4 blocks of 8 x 8 texels
RNG = np.random.default_rng(14)
BLOCK_RGB8 = RNG.integers(0, 256, (BLOCKS, BLOCKS, 3), dtype=np.uint8)  # row 0: the image's top


def srgb(c8):
    c = np.asarray(c8, np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def write_png(path):
    Image.fromarray(np.kron(BLOCK_RGB8, np.ones((TEXELS, TEXELS, 1), np.uint8))).save(path)


def scene_file(tmp_path, objects: list, materials: dict | None = None, width=64, height=48):
    """The scene read back from a real scene file: a face-on camera, C_amb = 1, no lights."""
    doc = {"camera": {"eye": [0.0, 0.0, 5.0], "center": [0.0, 0.0, 0.0], "fovy": 60.0, "width": width, "height": height},
           "render": {"ambient": [1.0, 1.0, 1.0], "max_depth": 1}, "materials": materials or {}, "objects": objects}
    return warprt.load_scene(write_scene(tmp_path, doc, "s.toml"))


def quad_blocks(scene, margin_texels: float = 1.5):
    """(row, col, block row from the image's top, block col) of the pixels whose uv lies at least
    margin_texels from every block edge: p = (x, y, 0) on the quad has uv ((x + S) / 2S, (y + S) / 2S)."""
    eye, d = camera_rays(scene.camera)
    p = eye + ray_plane(eye, d, np.zeros(3), np.array([0.0, 0.0, 1.0]))[..., None] * d
    uv = (p[..., :2] + S) / (2 * S)
    cell = uv * BLOCKS
    inside = (uv > 0) & (uv < 1) & (np.abs(cell - np.round(cell)) * TEXELS > margin_texels)
    rows, cols = np.nonzero(inside.all(-1))
    return [(r, c, BLOCKS - 1 - int(cell[r, c, 1]), int(cell[r, c, 0])) for r, c in zip(rows, cols)]


def assert_blocks(scene, factor=(1.0, 1.0, 1.0)):
    image, _ = warprt.render(scene)
    pixels = quad_blocks(scene)
    assert len(pixels) > 300  # most of the quad, every block
    assert len({(i, j) for _, _, i, j in pixels}) == BLOCKS * BLOCKS
    expected = np.array([srgb(BLOCK_RGB8[i, j]) * factor for _, _, i, j in pixels])
    got = np.array([image[r, c] for r, c, _, _ in pixels])
    np.testing.assert_allclose(got, expected, atol=2e-6)


QUAD_OBJ = "v -2 -2 0\nv 2 -2 0\nv 2 2 0\nv -2 2 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"


def test_obj_mtl_png_map_kd_replaces_kd(tmp_path):
    """map_Kd with Blender's Kd 0.8 beside it: the texture is the colour (Blender's reading, not the
    MTL spec's product)."""
    write_png(tmp_path / "blocks.png")
    (tmp_path / "q.obj").write_text("mtllib q.mtl\n" + QUAD_OBJ + "usemtl tex\nf 1/1 2/2 3/3 4/4\n")
    (tmp_path / "q.mtl").write_text("newmtl tex\nKd 0.8 0.8 0.8\nmap_Kd blocks.png\n")
    assert_blocks(scene_file(tmp_path, [{"mesh": "q.obj"}]))


def test_mtl_map_scale_and_offset_options(tmp_path):
    """map_Kd -s 2 2 1 -o 0.5 0 0: the texture repeats twice across u and v, shifted half a repeat in
    u; uv (u, v) reads the image at (2u + 0.5, 2v) mod 1."""
    write_png(tmp_path / "blocks.png")
    (tmp_path / "q.obj").write_text("mtllib q.mtl\n" + QUAD_OBJ + "usemtl tex\nf 1/1 2/2 3/3 4/4\n")
    (tmp_path / "q.mtl").write_text("newmtl tex\nmap_Kd -s 2 2 1 -o 0.5 0 0 blocks.png\n")
    scene = scene_file(tmp_path, [{"mesh": "q.obj"}], width=128, height=96)
    image, _ = warprt.render(scene)
    eye, d = camera_rays(scene.camera)
    p = eye + ray_plane(eye, d, np.zeros(3), np.array([0.0, 0.0, 1.0]))[..., None] * d
    uv = (p[..., :2] + S) / (2 * S)
    mapped = np.mod(uv * 2 + [0.5, 0.0], 1.0) * BLOCKS
    ok = (uv > 0).all(-1) & (uv < 1).all(-1) & (np.abs(mapped - np.round(mapped)) * TEXELS > 1.5).all(-1)
    rows, cols = np.nonzero(ok)
    assert len(rows) > 300
    expected = np.array([srgb(BLOCK_RGB8[BLOCKS - 1 - int(mapped[r, c, 1]), int(mapped[r, c, 0])]) for r, c in zip(rows, cols)])
    np.testing.assert_allclose(image[rows, cols], expected, atol=2e-6)


def write_glb(path, factor, image_bytes):
    """A GLB by hand: the quad (glTF's uv has v down, so the corners read (u, 1 - v)), a material of
    baseColorFactor times an embedded PNG."""
    p = np.array([[-S, -S, 0], [S, -S, 0], [S, S, 0], [-S, S, 0]], np.float32)
    uv = np.array([[0, 1], [1, 1], [1, 0], [0, 0]], np.float32)
    idx = np.array([0, 1, 2, 0, 2, 3], np.uint16)
    blob = bytearray()
    views = []
    for data in (p.tobytes(), uv.tobytes(), idx.tobytes(), image_bytes):
        while len(blob) % 4:
            blob.append(0)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        blob.extend(data)
    while len(blob) % 4:
        blob.append(0)
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
           "materials": [{"name": "m", "pbrMetallicRoughness": {"baseColorFactor": [*factor, 1.0],
                                                                "baseColorTexture": {"index": 0}}}],
           "textures": [{"source": 0}], "images": [{"bufferView": 3, "mimeType": "image/png"}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                          "min": [-S, -S, 0], "max": [S, S, 0]},
                         {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
                         {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}],
           "bufferViews": views, "buffers": [{"byteLength": len(blob)}]}
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    path.write_bytes(struct.pack("<III", 0x46546C67, 2, 28 + len(js) + len(blob)) + struct.pack("<I4s", len(js), b"JSON")
                     + js + struct.pack("<I4s", len(blob), b"BIN\0") + bytes(blob))


def test_glb_embedded_texture_times_base_color_factor(tmp_path):
    """glTF's base colour is baseColorFactor times the texture (the spec); 0.123 needs more than 8 bits."""
    import io

    buf = io.BytesIO()
    Image.fromarray(np.kron(BLOCK_RGB8, np.ones((TEXELS, TEXELS, 1), np.uint8))).save(buf, "PNG")
    factor = (0.123, 0.5, 1.0)
    write_glb(tmp_path / "q.glb", factor, buf.getvalue())
    assert_blocks(scene_file(tmp_path, [{"mesh": "q.glb"}]), factor)


def test_usd_preview_surface_with_uv_texture(tmp_path):
    """diffuseColor <- UsdUVTexture (scale 0.5) <- UsdPrimvarReader_float2 reading the primvar the
    material names ('uvmap', through a Material interface input), faceVarying and indexed."""
    pytest.importorskip("pxr")
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade, Vt

    write_png(tmp_path / "blocks.png")
    stage = Usd.Stage.CreateNew(str(tmp_path / "q.usda"))
    mesh = UsdGeom.Mesh.Define(stage, "/quad")
    mesh.CreatePointsAttr([(-S, -S, 0), (S, -S, 0), (S, S, 0), (-S, S, 0)])
    mesh.CreateFaceVertexCountsAttr([4])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2, 3])
    st = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar("uvmap", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.faceVarying)
    st.Set([(0, 0), (1, 0), (1, 1), (0, 1)])
    st.SetIndices(Vt.IntArray([0, 1, 2, 3]))
    UsdGeom.PrimvarsAPI(mesh).CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray,
                                            UsdGeom.Tokens.faceVarying).Set([(0.5, 0.5)] * 4)  # not the one named
    mat = UsdShade.Material.Define(stage, "/looks/m")
    surface = UsdShade.Shader.Define(stage, "/looks/m/surface")
    surface.CreateIdAttr("UsdPreviewSurface")
    reader = UsdShade.Shader.Define(stage, "/looks/m/reader")
    reader.CreateIdAttr("UsdPrimvarReader_float2")
    name = mat.CreateInput("stName", Sdf.ValueTypeNames.Token)
    name.Set("uvmap")
    reader.CreateInput("varname", Sdf.ValueTypeNames.Token).ConnectToSource(name)
    tex = UsdShade.Shader.Define(stage, "/looks/m/texture")
    tex.CreateIdAttr("UsdUVTexture")
    tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(Sdf.AssetPath("blocks.png"))
    tex.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set("sRGB")
    tex.CreateInput("scale", Sdf.ValueTypeNames.Float4).Set(Gf.Vec4f(0.5, 0.5, 0.5, 1.0))
    tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(reader.ConnectableAPI(), "result")
    tex.CreateOutput("rgb", Sdf.ValueTypeNames.Float3)
    surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(tex.ConnectableAPI(), "rgb")
    mat.CreateSurfaceOutput().ConnectToSource(surface.ConnectableAPI(), "surface")
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(mat)
    stage.GetRootLayer().Save()
    assert_blocks(scene_file(tmp_path, [{"mesh": "q.usda"}]), (0.5, 0.5, 0.5))


def test_scene_file_image_texture_on_a_plane(tmp_path):
    """kd_texture = "file.png" on the plane shape: uv ((x + sx) / 2sx, (sz - z) / 2sz), here turned by
    90 degrees about x to face the camera ((x, 0, z) -> (x, -z, 0)): the quad's uv, the image upright."""
    write_png(tmp_path / "blocks.png")
    scene = scene_file(tmp_path, [{"shape": "plane", "size": [4.0, 4.0], "rotate": [90.0, 0.0, 0.0], "material": "tiles"}],
                       {"tiles": {"kd_texture": "blocks.png"}})
    assert_blocks(scene)


def test_scene_file_checker(tmp_path):
    """{checker = [c0, c1], scale = 4}: 4 x 4 checks over the plane's uv square, c0 where
    floor(4u) + floor(4v) is even."""
    c0, c1 = [0.9, 0.5, 0.1], [0.05, 0.2, 0.7]
    scene = scene_file(tmp_path, [{"shape": "plane", "size": [4.0, 4.0], "rotate": [90.0, 0.0, 0.0], "material": "checks"}],
                       {"checks": {"kd_texture": {"checker": [c0, c1], "scale": 4}}})
    image, _ = warprt.render(scene)
    pixels = quad_blocks(scene, margin_texels=0.5)
    expected = np.array([c0 if ((BLOCKS - 1 - i) + j) % 2 == 0 else c1 for _, _, i, j in pixels])
    np.testing.assert_allclose(np.array([image[r, c] for r, c, _, _ in pixels]), expected, atol=1e-6)


def test_vertex_coloured_ply(tmp_path):
    """A binary PLY triangle with uchar colours (sRGB, decoded to linear as Blender reads them): each
    pixel is the barycentric mix of the three linear colours at its hit point."""
    corners = np.array([[-2.5, -2, 0], [2.5, -2, 0], [0, 2.5, 0]], np.float32)
    rgb8 = np.array([[255, 30, 0], [0, 200, 60], [20, 40, 250]], np.uint8)
    rec = np.empty(3, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("red", "u1"), ("green", "u1"), ("blue", "u1")])
    for k, name in enumerate("xyz"):
        rec[name] = corners[:, k]
    for k, name in enumerate(("red", "green", "blue")):
        rec[name] = rgb8[:, k]
    face = np.empty(1, dtype=[("n", "u1"), ("i", "<i4", 3)])
    face["n"], face["i"] = 3, [0, 1, 2]
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
              "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\n"
              "property list uchar int vertex_indices\nend_header\n")
    (tmp_path / "t.ply").write_bytes(header.encode() + rec.tobytes() + face.tobytes())
    scene = scene_file(tmp_path, [{"mesh": "t.ply", "material": "white"}], {"white": {"kd": [1.0, 1.0, 1.0]}})
    image, stats = warprt.render(scene)
    assert "vertex_color" in stats.effects
    eye, d = camera_rays(scene.camera)
    p = eye + ray_plane(eye, d, np.zeros(3), np.array([0.0, 0.0, 1.0]))[..., None] * d
    a, b, c = corners.astype(np.float64)
    area = np.cross(b - a, c - a)[2]
    w = np.stack([np.cross(c - b, p - b)[..., 2], np.cross(a - c, p - c)[..., 2], np.cross(b - a, p - a)[..., 2]], -1) / area
    inside = (w > 0.02).all(-1)
    assert inside.sum() > 200
    np.testing.assert_allclose(image[inside], (w @ srgb(rgb8))[inside], atol=2e-6)


def test_a_texture_without_uv_warns_and_samples_uv_zero(tmp_path, capsys):
    write_png(tmp_path / "blocks.png")
    scene = scene_file(tmp_path, [{"shape": "sphere", "material": "tiles"}], {"tiles": {"kd_texture": "blocks.png"}})
    err = capsys.readouterr().err  # load_scene turns its warnings into warprt's one-line ones
    assert "objects[0]: material 'tiles' has a texture but 'sphere' has no texture coordinates" in err
    image, _ = warprt.render(scene)
    # uv (0, 0) is a corner shared by four texels once the image repeats: the bottom-left and
    # bottom-right blocks' outer texels and, wrapped around v, the top ones; bilinear weights 1/4 each.
    corners = [BLOCK_RGB8[i, j] for i in (0, BLOCKS - 1) for j in (0, BLOCKS - 1)]
    np.testing.assert_allclose(image[24, 32], np.mean([srgb(c) for c in corners], 0), atol=2e-6)
