"""PLY: trimesh parses the file (ASCII or binary, any property layout), and the mesh is built from
its raw elements rather than from trimesh's Trimesh, which turns colours into 8-bit visuals and
reorders triangulated polygons.

What is read: vertex x y z, nx ny nz, uv (s t, u v, texture_u texture_v, texture_s texture_t, or
a per-face texcoord list), colours (red green blue, per vertex or per face; 8-bit, 16-bit or float,
sRGB-encoded as Blender reads them), face vertex_indices polygons (fanned), and a MeshLab
'comment TextureFile' as the texture its uvs refer to.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ...diagnostics import warn
from ...errors import SceneError, one_line
from ..model import Material
from ..texture import image_texture, srgb_to_linear
from . import MeshFile, MeshPart, dedupe, fan_corners, weld_corners

_UV_NAMES = [("s", "t"), ("u", "v"), ("texture_u", "texture_v"), ("texture_s", "texture_t")]
_COLOR_NAMES = [("red", "green", "blue"), ("diffuse_red", "diffuse_green", "diffuse_blue"), ("r", "g", "b")]


def read_ply(path: Path) -> MeshFile:
    import trimesh

    src = str(path)
    try:
        loaded = trimesh.load(src, process=False)
    except Exception as e:
        raise SceneError(src, None, f"cannot read PLY file: {one_line(e, type(e).__name__)}") from None
    raw = getattr(loaded, "metadata", {}).get("_ply_raw")
    if raw is None or "vertex" not in raw:
        raise SceneError(src, None, "the mesh has no triangles")
    vc = _columns(raw["vertex"])
    if not all(k in vc for k in "xyz"):
        raise SceneError(src, None, "the vertex element has no x, y, z properties")
    v = np.column_stack([np.asarray(vc[k], np.float64) for k in "xyz"])
    fc = _columns(raw["face"]) if "face" in raw and raw["face"]["length"] else {}
    key = next((k for k in ("vertex_indices", "vertex_index") if k in fc), None)
    if key is None:
        return MeshFile(path, [MeshPart(path.stem, v, np.zeros((0, 3), np.int64), np.zeros(0, np.int64))])
    counts, flat = _lists(fc[key], np.int64)
    corner, polygon = fan_corners(counts)
    position = flat[corner]
    keys, uv, colors = [position], None, None
    for a, b in _UV_NAMES:
        if a in vc and b in vc:
            uv = np.column_stack([_unit(vc[a]), _unit(vc[b])])
            keys.append(position)
            break
    if uv is None and "texcoord" in fc:  # MeshLab: a list of 2 floats per corner on each face
        tc_counts, tc = _lists(fc["texcoord"], np.float64)
        if np.array_equal(tc_counts, 2 * counts):
            uv, uv_key = dedupe(tc.reshape(-1, 2), corner)
            keys.append(uv_key)
        else:
            warn(src, "texcoord", "the per-face texture coordinates do not match the faces' corners; not read")
    for names in _COLOR_NAMES:
        if all(n in vc for n in names):
            colors = np.column_stack([_unit(vc[n]) for n in names])
            keys.append(position)
            break
        if all(n in fc for n in names):  # a colour per face
            colors, color_key = dedupe(np.column_stack([_unit(fc[n]) for n in names]),
                                       np.repeat(polygon[:, None], 3, 1))
            keys.append(color_key)
            break
    normals = None
    if all(n in vc for n in ("nx", "ny", "nz")):
        normals = np.column_stack([np.asarray(vc[n], np.float64) for n in ("nx", "ny", "nz")])
    faces, rows = weld_corners(keys, len(v))
    rows = iter(rows)
    part = MeshPart(path.stem, v[next(rows)], faces, np.full(len(faces), -1, np.int64))
    if uv is not None:
        part.uv = uv[next(rows)]
    if colors is not None:
        part.colors = srgb_to_linear(np.clip(colors[next(rows)], 0.0, None))
    if normals is not None:
        part.normals = normals[position]
    materials = []
    texture = _texture_file(path)
    if texture is not None and part.uv is None:
        warn(src, "comment TextureFile", "the mesh has no texture coordinates; the texture is not used")
    elif texture is not None:
        part.face_material[:] = 0
        materials.append((Path(texture.source).stem, Material(kd=(1.0, 1.0, 1.0), kd_texture=texture)))
    return MeshFile(path, [part], materials)


def _columns(element) -> dict:
    """{property: values} for an element read as a dict (ASCII) or a structured array (binary)."""
    data = element["data"]
    if isinstance(data, dict):
        return data
    out = {}
    for name in data.dtype.names:
        column = data[name]
        if column.dtype.names:  # a list property of fixed length: (count, values)
            column = column[column.dtype.names[-1]]
        out[name] = column
    return out


def _lists(column, dtype) -> tuple[np.ndarray, np.ndarray]:
    """A list property as per-row counts and the values of all rows one after another."""
    column = np.asarray(column) if not isinstance(column, np.ndarray) else column
    if column.dtype == object:
        rows = [np.asarray(r, dtype).reshape(-1) for r in column]
        counts = np.array([len(r) for r in rows], np.int64)
        return counts, (np.concatenate(rows) if rows else np.zeros(0, dtype))
    column = np.asarray(column, dtype).reshape(len(column), -1)
    return np.full(len(column), column.shape[1], np.int64), column.reshape(-1)


def _unit(column) -> np.ndarray:
    """Integer colours and texture coordinates scaled to [0, 1] by their type's range."""
    column = np.asarray(column)
    if column.dtype.kind in "ui":
        return column.astype(np.float64) / np.iinfo(column.dtype).max
    return column.astype(np.float64)


def _texture_file(path: Path):
    head = path.read_bytes()[:65536].split(b"end_header", 1)[0].decode("latin-1")
    m = re.search(r"^comment\s+TextureFile\s+(.+?)\s*$", head, re.M | re.I)
    if not m:
        return None
    try:
        return image_texture(path.parent / m.group(1))
    except SceneError as e:
        warn(str(path), "comment TextureFile", f"{e}; the mesh is untextured")
        return None
