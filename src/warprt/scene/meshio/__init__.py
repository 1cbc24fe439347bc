"""Mesh files in, one reader a format: obj.py (OBJ + MTL), ply.py, gltf.py (glTF/GLB), usd.py (pxr), and
others.py (STL, OFF and the rest trimesh reads). A file becomes parts, float64 triangles in the file's
world space with what each vertex carries (uv, colour; normals per corner), and its materials.

Attributes are per vertex with one face index array: where a file indexes its uvs or colours apart
from its positions (OBJ v/vt, USD faceVarying primvars), a reader splits the vertex (weld_corners).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...diagnostics import warn
from ...errors import SceneError
from ..model import Material, SceneObject
from ..normals import face_normals_and_angles, vertex_normals, weld_corner_normals
from ..placement import Placement, place_triangles

OWN_READERS = (".obj", ".ply", ".glb", ".gltf")
TRIMESH_FORMATS = (".stl", ".off")
USD_FORMATS = (".usd", ".usda", ".usdc", ".usdz")
FORMATS = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf") + USD_FORMATS

# Warp's float32 ray test misses triangles under about 3e-13 across (README, Numerical robustness).
TINY_EXTENT = 1e-11


@dataclass
class MeshPart:
    """One object of the file (an OBJ file, a glTF node's primitive, a USD Mesh prim)."""

    name: str
    vertices: np.ndarray  # (N, 3) float64, the file's world space
    faces: np.ndarray  # (M, 3) int64, counter-clockwise seen from the front
    face_material: np.ndarray  # (M,) int64 index into MeshFile.materials; -1: none of the file's
    uv: np.ndarray | None = None  # (N, 2), v = 0 at an image's bottom row
    colors: np.ndarray | None = None  # (N, 3) linear RGB
    normals: np.ndarray | None = None  # (M, 3, 3) the file's own normals at each triangle corner
    smoothing_group: np.ndarray | None = None  # (M,) OBJ 's' of each triangle, 0 = off


@dataclass
class MeshFile:
    path: Path
    parts: list[MeshPart]
    materials: list[tuple[str, Material]] = field(default_factory=list)  # the file's own, by name
    up_axis: str | None = None  # the up direction the file declares ("Y", "Z"), None where it says nothing
    cameras: list = field(default_factory=list)  # camera.FileCamera, in the file's world space, as placed
    lights: list = field(default_factory=list)  # model.Light, in the file's world space

    @property
    def triangle_count(self) -> int:
        return int(sum(len(p.faces) for p in self.parts))

    def concatenated(self):
        """All parts as one vertex, face and face-material array, and where each part's vertices start."""
        starts = np.cumsum([0] + [len(p.vertices) for p in self.parts])
        vertices = np.concatenate([p.vertices for p in self.parts])
        faces = np.concatenate([p.faces + s for p, s in zip(self.parts, starts)])
        face_material = np.concatenate([p.face_material for p in self.parts])
        return vertices, faces, face_material, starts[:-1]


def read_mesh_file(path) -> MeshFile:
    """Read and check a mesh file; every failure is a SceneError naming the file, every feature it has
    that is not read a warning."""
    path = Path(path)
    src = str(path)
    ext = path.suffix.lower()
    if ext not in FORMATS and not _trimesh_reads(ext):
        raise SceneError(src, None, f"unknown mesh format '{ext or '(none)'}'; expected one of: {', '.join(FORMATS)}")
    if path.is_dir():
        raise SceneError(src, None, "is a folder, not a mesh file")
    try:
        size = path.stat().st_size
        with open(path, "rb") as f:
            head = f.read(512)
    except FileNotFoundError:
        raise SceneError(src, None, "mesh file not found") from None
    except OSError as e:
        raise SceneError(src, None, f"cannot read mesh file: {e.strerror or e}") from None
    if size == 0:
        raise SceneError(src, None, "the file is empty")
    _sniff(src, ext, head, size)
    # Overflow and invalid-value warnings of NumPy on damaged files are not for the user's terminal:
    # the checks below report what matters as one line.
    with np.errstate(all="ignore"):
        if ext == ".obj":
            from .obj import read_obj as reader
        elif ext == ".ply":
            from .ply import read_ply as reader
        elif ext in (".glb", ".gltf"):
            from .gltf import read_gltf as reader
        elif ext in USD_FORMATS:
            from .usd import read_usd as reader
        else:
            from .others import read_with_trimesh as reader
        mesh = reader(path)
    _check(src, mesh)
    return mesh


def load_mesh(path) -> tuple[np.ndarray, np.ndarray]:
    """All triangles of a file as one vertex (N, 3) float64 and face (M, 3) int64 array."""
    vertices, faces, _, _ = read_mesh_file(path).concatenated()
    return vertices, faces


def is_mesh_path(path) -> bool:
    """Whether the extension names a mesh format read here."""
    ext = Path(path).suffix.lower()
    return ext in FORMATS or (bool(ext) and _trimesh_reads(ext))


def _trimesh_reads(ext: str) -> bool:
    import trimesh

    return ext[1:] in trimesh.available_formats()


def _sniff(src: str, ext: str, head: bytes, size: int):
    """Reject a file whose first bytes cannot be its format, with a reason a parser does not give
    (trimesh reads a damaged STL as an empty scene)."""
    if ext == ".ply" and not head.startswith(b"ply"):
        raise SceneError(src, None, "not a PLY file (it does not start with 'ply')")
    if ext == ".glb" and not head.startswith(b"glTF"):
        raise SceneError(src, None, "not a GLB file (it does not start with 'glTF')")
    if ext == ".stl" and not head.lstrip().startswith(b"solid"):
        n = struct.unpack("<I", head[80:84])[0] if len(head) >= 84 else -1
        if size != 84 + 50 * n:
            raise SceneError(src, None, f"not an STL file (binary STL of {size} bytes, expected 84 + 50 * triangles)")
    if ext == ".usda" and not head.startswith(b"#usda"):
        raise SceneError(src, None, "not a USDA file (it does not start with '#usda')")


def _check(src: str, mesh: MeshFile):
    if mesh.triangle_count == 0:
        raise SceneError(src, None, "the mesh has no triangles")
    for p in mesh.parts:
        where = p.name if len(mesh.parts) > 1 else None
        if not np.all(np.isfinite(p.vertices)):
            raise SceneError(src, where, "vertex coordinates contain NaN or Inf")
        if len(p.faces) and (p.faces.min() < 0 or p.faces.max() >= len(p.vertices)):
            raise SceneError(src, where, f"a face refers to a vertex that does not exist (the file has {len(p.vertices)})")
        for name, a, width in (("texture coordinates", p.uv, 2), ("vertex colours", p.colors, 3)):
            if a is not None and (a.shape != (len(p.vertices), width) or not np.all(np.isfinite(a))):
                raise SceneError(src, where, f"{name} contain NaN or Inf")
        if p.colors is not None and (p.colors < 0).any():
            raise SceneError(src, where, "vertex colours must not be negative")
        if p.normals is not None and not np.all(np.isfinite(p.normals)):
            warn(src, where, "normals contain NaN or Inf; normals are computed instead")
            p.normals = None


# --- what every reader shares ------------------------------------------------------------------------


def weld_corners(keys: list[np.ndarray], n_positions: int) -> tuple[np.ndarray, list[np.ndarray]]:
    """One vertex per distinct tuple of attribute indices at the triangle corners. ``keys``: per
    attribute an (M, 3) index array, the first into the ``n_positions`` positions. Returns the faces
    and, per new vertex, its index into each attribute. Where every attribute follows the positions,
    the file's vertices are kept as they are (what a reader without attributes gives)."""
    first = np.asarray(keys[0], np.int64)
    if all(k is first or np.array_equal(k, first) for k in keys[1:]):
        return first, [np.arange(n_positions)] * len(keys)
    stack = np.ascontiguousarray(np.stack([np.asarray(k, np.int64).reshape(-1) for k in keys], 1))
    as_bytes = stack.view(np.dtype((np.void, stack.dtype.itemsize * stack.shape[1]))).ravel()
    _, first_at, inverse = np.unique(as_bytes, return_index=True, return_inverse=True)
    rows = stack[first_at]
    return inverse.reshape(-1, 3).astype(np.int64), [rows[:, j] for j in range(stack.shape[1])]


def dedupe(values: np.ndarray, index: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge equal rows of an attribute and re-point ``index`` at them: face-varying data gives every
    corner its own row, which would otherwise make every corner its own vertex."""
    values = np.ascontiguousarray(values, np.float64) + 0.0  # -0.0 == 0.0
    keys = values.view(np.dtype((np.void, values.itemsize * values.shape[1]))).ravel()
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    return values[first], inverse.reshape(-1)[index]


def fan_corners(counts, holes=()) -> tuple[np.ndarray, np.ndarray]:
    """Polygons of ``counts`` corners to triangles (v0, vk, vk+1), as Hydra does; polygons under 3
    corners and hole faces are dropped. Returns, per triangle corner, its position in the flat corner
    list (the face-varying index), and each triangle's polygon."""
    counts = np.asarray(counts, np.int64)
    starts = np.cumsum(counts) - counts
    n_tri = np.maximum(counts - 2, 0)
    holes = np.asarray(holes, np.int64)
    if len(holes):
        n_tri[holes[(holes >= 0) & (holes < len(counts))]] = 0
    polygon = np.repeat(np.arange(len(counts)), n_tri)
    k = np.arange(len(polygon)) - np.repeat(np.cumsum(n_tri) - n_tri, n_tri) + 1
    first = starts[polygon]
    return np.stack([first, first + k, first + k + 1], 1).reshape(-1, 3), polygon


def fan_triangulate(counts: np.ndarray, indices: np.ndarray, holes=()) -> tuple[np.ndarray, np.ndarray]:
    """Polygons (corner counts and the flat vertex indices) to triangles and each one's polygon."""
    corner, polygon = fan_corners(counts, holes)
    return np.asarray(indices, np.int64)[corner].reshape(-1, 3), polygon


def unit_rows(a: np.ndarray) -> np.ndarray:
    length = np.linalg.norm(a, axis=-1, keepdims=True)
    return np.divide(a, length, out=np.zeros_like(a), where=length > 0)


def unique_name(name: str, taken) -> str:
    out, k = name, 2
    while out in taken:
        out, k = f"{name}#{k}", k + 1
    return out


# --- a file's parts as scene objects ------------------------------------------------------------------


def file_objects(name: str, mesh: MeshFile, materials: dict, fallback: str, smooth, placement: Placement | None = None,
                 use_file_materials: bool = True, auto_crease: float | None = None) -> list[SceneObject]:
    """The file placed in the scene by ``placement`` (None: as the file places it) as SceneObjects: one per
    material the file gives its faces (its materials join ``materials`` as "<name>/<material>"; faces
    without one, or all of them when use_file_materials is False, get ``fallback``), shaded as ``smooth``
    says (normals.resolve_normals), with the file's uvs and vertex colours."""
    kw = {} if auto_crease is None else {"auto_crease": auto_crease}
    placed = []
    for p in mesh.parts:
        vertices, shading = place_triangles(p.vertices, p.faces, smooth, placement, p.normals, p.smoothing_group, **kw)
        placed.append([shading.take(vertices), shading.faces, p.face_material, shading.take(p.uv), shading.take(p.colors),
                       shading.normals, shading.smooth])
    any_smooth = any(q[6] for q in placed)
    given = any(q[5] is not None for q in placed)
    for q in placed:
        if given and q[5] is None:
            if q[6]:  # smoothed over its triangles, as its neighbours are by their own normals
                q[5] = vertex_normals(q[0], q[1])
            else:  # flat among smooth parts: every face its own normal at its corners
                fn, _ = face_normals_and_angles(q[0], q[1])
                keep, q[1], q[5] = weld_corner_normals(q[1], np.repeat(fn[:, None, :], 3, 1))
                q[0], q[3], q[4] = (a if a is None else a[keep] for a in (q[0], q[3], q[4]))
    starts = np.cumsum([0] + [len(q[0]) for q in placed])
    vertices = np.concatenate([q[0] for q in placed])
    faces = np.concatenate([q[1] + s for q, s in zip(placed, starts)])
    face_material = np.concatenate([q[2] for q in placed])
    uv = _joined([q[3] for q in placed], [len(q[0]) for q in placed], 0.0)
    colors = _joined([q[4] for q in placed], [len(q[0]) for q in placed], 1.0)
    normals = np.concatenate([q[5] for q in placed]) if given else None
    if not use_file_materials:
        face_material = np.full(len(faces), -1, np.int64)
    return split_by_material(name, vertices, faces, face_material, mesh.materials if use_file_materials else [],
                             materials, fallback, any_smooth, starts[:-1], normals, uv, colors)


def _joined(arrays, lengths, fill):
    """Per-part attributes as one array; parts without one get ``fill`` (uv 0, colour white)."""
    if all(a is None for a in arrays):
        return None
    width = next(a.shape[1] for a in arrays if a is not None)
    return np.concatenate([a if a is not None else np.full((n, width), fill) for a, n in zip(arrays, lengths)])


def split_by_material(name: str, vertices, faces, face_material, file_materials, materials: dict,
                      fallback: str, smooth: bool, part_starts=(0,), normals=None, uv=None,
                      colors=None) -> list[SceneObject]:
    """One SceneObject per material a file gives its faces (face_material indexes file_materials,
    -1: ``fallback``). The file's materials join ``materials`` as "<name>/<material>". Smooth
    normals are computed per part of the file before the split, so the split leaves no crease."""
    keys = []
    for mname, m in file_materials:
        key, k = f"{name}/{mname}", 2
        while key in materials and materials[key] != m:
            key, k = f"{name}/{mname}#{k}", k + 1
        materials[key] = m
        keys.append(key)
    used = np.unique(face_material)
    if len(used) == 1:
        material = fallback if used[0] < 0 else keys[used[0]]
        return [SceneObject(name, vertices, faces, material, smooth, normals, uv, colors)]
    if smooth and normals is None:
        edges = list(part_starts) + [len(vertices)]
        normals = np.zeros_like(vertices)
        for a, b in zip(edges[:-1], edges[1:]):
            sel = (faces[:, 0] >= a) & (faces[:, 0] < b)
            if sel.any():
                normals[a:b] = vertex_normals(vertices[a:b], faces[sel] - a)
    out = []
    for idx in used:
        sel = face_material == idx
        keep, inverse = np.unique(faces[sel], return_inverse=True)
        material = fallback if idx < 0 else keys[idx]
        take = (lambda a: None if a is None else np.ascontiguousarray(a[keep]))
        out.append(SceneObject(material if idx >= 0 else f"{name}/{fallback}", np.ascontiguousarray(vertices[keep]),
                               inverse.reshape(-1, 3).astype(np.int64), material, smooth,
                               take(normals) if smooth else None, take(uv), take(colors)))
    return out


def warn_if_tiny(source: str, field: str | None, vertices: np.ndarray):
    """A mesh so small that float32 ray tests miss its triangles renders as nothing: say so."""
    extent = float(np.max(vertices.max(0) - vertices.min(0))) if len(vertices) else 0.0
    if 0.0 < extent < TINY_EXTENT:
        warn(source, field, f"the mesh is only {extent:.3g} across; float32 ray tests miss triangles under about "
                            "3e-13, so it may not show (scale it up)")


def warn_if_unmapped(source: str, field: str | None, objects, materials: dict, hint: str = ""):
    """A textured material on an object without texture coordinates shows one texel: say so."""
    for o in objects:
        if materials[o.material].textures and o.uv is None:
            warn(source, field, f"material '{o.material}' has a texture but '{o.name}' has no texture coordinates; "
                                f"it is sampled at uv (0, 0){hint}")
