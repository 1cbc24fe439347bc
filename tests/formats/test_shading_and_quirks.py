"""What a file says about its shading and placement, and the quirks real files have, read back from
files written here: OBJ smoothing groups and vn, MTL Ns <= 0, a Latin-1 OBJ, a z-up STL, a USD
PointInstancer and metersPerUnit, glTF nodes sharing a mesh, and the warnings for what is not read."""

import os
import struct
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import warprt
from marks import slow
from oracle import camera_rays, ray_plane
from scenekit import write_scene
from warprt.scene import read_mesh_file

SRC = str(Path(__file__).resolve().parents[2] / "src")


def run(*args, cwd):
    env = {**os.environ, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")}
    return subprocess.run([sys.executable, "-m", "warprt", *args], capture_output=True, text=True, cwd=cwd, env=env)


def load(tmp_path, objects: list, **tables):
    """The scene read back from a real scene file: a camera on +z, ``objects``, and the file's other
    tables (lights, materials, render) as given."""
    doc = {"camera": {"eye": [0.0, 0.0, 6.0], "center": [0.0, 0.0, 0.0], "width": 48, "height": 36}, **tables,
           "objects": objects}
    return warprt.load_scene(write_scene(tmp_path, doc, "s.toml"))


def face_normals(o):
    p = o.vertices[o.faces]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


# A cube as quads, outward: the four sides facing x and y in smoothing group 1, the two facing z 's off'.
CUBE_V = "".join(f"v {x} {y} {z}\n" for x in (-1, 1) for y in (-1, 1) for z in (-1, 1))
SIDES = "f 1 2 4 3\nf 5 7 8 6\nf 1 5 6 2\nf 3 4 8 7\n"
CAPS = "f 3 7 5 1\nf 2 6 8 4\n"


def test_obj_smoothing_groups_smooth_within_and_flat_off(tmp_path):
    (tmp_path / "c.obj").write_text(CUBE_V + "s 1\n" + SIDES + "s off\n" + CAPS)
    (o,) = load(tmp_path, [{"mesh": "c.obj", "smooth": "auto"}]).objects
    assert o.smooth and o.normals is not None
    n_corner = o.normals[o.faces]
    caps = np.abs(face_normals(o)[:, 2]) > 0.5  # the faces facing z ('s off')
    # 's off' faces: every corner's normal is the face's, so the face shades flat.
    np.testing.assert_allclose(n_corner[caps], np.repeat(face_normals(o)[caps][:, None], 3, 1), atol=1e-12)
    # Group 1 smooths across the sides' 90-degree edges: each side corner's normal is the mean of the
    # two side faces there, (+-1, +-1, 0) / sqrt 2; the caps' edges are not crossed.
    side = n_corner[~caps].reshape(-1, 3)
    np.testing.assert_allclose(side[:, 2], 0.0, atol=1e-12)
    np.testing.assert_allclose(np.abs(side[:, :2]), np.sqrt(0.5), atol=1e-12)


def test_obj_vn_are_the_normals_with_auto_and_ignored_when_flat(tmp_path):
    """A face-on quad whose vn all lean (0, 0.6, 0.8), lit from straight ahead: with smooth = "auto"
    every pixel is kd (n . L) for that n; with smooth = false the face's own +z."""
    (tmp_path / "q.obj").write_text("v -9 -9 0\nv 9 -9 0\nv 9 9 0\nv -9 9 0\nvn 0 0.6 0.8\nf 1//1 2//1 3//1 4//1\n")
    def render(smooth):
        scene = load(tmp_path, [{"mesh": "q.obj", "material": "m", "smooth": smooth}],
                     lights=[{"position": [0.0, 0.0, 1000.0]}], materials={"m": {"kd": [1.0, 1.0, 1.0], "ka": [0.0, 0.0, 0.0]}},
                     render={"ambient": [0.0, 0.0, 0.0], "shadows": False, "max_depth": 1})
        eye, d = camera_rays(scene.camera)
        p = eye + ray_plane(eye, d, np.zeros(3), np.array([0.0, 0.0, 1.0]))[..., None] * d
        to_light = np.array([0.0, 0.0, 1000.0]) - p
        return warprt.render(scene).image, to_light / np.linalg.norm(to_light, axis=-1, keepdims=True)

    image, L = render("auto")
    np.testing.assert_allclose(image[..., 0], L @ np.array([0.0, 0.6, 0.8]), atol=1e-5)
    image, L = render(False)
    np.testing.assert_allclose(image[..., 0], L @ np.array([0.0, 0.0, 1.0]), atol=1e-5)


def test_crease_angle_splits_a_cube_and_keeps_a_sphere_smooth(tmp_path):
    scene = load(tmp_path, [{"shape": "box", "smooth": 30},
                            {"shape": "sphere", "subdivisions": 2, "smooth": 30, "translate": [3.0, 0.0, 0.0]}])
    box, ball = scene.objects
    assert len(box.vertices) == 24  # 8 corners, each on 3 flat sides
    np.testing.assert_allclose(box.normals[box.faces], np.repeat(face_normals(box)[:, None], 3, 1), atol=1e-12)
    assert len(ball.vertices) == 162  # an icosphere's neighbours differ by under 30 degrees: no split
    radial = (ball.vertices - [3.0, 0.0, 0.0]) / np.linalg.norm(ball.vertices - [3.0, 0.0, 0.0], axis=1, keepdims=True)
    assert np.abs(ball.normals - radial).max() < 0.02


def test_crease_angle_on_a_cylinder_smooths_its_side_and_not_its_rims(tmp_path):
    (o,) = load(tmp_path, [{"shape": "cylinder", "sections": 16, "smooth": 30}]).objects
    n_corner = o.normals[o.faces]
    cap = np.abs(face_normals(o)[:, 1]) > 0.99
    np.testing.assert_allclose(np.abs(n_corner[cap][..., 1]), 1.0, atol=1e-12)  # flat caps
    side = n_corner[~cap].reshape(-1, 3)
    np.testing.assert_allclose(side[:, 1], 0.0, atol=1e-12)  # horizontal: no tilt from the caps
    p = o.vertices[o.faces][~cap].reshape(-1, 3)
    radial = p * [1.0, 0.0, 1.0] / np.linalg.norm(p * [1.0, 0.0, 1.0], axis=1, keepdims=True)
    np.testing.assert_allclose(side, radial, atol=1e-12)  # at a vertex, the two side faces' mean: radial


@slow
def test_negative_and_zero_ns_load_as_no_highlight_with_one_warning(tmp_path):
    """Blender's exporter writes 'Ns -1.960784' and 'Ns 0': neither is refused, both mean no highlight."""
    (tmp_path / "n.obj").write_text("mtllib n.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 1 3 2\n")
    (tmp_path / "n.mtl").write_text("newmtl a\nNs -1.960784\nKd 0.5 0.5 0.5\nKs 0.5 0.5 0.5\nKa 0 0 0\n"
                                    "newmtl b\nNs 0\nKs 0.9 0.9 0.9\n")
    r = run("info", "n.obj", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stderr.count("\n") == 1 and "n.mtl: Ns: negative values read as no highlight: a (-1.96078)" in r.stderr
    materials = dict(read_mesh_file(tmp_path / "n.obj").materials)
    assert materials["a"].ks == (0.0, 0.0, 0.0) and materials["b"].ks == (0.0, 0.0, 0.0)
    assert materials["a"].ka == (0.0, 0.0, 0.0)  # Ka 0 0 0 is what the file says


def test_latin1_obj_and_mtl_load_with_their_accented_names(tmp_path):
    obj = "# mod\xe8le cr\xe9\xe9 par Andr\xe9\nmtllib caf\xe9.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl caf\xe9\nf 1 2 3\n"
    (tmp_path / "l.obj").write_bytes(obj.encode("latin-1"))
    (tmp_path / "caf\xe9.mtl").write_bytes("# \xa9 Andr\xe9\nnewmtl caf\xe9\nKd 0.25 0.5 0.75\n".encode("latin-1"))
    mesh = read_mesh_file(tmp_path / "l.obj")
    assert [n for n, _ in mesh.materials] == ["caf\xe9"] and mesh.materials[0][1].kd == (0.25, 0.5, 0.75)
    assert mesh.parts[0].face_material.tolist() == [0]


def write_stl(path, triangles):
    data = b"z-up".ljust(80, b"\0") + struct.pack("<I", len(triangles))
    for t in np.asarray(triangles, np.float32):
        data += struct.pack("<3f", 0, 0, 0) + t.astype("<f4").tobytes() + b"\0\0"
    path.write_bytes(data)


def tall_z_box():
    """A box 0.4 x 0.6 x 3 (tall along z), as triangles."""
    from warprt.scene import shapes

    v, f = shapes.box([0.4, 0.6, 3.0])
    return v[f]


def test_up_z_on_an_object_turns_the_file_upright(tmp_path):
    write_stl(tmp_path / "t.stl", tall_z_box())
    (o,) = load(tmp_path, [{"mesh": "t.stl", "up": "z"}]).objects
    extent = o.vertices.max(0) - o.vertices.min(0)
    np.testing.assert_allclose(extent, [0.4, 3.0, 0.6], atol=1e-6)  # z -> y, y -> -z


@slow
def test_up_z_frames_a_bare_stl_along_z(tmp_path):
    write_stl(tmp_path / "t.stl", tall_z_box())
    for up, camera_up in ((None, (0.0, 1.0, 0.0)), ("z", (0.0, 0.0, 1.0)), ("-z", (0.0, 0.0, -1.0))):
        assert warprt.load_scene(tmp_path / "t.stl", up=up).camera.up == camera_up
    image = tmp_path / "z.png"
    r = run("render", "t.stl", "--up=-z", "-o", str(image), "--width", "40", "--height", "60", "-q", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    from warprt.image import read_image

    lit = read_image(image).max(-1) > 0.02
    rows, cols = np.nonzero(lit)
    assert np.ptp(rows) > 1.5 * np.ptp(cols)  # upright (upside down): taller than wide


def test_a_z_up_usd_stage_stands_upright_in_a_scene_unless_told(tmp_path):
    """A stage authoring upAxis Z is turned z -> y by default; up = "y" keeps it as placed."""
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.CreateNew(str(tmp_path / "z.usda"))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    m = UsdGeom.Mesh.Define(stage, "/post")
    m.CreatePointsAttr([(0, 0, 0), (0.1, 0, 0), (0, 0, 2.0)])
    m.CreateFaceVertexCountsAttr([3])
    m.CreateFaceVertexIndicesAttr([0, 1, 2])
    stage.GetRootLayer().Save()
    (o,) = load(tmp_path, [{"mesh": "z.usda"}]).objects
    np.testing.assert_allclose(np.ptp(o.vertices, axis=0), [0.1, 2.0, 0.0], atol=1e-12)
    (o,) = load(tmp_path, [{"mesh": "z.usda", "up": "y"}]).objects
    np.testing.assert_allclose(np.ptp(o.vertices, axis=0), [0.1, 0.0, 2.0], atol=1e-12)


def test_up_on_a_scene_file_is_refused(tmp_path):
    (tmp_path / "s.toml").write_text("")
    r = run("info", "s.toml", "--up", "z", cwd=tmp_path)
    assert r.returncode == 2
    assert r.stderr.startswith("warprt: error: command line: --up: applies to a mesh file")


@slow
def test_width_and_height_reframe_a_bare_mesh(tmp_path):
    """Framing comes after the overrides: a tall narrow image still holds the whole mesh."""
    import trimesh

    trimesh.creation.box(extents=[2.0, 1.0, 1.0]).export(tmp_path / "b.obj")
    out = tmp_path / "b.png"
    r = run("render", "b.obj", "-o", str(out), "--width", "24", "--height", "96", "-q", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    from warprt.image import read_image

    lit = read_image(out).max(-1) > 0.02
    assert lit.any() and not (lit[0].any() or lit[-1].any() or lit[:, 0].any() or lit[:, -1].any())


def test_point_instancer_places_each_instance_and_not_the_prototype(tmp_path):
    """5 instances of a cube of side 0.5 (its prototype defined under the instancer, hidden scope):
    positions (4 + k, 0, 0), the last scaled 2 along x and turned 90 degrees about z (a half-precision
    quaternion, normalised here); metersPerUnit 0.01 converts to metres."""
    pytest.importorskip("pxr")
    from pxr import Gf, Usd, UsdGeom

    stage = Usd.Stage.CreateNew(str(tmp_path / "i.usda"))
    UsdGeom.SetStageMetersPerUnit(stage, 0.01)
    inst = UsdGeom.PointInstancer.Define(stage, "/world/instancer")
    protos = UsdGeom.Scope.Define(stage, "/world/instancer/protos")
    protos.CreateVisibilityAttr("invisible")
    cube = UsdGeom.Cube.Define(stage, "/world/instancer/protos/cube_xform")  # not a Mesh: not read
    box = UsdGeom.Mesh.Define(stage, "/world/instancer/protos/box")
    corners = [(x, y, z) for x in (-0.25, 0.25) for y in (-0.25, 0.25) for z in (-0.25, 0.25)]
    box.CreatePointsAttr(corners)
    box.CreateFaceVertexCountsAttr([4] * 6)
    box.CreateFaceVertexIndicesAttr([0, 1, 3, 2, 4, 6, 7, 5, 0, 4, 5, 1, 2, 3, 7, 6, 0, 2, 6, 4, 1, 5, 7, 3])
    inst.CreatePrototypesRel().SetTargets([box.GetPath()])
    inst.CreateProtoIndicesAttr([0] * 5)
    inst.CreatePositionsAttr([Gf.Vec3f(4 + k, 0, 0) for k in range(5)])
    half = float(np.sqrt(0.5))
    inst.CreateOrientationsAttr([Gf.Quath(1, 0, 0, 0)] * 4 + [Gf.Quath(half, 0, 0, half)])
    inst.CreateScalesAttr([Gf.Vec3f(1, 1, 1)] * 4 + [Gf.Vec3f(2, 1, 1)])
    stage.GetRootLayer().Save()
    del cube
    mesh = read_mesh_file(tmp_path / "i.usda")
    assert len(mesh.parts) == 5 and mesh.triangle_count == 5 * 12
    centres = np.array([p.vertices.mean(0) for p in mesh.parts])
    np.testing.assert_allclose(centres, [[0.01 * (4 + k), 0.0, 0.0] for k in range(5)], atol=1e-12)
    last = mesh.parts[4].vertices
    np.testing.assert_allclose(np.ptp(last, axis=0), [0.005, 0.01, 0.005], atol=1e-12)  # 2 x 0.5 along y now


def test_usd_without_authored_meters_per_unit_is_not_scaled(tmp_path):
    """pxr answers 0.01 for a stage that does not say: only an authored metersPerUnit converts."""
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.CreateNew(str(tmp_path / "plain.usda"))
    m = UsdGeom.Mesh.Define(stage, "/tri")
    m.CreatePointsAttr([(0, 0, 0), (2, 0, 0), (0, 2, 0)])
    m.CreateFaceVertexCountsAttr([3])
    m.CreateFaceVertexIndicesAttr([0, 1, 2])
    stage.GetRootLayer().Save()
    assert UsdGeom.GetStageMetersPerUnit(stage) == 0.01
    mesh = read_mesh_file(tmp_path / "plain.usda")
    np.testing.assert_allclose(mesh.parts[0].vertices.max(0), [2.0, 2.0, 0.0])
    assert mesh.up_axis is None


def test_usd_face_varying_normals_make_a_flat_cube(tmp_path):
    """The committed flat-shaded USD cube: 6 sides of 4 corners each, every corner's normal its side's."""
    path = Path(__file__).resolve().parents[2] / "scenes" / "meshes" / "cube_flat.usda"
    (o,) = warprt.load_scene(write_scene(tmp_path, {"objects": [{"mesh": str(path), "smooth": "auto"}]})).objects
    assert len(o.vertices) == 24
    np.testing.assert_allclose(o.normals[o.faces], np.repeat(face_normals(o)[:, None], 3, 1), atol=1e-6)


def test_gltf_nodes_reusing_a_mesh_are_placed_copies():
    path = Path(__file__).resolve().parents[2] / "scenes" / "meshes" / "tile.glb"
    mesh = read_mesh_file(path)
    assert len(mesh.parts) == 2 and mesh.up_axis == "Y"
    a, b = (p.vertices.mean(0) for p in mesh.parts)
    np.testing.assert_allclose(a, [-0.7, 0.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(b, [0.7, 0.0, 0.0], atol=1e-6)
    assert mesh.parts[0].colors is None and mesh.parts[1].colors is not None  # COLOR_0 on the second only


@slow
def test_warnings_are_one_line_each_and_silenced_by_q(tmp_path):
    (tmp_path / "w.obj").write_text("mtllib w.mtl\nmtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                                    "usemtl glass\nf 1 2 3\nusemtl nowhere\nf 1 3 2\nfoo 1 2\n")
    (tmp_path / "w.mtl").write_text("newmtl glass\nKd 0.5 0.5 0.5\nd 0.3\nmap_Ke glow.png\nmap_Kd missing.png\nzz 3\n")
    r = run("render", "w.obj", "-o", "w.png", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    warnings = [l for l in r.stderr.splitlines() if l.startswith("warprt: warning: ")]
    expected = ["w.obj: line 2: mtllib gone.mtl: file not found", "w.obj: usemtl: no material named 'nowhere'",
                "w.obj: statements not read: foo", "w.mtl: statements not read: zz",
                "w.mtl: newmtl glass: map_Kd: missing.png: texture file not found",
                "w.mtl: newmtl glass: transparency", "w.mtl: newmtl glass: an emission map (map_Ke) is not read"]
    for text in expected:
        assert sum(text in w for w in warnings) == 1, (text, warnings)
    assert len(warnings) == len(expected)
    quiet = run("render", "w.obj", "-o", "w.png", "-q", cwd=tmp_path)
    assert quiet.returncode == 0 and quiet.stderr == ""


@slow
def test_usd_diagnostics_become_one_warning_line(tmp_path):
    """pxr prints its C++ diagnostics straight to stderr, several lines each: they arrive as one
    warprt warning, and the stage still loads."""
    pytest.importorskip("pxr")
    (tmp_path / "r.usda").write_text(textwrap.dedent("""\
        #usda 1.0
        def Xform "root" (
            references = @./nothere.usda@
        )
        {
            def Mesh "tri"
            {
                int[] faceVertexCounts = [3]
                int[] faceVertexIndices = [0, 1, 2]
                point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
            }
        }
        """))
    r = run("info", "r.usda", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("warprt: warning: r.usda: USD: In </root>: Could not open asset")
    assert "0x" not in lines[0] and "stage.cpp" not in lines[0]
