"""Mesh files in: OBJ (+MTL), PLY, STL, OFF and glTF/GLB through trimesh, USD through pxr.

A file becomes parts (float64 triangles in the file's world space, counter-clockwise from the
front) and the file's own materials mapped to Phong, with a material index per triangle.
"""

from __future__ import annotations

import json
import math
import re
import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..diagnostics import native_stderr, usd_messages, warn
from ..errors import SceneError, show
from .model import Material, SceneObject
from .normals import vertex_normals
from .usdcrate import MAGIC as CRATE_MAGIC, check_crate

TRIMESH_FORMATS = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")
USD_FORMATS = (".usd", ".usda", ".usdc", ".usdz")
FORMATS = TRIMESH_FORMATS + USD_FORMATS


@dataclass
class MeshPart:
    """One object of the file (an OBJ file, a glTF node, a USD Mesh prim)."""

    name: str
    vertices: np.ndarray  # (N, 3) float64, the file's world space
    faces: np.ndarray  # (M, 3) int64, counter-clockwise seen from the front
    face_material: np.ndarray  # (M,) int64 index into MeshFile.materials; -1: none of the file's


@dataclass
class MeshFile:
    path: Path
    parts: list[MeshPart]
    materials: list[tuple[str, Material]] = field(default_factory=list)  # the file's own, by name
    up_axis: str = "Y"  # the file's up direction (USD stages say; the other formats are y-up)

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
    """Read and check a mesh file; every failure is a SceneError naming the file."""
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
    if ext in USD_FORMATS and head.startswith(CRATE_MAGIC):
        check_crate(src, path, size)
    if ext in USD_FORMATS:
        # USD reports on fd 2 in multi-line C++ diagnostics: each becomes one warprt warning.
        native = None
        try:
            with native_stderr() as native:
                mesh = _load_usd(path)
        except Exception as e:
            if not type(e).__module__.startswith("pxr"):
                raise
            # USD read the layer but a value in it is damaged (a corrupt crate value, a bad array).
            raise SceneError(src, None, f"cannot read USD file: {_pxr_message(e)}") from None
        finally:
            for message in usd_messages(native.text if native else ""):
                warn(f"{src}: USD: {message}")
    else:
        mesh = _load_trimesh(path)
    _check(src, mesh)
    return mesh


def load_mesh(path) -> tuple[np.ndarray, np.ndarray]:
    """All triangles of a file as one vertex (N, 3) float64 and face (M, 3) int64 array."""
    vertices, faces, _, _ = read_mesh_file(path).concatenated()
    return vertices, faces


def split_by_material(name: str, vertices, faces, face_material, file_materials, materials: dict,
                      fallback: str, smooth: bool, part_starts=(0,)) -> list[SceneObject]:
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
        return [SceneObject(name, vertices, faces, material, smooth)]
    normals = None
    if smooth:
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
        out.append(SceneObject(material if idx >= 0 else f"{name}/{fallback}", np.ascontiguousarray(vertices[keep]),
                               inverse.reshape(-1, 3).astype(np.int64), material, smooth,
                               None if normals is None else np.ascontiguousarray(normals[keep])))
    return out


def is_mesh_path(path) -> bool:
    """Whether the extension names a mesh format read here."""
    ext = Path(path).suffix.lower()
    return ext in FORMATS or (bool(ext) and _trimesh_reads(ext))


def _trimesh_reads(ext: str) -> bool:
    import trimesh

    return ext[1:] in trimesh.available_formats()


def _sniff(src: str, ext: str, head: bytes, size: int):
    """Reject a file whose first bytes cannot be its format, with a reason trimesh does not give
    (it reads a damaged STL or OBJ as an empty scene)."""
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
        if not np.all(np.isfinite(p.vertices)):
            raise SceneError(src, p.name if len(mesh.parts) > 1 else None, "vertex coordinates contain NaN or Inf")
        if len(p.faces) and (p.faces.min() < 0 or p.faces.max() >= len(p.vertices)):
            raise SceneError(src, p.name if len(mesh.parts) > 1 else None,
                             f"a face refers to a vertex that does not exist (the file has {len(p.vertices)})")


# --- trimesh: OBJ, PLY, STL, OFF, glTF/GLB -------------------------------------------------------


def _load_trimesh(path: Path) -> MeshFile:
    import trimesh

    src, ext = str(path), path.suffix.lower()
    try:
        # process=False keeps the file's vertices as they are: no merging, no removal of faces.
        loaded = trimesh.load(str(path), process=False)
    except IndexError as e:  # trimesh's OBJ reader on a face index past the vertex list
        m = re.search(r"index (-?\d+) is out of bounds for axis 0 with size (\d+)", str(e))
        # OBJ counts vertices from 1: trimesh's index 8 is the file's 'f ... 9'.
        which = f" (vertex {int(m[1]) + 1}; the file has {m[2]})" if m and ext == ".obj" and int(m[1]) >= 0 else ""
        raise SceneError(src, None, f"a face refers to a vertex that does not exist{which}") from None
    except FileNotFoundError as e:
        # trimesh names only the file it looked for: a glTF's buffer or image, or, for a .gltf that
        # is not glTF JSON, the 'model.gltf' it then looks for inside it as if it were an archive.
        if ext == ".gltf":
            _check_gltf_json(path)
        missing = e.filename or (e.args[0] if e.args else "?")
        raise SceneError(src, None, f"cannot read {ext[1:].upper()} file: a file it refers to is missing: "
                                    f"{missing} (looked for in {path.parent})") from None
    except Exception as e:
        if ext == ".gltf":
            _check_gltf_json(path)
        raise SceneError(src, None, f"cannot read {ext[1:].upper()} file: {_one_line(e)}") from None
    if isinstance(loaded, trimesh.Trimesh):
        loaded = trimesh.Scene(loaded)
    if not isinstance(loaded, trimesh.Scene):
        raise SceneError(src, None, "the mesh has no triangles")

    exact = _gltf_base_colors(path) if ext in (".glb", ".gltf") else {}
    materials: list[tuple[str, Material]] = []
    index_of: dict[int, int] = {}  # id(trimesh material) -> index in materials

    def material_index(visual) -> int:
        # Only texture visuals carry a file material; vertex and face colours are not read.
        if not isinstance(visual, trimesh.visual.TextureVisuals) or visual.material is None:
            return -1
        m = visual.material
        if id(m) not in index_of:
            phong = _phong_from_trimesh(src, m, exact)
            if phong is None:
                index_of[id(m)] = -1
            else:
                name = _unique(_name(m) or f"material{len(materials)}", [n for n, _ in materials])
                index_of[id(m)] = len(materials)
                materials.append((name, phong))
        return index_of[id(m)]

    parts = []
    for node in loaded.graph.nodes_geometry:
        transform, geom_name = loaded.graph[node]
        g = loaded.geometry[geom_name]
        if not isinstance(g, trimesh.Trimesh) or len(g.faces) == 0:
            continue
        t = np.asarray(transform, np.float64)
        vertices = np.asarray(g.vertices, np.float64)
        if vertices.ndim != 2 or vertices.shape[1] != 3 or t.shape != (4, 4):
            # trimesh passes on what a damaged file says: 'v 1 2' lines, a glTF accessor of VEC2
            what = f"vertices of {vertices.shape[-1]} coordinates" if t.shape == (4, 4) else f"a {t.shape} node transform"
            raise SceneError(src, None, f"cannot read {ext[1:].upper()} file: {what}; expected 3 (x, y, z)")
        with np.errstate(over="ignore", invalid="ignore"):  # a transform beyond float64 is caught by _check
            vertices = vertices @ t[:3, :3].T + t[:3, 3]
        faces = np.asarray(g.faces, np.int64).reshape(-1, 3)
        if np.linalg.det(t[:3, :3]) < 0:  # a mirroring node transform turns the winding over
            faces = faces[:, ::-1]
        mat = np.full(len(faces), material_index(g.visual), np.int64)
        parts.append(MeshPart(str(node), vertices, np.ascontiguousarray(faces), mat))
    if ext == ".obj" and len(parts) > 1:
        # trimesh splits an OBJ by material; it is one object with a material per face.
        parts = [_merge(path.stem, parts)]
    return MeshFile(path, parts, materials)


def _check_gltf_json(path: Path):
    """A .gltf is JSON text: say so when it is not, rather than what trimesh then looked for."""
    try:
        json.loads(path.read_bytes())
    except UnicodeDecodeError as e:
        raise SceneError(str(path), None, f"not a glTF file (not UTF-8 JSON text: byte 0x{e.object[e.start]:02x} "
                                          f"at offset {e.start})") from None
    except json.JSONDecodeError as e:
        raise SceneError(str(path), None, f"not a glTF file (not JSON: {e.msg} at line {e.lineno}, "
                                          f"column {e.colno})") from None
    except RecursionError:
        raise SceneError(str(path), None, "not a glTF file (JSON nested too deeply to read)") from None


def _merge(name: str, parts: list[MeshPart]) -> MeshPart:
    offsets = np.cumsum([0] + [len(p.vertices) for p in parts])
    return MeshPart(name, np.concatenate([p.vertices for p in parts]),
                    np.concatenate([p.faces + o for p, o in zip(parts, offsets)]),
                    np.concatenate([p.face_material for p in parts]))


def _name(m) -> str | None:
    """A trimesh material's name, if the file gave it one that is a string (a damaged glTF may not)."""
    name = getattr(m, "name", None)
    return name if isinstance(name, str) else None


def _phong_from_trimesh(src: str, m, exact: dict) -> Material | None:
    """A glTF material or an MTL one; None for trimesh's stand-in when the file has none."""
    from trimesh.visual.material import PBRMaterial

    if isinstance(m, PBRMaterial):
        # glTF: the base colour is the diffuse colour; metallic-roughness has no Phong term here.
        rgba = m.baseColorFactor
        key = (_name(m), None if rgba is None else tuple(int(x) for x in rgba))
        if key in exact:
            kd = exact[key]
        elif rgba is None:
            kd = (1.0, 1.0, 1.0)  # the glTF default
        else:
            kd = tuple(float(x) / 255.0 for x in np.asarray(rgba)[:3])
        return Material(kd=kd, ka=kd, ks=(0.0, 0.0, 0.0))
    # trimesh keeps an MTL's statements as they were written in the material's kwargs
    # (its own diffuse/ambient/specular are 8-bit copies).
    raw = getattr(m, "kwargs", None) or {}
    if any(k in raw for k in ("ka", "kd", "ks", "ns", "illum")):
        return _phong_from_mtl(src, _name(m) or "?", raw)
    return None


def _phong_from_mtl(src: str, name: str, raw: dict) -> Material:
    """MTL statements to Phong: Ka, Kd, Ks, Ns as they are; illum 0 and 1 have no highlight and
    illum 3 adds a mirror reflection weighted by Ks (the MTL specification's illumination models)."""

    def rgb(key, default):
        v = raw.get(key)
        if v is None:
            return default
        try:
            v = [float(x) for x in np.atleast_1d(v)]
        except (TypeError, ValueError):
            v = None
        if v is not None and len(v) == 1:
            v = v * 3  # 'Kd r' means r = g = b
        if v is None or len(v) != 3 or not all(math.isfinite(x) and x >= 0 for x in v):
            raise SceneError(src, f"newmtl {name}: {key.capitalize()}",
                             f"expected 3 non-negative numbers, got {show(raw.get(key))}")
        return tuple(v)

    kd = rgb("kd", (0.8, 0.8, 0.8))  # 0.8: what common MTL readers assume without a Kd
    ka = rgb("ka", kd)
    ks = rgb("ks", (0.0, 0.0, 0.0))
    ns = raw.get("ns", 32.0)
    try:
        ns = float(np.atleast_1d(ns)[0])
    except (TypeError, ValueError, IndexError):
        ns = float("nan")
    if not (math.isfinite(ns) and ns >= 0):
        raise SceneError(src, f"newmtl {name}: Ns", f"expected a number >= 0, got {show(raw.get('ns'))}")
    illum = raw.get("illum")
    try:
        illum = int(float(np.atleast_1d(illum)[0])) if illum is not None else 2
    except (TypeError, ValueError, IndexError, OverflowError):
        raise SceneError(src, f"newmtl {name}: illum", f"expected an integer, got {show(illum)}") from None
    kr = ks if illum == 3 else (0.0, 0.0, 0.0)
    if illum in (0, 1):
        ks = (0.0, 0.0, 0.0)
    return Material(kd=kd, ka=ka, ks=ks, shininess=ns, reflectivity=kr)


def _gltf_base_colors(path: Path) -> dict:
    """Exact base colours from the glTF JSON, keyed the way trimesh shows the material (name,
    8-bit RGBA): trimesh keeps them only as 8-bit values. Ambiguous keys are left out."""
    try:
        data = path.read_bytes()
        if data[:4] == b"glTF":
            length = struct.unpack("<I", data[12:16])[0]
            header = json.loads(data[20:20 + length])
        else:
            header = json.loads(data)
    except Exception:
        return {}
    out, seen = {}, set()
    for m in header.get("materials", []) if isinstance(header, dict) else []:
        pbr = m.get("pbrMetallicRoughness", {}) if isinstance(m, dict) else {}
        rgba = pbr.get("baseColorFactor")
        if not (isinstance(rgba, list) and len(rgba) == 4):
            continue
        try:
            if not isinstance(m.get("name"), (str, type(None))):
                continue  # trimesh would not have kept such a name either
            key = (m.get("name"), tuple(int(x) for x in np.round(np.clip(np.asarray(rgba, np.float64), 0, 1) * 255)))
        except (TypeError, ValueError):
            continue
        if key in seen:
            out.pop(key, None)
        else:
            seen.add(key)
            out[key] = tuple(float(x) for x in rgba[:3])
    return out


# --- USD through pxr --------------------------------------------------------------------------------


def _load_usd(path: Path) -> MeshFile:
    src = str(path)
    try:
        from pxr import Usd, UsdGeom, UsdShade
    except ImportError:
        raise SceneError(src, None, "reading USD needs the usd-core package (pip install usd-core)") from None
    try:
        stage = Usd.Stage.Open(src)
    except Exception as e:
        raise SceneError(src, None, f"cannot open USD stage: {_pxr_message(e)}") from None
    if stage is None:
        raise SceneError(src, None, "cannot open USD stage")
    # The earliest time sample: a stage animated from frame 1 has no value at the default time.
    time = Usd.TimeCode.EarliestTime()
    xforms = UsdGeom.XformCache(time)
    materials: list[tuple[str, Material]] = []
    index_of: dict[str, int] = {}

    def material_index(key: str, name: str, make) -> int:
        if key not in index_of:
            index_of[key] = len(materials)
            materials.append((_unique(name, [n for n, _ in materials]), make()))
        return index_of[key]

    def bound(prim) -> int:
        mat, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
        if not mat:
            return -1
        return material_index(str(mat.GetPath()), mat.GetPrim().GetName(), lambda: _phong_from_usd(mat))

    parts = []
    for prim in stage.Traverse(Usd.TraverseInstanceProxies()):
        if not prim.IsA(UsdGeom.Mesh):
            continue
        image = UsdGeom.Imageable(prim)
        if image.ComputeVisibility(time) == UsdGeom.Tokens.invisible:
            continue
        if image.ComputePurpose() in (UsdGeom.Tokens.guide, UsdGeom.Tokens.proxy):
            continue
        mesh = UsdGeom.Mesh(prim)
        where = str(prim.GetPath())
        points = mesh.GetPointsAttr().Get(time)
        counts = mesh.GetFaceVertexCountsAttr().Get(time)
        indices = mesh.GetFaceVertexIndicesAttr().Get(time)
        if points is None or counts is None or indices is None or len(counts) == 0:
            continue
        points = np.asarray(points, np.float64).reshape(-1, 3)
        counts = np.asarray(counts, np.int64)
        indices = np.asarray(indices, np.int64)
        if counts.sum() != len(indices) or (counts < 0).any():
            raise SceneError(src, where, f"faceVertexCounts add up to {counts.sum()} but there are "
                                         f"{len(indices)} faceVertexIndices")
        if len(indices) and (indices.min() < 0 or indices.max() >= len(points)):
            raise SceneError(src, where, f"a face refers to a vertex that does not exist (the prim has {len(points)})")
        holes = np.asarray(mesh.GetHoleIndicesAttr().Get(time) or [], np.int64)
        faces, polygon = fan_triangulate(counts, indices, holes)
        # Gf matrices act on row vectors: p_world = p @ M.
        m = np.asarray(xforms.GetLocalToWorldTransform(prim), np.float64)
        vertices = points @ m[:3, :3] + m[3, :3]
        left = mesh.GetOrientationAttr().Get(time) == UsdGeom.Tokens.leftHanded
        if left != (np.linalg.det(m[:3, :3]) < 0):  # clockwise front faces, or mirrored by the transform
            faces = faces[:, ::-1]
        per_polygon = np.full(len(counts), bound(prim), np.int64)
        if per_polygon[0] < 0:
            color = _display_color(mesh, time)
            if color is not None:
                kd = color
                per_polygon[:] = material_index(where + ".displayColor", f"{prim.GetName()}.displayColor",
                                                lambda: Material(kd=kd, ka=kd, ks=(0.0, 0.0, 0.0)))
        for subset in UsdShade.MaterialBindingAPI(prim).GetMaterialBindSubsets():
            k = bound(subset.GetPrim())
            ids = np.asarray(subset.GetIndicesAttr().Get(time) or [], np.int64)
            if k >= 0 and len(ids):
                per_polygon[ids[(ids >= 0) & (ids < len(counts))]] = k
        parts.append(MeshPart(where, vertices, np.ascontiguousarray(faces), per_polygon[polygon]))
    up = UsdGeom.GetStageUpAxis(stage)
    return MeshFile(path, parts, materials, up_axis=str(up) if up else "Y")


def fan_triangulate(counts: np.ndarray, indices: np.ndarray, holes=()) -> tuple[np.ndarray, np.ndarray]:
    """Polygons to triangles (v0, vk, vk+1), as Hydra does; polygons with fewer than 3 vertices
    and hole faces are dropped. Returns the triangles and, for each, its polygon's index."""
    counts = np.asarray(counts, np.int64)
    starts = np.cumsum(counts) - counts
    n_tri = np.maximum(counts - 2, 0)
    if len(holes):
        n_tri[np.asarray(holes, np.int64)[(np.asarray(holes) >= 0) & (np.asarray(holes) < len(counts))]] = 0
    polygon = np.repeat(np.arange(len(counts)), n_tri)
    k = np.arange(len(polygon)) - np.repeat(np.cumsum(n_tri) - n_tri, n_tri) + 1
    first = starts[polygon]
    faces = np.stack([indices[first], indices[first + k], indices[first + k + 1]], 1)
    return faces.astype(np.int64).reshape(-1, 3), polygon


def _phong_from_usd(mat) -> Material:
    """UsdPreviewSurface's diffuseColor is the diffuse colour (0.18 grey when not authored)."""
    kd = (0.18, 0.18, 0.18)
    shader = mat.ComputeSurfaceSource()[0]
    if shader and shader.GetIdAttr().Get() == "UsdPreviewSurface":
        inp = shader.GetInput("diffuseColor")
        value = inp.Get() if inp else None
        if value is not None:
            kd = tuple(max(0.0, float(x)) for x in value)
    return Material(kd=kd, ka=kd, ks=(0.0, 0.0, 0.0))


def _display_color(mesh, time):
    pv = mesh.GetDisplayColorPrimvar()
    if not pv or not pv.HasValue() or pv.GetInterpolation() != "constant":
        return None
    value = pv.Get(time)
    if value is None or len(value) == 0:
        return None
    return tuple(max(0.0, float(x)) for x in value[0])


def _pxr_message(e: Exception) -> str:
    """The first quoted reason in a pxr error, without its C++ namespaces."""
    try:
        text = str(e)
    except UnicodeDecodeError:  # USD's message quotes the file's own bytes, and they are not UTF-8
        text = "\n".join(_commentary(a) for a in e.args)
    found = re.findall(r": '(.*?)'\s*(?:\n|$)", text, flags=re.S)
    msg = found[0] if found else text
    msg = re.sub(r"pxrInternal_[A-Za-z0-9_]*::", "", msg)
    return " ".join(msg.split())


def _commentary(error) -> str:
    try:
        return f": '{error.commentary}'"
    except (UnicodeDecodeError, AttributeError):
        return ": 'the file holds bytes that are not UTF-8 text where USD expects text'"


def _one_line(e: Exception) -> str:
    return " ".join(str(e).split()) or type(e).__name__


def _unique(name: str, taken: list[str]) -> str:
    out, k = name, 2
    while out in taken:
        out, k = f"{name}#{k}", k + 1
    return out
