"""warprt's PLY reader against files this test writes byte by byte (struct for binary, text for ASCII)
with known contents: every layout gives the written corners, normals, uvs and colours; damaged files
are refused in one line naming the file and the element or property; no trimesh is imported.

Triangles are compared corner by corner (the polygon fanned as (v0, vk, vk+1)), so a reader may
number its vertices as it likes.
"""

import os
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from warprt import SceneError
from warprt.scene import read_mesh_file

SRC = str(Path(__file__).resolve().parents[2] / "src")
ENV = {**os.environ, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")}

# Five vertices, all values exact in float32; a quad and a triangle sharing an edge.
XYZ = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0], [1, 3, 0.5]])
NORMALS = np.array([[0, 0, 1], [0.5, 0, 0.75], [0, -0.25, 1], [0.125, 0.5, 0.5], [1, 0, 0]])
UV = np.array([[0, 0], [1, 0], [1, 0.5], [0, 0.5], [0.5, 1]])
RGB8 = np.array([[255, 0, 0], [0, 255, 0], [0, 0, 255], [10, 20, 30], [200, 100, 50]])
POLYGONS = [[0, 1, 2, 3], [3, 2, 4]]
CORNERS = [0, 1, 2, 0, 2, 3, 3, 2, 4]  # the fan of each polygon, corner by corner

TYPES = {"char": "b", "uchar": "B", "short": "h", "ushort": "H", "int": "i", "uint": "I", "float": "f", "double": "d"}


def srgb_to_linear(c):
    """The sRGB decode (IEC 61966-2-1), written here from the standard."""
    c = np.asarray(c, np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def write_ply(path: Path, fmt: str, vertex: list, faces: list, face_extra: list = (), index_name="vertex_indices",
              index_type="int", comments=()):
    """A PLY file written row by row: ``vertex`` [(type, name, values)], ``faces`` polygons (lists of
    vertex indices), ``face_extra`` more face properties [(type or 'list T', name, values per face)]."""
    n = len(vertex[0][2])
    head = ["ply", f"format {fmt} 1.0", *(f"comment {c}" for c in comments), f"element vertex {n}"]
    head += [f"property {t} {name}" for t, name, _ in vertex]
    head += [f"element face {len(faces)}", f"property list uchar {index_type} {index_name}"]
    head += [f"property {'list uchar ' + t[5:] if t.startswith('list ') else t} {name}" for t, name, _ in face_extra]
    text = "\n".join(head + ["end_header"]) + "\n"
    if fmt == "ascii":
        rows = [" ".join(_ascii(t, v[i]) for t, _, v in vertex) for i in range(n)]
        for k, f in enumerate(faces):
            row = [str(len(f)), *map(str, f)]
            for t, _, v in face_extra:
                row += [str(len(v[k])), *(_ascii(t[5:], x) for x in v[k])] if t.startswith("list ") else [_ascii(t, v[k])]
            rows.append(" ".join(row))
        path.write_text(text + "\n".join(rows) + "\n")
        return
    order = "<" if fmt == "binary_little_endian" else ">"
    body = bytearray()
    for i in range(n):
        for t, _, v in vertex:
            body += struct.pack(order + TYPES[t], v[i])
    for k, f in enumerate(faces):
        body += struct.pack(order + "B" + TYPES[index_type] * len(f), len(f), *f)
        for t, _, v in face_extra:
            if t.startswith("list "):
                body += struct.pack(order + "B" + TYPES[t[5:]] * len(v[k]), len(v[k]), *v[k])
            else:
                body += struct.pack(order + TYPES[t], v[k])
    path.write_bytes(text.encode() + bytes(body))


def _ascii(t, x):
    return repr(float(x)) if t in ("float", "double") else str(int(x))


def corners(mesh):
    """Per triangle corner: its position, and its uv and colour where the part has them."""
    (p,) = mesh.parts
    f = p.faces.reshape(-1)
    return (p.vertices[f], None if p.uv is None else p.uv[f], None if p.colors is None else p.colors[f],
            None if p.normals is None else p.normals.reshape(-1, 3))


def full_vertex(position="float", color="uchar"):
    return [(position, "x", XYZ[:, 0]), (position, "y", XYZ[:, 1]), (position, "z", XYZ[:, 2]),
            ("float", "nx", NORMALS[:, 0]), ("float", "ny", NORMALS[:, 1]), ("float", "nz", NORMALS[:, 2]),
            ("float", "s", UV[:, 0]), ("float", "t", UV[:, 1]),
            (color, "red", RGB8[:, 0]), (color, "green", RGB8[:, 1]), (color, "blue", RGB8[:, 2])]


FORMATS = ["ascii", "binary_little_endian", "binary_big_endian"]


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("position", ["float", "double"])
def test_every_format_gives_the_written_corners_normals_uvs_and_colours(tmp_path, fmt, position):
    write_ply(tmp_path / "m.ply", fmt, full_vertex(position), POLYGONS)
    xyz, uv, rgb, normals = corners(read_mesh_file(tmp_path / "m.ply"))
    np.testing.assert_array_equal(xyz, XYZ[CORNERS])
    np.testing.assert_array_equal(normals, NORMALS[CORNERS])
    np.testing.assert_array_equal(uv, UV[CORNERS])
    np.testing.assert_allclose(rgb, srgb_to_linear(RGB8[CORNERS] / 255.0), rtol=1e-12, atol=0)


def test_negative_control_a_big_endian_file_read_as_little_endian_is_not_the_written_mesh(tmp_path):
    """The comparison above can fail: the same bytes under the other byte order's header are other numbers."""
    write_ply(tmp_path / "m.ply", "binary_big_endian", full_vertex(), POLYGONS)
    data = (tmp_path / "m.ply").read_bytes().replace(b"binary_big_endian", b"binary_little_endian", 1)
    (tmp_path / "m.ply").write_bytes(data)
    try:
        xyz = corners(read_mesh_file(tmp_path / "m.ply"))[0]
    except SceneError:
        return  # refused is also not the written mesh
    assert xyz.shape != XYZ[CORNERS].shape or not np.array_equal(xyz, XYZ[CORNERS])


@pytest.mark.parametrize("names", [("s", "t"), ("u", "v"), ("texture_u", "texture_v"), ("texture_s", "texture_t")])
def test_each_uv_naming_is_read(tmp_path, names):
    vertex = [("float", n, XYZ[:, k]) for k, n in enumerate("xyz")] + [("float", names[0], UV[:, 0]), ("float", names[1], UV[:, 1])]
    write_ply(tmp_path / "m.ply", "binary_little_endian", vertex, POLYGONS)
    np.testing.assert_array_equal(corners(read_mesh_file(tmp_path / "m.ply"))[1], UV[CORNERS])


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("ctype,scale", [("uchar", 255), ("ushort", 65535), ("float", 1.0), ("double", 1.0)])
def test_vertex_colours_of_each_type_are_scaled_by_its_range_and_decoded_from_srgb(tmp_path, fmt, ctype, scale):
    values = RGB8 * 257 if ctype == "ushort" else RGB8 / 255.0 if scale == 1.0 else RGB8
    alpha = np.full(len(XYZ), 0.5 if scale == 1.0 else scale // 2)  # alpha is not read
    vertex = [("float", n, XYZ[:, k]) for k, n in enumerate("xyz")] + [
        (ctype, n, values[:, k]) for k, n in enumerate(("red", "green", "blue"))] + [(ctype, "alpha", alpha)]
    write_ply(tmp_path / "m.ply", fmt, vertex, POLYGONS)
    expected = srgb_to_linear(np.asarray(values, np.float32 if ctype == "float" else np.float64) / scale)
    np.testing.assert_allclose(corners(read_mesh_file(tmp_path / "m.ply"))[2], expected[CORNERS], rtol=1e-12, atol=0)


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_colour_per_face_colours_each_of_its_triangles(tmp_path, fmt):
    face_rgb = np.array([[250, 0, 5], [0, 128, 255]])
    vertex = [("float", n, XYZ[:, k]) for k, n in enumerate("xyz")]
    extra = [("uchar", n, face_rgb[:, k]) for k, n in enumerate(("red", "green", "blue"))]
    write_ply(tmp_path / "m.ply", fmt, vertex, POLYGONS, extra)
    xyz, _, rgb, _ = corners(read_mesh_file(tmp_path / "m.ply"))
    np.testing.assert_array_equal(xyz, XYZ[CORNERS])
    polygon_of_corner = [0] * 6 + [1] * 3
    np.testing.assert_allclose(rgb, srgb_to_linear(face_rgb[polygon_of_corner] / 255.0), rtol=1e-12, atol=0)


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_texcoord_list_per_face_and_the_texture_file_comment(tmp_path, fmt):
    """MeshLab's layout: uvs per face corner (so a vertex may have two), the image named in a comment."""
    face_uv = [[0, 0, 1, 0, 1, 1, 0, 1], [0.25, 0.25, 0.75, 0.25, 0.5, 0.75]]  # vertex 2 and 3: other uvs in face 1
    Image.fromarray(np.full((2, 2, 3), 200, np.uint8)).save(tmp_path / "paint.png")
    vertex = [("float", n, XYZ[:, k]) for k, n in enumerate("xyz")]
    write_ply(tmp_path / "m.ply", fmt, vertex, POLYGONS, [("list float", "texcoord", face_uv)],
              comments=["TextureFile paint.png"])
    mesh = read_mesh_file(tmp_path / "m.ply")
    xyz, uv, _, _ = corners(mesh)
    corner_uv = np.array(face_uv[0]).reshape(4, 2)[[0, 1, 2, 0, 2, 3]].tolist() + \
        np.array(face_uv[1]).reshape(3, 2).tolist()
    np.testing.assert_array_equal(xyz, XYZ[CORNERS])
    np.testing.assert_array_equal(uv, corner_uv)
    assert [name for name, _ in mesh.materials] == ["paint"]
    assert (mesh.parts[0].face_material == 0).all()
    assert mesh.materials[0][1].kd_texture is not None


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("index_name,index_type", [("vertex_indices", "int"), ("vertex_index", "uint"),
                                                   ("vertex_indices", "ushort")])
def test_polygons_of_differing_lengths_are_fanned(tmp_path, fmt, index_name, index_type):
    """Triangles, quads and a hexagon in one face element: in a binary file each row's length is read in turn."""
    hexagon_xyz = np.array([[np.cos(a), np.sin(a), 1.0] for a in np.arange(6) * np.pi / 3]).round(3)
    xyz_all = np.concatenate([XYZ, hexagon_xyz])
    polygons = POLYGONS + [[5, 6, 7, 8, 9, 10], [0, 1, 4]]
    vertex = [("double", n, xyz_all[:, k]) for k, n in enumerate("xyz")]
    write_ply(tmp_path / "m.ply", fmt, vertex, polygons, index_name=index_name, index_type=index_type)
    fan = CORNERS + [5, 6, 7, 5, 7, 8, 5, 8, 9, 5, 9, 10] + [0, 1, 4]
    np.testing.assert_array_equal(corners(read_mesh_file(tmp_path / "m.ply"))[0], xyz_all[fan])


def test_elements_the_mesh_does_not_use_are_passed_over(tmp_path):
    """An edge element between vertex and face, and a material element after, as some exporters write."""
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
              "property float z\nelement edge 2\nproperty int vertex1\nproperty int vertex2\nelement face 1\n"
              "property list uchar int vertex_indices\nelement material 1\nproperty list uchar uchar name\nend_header\n")
    body = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<4i", 0, 1, 1, 2) + struct.pack("<B3i", 3, 0, 1, 2)
    body += struct.pack("<B3B", 3, 97, 98, 99)
    (tmp_path / "m.ply").write_bytes(header.encode() + body)
    np.testing.assert_array_equal(corners(read_mesh_file(tmp_path / "m.ply"))[0], [[0, 0, 0], [1, 0, 0], [0, 1, 0]])


# --- damaged files: one line naming the file and the element or property ----------------------------------

TRIANGLE = ("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n")
TRIANGLE_BODY = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<B3i", 3, 0, 1, 2)
ASCII = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
         "element face 1\nproperty list uchar int vertex_indices\nend_header\n")

BROKEN = [
    ("vertices cut short", TRIANGLE.encode() + TRIANGLE_BODY[:20],
     "element vertex: the file ends before its 3 rows (20 bytes left)"),
    ("face cut short", TRIANGLE.encode() + TRIANGLE_BODY[:-3], "element face: the file ends within row 0 of 1"),
    ("a count the file cannot hold", TRIANGLE.replace("vertex 3", "vertex 2147483648").encode() + TRIANGLE_BODY,
     "element vertex: the file ends before its 2147483648 rows (49 bytes left)"),
    ("an unknown type", TRIANGLE.replace("float y", "flaot y").encode() + TRIANGLE_BODY,
     "element vertex: property y: unknown type 'flaot'; expected one of: char, uchar, short, ushort, int, uint, "
     "float, double, int8, uint8, int16, uint16, int32, uint32, int64, uint64, float16, float32, float64"),
    ("a float list length", TRIANGLE.replace("list uchar int", "list float int").encode() + TRIANGLE_BODY,
     "element face: property vertex_indices: a list's length type must be an integer, got 'float'"),
    ("no end_header", TRIANGLE.replace("end_header\n", "").encode(), "the header has no end_header line"),
    ("no format", TRIANGLE.replace("format binary_little_endian 1.0\n", "").encode() + TRIANGLE_BODY,
     "the header has no format line"),
    ("an unknown format", TRIANGLE.replace("binary_little_endian", "binary_middle_endian").encode() + TRIANGLE_BODY,
     "header line 2: expected 'format ascii 1.0', 'format binary_little_endian 1.0' or 'format binary_big_endian "
     "1.0', got 'format binary_middle_endian 1.0'"),
    ("an element without a count", TRIANGLE.replace("element face 1", "element face").encode() + TRIANGLE_BODY,
     "header line 7: expected 'element <name> <count>', got 'element face'"),
    ("a property before any element", b"ply\nformat ascii 1.0\nproperty float x\nend_header\n",
     "header line 3: a property before any element"),
    ("x as a list", TRIANGLE.replace("property float x", "property list uchar float x").encode() + TRIANGLE_BODY,
     "element vertex: property x: expected one value a row, not a list"),
    ("a face beyond the vertices", TRIANGLE.encode() + TRIANGLE_BODY[:-4] + struct.pack("<i", 3),
     "element face: property vertex_indices: a face refers to a vertex that does not exist (the file has 3)"),
    ("no x, y, z", TRIANGLE.replace(" x\n", " a\n").encode() + TRIANGLE_BODY, "element vertex: has no x, y, z properties"),
    ("ASCII: a word for a number", (ASCII + "0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n").encode(),
     "element vertex: expected a number, got 'zero'"),
    ("ASCII: rows missing", (ASCII + "0 0 0\n1 0 0\n").encode(), "element vertex: the file ends before its 3 rows (6 numbers left)"),
    ("ASCII: a negative list length", (ASCII + "0 0 0\n1 0 0\n0 1 0\n-3 0 1 2\n").encode(),
     "element face: property vertex_indices: row 0 is a list of -3 values"),
    ("ASCII: a list longer than the file", (ASCII + "0 0 0\n1 0 0\n0 1 0\n30 0 1 2\n").encode(),
     "element face: the file ends within row 0 of 1"),
]


@pytest.mark.parametrize("data,message", [b[1:] for b in BROKEN], ids=[b[0] for b in BROKEN])
def test_a_damaged_file_is_one_error_naming_the_file_and_the_element(tmp_path, data, message):
    path = tmp_path / "m.ply"
    path.write_bytes(data)
    with pytest.raises(SceneError) as e:
        read_mesh_file(path)
    assert str(e.value) == f"{path}: {message}"


def test_the_intact_triangles_of_the_damaged_files_are_read(tmp_path):
    """The negative control of the damaged files: unbroken, each base reads as its triangle."""
    for name, data in (("b.ply", TRIANGLE.encode() + TRIANGLE_BODY), ("a.ply", (ASCII + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").encode())):
        (tmp_path / name).write_bytes(data)
        np.testing.assert_array_equal(corners(read_mesh_file(tmp_path / name))[0], [[0, 0, 0], [1, 0, 0], [0, 1, 0]])


# --- what reading costs: no trimesh --------------------------------------------------------------------


def imported(folder: Path, mesh: str) -> set:
    """The top-level packages of trimesh, SciPy and PIL that `warprt render` of a scene holding ``mesh``
    imports (python -X importtime lists every import)."""
    (folder / "s.toml").write_text(f'[[lights]]\nposition = [2.0, 3.0, 4.0]\n\n[[objects]]\nmesh = "{mesh}"\n')
    r = subprocess.run([sys.executable, "-X", "importtime", "-m", "warprt", "render", "s.toml", "-o", "x.png", "-q",
                        "--width", "16", "--height", "12"], cwd=folder, capture_output=True, text=True, env=ENV)
    assert r.returncode == 0 and (folder / "x.png").exists(), r.stderr[-2000:]
    names = {line.rsplit("|", 1)[-1].strip().split(".")[0] for line in r.stderr.splitlines() if line.startswith("import time:")}
    return names & {"trimesh", "scipy", "PIL"}


def test_rendering_ply_and_obj_files_imports_neither_trimesh_nor_scipy(tmp_path):
    write_ply(tmp_path / "m.ply", "binary_little_endian", full_vertex(), POLYGONS)
    (tmp_path / "m.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1\n")
    (tmp_path / "m.stl").write_text("solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                                    "vertex 0 1 0\nendloop\nendfacet\nendsolid t\n")
    assert imported(tmp_path, "m.ply") == set()
    assert imported(tmp_path, "m.obj") == set()
    assert "trimesh" in imported(tmp_path, "m.stl")  # the negative control: STL is trimesh's, and the check sees it
