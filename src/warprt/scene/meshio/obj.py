"""OBJ + MTL, read here rather than by trimesh, which drops what a model's look depends on: smoothing
groups, per-corner normals, map_Kd with options, 0-255 vertex colours, and files that are not UTF-8.

What is read: v (with r g b colours), vt, vn, f (any of v, v/vt, v//vn, v/vt/vn, negative indices,
polygons fanned), s, usemtl, mtllib; from the MTL Ka Kd Ks Ns illum map_Ka map_Kd map_Ks (-s -o -clamp).
The rest is ignored with one warning. Materials are read as Blender's importer reads them.
"""

from __future__ import annotations

import codecs
import math
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from ...diagnostics import warn
from ...errors import SceneError, show
from ..dielectric_formats import dielectric_from_mtl
from ..model import Material
from ..texture import affine, image_texture
from . import MeshFile, MeshPart, fan_corners, unique_name, weld_corners

# Statements that carry nothing a triangle renderer draws (curves, lines, render hints): ignored quietly.
_OBJ_QUIET = {"o", "g", "vp", "l", "p", "cstype", "deg", "bmat", "step", "curv", "curv2", "surf", "parm", "trim",
              "hole", "scrv", "sp", "end", "con", "mg", "bevel", "c_interp", "d_interp", "lod", "maplib", "usemap",
              "shadow_obj", "trace_obj", "ctech", "stech", "call", "csh"}
# MTL statements for what Phong has no term for (refraction, PBR, bump and displacement): ignored
# quietly; transparency is warned about when a material has it. Ke is the emission (an area light).
_MTL_QUIET = {"pr", "pm", "ps", "pc", "pcr", "aniso", "anisor", "sharpness", "map_ns", "map_bump", "bump",
              "disp", "decal", "refl", "norm", "map_pr", "map_pm", "map_ps", "map_refl", "map_aat"}
_MAP_OPTIONS = {"-blendu": 1, "-blendv": 1, "-bm": 1, "-boost": 1, "-cc": 1, "-clamp": 1, "-imfchan": 1,
                "-texres": 1, "-type": 1, "-mm": 2, "-o": 3, "-s": 3, "-t": 3}
_NUMERIC_OPTIONS = {"-o", "-s", "-t", "-mm", "-bm", "-boost", "-texres"}
_DEFAULT_KD = (0.8, 0.8, 0.8)  # what Blender and most MTL readers assume without a Kd


def decode_text(raw: bytes) -> str:
    """Bytes to text as OBJ writers leave them: a byte-order mark says; else UTF-8; else Windows-1252;
    else Latin-1, which decodes anything. (trimesh guesses with charset_normalizer, which it does not
    install, and a wrong guess silently loses a material whose name has an accent.)"""
    if raw.startswith(codecs.BOM_UTF8):
        return raw[3:].decode("utf-8", errors="replace")
    if raw.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        return raw.decode("utf-16", errors="replace")
    for encoding in ("utf-8", "cp1252"):
        try:
            return raw.decode(encoding)
        except UnicodeDecodeError:
            pass
    return raw.decode("latin-1")


def _numbers(src: str, statement: str, lines: list[str]) -> np.ndarray:
    """Lines of numbers as an (n, k) float64 array, k the most any line has (NaN pads shorter ones)."""
    if not lines:
        return np.zeros((0, 3))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            flat = np.fromstring(" ".join(lines), sep=" ")
        except (ValueError, DeprecationWarning):
            flat = None
    if flat is not None and flat.size % len(lines) == 0 and flat.size:
        width = flat.size // len(lines)
        if all(len(s.split()) == width for s in lines[:: max(1, len(lines) // 64)]):
            return flat.reshape(len(lines), width)
    rows = []
    for s in lines:
        try:
            rows.append([float(t) for t in s.split()])
        except ValueError:
            raise SceneError(src, None, f"'{statement} {s.strip()}': expected numbers") from None
    out = np.full((len(rows), max(len(r) for r in rows)), np.nan)
    for i, r in enumerate(rows):
        out[i, :len(r)] = r
    return out


def _zero_based(index: np.ndarray, count_before: np.ndarray) -> np.ndarray:
    """OBJ indices (from 1; negative: back from the elements read so far; 0: absent) to 0-based, -1 absent."""
    out = np.where(index > 0, index - 1, count_before + index)
    return np.where(index == 0, -1, out)


def _lines(text: str) -> list[str]:
    text = text.replace("\r\n", "\n").replace("\r", "\n").replace("\t", " ").replace("\\\n", " ")
    lines = [l.split("#", 1)[0].strip() if "#" in l else l.strip() for l in text.split("\n")]
    return lines


def read_obj(path: Path) -> MeshFile:
    """The whole file as one part with a material per face (in file order), and its MTL materials."""
    src = str(path)
    lines = _lines(decode_text(path.read_bytes()))
    kind = np.array([l[:2] for l in lines], dtype="<U2") if lines else np.zeros(0, "<U2")
    is_v, is_vt, is_vn, is_f = kind == "v ", kind == "vt", kind == "vn", kind == "f "
    v_at, vt_at, vn_at, f_at = (np.nonzero(m)[0] for m in (is_v, is_vt, is_vn, is_f))
    # 'vt ' and 'vn ' need their space too: 'vtx' is not a texture coordinate.
    vt_at = vt_at[[lines[i][2:3] == " " for i in vt_at]] if len(vt_at) else vt_at
    vn_at = vn_at[[lines[i][2:3] == " " for i in vn_at]] if len(vn_at) else vn_at

    v = _numbers(src, "v", [lines[i][2:] for i in v_at])
    if v.shape[1] < 3:
        raise SceneError(src, None, "a vertex (v) has fewer than 3 coordinates")
    colors = _vertex_colors(src, v)
    v = np.ascontiguousarray(v[:, :3])
    vt = _numbers(src, "vt", [lines[i][3:] for i in vt_at])
    vt = np.nan_to_num(np.c_[vt, np.zeros((len(vt), 2))][:, :2])
    vn = _numbers(src, "vn", [lines[i][3:] for i in vn_at])
    if len(vn) and vn.shape[1] < 3:
        raise SceneError(src, None, "a normal (vn) has fewer than 3 components")
    vn = vn[:, :3]

    tokens, counts = _face_tokens(src, [lines[i][2:] for i in f_at])
    line_of = np.repeat(f_at, counts)
    tv = _zero_based(tokens[:, 0], np.searchsorted(v_at, line_of))
    tt = _zero_based(tokens[:, 1], np.searchsorted(vt_at, line_of))
    tn = _zero_based(tokens[:, 2], np.searchsorted(vn_at, line_of))
    for what, index, n, column in (("vertex", tv, len(v), 0), ("texture coordinate", tt, len(vt), 1),
                                   ("normal", tn, len(vn), 2)):
        bad = (index >= n) | ((index < 0) & (tokens[:, column] != 0)) | ((index < 0) & (column == 0))
        if bad.any():
            k = int(np.nonzero(bad)[0][0])
            raise SceneError(src, None, f"a face refers to a {what} that does not exist "
                                        f"({what} {tokens[k, column]}; the file has {n})")
    if (counts < 3).any():
        warn(src, None, f"{int((counts < 3).sum())} faces with fewer than 3 corners ignored")
    corner, polygon = fan_corners(counts)
    tri_line = f_at[polygon] if len(polygon) else np.zeros(0, np.int64)

    mtllibs, usemtl, groups = _statements(src, lines, ~(is_v | is_vt | is_vn | is_f))
    materials, by_name = [], {}
    for spec, line in mtllibs:
        files = _mtl_files(path.parent, spec)
        if not files:
            warn(src, f"line {line + 1}", f"mtllib {spec}: file not found; faces get the default material")
        for mtl in files:
            for name, m in read_mtl(mtl):
                if name not in by_name:
                    by_name[name] = len(materials)
                    materials.append((name, m))
    missing = sorted({n for n in usemtl[1] if n not in by_name})
    if missing:
        warn(src, "usemtl", f"no material named {', '.join(repr(n) for n in missing[:3])}"
                            f"{f' and {len(missing) - 3} more' if len(missing) > 3 else ''} in the MTL files; "
                            "those faces get the default material")
    face_material = _at_lines((usemtl[0], [by_name.get(n, -1) for n in usemtl[1]]), tri_line, -1)
    smoothing = _at_lines(groups, tri_line, 0) if groups else None

    cv, ct, cn = tv[corner], tt[corner], tn[corner]
    keys, has_uv, has_normals = [cv], len(vt) > 0 and (ct >= 0).any(), len(vn) > 0 and (cn >= 0).all()
    if len(vn) and not has_normals and (cn >= 0).any():
        warn(src, "vn", "some faces have normals and some do not; normals are computed instead")
    if has_uv:
        ct = np.where(ct < 0, len(vt), ct)  # a corner without vt reads (0, 0)
        vt = np.r_[vt, [[0.0, 0.0]]]
        keys.append(ct)
    faces, rows = weld_corners(keys, len(v))
    part = MeshPart(path.stem, v[rows[0]], faces, face_material,
                    uv=vt[rows[1]] if has_uv else None,
                    colors=None if colors is None else colors[rows[0]],
                    normals=vn[cn] if has_normals else None, smoothing_group=smoothing)
    return MeshFile(path, [part], materials)


def _vertex_colors(src: str, v: np.ndarray) -> np.ndarray | None:
    """'v x y z r g b': colours as Blender reads them, sRGB-encoded, decoded to linear. Writers that
    use 0-255 are recognised by a value above 1. ('v x y z w' is a weight, not a colour.)"""
    if v.shape[1] < 6:
        return None
    c = v[:, 3:6]
    if np.isnan(c).all():
        return None
    if np.isnan(c).any():
        warn(src, "v", "some vertices have colours and some do not; the others are white")
        c = np.where(np.isnan(c), 1.0, c)
    if (c < 0).any():
        warn(src, "v", "negative vertex colours read as 0")
        c = np.maximum(c, 0.0)
    if c.max(initial=0.0) > 1.0:
        c = c / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _face_tokens(src: str, lines: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Face corners as (n, 3) OBJ indices (v, vt, vn; 0 where absent) and the corner count per face."""
    counts = np.fromiter((len(s.split()) for s in lines), np.int64, len(lines))
    n = int(counts.sum())
    flat = " ".join(lines).replace("//", "/0/")
    slashes = flat.count("/")
    per = slashes // n if n and slashes % n == 0 else -1
    if n == 0:
        return np.zeros((0, 3), np.int64), counts
    ints = None
    if per in (0, 1, 2) and all(t.count("/") == per for t in flat.split()[:: max(1, n // 64)]):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            try:
                ints = np.fromstring(flat.replace("/", " "), dtype=np.int64, sep=" ")
            except (ValueError, DeprecationWarning):
                ints = None
        if ints is not None and ints.size != n * (per + 1):
            ints = None
    if ints is None:  # mixed corner formats, or something that is not an integer
        rows = []
        for t in flat.split():
            parts = (t.split("/") + ["", ""])[:3]
            try:
                rows.append([int(p) if p else 0 for p in parts])
            except ValueError:
                raise SceneError(src, None, f"a face corner '{t}' is not of the form v, v/vt, v//vn or v/vt/vn") from None
        tokens = np.asarray(rows, np.int64).reshape(-1, 3)
    else:
        tokens = ints.reshape(n, per + 1)
    return np.c_[tokens, np.zeros((len(tokens), 3 - tokens.shape[1]), np.int64)], counts


def _statements(src: str, lines: list[str], other: np.ndarray):
    """The state lines in file order: mtllib (name, line), usemtl and s as (lines, values)."""
    mtllibs, usemtl, groups, unknown = [], ([], []), ([], []), set()
    for i in np.nonzero(other)[0]:
        words = lines[i].split(None, 1)
        if not words:
            continue
        key, rest = words[0], (words[1].strip() if len(words) > 1 else "")
        if key == "usemtl":
            usemtl[0].append(i), usemtl[1].append(rest)
        elif key == "s":
            off = rest.lower() in ("off", "", "0")
            groups[0].append(i), groups[1].append(0 if off else (int(rest) if rest.isdigit() else 1))
        elif key == "mtllib":
            mtllibs.append((rest, i))
        elif key not in _OBJ_QUIET and key not in ("v", "vt", "vn", "f"):
            unknown.add(key)
    if unknown:
        warn(src, None, f"statements not read: {', '.join(sorted(unknown))}")
    return mtllibs, usemtl, (groups if groups[0] else None)


def _at_lines(state, tri_line: np.ndarray, default: int) -> np.ndarray:
    """The integer value of a state statement (usemtl's material, s) in force at each triangle's line."""
    lines, values = state
    if not lines:
        return np.full(len(tri_line), default, np.int64)
    j = np.searchsorted(np.asarray(lines), tri_line, side="right") - 1
    return np.asarray(list(values) + [default], np.int64)[np.where(j >= 0, j, len(values))]


def _mtl_files(folder: Path, spec: str) -> list[Path]:
    """'mtllib a.mtl b.mtl' may name several files, or one whose name has spaces."""
    whole = find_file(folder, spec)
    if whole:
        return [whole]
    return [f for f in (find_file(folder, name) for name in spec.split()) if f]


def find_file(folder: Path, name: str) -> Path | None:
    """A file an OBJ or MTL names: relative to its folder, with Windows separators, in another case
    (files written on Windows), or an absolute path from the author's machine found by its trailing
    folders under this folder or one of its parents."""
    name = name.strip().strip('"').replace("\\", "/")
    if not name:
        return None
    p = Path(name)
    for candidate in ([p] if p.is_absolute() else []) + [folder / name, folder / p.name]:
        if candidate.is_file():
            return candidate
    try:
        lower = {c.name.lower(): c for c in folder.iterdir()}
    except OSError:
        lower = {}
    if p.name.lower() in lower and lower[p.name.lower()].is_file():
        return lower[p.name.lower()]
    tail = [t for t in p.parts if t != "/" and not t.endswith(":")]
    for up in [folder, *list(folder.parents)[:3]]:
        for k in range(min(len(tail), 4), 1, -1):
            candidate = up.joinpath(*tail[-k:])
            if candidate.is_file():
                return candidate
    return None


def parse_map(rest: str) -> tuple[dict, str]:
    """'-s 2 2 1 -o 0.5 0 0 -bm 1 my tex.png' -> ({'-s': [2, 2, 1], '-o': [0.5, 0, 0], '-bm': [1]}, 'my tex.png')."""
    tokens = rest.split()
    options, i = {}, 0
    while i < len(tokens) - 1 and tokens[i].lower() in _MAP_OPTIONS:
        key = tokens[i].lower()
        i += 1
        values = []
        while len(values) < _MAP_OPTIONS[key] and i < len(tokens) - 1:  # the last token is the file
            if key in _NUMERIC_OPTIONS:
                try:
                    values.append(float(tokens[i]))
                except ValueError:
                    break
            else:
                values.append(tokens[i])
            i += 1
        options[key] = values
    return options, " ".join(tokens[i:])


def read_mtl(path: Path) -> list[tuple[str, Material]]:
    """An MTL file's materials as Phong, the way Blender's importer reads them: Ka, Kd, Ks and Ns as
    written (Ka 0 0 0 kept), Ns <= 0 no highlight, illum 0 and 1 no highlight, illum 3 a mirror
    weighted by Ks, a map replacing its colour (Blender's exporter writes Kd 0.8 beside map_Kd)."""
    src = str(path)
    entries, current, unknown, negative_ns = [], None, set(), []
    for raw in decode_text(path.read_bytes()).replace("\r\n", "\n").replace("\r", "\n").replace("\t", " ").split("\n"):
        line = raw.strip()
        if not line.lower().startswith("map_"):  # a texture file's name may hold a '#'
            line = line.split("#", 1)[0].strip()
        words = line.split(None, 1)
        if not words:
            continue
        key, rest = words[0].lower(), (words[1].strip() if len(words) > 1 else "")
        if key == "newmtl":
            current = {"name": rest, "textures": {}}
            entries.append(current)
        elif current is None:
            continue
        elif key in ("ka", "kd", "ks", "ke"):
            if rest.split()[:1] and rest.split()[0].lower() in ("spectral", "xyz"):
                warn(src, f"newmtl {current['name']}: {words[0]}", f"'{rest.split()[0]}' colours are not read")
                continue
            current[key] = _rgb(src, current["name"], words[0], rest)
        elif key == "ns":
            current["ns"] = _number(src, current["name"], words[0], rest)
            if current["ns"] < 0:
                negative_ns.append(f"{current['name']} ({current['ns']:g})")
        elif key == "illum":
            current["illum"] = int(_number(src, current["name"], words[0], rest))
        elif key in ("d", "tr"):
            current[key] = _number(src, current["name"], words[0], rest)
        elif key in ("ni", "tf"):  # glass, with illum 4, 6 or 7 (dielectric_from_mtl reads and checks them)
            current[key] = rest.split()
        elif key in ("map_ka", "map_kd", "map_ks"):
            texture = _map(src, path.parent, current["name"], words[0], rest)
            if texture is not None:
                current["textures"][key[4:]] = texture
        elif key in ("map_d", "map_ke"):
            current["ignored_" + key] = True
        elif key not in _MTL_QUIET:
            unknown.add(words[0])
    if unknown:
        warn(src, None, f"statements not read: {', '.join(sorted(unknown))}")
    if negative_ns:
        more = f" and {len(negative_ns) - 3} more" if len(negative_ns) > 3 else ""
        warn(src, "Ns", f"negative values read as no highlight: {', '.join(negative_ns[:3])}{more}")
    taken: list[str] = []
    out = []
    for e in entries:
        name = unique_name(e["name"], taken)
        taken.append(name)
        out.append((name, _phong(src, e)))
    return out


def _phong(src: str, e: dict) -> Material:
    where = f"newmtl {e['name']}"
    textures = e["textures"]
    kd = e.get("kd", _DEFAULT_KD)
    ka = e.get("ka")
    ks = e.get("ks", (0.0, 0.0, 0.0))
    ns = e.get("ns", 32.0)
    illum = e.get("illum", 2)
    if "kd" in textures:
        kd = (1.0, 1.0, 1.0)
    if "ka" in textures:
        ka = (1.0, 1.0, 1.0)
    if "ks" in textures:
        ks = (1.0, 1.0, 1.0)
    kr = ks if illum == 3 else (0.0, 0.0, 0.0)
    if illum in (0, 1) or ns <= 0.0:  # Phong with n = 0 would add ks over every lit point
        ks, textures = (0.0, 0.0, 0.0), {k: t for k, t in textures.items() if k != "ks"}
    glass = dielectric_from_mtl(e, src, e["name"])
    if not glass and (e.get("d", 1.0) < 1.0 or e.get("tr", 0.0) > 0.0 or e.get("ignored_map_d")):
        warn(src, where, "transparency (d, Tr, map_d) is not rendered; the material is opaque")
    # Ke: the radiance the material emits (its objects become area lights); Blender writes Ke 0 0 0 for
    # every material, which emits nothing.
    ke = e.get("ke", (0.0, 0.0, 0.0))
    emission = tuple(ke) if max(ke) > 0.0 else None
    if e.get("ignored_map_ke"):
        warn(src, where, "an emission map (map_Ke) is not read" + ("; Ke is emitted everywhere" if emission else ""))
    # No Ka: ka is kd with kd's map (Material's own default).
    return replace(Material(kd=kd, ka=ka, ks=ks, shininess=max(ns, 0.0), reflectivity=kr, kd_texture=textures.get("kd"),
                            ka_texture=textures.get("ka"), ks_texture=textures.get("ks"), emission=emission), **glass)


def _rgb(src: str, name: str, key: str, rest: str) -> tuple:
    try:
        v = [float(x) for x in rest.split()[:3]]
    except ValueError:
        v = None
    if v is not None and len(v) == 1:
        v = v * 3  # 'Kd r' means r = g = b
    if v is None or len(v) != 3 or not all(math.isfinite(x) and x >= 0 for x in v):
        shown = v if v is not None else rest
        raise SceneError(src, f"newmtl {name}: {key}", f"expected 3 non-negative numbers, got {show(shown)}")
    return tuple(v)


def _number(src: str, name: str, key: str, rest: str) -> float:
    try:
        x = float(rest.split()[0])
    except (ValueError, IndexError):
        x = float("nan")
    if not math.isfinite(x):
        raise SceneError(src, f"newmtl {name}: {key}", f"expected a number, got {show(rest)}")
    return x


def _map(src: str, folder: Path, name: str, key: str, rest: str):
    """A map_K? statement as a Texture (its -s scale and -o offset as the uv map, -clamp on as clamp to edge),
    or None with a warning."""
    options, file_name = parse_map(rest)
    where = f"newmtl {name}: {key}"
    ignored = sorted(set(options) - {"-s", "-o", "-clamp"})
    if ignored:
        warn(src, where, f"options not read: {' '.join(ignored)}")
    found = find_file(folder, file_name)
    if found is None:
        warn(src, where, f"{file_name}: texture file not found; the material is untextured")
        return None
    s, o = options.get("-s", [1.0, 1.0]), options.get("-o", [0.0, 0.0])
    scale = (s[0], s[1] if len(s) > 1 else s[0]) if s else (1.0, 1.0)
    offset = (o[0], o[1] if len(o) > 1 else 0.0) if o else (0.0, 0.0)
    clamp = str((options.get("-clamp") or ["off"])[0]).lower() == "on"  # the MTL spec: uv clamped to [0, 1]
    try:
        texture = image_texture(found, uv_transform=affine(scale, offset))
        return texture.wrapped("clamp", "clamp") if clamp else texture
    except SceneError as e:
        warn(src, where, f"{e}; the material is untextured")
        return None
