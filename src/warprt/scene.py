"""The scene: dataclasses that mirror the TOML file one to one, and the reader that validates it.

Everything is float64 here; geometry becomes float32 only when it is handed to the BVH.
Validation speaks the file's vocabulary: every error names the file and the dotted field.
"""

from __future__ import annotations

import difflib
import math
import time
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from . import shapes
from .errors import SceneError


@dataclass(frozen=True)
class Camera:
    """The seed's pinhole camera: eye, center, up, fovy (degrees), near (d_f), image size."""

    eye: tuple = (0.0, 1.5, 5.0)
    center: tuple = (0.0, 0.8, 0.0)
    up: tuple = (0.0, 1.0, 0.0)
    fovy: float = 45.0
    near: float = 1.0
    width: int = 640
    height: int = 480


@dataclass(frozen=True)
class RenderSettings:
    ambient: tuple = (0.1, 0.1, 0.1)  # C_amb
    background: tuple = (0.0, 0.0, 0.0)
    max_depth: int = 3  # ray levels: 1 = primary only
    shadows: bool = True
    spp: int = 1  # k*k stratified samples per pixel
    effects: tuple | None = None  # None: every effect the scene calls for


@dataclass(frozen=True)
class Light:
    """A point light: position and colour C_l."""

    position: tuple
    color: tuple = (1.0, 1.0, 1.0)


@dataclass(frozen=True)
class Material:
    """Phong coefficients ka, kd, ks, the exponent n (shininess) and the mirror weight k_r."""

    kd: tuple = (0.7, 0.7, 0.7)
    ka: tuple | None = None  # defaults to kd
    ks: tuple = (0.0, 0.0, 0.0)
    shininess: float = 32.0
    reflectivity: tuple = (0.0, 0.0, 0.0)  # k_r

    @property
    def ka_(self) -> tuple:
        return self.kd if self.ka is None else self.ka


@dataclass
class SceneObject:
    """One object: its triangles in world space (float64) and the name of its material."""

    name: str
    vertices: np.ndarray  # (N, 3) float64, world space
    faces: np.ndarray  # (M, 3) int64
    material: str
    smooth: bool = False
    # Vertex normals (N, 3) when the object is part of a larger smooth mesh (a file split by
    # material): computed over the whole mesh, so the split leaves no crease.
    normals: np.ndarray | None = None


@dataclass
class Scene:
    camera: Camera
    render: RenderSettings
    lights: list[Light]
    materials: dict[str, Material]
    objects: list[SceneObject]
    source: str = "<scene>"
    load_seconds: float | None = None  # time load_scene spent reading and validating

    @property
    def triangle_count(self) -> int:
        return int(sum(len(o.faces) for o in self.objects))

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        v = np.concatenate([o.vertices for o in self.objects]) if self.objects else np.zeros((1, 3))
        return v.min(0), v.max(0)

    def with_camera(self, **kw) -> "Scene":
        return replace(self, camera=replace(self.camera, **kw))

    def with_render(self, **kw) -> "Scene":
        return replace(self, render=replace(self.render, **kw))


DEFAULT_MATERIAL = Material(kd=(0.7, 0.7, 0.7), ks=(0.3, 0.3, 0.3), shininess=32.0)
MAX_IMAGE_SIDE = 16384

_SECTIONS = {"camera", "render", "lights", "materials", "objects"}
_CAMERA_KEYS = {"eye", "center", "up", "fovy", "near", "width", "height"}
_RENDER_KEYS = {"ambient", "background", "max_depth", "shadows", "spp", "effects"}
_LIGHT_KEYS = {"position", "color"}
_MATERIAL_KEYS = {"ka", "kd", "ks", "shininess", "reflectivity"}
_OBJECT_KEYS = {"name", "mesh", "shape", "material", "scale", "rotate", "translate", "smooth"}


class _Reader:
    """Typed access to one TOML table, raising SceneError with the file and dotted field."""

    def __init__(self, source: str, table: dict, prefix: str):
        self.source, self.table, self.prefix = source, table, prefix

    def fail(self, key: str | None, message: str):
        raise SceneError(self.source, f"{self.prefix}.{key}" if key else self.prefix, message)

    def check_keys(self, allowed: set):
        for key in self.table:
            if key not in allowed:
                close = difflib.get_close_matches(key, sorted(allowed), n=1)
                hint = f" (did you mean '{close[0]}'?)" if close else f" (expected one of: {', '.join(sorted(allowed))})"
                self.fail(key, f"unknown key{hint}")

    def number(self, key, default=None, lo=None, hi=None, lo_open=False, hi_open=False):
        v = self.table.get(key, default)
        if v is None:
            self.fail(key, "is required")
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(key, f"expected a number, got {_show(v)}")
        v = float(v)
        if not math.isfinite(v):
            self.fail(key, f"expected a finite number, got {v}")
        if lo is not None and (v < lo or (lo_open and v == lo)):
            self.fail(key, f"expected a number {'>' if lo_open else '>='} {lo:g}, got {v:g}")
        if hi is not None and (v > hi or (hi_open and v == hi)):
            self.fail(key, f"expected a number {'<' if hi_open else '<='} {hi:g}, got {v:g}")
        return v

    def integer(self, key, default=None, lo=None, hi=None):
        v = self.table.get(key, default)
        if v is None:
            self.fail(key, "is required")
        if isinstance(v, bool) or not isinstance(v, int):
            self.fail(key, f"expected an integer, got {_show(v)}")
        if (lo is not None and v < lo) or (hi is not None and v > hi):
            self.fail(key, f"expected an integer in [{lo}, {hi}], got {v}")
        return int(v)

    def boolean(self, key, default):
        v = self.table.get(key, default)
        if not isinstance(v, bool):
            self.fail(key, f"expected true or false, got {_show(v)}")
        return v

    def string(self, key, default=None):
        v = self.table.get(key, default)
        if v is None:
            self.fail(key, "is required")
        if not isinstance(v, str):
            self.fail(key, f"expected a string, got {_show(v)}")
        return v

    def vector(self, key, default=None, n=3, nonneg=False, allow_scalar=False):
        v = self.table.get(key, default)
        if v is None:
            self.fail(key, "is required")
        if allow_scalar and isinstance(v, (int, float)) and not isinstance(v, bool):
            v = [v] * n
        if not isinstance(v, (list, tuple)) or len(v) != n:
            what = f"a number or a list of {n} numbers" if allow_scalar else f"a list of {n} numbers"
            self.fail(key, f"expected {what}, got {_show(v)}")
        out = []
        for x in v:
            if isinstance(x, bool) or not isinstance(x, (int, float)):
                self.fail(key, f"expected a list of {n} numbers, got {_show(v)}")
            if not math.isfinite(x):
                self.fail(key, f"expected finite numbers, got {_show(v)}")
            if nonneg and x < 0:
                self.fail(key, f"expected non-negative numbers, got {_show(v)}")
            out.append(float(x))
        return tuple(out)


def _show(v) -> str:
    s = repr(v)
    return s if len(s) <= 60 else s[:57] + "..."


def _table(source, data, key, prefix=None) -> dict:
    v = data.get(key, {})
    if not isinstance(v, dict):
        raise SceneError(source, prefix or key, f"expected a table, got {_show(v)}")
    return v


def _array_of_tables(source, data, key) -> list:
    v = data.get(key, [])
    if not isinstance(v, list) or not all(isinstance(t, dict) for t in v):
        raise SceneError(source, key, f"expected an array of tables ([[{key}]]), got {_show(v)}")
    return v


def read_camera(source: str, t: dict) -> Camera:
    r = _Reader(source, t, "camera")
    r.check_keys(_CAMERA_KEYS)
    d = Camera()
    cam = Camera(
        eye=r.vector("eye", d.eye),
        center=r.vector("center", d.center),
        up=r.vector("up", d.up),
        fovy=r.number("fovy", d.fovy, lo=0.0, hi=180.0, lo_open=True, hi_open=True),
        near=r.number("near", d.near, lo=0.0, lo_open=True),
        width=r.integer("width", d.width, lo=1, hi=MAX_IMAGE_SIDE),
        height=r.integer("height", d.height, lo=1, hi=MAX_IMAGE_SIDE),
    )
    validate_camera(cam, source)
    return cam


def _is_real(v) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)


def _num(v) -> str:
    return f"{v:g}" if _is_real(v) else _show(v)


def validate_camera(cam: Camera, source: str = "camera"):
    """The checks that need more than one field: a view direction, and an up not parallel to it."""
    eye, center, up = (np.asarray(v, np.float64) for v in (cam.eye, cam.center, cam.up))
    for name, v in (("eye", eye), ("center", center), ("up", up)):
        if v.shape != (3,) or not np.all(np.isfinite(v)):
            raise SceneError(source, f"camera.{name}", f"expected 3 finite numbers, got {list(v)}")
    if not _is_real(cam.fovy) or not (0.0 < cam.fovy < 180.0) or not math.isfinite(cam.fovy):
        raise SceneError(source, "camera.fovy", f"expected a number in (0, 180) degrees, got {_num(cam.fovy)}")
    if not _is_real(cam.near) or not (cam.near > 0.0) or not math.isfinite(cam.near):
        raise SceneError(source, "camera.near", f"expected a number > 0, got {_num(cam.near)}")
    for name in ("width", "height"):
        v = getattr(cam, name)
        if not isinstance(v, (int, np.integer)) or not (1 <= v <= MAX_IMAGE_SIDE):
            raise SceneError(source, f"camera.{name}", f"expected an integer in [1, {MAX_IMAGE_SIDE}], got {v}")
    # The kernels build ray directions from d_f = near and the image plane's h, w in float32 and
    # normalize them: their squares must neither underflow nor overflow.
    h = 2.0 * cam.near * math.tan(math.radians(cam.fovy) / 2.0)
    if not (1e-18 <= cam.near and h <= 1e18 and h * cam.width / cam.height <= 1e18):
        raise SceneError(source, "camera.near", f"near {cam.near:g} puts the image plane (height 2 near tan(fovy/2) = "
                                                f"{h:.3g}) outside the float32 range of ray directions [1e-18, 1e18]")
    view = eye - center
    # Relative to the coordinates' size: a scene 1e-12 across is fine, eye and center a rounding apart are not.
    if np.linalg.norm(view) <= 1e-12 * np.abs(np.concatenate([eye, center])).max():
        raise SceneError(source, "camera.center", "must differ from camera.eye (no viewing direction)")
    z = view / np.linalg.norm(view)
    if np.linalg.norm(up) == 0.0:
        raise SceneError(source, "camera.up", "must not be the zero vector")
    if np.linalg.norm(np.cross(up / np.linalg.norm(up), z)) < 1e-6:
        raise SceneError(source, "camera.up", "is parallel to the viewing direction (eye - center)")


# Warp's float32 ray-triangle test multiplies three coordinate differences (its T = U Az): for
# geometry 1e14 from the eye that overflows and triangles silently vanish (measured: a sphere of
# radius 1e13 seen from 5e13 renders, radius 1e14 from 5e14 does not). Scenes must stay within
# this reach of the eye.
MAX_REACH = 1e12
FLOAT32_MAX = float(np.finfo(np.float32).max)


def _check_vector(source, field_name, v, nonneg=False):
    a = np.asarray(v, np.float64) if v is not None else None
    if a is None or a.shape != (3,) or not np.all(np.isfinite(a)) or (nonneg and np.any(a < 0)):
        what = "3 finite non-negative numbers" if nonneg else "3 finite numbers"
        raise SceneError(source, field_name, f"expected {what}, got {_show(v)}")
    return a


def _check_number(source, field_name, v, lo=0.0):
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) or not math.isfinite(v) or v < lo:
        raise SceneError(source, field_name, f"expected a finite number >= {lo:g}, got {_show(v)}")


def validate_scene(scene: Scene):
    """Everything render() relies on, for scenes built in Python as well as read from files: finite
    values in range, geometry within float32 reach of the eye, and an image that cannot overflow.
    Raises SceneError naming the field, before any kernel runs."""
    src = scene.source
    cam = scene.camera
    validate_camera(cam, src)
    eye = np.asarray(cam.eye, np.float64)
    r = scene.render
    ambient = _check_vector(src, "render.ambient", r.ambient, nonneg=True)
    background = _check_vector(src, "render.background", r.background, nonneg=True)
    for name, lo, hi in (("max_depth", 1, 1024), ("spp", 1, 4096)):
        v = getattr(r, name)
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= v <= hi:
            raise SceneError(src, f"render.{name}", f"expected an integer in [{lo}, {hi}], got {_show(v)}")
    if math.isqrt(r.spp) ** 2 != r.spp:
        raise SceneError(src, "render.spp", f"expected a square number of samples (1, 4, 9, ...), got {r.spp}")
    light_max = np.zeros(3)
    for i, light in enumerate(scene.lights):
        position = _check_vector(src, f"lights[{i}].position", light.position)
        light_max = light_max + _check_vector(src, f"lights[{i}].color", light.color, nonneg=True)
        if np.abs(position - eye).max() > MAX_REACH:
            raise SceneError(src, f"lights[{i}].position", f"is more than {MAX_REACH:g} from camera.eye; "
                                                           "float32 ray tests cannot reach it")
    lit_max, kr_max, coef_max = np.zeros(3), 0.0, 0.0
    for name, m in scene.materials.items():
        for key in ("kd", "ks", "reflectivity") + (("ka",) if m.ka is not None else ()):
            _check_vector(src, f"materials.{name}.{key}", getattr(m, key), nonneg=True)
        _check_number(src, f"materials.{name}.shininess", m.shininess)
        lit = ambient * np.asarray(m.ka_) + light_max * (np.asarray(m.kd) + np.asarray(m.ks))
        lit_max = np.maximum(lit_max, lit)
        kr_max = max(kr_max, float(np.max(m.reflectivity)))
        coef_max = max(coef_max, float(np.max(np.asarray(m.kd) + np.asarray(m.ks))), float(np.max(m.ka_)))
    for i, obj in enumerate(scene.objects):
        where = f"objects[{i}]"
        v = np.asarray(obj.vertices)
        f = np.asarray(obj.faces)
        if v.ndim != 2 or v.shape[1:] != (3,) or not np.all(np.isfinite(v)):
            raise SceneError(src, f"{where}.vertices", f"expected (N, 3) finite coordinates ('{obj.name}')")
        if f.ndim != 2 or f.shape[1:] != (3,) or f.dtype.kind not in "iu" or len(f) == 0 or f.min() < 0 or f.max() >= len(v):
            raise SceneError(src, f"{where}.faces", f"expected (M, 3) vertex indices in [0, {len(v) - 1}] ('{obj.name}')")
        if obj.material not in scene.materials:
            raise SceneError(src, f"{where}.material", f"no material named '{obj.material}'")
        if len(v) and np.abs(v - eye).max() > MAX_REACH:
            raise SceneError(src, where, f"'{obj.name}' reaches more than {MAX_REACH:g} from "
                                                       "camera.eye; float32 ray tests cannot reach it")
    # The brightest possible pixel: every level of the mirror series fully lit, then the background.
    depth = r.max_depth
    grows = kr_max > 1.0 and depth * math.log(kr_max) > 700.0  # kr^depth beyond float64
    if grows:
        bound = math.inf
    else:
        series = float(depth) if kr_max == 1.0 else (kr_max**depth - 1.0) / (kr_max - 1.0)
        bound = float(np.max(lit_max)) * series + float(np.max(background)) * kr_max ** (depth - 1)
    if not bound < FLOAT32_MAX / 16:
        if kr_max > 1.0:
            raise SceneError(src, "render.max_depth", f"with reflectivity up to {kr_max:g} (> 1) light grows by that "
                                                      f"factor per bounce and {depth} levels overflow float32")
        field_name = "lights" if float(np.max(light_max)) >= coef_max else "materials"
        raise SceneError(src, field_name, f"colours and light intensities this large (a pixel could reach "
                                          f"{bound:.3g}) overflow float32")


def read_render(source: str, t: dict) -> RenderSettings:
    r = _Reader(source, t, "render")
    r.check_keys(_RENDER_KEYS)
    d = RenderSettings()
    spp = r.integer("spp", d.spp, lo=1, hi=4096)
    k = math.isqrt(spp)
    if k * k != spp:
        r.fail("spp", f"expected a square number of samples (k*k stratified: 1, 4, 9, 16, ...), got {spp}")
    effects = t.get("effects")
    if effects is not None:
        if not isinstance(effects, list) or not all(isinstance(e, str) for e in effects):
            r.fail("effects", f"expected a list of effect names, got {_show(effects)}")
        effects = tuple(effects)
    return RenderSettings(
        ambient=r.vector("ambient", d.ambient, nonneg=True),
        background=r.vector("background", d.background, nonneg=True),
        max_depth=r.integer("max_depth", d.max_depth, lo=1, hi=1024),
        shadows=r.boolean("shadows", d.shadows),
        spp=spp,
        effects=effects,
    )


def read_light(source: str, t: dict, i: int) -> Light:
    r = _Reader(source, t, f"lights[{i}]")
    r.check_keys(_LIGHT_KEYS)
    return Light(position=r.vector("position"), color=r.vector("color", (1.0, 1.0, 1.0), nonneg=True))


def read_material(source: str, name: str, t) -> Material:
    if not isinstance(t, dict):
        raise SceneError(source, f"materials.{name}", f"expected a table, got {_show(t)}")
    r = _Reader(source, t, f"materials.{name}")
    r.check_keys(_MATERIAL_KEYS)
    kd = r.vector("kd", DEFAULT_MATERIAL.kd, nonneg=True)
    return Material(
        kd=kd,
        ka=r.vector("ka", kd, nonneg=True),
        ks=r.vector("ks", (0.0, 0.0, 0.0), nonneg=True),
        shininess=r.number("shininess", 32.0, lo=0.0),
        reflectivity=r.vector("reflectivity", (0.0, 0.0, 0.0), nonneg=True, allow_scalar=True),
    )


def _rotation(degrees) -> np.ndarray:
    """Rotation about x, then y, then z (R = Rz Ry Rx), angles in degrees."""
    ax, ay, az = np.radians(degrees)
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _shape_geometry(r: _Reader, kind: str):
    builder, params = shapes.SHAPES[kind]
    r.check_keys(_OBJECT_KEYS | set(params))
    args = {}
    for p, (ptype, default) in params.items():
        if ptype == "positive":
            args[p] = r.number(p, default, lo=0.0, lo_open=True)
        elif ptype.startswith("int"):
            lo = int(ptype[3:])
            if isinstance(default, list):
                v = r.vector(p, default, n=2)
                if any(x != int(x) or x < 3 for x in v):
                    r.fail(p, f"expected 2 integers >= 3, got {list(v)}")
                args[p] = tuple(int(x) for x in v)
            else:
                args[p] = r.integer(p, default, lo=lo, hi=8 if p == "subdivisions" else 100000)
        elif ptype in ("size3", "size2"):
            v = r.vector(p, default, n=int(ptype[-1]), allow_scalar=True)
            if min(v) <= 0:
                r.fail(p, f"expected positive sizes, got {list(v)}")
            args[p] = v
        elif ptype == "points":
            v = r.table.get(p)
            try:
                a = np.asarray(v, np.float64)
            except (TypeError, ValueError):
                a = None
            if a is None or a.ndim != 2 or a.shape[1] != 3 or len(a) < 3:
                r.fail(p, f"expected a list of [x, y, z] points (at least 3), got {_show(v)}")
            if not np.all(np.isfinite(a)):
                r.fail(p, "expected finite coordinates, found NaN or Inf")
            args[p] = a
        elif ptype == "faces":
            v = r.table.get(p)
            try:
                a = np.asarray(v)
            except (TypeError, ValueError):
                a = None
            if a is None or a.ndim != 2 or a.shape[1] != 3 or len(a) < 1 or a.dtype.kind not in "iu":
                r.fail(p, f"expected a list of [i, j, k] integer vertex indices, got {_show(v)}")
            args[p] = a.astype(np.int64)
    return builder(**args)


def _load_mesh_file(source: str, field_name: str, path: Path):
    """The file's parts and materials (meshio.MeshFile); its errors name the scene field too."""
    from . import meshio

    try:
        return meshio.read_mesh_file(path)
    except SceneError as e:
        raise SceneError(source, field_name, str(e)) from None
    except Exception as e:  # a reader's own failure on a damaged file
        raise SceneError(source, field_name, f"{path}: cannot read mesh file: {' '.join(str(e).split())}") from None


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
        from .normals import vertex_normals

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


def read_object(source: str, base: Path, t: dict, i: int, materials: dict) -> list[SceneObject]:
    """An [[objects]] table: one SceneObject, or one per material for a file with several."""
    r = _Reader(source, t, f"objects[{i}]")
    if ("mesh" in t) == ("shape" in t):
        r.fail(None, "expected exactly one of 'mesh' (a file) or 'shape' (" + ", ".join(shapes.SHAPES) + ")")
    mesh = None
    if "mesh" in t:
        r.check_keys(_OBJECT_KEYS)
        path = base / r.string("mesh")
        mesh = _load_mesh_file(source, f"objects[{i}].mesh", path)
        vertices, faces, face_material, part_starts = mesh.concatenated()
        default_name = path.stem
    else:
        kind = r.string("shape")
        if kind not in shapes.SHAPES:
            close = difflib.get_close_matches(kind, list(shapes.SHAPES), n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            r.fail("shape", f"unknown shape '{kind}'{hint}; expected one of: {', '.join(shapes.SHAPES)}")
        vertices, faces = _shape_geometry(r, kind)
        default_name = kind
    material = r.string("material", "default")
    if material not in materials:
        close = difflib.get_close_matches(material, list(materials), n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else f" (defined: {', '.join(materials) or 'none'})"
        r.fail("material", f"no material named '{material}'{hint}")
    scale = np.asarray(r.vector("scale", 1.0, allow_scalar=True))
    if np.any(scale == 0.0):
        r.fail("scale", f"expected non-zero scale factors, got {list(scale)}")
    rot = _rotation(r.vector("rotate", (0.0, 0.0, 0.0)))
    translate = np.asarray(r.vector("translate", (0.0, 0.0, 0.0)))
    if len(faces) == 0:
        r.fail("mesh" if "mesh" in t else "shape", "the mesh has no triangles")
    if faces.min() < 0 or faces.max() >= len(vertices):
        r.fail("faces" if "shape" in t else "mesh", f"vertex index out of range [0, {len(vertices) - 1}]")
    world = (vertices * scale) @ rot.T + translate
    if np.linalg.det(np.diag(scale)) < 0:  # a mirroring scale flips the winding; keep faces outward
        faces = faces[:, ::-1]
    name, smooth = r.string("name", default_name), r.boolean("smooth", False)
    world, faces = np.ascontiguousarray(world, np.float64), np.ascontiguousarray(faces, np.int64)
    if mesh is not None and "material" not in t and mesh.materials:
        # The file's own materials, unless the scene file names one for the object.
        return split_by_material(name, world, faces, face_material, mesh.materials, materials,
                                 material, smooth, part_starts)
    return [SceneObject(name=name, vertices=world, faces=faces, material=material, smooth=smooth)]


def scene_from_dict(data: dict, source: str = "<scene>", base: Path | None = None) -> Scene:
    """Build and validate a Scene from a parsed TOML document."""
    base = Path(base) if base is not None else Path(".")
    for key in data:
        if key not in _SECTIONS:
            close = difflib.get_close_matches(key, sorted(_SECTIONS), n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else f" (expected: {', '.join(sorted(_SECTIONS))})"
            raise SceneError(source, key, f"unknown section{hint}")
    camera = read_camera(source, _table(source, data, "camera"))
    render = read_render(source, _table(source, data, "render"))
    lights = [read_light(source, t, i) for i, t in enumerate(_array_of_tables(source, data, "lights"))]
    materials = {"default": DEFAULT_MATERIAL}
    for name, t in _table(source, data, "materials").items():
        materials[name] = read_material(source, name, t)
    objects = [o for i, t in enumerate(_array_of_tables(source, data, "objects"))
               for o in read_object(source, base, t, i, materials)]
    scene = Scene(camera, render, lights, materials, objects, source)
    validate_scene(scene)  # what needs the whole scene: reach from the eye, float32 overflow
    return scene


def apply_overrides(data: dict, overrides: dict, source: str) -> dict:
    """Set dotted keys ("camera.width", "lights[0].color") on a parsed document before validation."""
    for key, value in overrides.items():
        node, parts = data, key.split(".")
        for j, part in enumerate(parts):
            name, index = part, None
            if part.endswith("]") and "[" in part:
                name, idx = part[:-1].split("[", 1)
                if not idx.isdigit():
                    raise SceneError(source, key, "expected an index like lights[0]")
                index = int(idx)
            last = j == len(parts) - 1
            if index is None:
                if last:
                    node[name] = value
                else:
                    node = node.setdefault(name, {})
                    if not isinstance(node, dict):
                        raise SceneError(source, key, f"'{name}' is not a table")
            else:
                arr = node.get(name)
                if not isinstance(arr, list) or index >= len(arr):
                    raise SceneError(source, key, f"there is no {name}[{index}]")
                if last:
                    arr[index] = value
                else:
                    node = arr[index]
    return data


def load_scene(path=None, overrides: dict | None = None) -> Scene:
    """Read a scene: a TOML scene file, any mesh file trimesh reads (framed automatically),
    or None for the built-in default scene."""
    t = time.perf_counter()
    scene = _load_scene(path, overrides)
    scene.load_seconds = time.perf_counter() - t
    return scene


def _load_scene(path, overrides) -> Scene:
    if path is None:
        path = default_scene_path()
    path = Path(path)
    source = str(path)
    if path.suffix.lower() != ".toml":
        from .autoframe import scene_for_mesh
        from .meshio import FORMATS, is_mesh_path

        if path.is_dir():
            raise SceneError(source, None, "is a folder; expected a scene file (.toml) or a mesh file")
        if not is_mesh_path(path):
            raise SceneError(source, None, f"unknown file type '{path.suffix or '(none)'}'; expected a scene file "
                                           f"(.toml) or a mesh file ({', '.join(FORMATS)})")
        scene = scene_for_mesh(path)
        if overrides:
            raise SceneError(source, None, "--set applies to TOML scene files only")
        return scene
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SceneError(source, None, "scene file not found") from None
    except IsADirectoryError:
        raise SceneError(source, None, "is a folder, not a scene file") from None
    except UnicodeDecodeError as e:
        line = e.object[:e.start].count(b"\n") + 1
        raise SceneError(source, None, f"not UTF-8 text (byte 0x{e.object[e.start]:02x} on line {line}); "
                                       "a TOML file must be UTF-8") from None
    except OSError as e:
        raise SceneError(source, None, f"cannot read scene file: {e.strerror or e}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SceneError(source, None, f"malformed TOML: {e}") from None
    if overrides:
        data = apply_overrides(data, overrides, source)
    return scene_from_dict(data, source, path.parent)


def default_scene_path() -> Path:
    return Path(__file__).parent / "data" / "default.toml"
