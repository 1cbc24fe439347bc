"""PLY read in NumPy (ASCII, binary little and big endian), without trimesh, whose import costs more than
a cold render: the header, then each element as columns, and the mesh built from them.

What is read: vertex x y z, nx ny nz, uv (s t, u v, texture_u texture_v, texture_s texture_t, or
a per-face texcoord list), colours (red green blue, per vertex or per face; 8-bit, 16-bit or float,
sRGB-encoded as Blender reads them), face vertex_indices polygons (fanned), and a MeshLab
'comment TextureFile' as the texture its uvs refer to.
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...diagnostics import warn
from ...errors import SceneError, one_line, show
from ..model import Material
from ..texture import image_texture, srgb_to_linear
from . import MeshFile, MeshPart, dedupe, fan_corners, weld_corners

_UV_NAMES = [("s", "t"), ("u", "v"), ("texture_u", "texture_v"), ("texture_s", "texture_t")]
_COLOR_NAMES = [("red", "green", "blue"), ("diffuse_red", "diffuse_green", "diffuse_blue"), ("r", "g", "b")]

# The PLY specification's type names and the sized ones other writers use.
_TYPES = {"char": "i1", "uchar": "u1", "short": "i2", "ushort": "u2", "int": "i4", "uint": "u4", "float": "f4",
          "double": "f8", "int8": "i1", "uint8": "u1", "int16": "i2", "uint16": "u2", "int32": "i4", "uint32": "u4",
          "int64": "i8", "uint64": "u8", "float16": "f2", "float32": "f4", "float64": "f8"}
_FORMATS = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}


@dataclass
class _Property:
    name: str
    dtype: np.dtype  # the values' type (a list's items)
    count: np.dtype | None = None  # a list's length type; None: one value


@dataclass
class _Element:
    name: str
    length: int
    properties: list[_Property] = field(default_factory=list)

    @property
    def where(self) -> str:
        return f"element {self.name}"


class _List:
    """A list property's rows: their lengths and all their values one after another."""

    def __init__(self, counts: np.ndarray, values: np.ndarray):
        self.counts, self.values = counts, values


def read_ply(path: Path) -> MeshFile:
    src = str(path)
    data = path.read_bytes()
    fmt, elements, comments, start = _header(src, data)
    columns = _ascii_columns(src, data[start:], elements) if fmt is None else _binary_columns(src, data, start, elements, fmt)
    vc, fc = columns.get("vertex", {}), columns.get("face", {})
    if not vc:
        raise SceneError(src, None, "the mesh has no triangles")
    if not all(k in vc for k in "xyz"):
        raise SceneError(src, "element vertex", "has no x, y, z properties")
    v = np.column_stack([_scalar(src, "vertex", k, vc[k]).astype(np.float64) for k in "xyz"])
    key = next((k for k in ("vertex_indices", "vertex_index") if isinstance(fc.get(k), _List)), None)
    if key is None:
        return MeshFile(path, [MeshPart(path.stem, v, np.zeros((0, 3), np.int64), np.zeros(0, np.int64))])
    counts, flat = fc[key].counts, fc[key].values.astype(np.int64)
    corner, polygon = fan_corners(counts)
    position = flat[corner]
    if position.size and (position.min() < 0 or position.max() >= len(v)):
        raise SceneError(src, f"element face: property {key}", f"a face refers to a vertex that does not exist "
                                                               f"(the file has {len(v)})")
    keys, uv, colors = [position], None, None
    for a, b in _UV_NAMES:
        if _has(vc, a, b):
            uv = np.column_stack([_unit(vc[a]), _unit(vc[b])])
            keys.append(position)
            break
    if uv is None and isinstance(fc.get("texcoord"), _List):  # MeshLab: a list of 2 floats per corner on each face
        tc = fc["texcoord"]
        if np.array_equal(tc.counts, 2 * counts):
            uv, uv_key = dedupe(tc.values.astype(np.float64).reshape(-1, 2), corner)
            keys.append(uv_key)
        else:
            warn(src, "texcoord", "the per-face texture coordinates do not match the faces' corners; not read")
    for names in _COLOR_NAMES:
        if _has(vc, *names):
            colors = np.column_stack([_unit(vc[n]) for n in names])
            keys.append(position)
            break
        if _has(fc, *names):  # a colour per face
            colors, color_key = dedupe(np.column_stack([_unit(fc[n]) for n in names]),
                                       np.repeat(polygon[:, None], 3, 1))
            keys.append(color_key)
            break
    normals = None
    if _has(vc, "nx", "ny", "nz"):
        normals = np.column_stack([vc[n].astype(np.float64) for n in ("nx", "ny", "nz")])
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
    texture = _texture_file(path, comments)
    if texture is not None and part.uv is None:
        warn(src, "comment TextureFile", "the mesh has no texture coordinates; the texture is not used")
    elif texture is not None:
        part.face_material[:] = 0
        materials.append((Path(texture.source).stem, Material(kd=(1.0, 1.0, 1.0), kd_texture=texture)))
    return MeshFile(path, [part], materials)


# --- the header -----------------------------------------------------------------------------------------


def _header(src: str, data: bytes) -> tuple[str | None, list[_Element], list[str], int]:
    """The format's byte order (None: ASCII), the elements, the comment lines' text and where the data
    starts: just after the end_header line."""
    fmt, elements, comments, pos, number = "", [], [], 0, 0
    while True:
        end = data.find(b"\n", pos)
        if end < 0:
            raise SceneError(src, None, "the header has no end_header line")
        line = data[pos:end].decode("latin-1").strip()
        pos, number = end + 1, number + 1
        words = line.split()
        if number == 1 or not words:
            continue  # 'ply', checked by the caller's sniff
        keyword = words[0]
        if keyword == "end_header":
            break
        if keyword == "format":
            if len(words) < 2 or words[1] not in _FORMATS:
                raise SceneError(src, f"header line {number}", f"expected 'format ascii 1.0', 'format binary_little_endian "
                                                               f"1.0' or 'format binary_big_endian 1.0', got {show(line)}")
            fmt = _FORMATS[words[1]]
        elif keyword == "comment":
            comments.append(line[len("comment"):].strip())
        elif keyword == "element":
            if len(words) != 3 or not words[2].isdigit():
                raise SceneError(src, f"header line {number}", f"expected 'element <name> <count>', got {show(line)}")
            elements.append(_Element(words[1], int(words[2])))
        elif keyword == "property":
            if not elements:
                raise SceneError(src, f"header line {number}", "a property before any element")
            elements[-1].properties.append(_property(src, number, line, words, elements[-1]))
        # obj_info and the lines other writers add say nothing the mesh needs
    if fmt == "":
        raise SceneError(src, None, "the header has no format line")
    return fmt, elements, comments, pos


def _property(src: str, number: int, line: str, words: list[str], element: _Element) -> _Property:
    where = f"header line {number}"
    if len(words) == 5 and words[1] == "list":
        count, item, name = words[2:]
    elif len(words) == 3:
        count, item, name = None, words[1], words[2]
    else:
        raise SceneError(src, where, f"expected 'property <type> <name>' or 'property list <count type> <type> <name>', "
                                     f"got {show(line)}")
    for t in (count, item):
        if t is not None and t not in _TYPES:
            raise SceneError(src, f"{element.where}: property {name}", f"unknown type '{t}'; expected one of: "
                                                                       f"{', '.join(_TYPES)}")
    if count is not None and _TYPES[count][0] == "f":
        raise SceneError(src, f"{element.where}: property {name}", f"a list's length type must be an integer, got '{count}'")
    return _Property(name, np.dtype(_TYPES[item]), None if count is None else np.dtype(_TYPES[count]))


# --- binary data ----------------------------------------------------------------------------------------


def _binary_columns(src: str, data: bytes, pos: int, elements: list[_Element], order: str) -> dict:
    """{element: {property: values}}: each element one structured array where its lists have the length
    of its first row's (nearly every file: triangles), else row by row."""
    out = {}
    for e in elements:
        props = [_in_order(p, order) for p in e.properties]
        if e.length == 0 or not props:
            out[e.name] = {p.name: _empty(p) for p in props}
            continue
        # Every row takes at least its scalars and its lists' lengths: a count the file cannot hold is
        # refused before anything is allocated for it.
        least = sum(p.dtype.itemsize if p.count is None else p.count.itemsize for p in props)
        if pos + e.length * least > len(data):
            raise SceneError(src, e.where, f"the file ends before its {e.length} rows ({len(data) - pos} bytes left)")
        fixed = _fixed_row(data, pos, props)
        columns = None
        if fixed is not None:
            dtype, lengths = fixed
            if pos + e.length * dtype.itemsize <= len(data):
                rows = np.frombuffer(data, dtype, e.length, pos)
                if all(np.all(rows[f"{p.name}#n"] == lengths[p.name]) for p in props if p.count is not None):
                    columns = {p.name: _List(np.full(e.length, lengths[p.name], np.int64), rows[p.name].reshape(-1))
                               if p.count is not None else rows[p.name] for p in props}
                    pos += e.length * dtype.itemsize
        if columns is None:
            columns, pos = _binary_rows(src, data, pos, e, props, order)
        out[e.name] = columns
    if len(data) > pos:
        warn(src, None, f"{len(data) - pos} bytes after the last element are not read")
    return out


def _in_order(p: _Property, order: str) -> _Property:
    return _Property(p.name, p.dtype.newbyteorder(order), None if p.count is None else p.count.newbyteorder(order))


def _fixed_row(data: bytes, pos: int, props: list[_Property]):
    """The element's row as a structured dtype with each list as long as in the first row (its length
    field named '<name>#n'), and those lengths; None where the first row is cut off."""
    fields, lengths, at = [], {}, pos
    for p in props:
        if p.count is None:
            fields.append((p.name, p.dtype))
            at += p.dtype.itemsize
            continue
        if at + p.count.itemsize > len(data):
            return None
        n = int(np.frombuffer(data, p.count, 1, at)[0])
        if n < 0:
            return None
        fields += [(f"{p.name}#n", p.count), (p.name, p.dtype, (n,))]
        lengths[p.name] = n
        at += p.count.itemsize + n * p.dtype.itemsize
    try:
        return np.dtype(fields), lengths
    except (ValueError, TypeError):  # a repeated property name
        return None


def _binary_rows(src: str, data: bytes, pos: int, e: _Element, props: list[_Property], order: str) -> tuple[dict, int]:
    """The general case, lists of differing lengths (triangles and quads): where each row's values
    start, found row by row, then each property gathered at once."""
    view = np.frombuffer(data, np.uint8)
    starts = {p.name: np.empty(e.length, np.int64) for p in props}
    counts = {p.name: np.zeros(e.length, np.int64) for p in props if p.count is not None}
    plan = [(p.name, p.dtype.itemsize, None if p.count is None else (_struct_code(p.count, order), p.count.itemsize))
            for p in props]
    size = len(data)
    for row in range(e.length):
        for name, itemsize, count in plan:
            if count is None:
                starts[name][row] = pos
                pos += itemsize
                continue
            fmt, count_size = count
            if pos + count_size > size:
                pos = size + 1
                break
            n = struct.unpack_from(fmt, data, pos)[0]
            if n < 0:
                raise SceneError(src, f"{e.where}: property {name}", f"row {row} is a list of {n} values")
            starts[name][row], counts[name][row] = pos + count_size, n
            pos += count_size + n * itemsize
        if pos > size:
            raise SceneError(src, e.where, f"the file ends within row {row} of {e.length}")
    columns = {}
    for p in props:
        if p.count is None:
            columns[p.name] = _gather(view, starts[p.name], np.ones(e.length, np.int64), p.dtype)
        else:
            columns[p.name] = _List(counts[p.name], _gather(view, starts[p.name], counts[p.name], p.dtype))
    return columns, pos


def _struct_code(t: np.dtype, order: str) -> str:
    """The struct module's code for an integer type in the file's byte order, at its standard size."""
    code = {1: "b", 2: "h", 4: "i", 8: "q"}[t.itemsize]
    return order + (code.upper() if t.kind == "u" else code)


def _gather(view: np.ndarray, starts: np.ndarray, counts: np.ndarray, dtype: np.dtype) -> np.ndarray:
    """Values of ``dtype`` at byte offsets: ``counts[i]`` of them from ``starts[i]``."""
    k = dtype.itemsize
    first = np.repeat(starts, counts) + k * (np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts))
    return np.ascontiguousarray(view[first[:, None] + np.arange(k)]).view(dtype).reshape(-1)


# --- ASCII data -----------------------------------------------------------------------------------------


def _ascii_columns(src: str, body: bytes, elements: list[_Element]) -> dict:
    """{element: {property: values}}: every number of the data read as float64 (then cast to the
    property's type, as a reader parsing text does); an element's rows one array where its lists have
    one length, else found row by row."""
    tokens = body.split()
    out, at = {}, 0
    for e in elements:
        props = e.properties
        if e.length == 0 or not props:
            out[e.name] = {p.name: _empty(p) for p in props}
            continue
        if at + e.length * len(props) > len(tokens):  # each property takes at least one number a row
            raise SceneError(src, e.where, f"the file ends before its {e.length} rows ({len(tokens) - at} numbers left)")
        scalars = sum(p.count is None for p in props)
        lists = [p for p in props if p.count is not None]
        if not lists:
            values = _numbers(src, e, tokens, at, e.length * scalars)
            rows = values.reshape(e.length, scalars)
            out[e.name] = {p.name: rows[:, j].astype(p.dtype) for j, p in enumerate(props)}
            at += e.length * scalars
            continue
        columns, at = _ascii_lists(src, e, tokens, at)
        out[e.name] = columns
    return out


def _ascii_lists(src: str, e: _Element, tokens: list, at: int) -> tuple[dict, int]:
    # Where every row's lists are as long as the first row's, the rows are one (rows, width) array.
    first, offsets, width = {}, [], 0
    for p in e.properties:
        offsets.append(width)
        if p.count is None:
            width += 1
            continue
        n = _count(src, e, p, tokens, at + width, 0)
        first[p.name] = n
        width += 1 + n
    if at + e.length * width <= len(tokens):
        rows = _numbers(src, e, tokens, at, e.length * width).reshape(e.length, width)
        if all(np.all(rows[:, o] == first[p.name]) for p, o in zip(e.properties, offsets) if p.count is not None):
            columns = {}
            for p, o in zip(e.properties, offsets):
                if p.count is None:
                    columns[p.name] = rows[:, o].astype(p.dtype)
                else:
                    n = first[p.name]
                    columns[p.name] = _List(np.full(e.length, n, np.int64), rows[:, o + 1:o + 1 + n].astype(p.dtype).reshape(-1))
            return columns, at + e.length * width
    # Lists of differing lengths: each row's length read in turn.
    scalar = {p.name: [] for p in e.properties if p.count is None}
    listed = {p.name: ([], []) for p in e.properties if p.count is not None}
    for row in range(e.length):
        for p in e.properties:
            if p.count is None:
                scalar[p.name].append(at)
                at += 1
            else:
                n = _count(src, e, p, tokens, at, row)
                listed[p.name][0].append(at + 1)
                listed[p.name][1].append(n)
                at += 1 + n
        if at > len(tokens):
            raise SceneError(src, e.where, f"the file ends within row {row} of {e.length}")
    columns = {}
    for p in e.properties:
        if p.count is None:
            columns[p.name] = _numbers(src, e, [tokens[i] for i in scalar[p.name]], 0, e.length).astype(p.dtype)
        else:
            starts, counts = (np.asarray(a, np.int64) for a in listed[p.name])
            index = np.repeat(starts, counts) + np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
            values = _numbers(src, e, [tokens[i] for i in index], 0, len(index)).astype(p.dtype)
            columns[p.name] = _List(counts, values)
    return columns, at


def _count(src: str, e: _Element, p: _Property, tokens: list, at: int, row: int) -> int:
    if at >= len(tokens):
        raise SceneError(src, e.where, f"the file ends within row {row} of {e.length}")
    try:
        n = float(tokens[at])
    except ValueError:
        raise SceneError(src, f"{e.where}: property {p.name}", f"row {row}: expected a list length, got "
                                                               f"{show(tokens[at].decode('latin-1'))}") from None
    if not (n >= 0 and n == int(n)):
        raise SceneError(src, f"{e.where}: property {p.name}", f"row {row} is a list of {n:g} values")
    return int(n)


def _numbers(src: str, e: _Element, tokens: list, at: int, n: int) -> np.ndarray:
    if at + n > len(tokens):
        raise SceneError(src, e.where, f"the file ends within its {e.length} rows ({len(tokens) - at} numbers left, "
                                       f"{n} needed)")
    part = tokens[at:at + n]
    try:
        return np.array(part, np.float64)
    except ValueError:
        bad = next(t for t in part if not _is_number(t))
        raise SceneError(src, e.where, f"expected a number, got {show(bad.decode('latin-1'))}") from None


def _is_number(token: bytes) -> bool:
    try:
        float(token)
        return True
    except ValueError:
        return False


# --- columns to attributes ------------------------------------------------------------------------------


def _empty(p: _Property):
    return np.zeros(0, p.dtype) if p.count is None else _List(np.zeros(0, np.int64), np.zeros(0, p.dtype))


def _has(columns: dict, *names) -> bool:
    return all(isinstance(columns.get(n), np.ndarray) for n in names)


def _scalar(src: str, element: str, name: str, column) -> np.ndarray:
    if not isinstance(column, np.ndarray):
        raise SceneError(src, f"element {element}: property {name}", "expected one value a row, not a list")
    return column


def _unit(column: np.ndarray) -> np.ndarray:
    """Integer colours and texture coordinates scaled to [0, 1] by their type's range."""
    if column.dtype.kind in "ui":
        return column.astype(np.float64) / np.iinfo(column.dtype).max
    return column.astype(np.float64)


def _texture_file(path: Path, comments: list[str]):
    name = next((m.group(1) for c in comments if (m := re.match(r"TextureFile\s+(.+?)\s*$", c, re.I))), None)
    if name is None:
        return None
    try:
        return image_texture(path.parent / name)
    except SceneError as e:
        warn(str(path), "comment TextureFile", f"{one_line(e)}; the mesh is untextured")
        return None
