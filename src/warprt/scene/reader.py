"""The TOML scene file to a Scene: typed access to each table, with every error naming the file and
the dotted field in the file's own vocabulary (``camera.fovy``, ``objects[2].mesh``)."""

from __future__ import annotations

import difflib
import math
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..diagnostics import warn
from ..errors import SceneError, one_line, show
from . import shapes
from .camera import aspect_note, find_camera
from .dielectric import warn_unclosed
from .meshio import file_objects, read_mesh_file, warn_if_tiny, warn_if_unmapped
from .model import DEFAULT_MATERIAL, FALLOFFS, LIGHT_TYPES, Camera, Light, Material, RenderSettings, Scene, SceneObject
from .normals import resolve_normals
from .texture import affine, checker_texture, image_texture
from .validate import check_setting, validate_camera, validate_scene

SECTIONS = {"camera", "render", "lights", "materials", "objects"}
_CAMERA_KEYS = {"eye", "center", "up", "fovy", "near", "width", "height"}
_RENDER_KEYS = {"ambient", "background", "max_depth", "shadows", "spp", "effects"}
_LIGHT_KEYS = {"type", "position", "color", "direction", "target", "cutoff_angle", "beam_width", "falloff"}
_SPOT_KEYS = ("target", "cutoff_angle", "beam_width")  # meaningful only for a spot
_MATERIAL_KEYS = {"ka", "kd", "ks", "shininess", "reflectivity", "ka_texture", "kd_texture", "ks_texture", "ior",
                  "transmittance", "absorption", "double_sided"}
_DIELECTRIC_KEYS = ("transmittance", "absorption")  # meaningful only with an ior
_TEXTURE_KEYS = {"image", "checker", "scale", "offset", "srgb"}
_OBJECT_KEYS = {"name", "mesh", "shape", "material", "scale", "rotate", "translate", "smooth", "up"}
UP_AXES = ("x", "y", "z", "-x", "-y", "-z")


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
            self.fail(key, f"expected a number, got {show(v)}")
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
            self.fail(key, f"expected an integer, got {show(v)}")
        if (lo is not None and v < lo) or (hi is not None and v > hi):
            self.fail(key, f"expected an integer in [{lo}, {hi}], got {v}")
        return int(v)

    def boolean(self, key, default):
        v = self.table.get(key, default)
        if not isinstance(v, bool):
            self.fail(key, f"expected true or false, got {show(v)}")
        return v

    def string(self, key, default=None):
        v = self.table.get(key, default)
        if v is None:
            self.fail(key, "is required")
        if not isinstance(v, str):
            self.fail(key, f"expected a string, got {show(v)}")
        return v

    def choice(self, key, allowed: tuple, default=None) -> str:
        v = self.string(key, default)
        if v not in allowed:
            self.fail(key, f"expected one of {', '.join(map(repr, allowed))}, got {show(v)}")
        return v

    def vector(self, key, default=None, n=3, nonneg=False, allow_scalar=False):
        v = self.table.get(key, default)
        if v is None:
            self.fail(key, "is required")
        if allow_scalar and isinstance(v, (int, float)) and not isinstance(v, bool):
            v = [v] * n
        if not isinstance(v, (list, tuple)) or len(v) != n:
            what = f"a number or a list of {n} numbers" if allow_scalar else f"a list of {n} numbers"
            self.fail(key, f"expected {what}, got {show(v)}")
        out = []
        for x in v:
            if isinstance(x, bool) or not isinstance(x, (int, float)):
                self.fail(key, f"expected a list of {n} numbers, got {show(v)}")
            if not math.isfinite(x):
                self.fail(key, f"expected finite numbers, got {show(v)}")
            if nonneg and x < 0:
                self.fail(key, f"expected non-negative numbers, got {show(v)}")
            out.append(float(x))
        return tuple(out)


def _table(source, data, key, prefix=None) -> dict:
    v = data.get(key, {})
    if not isinstance(v, dict):
        raise SceneError(source, prefix or key, f"expected a table, got {show(v)}")
    return v


def _array_of_tables(source, data, key) -> list:
    v = data.get(key, [])
    if not isinstance(v, list) or not all(isinstance(t, dict) for t in v):
        raise SceneError(source, key, f"expected an array of tables ([[{key}]]), got {show(v)}")
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
        width=check_setting(source, "camera.width", "camera.width", r.integer("width", d.width)),
        height=check_setting(source, "camera.height", "camera.height", r.integer("height", d.height)),
    )
    validate_camera(cam, source)
    return cam


class _CameraFile(NamedTuple):
    files: tuple = ()  # the model file camera.from names
    cameras: tuple = ()  # its cameras (FileCamera), for `warprt info`


def _file_camera(source: str, t: dict, base: Path):
    """The [camera] table with ``from`` (a model file: glTF, USD) and ``name`` (one of its cameras, by name
    or index; default its first) as that camera's fields, placed as an object of the file is by default,
    the table's own fields over them; the file camera and its file."""
    if "from" not in t:
        if "name" in t:
            raise SceneError(source, "camera.name", "names a camera of a model file: give the file as camera.from")
        return t, None, _CameraFile()
    r = _Reader(source, t, "camera")
    path = base / r.string("from")
    choice = t.get("name")
    if choice is not None and (isinstance(choice, bool) or not isinstance(choice, (str, int))):
        r.fail("name", f"expected a camera's name or index, got {show(choice)}")
    mesh = _load_mesh_file(source, "camera.from", path)
    try:
        cam = find_camera(mesh.cameras, choice)
    except LookupError as e:
        raise SceneError(source, "camera.name" if choice is not None else "camera.from", f"{path}: {e}") from None
    # Where an [[objects]] entry places the file by default: its up axis turned to y (a z-up USD stage), no
    # more (an object's own scale, rotate and translate are that object's, not the file's).
    turn = up_rotation(mesh.up_axis or "y")
    placed = {k: [float(x) for x in turn @ np.asarray(v, np.float64)] if k in ("eye", "center", "up") else v
              for k, v in cam.fields(_middle(mesh)).items()}
    own = {k: v for k, v in t.items() if k not in ("from", "name")}
    return {**placed, **own}, cam, _CameraFile((path,), tuple(mesh.cameras))


def _middle(mesh) -> np.ndarray:
    """The centre of a file's bounding box, in the file's space."""
    vertices = np.concatenate([p.vertices for p in mesh.parts])
    return 0.5 * (vertices.min(0) + vertices.max(0))


def read_render(source: str, t: dict) -> RenderSettings:
    r = _Reader(source, t, "render")
    r.check_keys(_RENDER_KEYS)
    d = RenderSettings()
    spp = check_setting(source, "render.spp", "render.spp", r.integer("spp", d.spp))
    effects = t.get("effects")
    if effects is not None:
        if not isinstance(effects, list) or not all(isinstance(e, str) for e in effects):
            r.fail("effects", f"expected a list of effect names, got {show(effects)}")
        effects = tuple(effects)
    return RenderSettings(
        ambient=r.vector("ambient", d.ambient, nonneg=True),
        background=r.vector("background", d.background, nonneg=True),
        max_depth=check_setting(source, "render.max_depth", "render.max_depth", r.integer("max_depth", d.max_depth)),
        shadows=r.boolean("shadows", d.shadows),
        spp=spp,
        effects=effects,
    )


def read_light(source: str, t: dict, i: int) -> Light:
    r = _Reader(source, t, f"lights[{i}]")
    r.check_keys(_LIGHT_KEYS)
    kind = r.choice("type", LIGHT_TYPES, "point")
    for key in _SPOT_KEYS:
        if key in t and kind != "spot":
            r.fail(key, f"only a spot light has it (this light's type is {kind})")
    if kind == "directional":
        if "position" in t:
            r.fail("position", "a directional light has no position (it is infinitely far): give only its direction")
        position = None
    else:
        position = r.vector("position")
    if kind == "point" and "direction" in t:
        r.fail("direction", "a point light shines in every direction: a cone is a spot (type = \"spot\")")
    if "direction" in t and "target" in t:
        r.fail("target", "give direction or target, not both")
    direction = None
    if "target" in t:
        direction = tuple(np.subtract(r.vector("target"), position))
        if not any(direction):
            r.fail("target", "must differ from position (the spot's axis runs from position to target)")
    elif kind != "point":
        direction = r.vector("direction")
    d = Light()
    cutoff = r.number("cutoff_angle", d.cutoff_angle, lo=0.0, hi=180.0, lo_open=True, hi_open=True)
    beam = r.number("beam_width", lo=0.0, hi=cutoff) if "beam_width" in t else None
    return Light(position=position, color=r.vector("color", d.color, nonneg=True), type=kind, direction=direction,
                 cutoff_angle=cutoff, beam_width=beam, falloff=r.choice("falloff", FALLOFFS, d.falloff))


def read_material(source: str, name: str, t, base: Path = Path(".")) -> Material:
    """A [materials.name] table. A colour with a texture is the texture times the colour, which then
    defaults to 1; ka defaults to kd, with kd's texture."""
    if not isinstance(t, dict):
        raise SceneError(source, f"materials.{name}", f"expected a table, got {show(t)}")
    r = _Reader(source, t, f"materials.{name}")
    r.check_keys(_MATERIAL_KEYS)
    tex = {k: read_texture(source, f"materials.{name}.{k}_texture", t[f"{k}_texture"], base)
           for k in ("ka", "kd", "ks") if f"{k}_texture" in t}
    white = (1.0, 1.0, 1.0)
    kd = r.vector("kd", white if "kd" in tex else DEFAULT_MATERIAL.kd, nonneg=True)
    if "ka" in t or "ka" in tex:
        ka, ka_texture = r.vector("ka", white, nonneg=True), tex.get("ka")
    else:
        ka, ka_texture = kd, tex.get("kd")
    reflectivity = r.vector("reflectivity", (0.0, 0.0, 0.0), nonneg=True, allow_scalar=True)
    ior, dielectric = None, {}
    if "ior" in t:
        ior = r.number("ior", lo=0.0, lo_open=True)
        if max(reflectivity) > 0.0:
            r.fail("reflectivity", "a dielectric (ior) reflects by its Fresnel term; reflectivity must be 0")
        transmittance = r.vector("transmittance", (1.0, 1.0, 1.0), nonneg=True, allow_scalar=True)
        if max(transmittance) > 1.0:
            r.fail("transmittance", f"expected values in [0, 1], got {list(transmittance)}")
        dielectric = {"transmittance": transmittance,
                      "absorption": r.vector("absorption", (0.0, 0.0, 0.0), nonneg=True, allow_scalar=True)}
    else:
        for key in _DIELECTRIC_KEYS:
            if key in t:
                r.fail(key, "only a dielectric has it: give the material an ior")
    return Material(
        kd=kd,
        ka=ka,
        ks=r.vector("ks", white if "ks" in tex else (0.0, 0.0, 0.0), nonneg=True),
        shininess=r.number("shininess", 32.0, lo=0.0),
        reflectivity=reflectivity,
        kd_texture=tex.get("kd"), ka_texture=ka_texture, ks_texture=tex.get("ks"),
        ior=ior,
        double_sided=r.boolean("double_sided", True),
        **dielectric,
    )


def read_texture(source: str, field: str, value, base: Path):
    """``"file.png"``, ``{image = "file.png", scale = ..., offset = [u, v], srgb = ...}`` or
    ``{checker = [[r, g, b], [r, g, b]], scale = ...}``: the uv map is uv * scale + offset; an image
    repeats once per unit of mapped uv, a checker has one check per unit."""
    given_as_name = isinstance(value, str)
    if given_as_name:
        value = {"image": value}
    if not isinstance(value, dict):
        raise SceneError(source, field, f"expected an image file name or a table with 'image' or 'checker', got {show(value)}")
    r = _Reader(source, value, field)
    r.check_keys(_TEXTURE_KEYS)
    if ("image" in value) == ("checker" in value):
        r.fail(None, "expected exactly one of 'image' (a file) or 'checker' (two colours)")
    scale = r.vector("scale", 1.0, n=2, allow_scalar=True)
    if 0.0 in scale:
        r.fail("scale", f"expected non-zero scale factors, got {list(scale)}")
    offset = r.vector("offset", (0.0, 0.0), n=2)
    if "checker" in value:
        c = value["checker"]
        if "srgb" in value:
            r.fail("srgb", "applies to an image, not to a checker")
        if not (isinstance(c, list) and len(c) == 2):
            r.fail("checker", f"expected two colours [[r, g, b], [r, g, b]], got {show(c)}")
        colours = [_Reader(source, {"checker": x}, field).vector("checker", nonneg=True) for x in c]
        return checker_texture(colours[0], colours[1], scale, offset)
    srgb = r.boolean("srgb", True) if "srgb" in value else None
    name = r.string("image")
    try:
        return image_texture(base / name, srgb=srgb, source=name, uv_transform=affine(scale, offset))
    except SceneError as e:
        raise SceneError(source, field if given_as_name else f"{field}.image", str(e)) from None


def rotation(degrees) -> np.ndarray:
    """Rotation about x, then y, then z (R = Rz Ry Rx), angles in degrees."""
    ax, ay, az = np.radians(degrees)
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _shape_geometry(r: _Reader, kind: str, with_uv: bool):
    """The shape's vertices, faces and, where it has them, uv (for a textured material) and colours."""
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
        elif ptype in ("points", "uv", "colors"):
            if p not in r.table and ptype != "points":
                continue
            width = 2 if ptype == "uv" else 3
            v = r.table.get(p)
            try:
                a = np.asarray(v, np.float64)
            except (TypeError, ValueError):
                a = None
            what = {"points": "[x, y, z] points (at least 3)", "uv": "[u, v] per vertex",
                    "colors": "[r, g, b] per vertex"}[ptype]
            if a is None or a.ndim != 2 or a.shape[1] != width or len(a) < (3 if ptype == "points" else 1):
                r.fail(p, f"expected a list of {what}, got {show(v)}")
            if not np.all(np.isfinite(a)):
                r.fail(p, "expected finite numbers, found NaN or Inf")
            if ptype == "colors" and (a < 0).any():
                r.fail(p, "expected non-negative colours")
            args[p] = a
        elif ptype == "faces":
            v = r.table.get(p)
            try:
                a = np.asarray(v)
            except (TypeError, ValueError):
                a = None
            if a is None or a.ndim != 2 or a.shape[1] != 3 or len(a) < 1 or a.dtype.kind not in "iu":
                r.fail(p, f"expected a list of [i, j, k] integer vertex indices, got {show(v)}")
            args[p] = a.astype(np.int64)
    uv = colors = None
    if kind == "triangles":
        n = len(args["vertices"])
        for key in ("uv", "colors"):
            if key in args and len(args[key]) != n:
                r.fail(key, f"expected one per vertex ({n}), got {len(args[key])}")
        uv, colors = args.pop("uv", None), args.pop("colors", None)
    elif with_uv and kind in shapes.WITH_UV:
        return (*shapes.WITH_UV[kind](**args), None)
    vertices, faces = builder(**args)
    return vertices, faces, uv, colors


def _load_mesh_file(source: str, field_name: str, path: Path):
    """The file's parts and materials (meshio.MeshFile); its errors name the scene field too."""
    try:
        return read_mesh_file(path)
    except SceneError as e:
        raise SceneError(source, field_name, str(e)) from None
    except Exception as e:  # a reader's own failure on a damaged file
        raise SceneError(source, field_name, f"{path}: cannot read mesh file: {one_line(e)}") from None


def up_rotation(axis: str) -> np.ndarray:
    """The rotation (det +1) that turns a file's up direction ("x", "-z", ...) to +y, warprt's up."""
    return _UP_TO_Y[axis.lower()]


_UP_TO_Y = {
    "y": np.eye(3),
    "-y": np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]),  # 180 degrees about x
    "z": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]),  # -90 about x: z -> y, y -> -z
    "-z": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]),  # +90 about x
    "x": np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),  # +90 about z: x -> y, y -> -x
    "-x": np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),  # -90 about z
}


def read_smooth(r: _Reader, key: str = "smooth", default=False):
    """true, false, "auto" or a crease angle in degrees (0 to 180)."""
    v = r.table.get(key, default)
    if isinstance(v, bool) or v == "auto":
        return v
    if isinstance(v, (int, float)):
        return r.number(key, lo=0.0, hi=180.0)
    r.fail(key, f"expected true, false, \"auto\" or a crease angle in degrees, got {show(v)}")


def read_up(r: _Reader, key: str = "up", default: str = "y"):
    v = r.table.get(key, default)
    if not isinstance(v, str) or v.lower() not in UP_AXES:
        r.fail(key, f"expected one of {', '.join(repr(a) for a in UP_AXES)}, got {show(v)}")
    return v.lower()


def read_object(source: str, base: Path, t: dict, i: int, materials: dict) -> list[SceneObject]:
    """An [[objects]] table: one SceneObject, or one per material for a file with several."""
    r = _Reader(source, t, f"objects[{i}]")
    if ("mesh" in t) == ("shape" in t):
        r.fail(None, "expected exactly one of 'mesh' (a file) or 'shape' (" + ", ".join(shapes.SHAPES) + ")")
    material = r.string("material", "default")
    if material not in materials:
        close = difflib.get_close_matches(material, list(materials), n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else f" (defined: {', '.join(materials) or 'none'})"
        r.fail("material", f"no material named '{material}'{hint}")
    mesh = None
    if "mesh" in t:
        r.check_keys(_OBJECT_KEYS)
        path = base / r.string("mesh")
        mesh = _load_mesh_file(source, f"objects[{i}].mesh", path)
        default_name = path.stem
    else:
        kind = r.string("shape")
        if kind not in shapes.SHAPES:
            close = difflib.get_close_matches(kind, list(shapes.SHAPES), n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            r.fail("shape", f"unknown shape '{kind}'{hint}; expected one of: {', '.join(shapes.SHAPES)}")
        vertices, faces, uv, colors = _shape_geometry(r, kind, bool(materials[material].textures))
        default_name = kind
    scale = np.asarray(r.vector("scale", 1.0, allow_scalar=True))
    if np.any(scale == 0.0):
        r.fail("scale", f"expected non-zero scale factors, got {[float(x) for x in scale]}")
    rot = rotation(r.vector("rotate", (0.0, 0.0, 0.0)))
    translate = np.asarray(r.vector("translate", (0.0, 0.0, 0.0)))
    # By default the file's own up axis (a USD stage's upAxis, glTF's y), else y: as placed in the file.
    up = up_rotation(read_up(r, default=(mesh.up_axis or "y") if mesh is not None else "y"))
    name, smooth = r.string("name", default_name), read_smooth(r)
    turn = None if up is _UP_TO_Y["y"] else up

    def place(v):
        v = v if turn is None else v @ turn.T
        with np.errstate(over="ignore", invalid="ignore"):  # an absurd scale is reported here, once
            world = (v * scale) @ rot.T + translate
        if not np.all(np.isfinite(world)):
            r.fail("scale", f"scale [{', '.join(f'{x:g}' for x in scale)}], rotate and translate take the mesh "
                            "beyond the range of float64")
        return np.ascontiguousarray(world, np.float64)

    linear = rot @ np.diag(scale) @ (np.eye(3) if turn is None else turn)
    if mesh is not None:
        # The file's own materials, unless the scene file names one for the object.
        objects = file_objects(name, mesh, materials, material, smooth, place, linear,
                               use_file_materials="material" not in t)
    else:
        if len(faces) == 0:
            r.fail("shape", "the mesh has no triangles")
        if faces.min() < 0 or faces.max() >= len(vertices):
            r.fail("faces", f"vertex index out of range [0, {len(vertices) - 1}]")
        world = place(vertices)
        if np.prod(np.sign(scale)) < 0:  # a mirroring scale flips the winding; keep faces outward
            faces = faces[:, ::-1]
        faces = np.ascontiguousarray(faces, np.int64)
        shading = resolve_normals(world, faces, smooth)
        keep = shading.keep
        take = (lambda a: a if a is None or keep is None else np.ascontiguousarray(a[keep]))
        objects = [SceneObject(name=name, vertices=take(world), faces=shading.faces, material=material,
                               smooth=shading.smooth, normals=shading.normals, uv=take(uv), colors=take(colors))]
    for o in objects:
        warn_if_tiny(source, f"objects[{i}]", o.vertices)
    warn_if_unmapped(source, f"objects[{i}]", objects, materials,
                     f" (shapes with them: {', '.join(shapes.WITH_UV)}, triangles with uv)" if mesh is None else "")
    return objects


def scene_from_dict(data: dict, source: str = "<scene>", base: Path | None = None) -> Scene:
    """Build and validate a Scene from a parsed TOML document."""
    base = Path(base) if base is not None else Path(".")
    for key in data:
        if key not in SECTIONS:
            close = difflib.get_close_matches(key, sorted(SECTIONS), n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else f" (expected: {', '.join(sorted(SECTIONS))})"
            raise SceneError(source, key, f"unknown section{hint}")
    camera_table, file_camera, camera_file = _file_camera(source, _table(source, data, "camera"), base)
    camera = read_camera(source, camera_table)
    if file_camera is not None:
        note = aspect_note(file_camera, camera.width, camera.height)
        if note:
            warn(source, "camera.from", note)
    render = read_render(source, _table(source, data, "render"))
    lights = [read_light(source, t, i) for i, t in enumerate(_array_of_tables(source, data, "lights"))]
    materials = {"default": DEFAULT_MATERIAL}
    for name, t in _table(source, data, "materials").items():
        materials[name] = read_material(source, name, t, base)
    objects = [o for i, t in enumerate(_array_of_tables(source, data, "objects"))
               for o in read_object(source, base, t, i, materials)]
    meshes = tuple(base / t["mesh"] for t in _array_of_tables(source, data, "objects") if isinstance(t.get("mesh"), str))
    scene = Scene(camera, render, lights, materials, objects, source, files=meshes + camera_file.files,
                  cameras=camera_file.cameras)
    validate_scene(scene)  # what needs the whole scene: reach from the eye, float32 overflow
    warn_unclosed(scene)
    return scene


