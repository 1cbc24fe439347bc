"""The TOML scene file to a Scene, table by table (typed access: toml_fields.TableReader), with every error
naming the file and the dotted field in the file's own vocabulary (``camera.fovy``, ``objects[2].mesh``)."""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..diagnostics import warn
from ..errors import SceneError, one_line, show
from . import shapes
from .camera import aspect_note, find_camera
from .dielectric import warn_unclosed
from .meshio import file_objects, read_mesh_file, warn_if_tiny, warn_if_unmapped
from .model import AREA_ESTIMATORS, AREA_SHAPES, DEFAULT_MATERIAL, FALLOFFS, LIGHT_TYPES, Camera, Light, Material, RenderSettings, Scene, SceneObject
from .placement import PlacementOverflow, read_placement, read_smooth, shape_fields, up_rotation
from .texture import affine, checker_texture, image_texture
from .toml_fields import TableReader, did_you_mean
from .validate import check_setting, validate_camera, validate_scene

SECTIONS = {"camera", "render", "lights", "materials", "objects"}
_CAMERA_KEYS = {"eye", "center", "up", "fovy", "near", "width", "height"}
_RENDER_KEYS = {"ambient", "background", "max_depth", "shadows", "spp", "effects", "light_samples",
                "area_estimator", "light_spread", "adaptive"}
_LIGHT_KEYS = {"type", "position", "color", "direction", "target", "cutoff_angle", "beam_width", "falloff"}
_AREA_KEYS = {"type", "radiance", "shape", "object", "center", "normal", "u", "v", "size", "radius"}
_ENVIRONMENT_KEYS = {"type", "image", "radiance", "scale", "rotate"}
_SPOT_KEYS = ("target", "cutoff_angle", "beam_width")  # meaningful only for a spot
_MATERIAL_KEYS = {"ka", "kd", "ks", "shininess", "reflectivity", "ka_texture", "kd_texture", "ks_texture", "ior",
                  "transmittance", "absorption", "double_sided", "emission"}
_DIELECTRIC_KEYS = ("transmittance", "absorption")  # meaningful only with an ior
_TEXTURE_KEYS = {"image", "checker", "scale", "offset", "srgb"}


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
    r = TableReader(source, t, "camera")
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
    r = TableReader(source, t, "camera")
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
    r = TableReader(source, t, "render")
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
        light_samples=check_setting(source, "render.light_samples", "render.light_samples",
                                    r.integer("light_samples", d.light_samples)),
        adaptive=r.number("adaptive", d.adaptive, lo=0.0),
        area_estimator=r.choice("area_estimator", AREA_ESTIMATORS, d.area_estimator),
        light_spread=r.boolean("light_spread", d.light_spread),
    )


def read_light(source: str, t: dict, i: int, base: Path = Path(".")) -> Light:
    r = TableReader(source, t, f"lights[{i}]")
    kind = r.choice("type", LIGHT_TYPES, "point")
    if kind == "area":
        return read_area_light(r)
    if kind == "environment":
        return read_environment_light(r, base)
    r.check_keys(_LIGHT_KEYS)
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


def read_area_light(r: TableReader) -> Light:
    """A ``type = "area"`` light: the fields' types here, what goes with what in validate.py (for Python's
    Light too)."""
    r.check_keys(_AREA_KEYS, "key for an area light")
    t = r.table
    vectors = {k: r.vector(k) for k in ("center", "normal", "u", "v") if k in t}
    return Light(type="area", radiance=r.vector("radiance", nonneg=True),
                 shape=r.choice("shape", AREA_SHAPES) if "shape" in t else None,
                 object=r.string("object") if "object" in t else None,
                 size=r.vector("size", n=2, allow_scalar=True) if "size" in t else None,
                 radius=r.number("radius") if "radius" in t else None, **vectors)


def read_environment_light(r: TableReader, base: Path) -> Light:
    """A ``type = "environment"`` light: an equirectangular ``image`` (EXR or Radiance HDR, linear) or a
    constant ``radiance``, with its ``scale`` and ``rotate``; exactly one of image and radiance."""
    r.check_keys(_ENVIRONMENT_KEYS, "key for an environment light")
    t = r.table
    if ("image" in t) == ("radiance" in t):
        r.fail("image", "an environment light takes an image (an equirectangular EXR or HDR file) or a "
                        "constant radiance = [r, g, b], one of them")
    image = None
    if "image" in t:
        name = r.string("image")
        try:
            image = image_texture(base / name, source=name)
        except SceneError as e:
            r.fail("image", str(e))
    return Light(type="environment", image=image, radiance=r.vector("radiance", nonneg=True) if "radiance" in t else None,
                 scale=r.number("scale", 1.0, lo=0.0), rotate=r.vector("rotate", (0.0, 0.0, 0.0)))


def read_material(source: str, name: str, t, base: Path = Path(".")) -> Material:
    """A [materials.name] table. A colour with a texture is the texture times the colour, which then
    defaults to 1; ka defaults to kd, with kd's texture."""
    if not isinstance(t, dict):
        raise SceneError(source, f"materials.{name}", f"expected a table, got {show(t)}")
    r = TableReader(source, t, f"materials.{name}")
    r.check_keys(_MATERIAL_KEYS)
    tex = {k: read_texture(source, f"materials.{name}.{k}_texture", t[f"{k}_texture"], base)
           for k in ("ka", "kd", "ks") if f"{k}_texture" in t}
    d, white = Material(), (1.0, 1.0, 1.0)
    kd = r.vector("kd", white if "kd" in tex else d.kd, nonneg=True)
    if "ka" in t or "ka" in tex:
        ka, ka_texture = r.vector("ka", white, nonneg=True), tex.get("ka")
    else:  # left to Material: kd and its texture, followed when kd changes (Renderer.params)
        ka, ka_texture = None, None
    reflectivity = r.vector("reflectivity", d.reflectivity, nonneg=True, allow_scalar=True)
    ior, dielectric = None, {}
    if "ior" in t:
        ior = r.number("ior", lo=0.0, lo_open=True)
        if max(reflectivity) > 0.0:
            r.fail("reflectivity", "a dielectric (ior) reflects by its Fresnel term; reflectivity must be 0")
        transmittance = r.vector("transmittance", d.transmittance, nonneg=True, allow_scalar=True)
        if max(transmittance) > 1.0:
            r.fail("transmittance", f"expected values in [0, 1], got {list(transmittance)}")
        dielectric = {"transmittance": transmittance,
                      "absorption": r.vector("absorption", d.absorption, nonneg=True, allow_scalar=True)}
    else:
        for key in _DIELECTRIC_KEYS:
            if key in t:
                r.fail(key, "only a dielectric has it: give the material an ior")
    return Material(
        kd=kd,
        ka=ka,
        ks=r.vector("ks", white if "ks" in tex else d.ks, nonneg=True),
        shininess=r.number("shininess", d.shininess, lo=0.0),
        reflectivity=reflectivity,
        kd_texture=tex.get("kd"), ka_texture=ka_texture, ks_texture=tex.get("ks"),
        ior=ior,
        double_sided=r.boolean("double_sided", d.double_sided),
        emission=r.vector("emission", None, nonneg=True) if "emission" in t else None,
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
    r = TableReader(source, value, field)
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
        colours = [TableReader(source, {"checker": x}, field).vector("checker", nonneg=True) for x in c]
        return checker_texture(colours[0], colours[1], scale, offset)
    srgb = r.boolean("srgb", True) if "srgb" in value else None
    name = r.string("image")
    try:
        return image_texture(base / name, srgb=srgb, source=name, uv_transform=affine(scale, offset))
    except SceneError as e:
        raise SceneError(source, field if given_as_name else f"{field}.image", str(e)) from None


def _load_mesh_file(source: str, field_name: str, path: Path):
    """The file's parts and materials (meshio.MeshFile); its errors name the scene field too."""
    try:
        return read_mesh_file(path)
    except SceneError as e:
        raise SceneError(source, field_name, str(e)) from None
    except Exception as e:  # a reader's own failure on a damaged file
        raise SceneError(source, field_name, f"{path}: cannot read mesh file: {one_line(e)}") from None


def read_object(source: str, base: Path, t: dict, i: int, materials: dict) -> list[SceneObject]:
    """An [[objects]] table: one SceneObject, or one per material for a file with several."""
    r = TableReader(source, t, f"objects[{i}]")
    if ("mesh" in t) == ("shape" in t):
        r.fail(None, "expected exactly one of 'mesh' (a file) or 'shape' (" + ", ".join(shapes.SHAPES) + ")")
    material = r.string("material", "default")
    if material not in materials:
        defined = f" (defined: {', '.join(materials) or 'none'})"
        r.fail("material", f"no material named '{material}'{did_you_mean(material, materials, defined)}")
    if "mesh" in t:
        objects = _mesh_objects(r, base, material, materials)
    else:
        objects = [SceneObject(material=material, **shape_fields(r, bool(materials[material].textures)))]
    for o in objects:
        warn_if_tiny(source, f"objects[{i}]", o.vertices)
    warn_if_unmapped(source, f"objects[{i}]", objects, materials,
                     f" (shapes with them: {', '.join(shapes.WITH_UV)}, triangles with uv)" if "mesh" not in t else "")
    return objects


def _mesh_objects(r: TableReader, base: Path, material: str, materials: dict) -> list[SceneObject]:
    """The objects of a mesh file an [[objects]] table names, placed as the table says."""
    r.check_keys(shapes.OBJECT_KEYS)
    path = base / r.string("mesh")
    mesh = _load_mesh_file(r.source, f"{r.prefix}.mesh", path)
    # By default the file's own up axis (a USD stage's upAxis, glTF's y), else y: as placed in the file.
    placement = read_placement(r, mesh.up_axis or "y")
    name, smooth = r.string("name", path.stem), read_smooth(r)
    try:
        # The file's own materials, unless the scene file names one for the object.
        return file_objects(name, mesh, materials, material, smooth, placement,
                            use_file_materials="material" not in r.table)
    except PlacementOverflow as e:
        r.fail("scale", str(e))


def scene_from_dict(data: dict, source: str = "<scene>", base: Path | None = None) -> Scene:
    """Build and validate a Scene from a parsed TOML document."""
    base = Path(base) if base is not None else Path(".")
    listed = f" (expected: {', '.join(sorted(SECTIONS))})"
    for key in data:
        if key not in SECTIONS:
            raise SceneError(source, key, f"unknown section{did_you_mean(key, SECTIONS, listed)}")
    camera_table, file_camera, camera_file = _file_camera(source, _table(source, data, "camera"), base)
    camera = read_camera(source, camera_table)
    if file_camera is not None:
        note = aspect_note(file_camera, camera.width, camera.height)
        if note:
            warn(source, "camera.from", note)
    render = read_render(source, _table(source, data, "render"))
    lights = [read_light(source, t, i, base) for i, t in enumerate(_array_of_tables(source, data, "lights"))]
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


