"""Each mesh format loads from a file the test writes, with the geometry and colours written:
OBJ + MTL, PLY and STL written by hand, GLB through trimesh, USD through pxr.

Triangles are compared as sets of world-space corner triples (a reader may reorder vertices),
each triple in its written winding order up to rotation; materials are compared exactly.
"""

import json
import struct
import textwrap

import numpy as np
import pytest

import warprt
from scenekit import write_scene
from warprt.scene import read_mesh_file
from warprt.scene import Material


def triangles(vertices, faces):
    """A canonical set of triangles: each (3, 3) corner list rotated to start at its smallest
    corner, so that winding is kept and the starting corner does not matter."""
    out = set()
    for tri in np.asarray(vertices, np.float64)[np.asarray(faces)]:
        rows = [tuple(np.round(p, 5)) for p in tri]
        k = rows.index(min(rows))
        out.add(tuple(rows[k:] + rows[:k]))
    return out


def mesh_triangles(mesh):
    v, f, _, _ = mesh.concatenated()
    return triangles(v, f)


def scene_file(tmp_path, objects, materials=None, render=None) -> "warprt.Scene":
    """A scene file beside the mesh files, its objects naming them, loaded as the command would."""
    doc = {"camera": {"eye": [0.0, 0.0, 10.0], "center": [0.0, 0.0, 0.0], "width": 16, "height": 12},
           **({"render": render} if render else {}), **({"materials": materials} if materials else {}), "objects": objects}
    return warprt.load_scene(write_scene(tmp_path, doc))


# --- OBJ + MTL ----------------------------------------------------------------------------------

OBJ = """\
mtllib paints.mtl
o thing
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 2 0 0
v 2 1 0
usemtl red
f 1 2 3 4
usemtl mirror
f 2 5 6
f 2 6 3
"""

MTL = """\
newmtl red
Ka 0.1 0.02 0.03
Kd 0.7 0.123 0.1
Ks 0.5 0.25 0.125
Ns 64
illum 2

newmtl mirror
Kd 0.01 0.02 0.03
Ks 0.9 0.8 0.7
Ns 300
illum 3
"""

P = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]]


@pytest.fixture
def obj_file(tmp_path):
    (tmp_path / "thing.obj").write_text(OBJ)
    (tmp_path / "paints.mtl").write_text(MTL)
    return tmp_path / "thing.obj"


def test_obj_geometry_is_the_written_faces(obj_file):
    mesh = read_mesh_file(obj_file)
    # The quad 1 2 3 4 is two triangles; which diagonal a reader picks is its choice, so compare
    # the area it covers and the two triangles of the second material exactly.
    v, f, mat, _ = mesh.concatenated()
    names = [n for n, _ in mesh.materials]
    mirror = mat == names.index("mirror")
    assert triangles(v, f[mirror]) == triangles(P, [[1, 4, 5], [1, 5, 2]])
    red = f[mat == names.index("red")]
    assert len(red) == 2
    area = sum(0.5 * np.linalg.norm(np.cross(v[b] - v[a], v[c] - v[a])) for a, b, c in red)
    assert area == pytest.approx(1.0)
    normal = np.cross(v[red[0, 1]] - v[red[0, 0]], v[red[0, 2]] - v[red[0, 0]])
    assert normal[2] > 0  # counter-clockwise as written: facing +z


def test_mtl_values_become_phong_materials(obj_file):
    materials = dict(read_mesh_file(obj_file).materials)
    assert materials["red"] == Material(ka=(0.1, 0.02, 0.03), kd=(0.7, 0.123, 0.1), ks=(0.5, 0.25, 0.125),
                                        shininess=64.0, reflectivity=(0.0, 0.0, 0.0))
    # illum 3: a mirror weighted by Ks; no Ka written: ka = kd, the scene file's own default.
    assert materials["mirror"] == Material(ka=(0.01, 0.02, 0.03), kd=(0.01, 0.02, 0.03), ks=(0.9, 0.8, 0.7),
                                           shininess=300.0, reflectivity=(0.9, 0.8, 0.7))


def test_obj_materials_join_the_scene_per_face(obj_file, tmp_path):
    scene = scene_file(tmp_path, [{"mesh": "thing.obj"}])
    by_name = {o.name: o for o in scene.objects}
    assert set(by_name) == {"thing/red", "thing/mirror"}
    assert by_name["thing/mirror"].material == "thing/mirror"
    assert scene.materials["thing/mirror"].reflectivity == (0.9, 0.8, 0.7)
    assert len(by_name["thing/red"].faces) == 2 and len(by_name["thing/mirror"].faces) == 2


def test_scene_material_overrides_the_files(obj_file, tmp_path):
    scene = scene_file(tmp_path, [{"mesh": "thing.obj", "material": "chalk"}], {"chalk": {"kd": [0.9, 0.9, 0.9]}})
    assert [(o.name, o.material, len(o.faces)) for o in scene.objects] == [("thing", "chalk", 4)]
    assert not any(name.startswith("thing/") for name in scene.materials)


def test_split_smooth_mesh_keeps_shared_normals(obj_file, tmp_path):
    """The two material parts meet along the edge x = 1; their vertex normals there are the same
    (the flat sheet's +z), not each part's own."""
    scene = scene_file(tmp_path, [{"mesh": "thing.obj", "smooth": True}])
    for o in scene.objects:
        np.testing.assert_allclose(o.normals, np.tile([0.0, 0.0, 1.0], (len(o.vertices), 1)), atol=1e-12)


def test_file_material_reaches_the_pixels(tmp_path):
    """A face-on quad whose MTL gives Ka, with C_amb = 1 and no lights: the pixel is Ka."""
    (tmp_path / "q.obj").write_text("mtllib q.mtl\nv -3 -3 0\nv 3 -3 0\nv 3 3 0\nv -3 3 0\nusemtl k\nf 1 2 3 4\n")
    (tmp_path / "q.mtl").write_text("newmtl k\nKa 0.25 0.5 0.75\nKd 0.1 0.1 0.1\n")
    scene = scene_file(tmp_path, [{"mesh": "q.obj"}], render={"ambient": [1.0, 1.0, 1.0]})
    image, _ = warprt.render(scene)
    np.testing.assert_allclose(image[6, 8], [0.25, 0.5, 0.75], atol=1e-6)


# --- PLY and STL ----------------------------------------------------------------------------------


def test_ply_ascii_with_a_quad(tmp_path):
    (tmp_path / "q.ply").write_text(textwrap.dedent("""\
        ply
        format ascii 1.0
        element vertex 5
        property float x
        property float y
        property float z
        element face 2
        property list uchar int vertex_indices
        end_header
        0 0 0
        2 0 0
        2 1 0
        0 1 0
        1 3 0.5
        4 0 1 2 3
        3 3 2 4
        """))
    v = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0], [1, 3, 0.5]], np.float64)
    mesh = read_mesh_file(tmp_path / "q.ply")
    assert mesh.materials == []
    got = mesh_triangles(mesh)
    assert triangles(v, [[3, 2, 4]]) <= got and len(got) == 3
    quad_area = sum(0.5 * np.linalg.norm(np.cross(np.array(b) - a, np.array(c) - a))
                    for a, b, c in (map(np.array, t) for t in got - triangles(v, [[3, 2, 4]])))
    assert quad_area == pytest.approx(2.0)


def test_stl_binary(tmp_path):
    """Binary STL: 80-byte header, count, then per triangle a normal, three corners and 2 bytes."""
    tris = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0.5], [0, 1, 0]]], np.float32)
    data = b"warprt test".ljust(80, b"\0") + struct.pack("<I", len(tris))
    for t in tris:
        data += struct.pack("<3f", 0, 0, 1) + t.astype("<f4").tobytes() + b"\0\0"
    (tmp_path / "t.stl").write_bytes(data)
    got = mesh_triangles(read_mesh_file(tmp_path / "t.stl"))
    assert got == triangles(tris.reshape(-1, 3), [[0, 1, 2], [3, 4, 5]])


def test_stl_ascii(tmp_path):
    (tmp_path / "a.stl").write_text(textwrap.dedent("""\
        solid one
          facet normal 0 0 1
            outer loop
              vertex 0 0 0
              vertex 1 0 0
              vertex 0 2 0
            endloop
          endfacet
        endsolid one
        """))
    assert mesh_triangles(read_mesh_file(tmp_path / "a.stl")) == triangles([[0, 0, 0], [1, 0, 0], [0, 2, 0]], [[0, 1, 2]])


# --- glTF / GLB -------------------------------------------------------------------------------------


def _rot_z(deg):
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    m = np.eye(4)
    m[:2, :2] = [[c, -s], [s, c]]
    return m


@pytest.fixture
def glb_file(tmp_path):
    """Two nodes with their own transforms and base colours, written by trimesh, then the JSON
    patched to colours that 8 bits cannot hold (trimesh stores colours as 8-bit)."""
    trimesh = pytest.importorskip("trimesh")
    from trimesh.visual.material import PBRMaterial

    box = trimesh.creation.box(extents=[1.0, 2.0, 3.0])
    box.visual = trimesh.visual.TextureVisuals(material=PBRMaterial(name="clay", baseColorFactor=[0.5, 0.5, 0.5, 1]))
    tri = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], process=False)
    tri.visual = trimesh.visual.TextureVisuals(material=PBRMaterial(name="leaf", baseColorFactor=[0.2, 0.6, 0.2, 1]))
    t_box = _rot_z(30.0)
    t_box[:3, 3] = [4.0, 0.0, -1.0]
    t_tri = np.diag([2.0, -1.0, 1.0, 1.0])  # a mirroring scale: the winding must turn over
    s = trimesh.Scene()
    s.add_geometry(box, node_name="crate", geom_name="box", transform=t_box)
    s.add_geometry(tri, node_name="sheet", geom_name="tri", transform=t_tri)
    data = s.export(file_type="glb")
    n = struct.unpack("<I", data[12:16])[0]
    header = json.loads(data[20:20 + n])
    exact = {"clay": [0.123, 0.456, 0.789, 1.0], "leaf": [0.2001, 0.6002, 0.2003, 1.0]}
    for m in header["materials"]:
        m["pbrMetallicRoughness"]["baseColorFactor"] = exact[m["name"]]
    chunk = json.dumps(header).encode()
    chunk += b" " * (-len(chunk) % 4)
    rest = data[20 + n:]
    out = b"glTF" + struct.pack("<II", 2, 12 + 8 + len(chunk) + len(rest)) + struct.pack("<I", len(chunk)) + b"JSON" + chunk + rest
    (tmp_path / "pair.glb").write_bytes(out)
    return tmp_path / "pair.glb", (box, t_box), (tri, t_tri)


def test_glb_nodes_in_world_space(glb_file):
    path, (box, t_box), (tri, t_tri) = glb_file
    mesh = read_mesh_file(path)
    world_box = box.vertices @ t_box[:3, :3].T + t_box[:3, 3]
    world_tri = tri.vertices @ t_tri[:3, :3].T
    expect = triangles(world_box, box.faces) | triangles(world_tri, tri.faces[:, ::-1])
    assert mesh_triangles(mesh) == expect


def test_glb_base_colours_are_kd(glb_file):
    materials = dict(read_mesh_file(glb_file[0]).materials)
    assert materials["clay"].kd == (0.123, 0.456, 0.789) and materials["clay"].ka == (0.123, 0.456, 0.789)
    assert materials["leaf"].kd == (0.2001, 0.6002, 0.2003)
    assert materials["leaf"].ks == (0.0, 0.0, 0.0)


def test_glb_as_scene_objects(glb_file, tmp_path):
    scene = scene_file(tmp_path, [{"mesh": "pair.glb", "name": "yard"}])
    assert {(o.name, o.material, len(o.faces)) for o in scene.objects} == {("yard/clay", "yard/clay", 12),
                                                                           ("yard/leaf", "yard/leaf", 1)}


# --- USD ---------------------------------------------------------------------------------------------


@pytest.fixture
def usd_file(tmp_path):
    """A transformed, left-handed mesh with a quad, a pentagon, a triangle and a hole, a bound
    UsdPreviewSurface, a GeomSubset with another material, and a second prim with a displayColor."""
    pytest.importorskip("pxr")
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade

    path = tmp_path / "stage.usda"
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    xf = UsdGeom.Xform.Define(stage, "/world")
    xf.AddTranslateOp().Set(Gf.Vec3d(1.0, 2.0, 3.0))
    xf.AddScaleOp().Set(Gf.Vec3f(2.0, 2.0, 2.0))
    mesh = UsdGeom.Mesh.Define(stage, "/world/shape")
    points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 0, 0), (3, 0, 0), (3, 1, 0), (2.5, 2, 0), (2, 1, 0),
              (0, 0, 1), (1, 0, 1), (0, 1, 1)]
    mesh.CreatePointsAttr(points)
    mesh.CreateFaceVertexCountsAttr([4, 5, 3, 3])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 0, 4, 8])
    mesh.CreateHoleIndicesAttr([3])  # the second triangle (face 3) is a hole
    mesh.CreateOrientationAttr(UsdGeom.Tokens.leftHanded)

    def material(name, rgb):
        mat = UsdShade.Material.Define(stage, f"/looks/{name}")
        shader = UsdShade.Shader.Define(stage, f"/looks/{name}/surface")
        shader.CreateIdAttr("UsdPreviewSurface")
        shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*rgb))
        mat.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
        return mat

    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material("steel", (0.25, 0.5, 0.75)))
    subset = UsdShade.MaterialBindingAPI(mesh.GetPrim()).CreateMaterialBindSubset("pent", [1])
    UsdShade.MaterialBindingAPI.Apply(subset.GetPrim()).Bind(material("brass", (0.8, 0.6, 0.2)))

    other = UsdGeom.Mesh.Define(stage, "/tag")
    other.CreatePointsAttr([(0, 0, 5), (1, 0, 5), (0, 1, 5)])
    other.CreateFaceVertexCountsAttr([3])
    other.CreateFaceVertexIndicesAttr([0, 1, 2])
    other.CreateDisplayColorAttr([(0.1, 0.9, 0.3)])
    stage.GetRootLayer().Save()
    world = np.asarray(points, np.float64) * 2.0 + [1.0, 2.0, 3.0]
    return path, world


def test_usd_polygons_transform_and_winding(usd_file):
    path, world = usd_file
    mesh = read_mesh_file(path)
    shape = next(p for p in mesh.parts if p.name == "/world/shape")
    # Fan triangles of the quad and the pentagon, the first triangle, the hole (the second
    # triangle) dropped, each turned from the stage's clockwise (leftHanded) to counter-clockwise.
    fan = [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7], [4, 7, 8], [9, 10, 11]]
    assert triangles(shape.vertices, shape.faces) == triangles(world, [f[::-1] for f in fan])
    tag = next(p for p in mesh.parts if p.name == "/tag")
    assert triangles(tag.vertices, tag.faces) == triangles([[0, 0, 5], [1, 0, 5], [0, 1, 5]], [[0, 1, 2]])
    assert mesh.up_axis == "Z"


def test_usd_materials_bound_subset_and_display_color(usd_file):
    mesh = read_mesh_file(usd_file[0])
    names = [n for n, _ in mesh.materials]
    kd = {n: m.kd for n, m in mesh.materials}
    assert kd["steel"] == pytest.approx((0.25, 0.5, 0.75)) and kd["brass"] == pytest.approx((0.8, 0.6, 0.2))
    assert kd["tag.displayColor"] == pytest.approx((0.1, 0.9, 0.3))
    shape = next(p for p in mesh.parts if p.name == "/world/shape")
    # The quad's two triangles and the triangle bound to steel, the pentagon's three to the subset's brass.
    assert [names[i] for i in shape.face_material] == ["steel"] * 2 + ["brass"] * 3 + ["steel"]


def test_z_up_stage_is_framed_with_z_up(usd_file):
    scene = warprt.load_scene(usd_file[0])
    assert scene.camera.up == (0.0, 0.0, 1.0)
    assert {o.material for o in scene.objects} == {"stage/steel", "stage/brass", "stage/tag.displayColor"}


def test_warp_example_assets_load():
    """The USD meshes shipped with warp-lang, triangulated as their face counts say."""
    pytest.importorskip("pxr")
    import os

    import warp.examples
    from pxr import Usd, UsdGeom

    folder = warp.examples.get_asset_directory()
    for name in ("bunny.usd", "bear.usd", "rocks.usd"):
        path = os.path.join(folder, name)
        stage = Usd.Stage.Open(path)
        expect_tris, lo, hi = 0, np.full(3, np.inf), np.full(3, -np.inf)
        for prim in stage.Traverse():
            if prim.IsA(UsdGeom.Mesh):
                m = UsdGeom.Mesh(prim)
                expect_tris += int(sum(c - 2 for c in m.GetFaceVertexCountsAttr().Get()))
                p = np.asarray(m.GetPointsAttr().Get(), np.float64)
                lo, hi = np.minimum(lo, p.min(0)), np.maximum(hi, p.max(0))
        mesh = read_mesh_file(path)
        assert mesh.triangle_count == expect_tris, name
        v, _, _, _ = mesh.concatenated()
        np.testing.assert_allclose(v.min(0), lo, rtol=1e-6)  # the assets sit at the identity transform
        np.testing.assert_allclose(v.max(0), hi, rtol=1e-6)


def test_off(tmp_path):
    (tmp_path / "t.off").write_text("OFF\n4 1 0\n0 0 0\n1 0 0\n1 2 0\n0 2 0\n4 0 1 2 3\n")
    mesh = read_mesh_file(tmp_path / "t.off")
    v, f, _, _ = mesh.concatenated()
    assert len(f) == 2
    assert sum(0.5 * np.linalg.norm(np.cross(v[b] - v[a], v[c] - v[a])) for a, b, c in f) == pytest.approx(2.0)
