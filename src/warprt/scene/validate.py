"""The checks render() relies on, for scenes read from files and built in Python alike: values in
range, geometry within float32 reach of the eye, an image that cannot overflow. Each failure is a
SceneError naming the field in the file's vocabulary, raised before any kernel runs."""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np

from ..errors import SceneError, show
from .model import AREA_ESTIMATORS, AREA_SHAPES, FALLOFFS, LIGHT_TYPES, Camera, Light, Scene
from .texture import Texture
from .toml_fields import did_you_mean

MAX_IMAGE_SIDE = 16384

# The integer settings and their ranges; a square spp (k*k stratified samples) on top.
SETTING_RANGES = {"camera.width": (1, MAX_IMAGE_SIDE), "camera.height": (1, MAX_IMAGE_SIDE),
                  "render.spp": (1, 4096), "render.max_depth": (1, 1024),
                  "render.light_samples": (1, 4096)}

# Warp's float32 ray-triangle test multiplies three coordinate differences (its T = U Az): for
# geometry 1e14 from the eye that overflows and triangles silently vanish (measured: a sphere of
# radius 1e13 seen from 5e13 renders, radius 1e14 from 5e14 does not). Scenes must stay within
# this reach of the eye.
MAX_REACH = 1e12
FLOAT32_MAX = float(np.finfo(np.float32).max)


def check_setting(source: str, field: str, key: str, v) -> int:
    """One integer setting of SETTING_RANGES (``key``, e.g. "render.spp"), reported as ``field``
    (the file's key, or the command-line flag that set it)."""
    lo, hi = SETTING_RANGES[key]
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= v <= hi:
        raise SceneError(source, field, f"expected an integer in [{lo}, {hi}], got {show(v)}")
    if key in ("render.spp", "render.light_samples") and math.isqrt(v) ** 2 != v:
        raise SceneError(source, field, f"expected a square number of samples (k*k stratified: 1, 4, 9, 16, ...), got {v}")
    return int(v)


def _is_real(v) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)


def _num(v) -> str:
    return f"{v:g}" if _is_real(v) else show(v)


def validate_camera(cam: Camera, source: str = "camera"):
    """The checks that need more than one field: a view direction, and an up not parallel to it."""
    eye, center, up = (np.asarray(v, np.float64) for v in (cam.eye, cam.center, cam.up))
    for name, v in (("eye", eye), ("center", center), ("up", up)):
        if v.shape != (3,) or not np.all(np.isfinite(v)):
            raise SceneError(source, f"camera.{name}", f"expected 3 finite numbers, got {v.tolist()}")
    if not _is_real(cam.fovy) or not (0.0 < cam.fovy < 180.0) or not math.isfinite(cam.fovy):
        raise SceneError(source, "camera.fovy", f"expected a number in (0, 180) degrees, got {_num(cam.fovy)}")
    if not _is_real(cam.near) or not (cam.near > 0.0) or not math.isfinite(cam.near):
        raise SceneError(source, "camera.near", f"expected a number > 0, got {_num(cam.near)}")
    for name in ("width", "height"):
        check_setting(source, f"camera.{name}", f"camera.{name}", getattr(cam, name))
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


def _check_vector(source, field_name, v, nonneg=False):
    a = np.asarray(v, np.float64) if v is not None else None
    if a is None or a.shape != (3,) or not np.all(np.isfinite(a)) or (nonneg and np.any(a < 0)):
        what = "3 finite non-negative numbers" if nonneg else "3 finite numbers"
        raise SceneError(source, field_name, f"expected {what}, got {show(v)}")
    return a


def _check_number(source, field_name, v, lo=0.0):
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) or not math.isfinite(v) or v < lo:
        raise SceneError(source, field_name, f"expected a finite number >= {lo:g}, got {show(v)}")


_checked_textures = weakref.WeakSet()  # a texture's image is checked once, not at every frame


def _check_texture(source, field_name, t):
    if t is None or t in _checked_textures:
        return
    if not isinstance(t, Texture):
        raise SceneError(source, field_name, f"expected a Texture, got {show(t)}")
    uv_map = np.asarray(t.uv_transform, np.float64)
    if uv_map.shape != (6,) or not np.all(np.isfinite(uv_map)):
        raise SceneError(source, field_name, f"expected a uv map of 6 finite numbers, got {show(t.uv_transform)}")
    if t.checker is not None:
        for c in t.checker:
            _check_vector(source, f"{field_name}.checker", c, nonneg=True)
    elif not (isinstance(t.image, np.ndarray) and t.image.ndim == 3 and t.image.shape[2] == 3 and t.image.size
              and np.all(np.isfinite(t.image)) and t.image.min() >= 0):
        raise SceneError(source, field_name, "expected an (H, W, 3) image of finite non-negative linear values")
    _checked_textures.add(t)
def _check_area_light(source, where, light, eye, objects):
    """An area light: a radiance >= 0 and either its own shape (a rectangle: u and v, or normal and size; a
    disk: normal and radius; a sphere: radius; each around center) or the name of objects of the scene, not both."""
    for key, v in (("position", light.position), ("direction", light.direction), ("beam_width", light.beam_width)):
        if v is not None:
            raise SceneError(source, f"{where}.{key}", "an area light has none: it emits from its shape or object")
    for key, default in (("color", Light.color), ("falloff", Light.falloff), ("cutoff_angle", Light.cutoff_angle)):
        if getattr(light, key) != default:
            raise SceneError(source, f"{where}.{key}", "an area light has none: its light is its radiance")
    if light.radiance is None:
        raise SceneError(source, f"{where}.radiance", "is required for an area light: L_e = [r, g, b]")
    _check_vector(source, f"{where}.radiance", light.radiance, nonneg=True)
    if (light.shape is None) == (light.object is None):
        raise SceneError(source, f"{where}.shape", "an area light takes a shape (\"rectangle\", \"disk\", \"sphere\") or "
                                                   "object = \"name\", one of the two")
    if light.object is not None:
        names = [o.name for o in objects]
        if light.object not in names:
            raise SceneError(source, f"{where}.object", f"no object named {show(light.object)}"
                                                        f"{did_you_mean(str(light.object), names, ' (objects: ' + ', '.join(map(repr, names)) + ')' if names else ' (the scene has no objects)')}")
        for key in ("center", "normal", "u", "v", "size", "radius"):
            if getattr(light, key) is not None:
                raise SceneError(source, f"{where}.{key}", "an area light on an object takes the object's triangles")
        return
    if light.shape not in AREA_SHAPES:
        raise SceneError(source, f"{where}.shape", f"expected one of {', '.join(map(repr, AREA_SHAPES))}, "
                                                   f"got {show(light.shape)}")
    center = _check_vector(source, f"{where}.center", light.center) if light.center is not None else np.zeros(3)
    _check_light_reach(source, where, center, eye, "center")
    own = {"rectangle": ("u", "v", "normal", "size"), "disk": ("normal", "radius"), "sphere": ("radius",)}[light.shape]
    for key in ("u", "v", "size", "radius", "normal"):
        if getattr(light, key) is not None and key not in own:
            raise SceneError(source, f"{where}.{key}", f"a {light.shape} has none")
    if light.shape == "sphere":
        if not _is_real(light.radius) or not math.isfinite(light.radius) or not light.radius > 0.0:
            raise SceneError(source, f"{where}.radius", f"expected a number > 0, got {_num(light.radius)}")
        return
    if light.shape == "rectangle" and (light.u is not None or light.v is not None):
        for key in ("u", "v"):
            if getattr(light, key) is None:
                raise SceneError(source, f"{where}.{key}", "a rectangle takes both half-edges u and v")
        if light.normal is not None or light.size is not None:
            raise SceneError(source, f"{where}.{'normal' if light.normal is not None else 'size'}",
                             "give u and v (the half-edges) or normal and size, not both")
        u = _check_vector(source, f"{where}.u", light.u)
        v = _check_vector(source, f"{where}.v", light.v)
        if not np.linalg.norm(np.cross(u, v)) > 0.0:
            raise SceneError(source, f"{where}.v", "u and v must span a rectangle (not zero, not parallel)")
        return
    if light.normal is None:
        raise SceneError(source, f"{where}.normal", f"is required for a {light.shape}" +
                         (" (or the half-edges u and v)" if light.shape == "rectangle" else ""))
    if not np.any(_check_vector(source, f"{where}.normal", light.normal)):
        raise SceneError(source, f"{where}.normal", "must not be the zero vector")
    if light.shape == "rectangle":
        size = np.asarray(light.size if light.size is not None else (), np.float64)
        if size.shape != (2,) or not np.all(np.isfinite(size)) or not np.all(size > 0):
            raise SceneError(source, f"{where}.size", f"expected a number > 0 or [width, height] > 0, got "
                                                      f"{show(light.size)}")
    elif not _is_real(light.radius) or not math.isfinite(light.radius) or not light.radius > 0.0:
        raise SceneError(source, f"{where}.radius", f"expected a number > 0, got {_num(light.radius)}")


def _check_environment_light(source, where, light) -> float:
    """An environment light: an image or a radiance (one of them), a scale >= 0, a rotation, nothing of the
    other lights'; returns the brightest radiance it gives (the image's or radiance's peak times scale)."""
    for key in ("position", "direction", "beam_width", "shape", "object", "center", "normal", "u", "v", "size", "radius"):
        if getattr(light, key) is not None:
            raise SceneError(source, f"{where}.{key}", "an environment light has none: it lies at infinity all round")
    for key, default in (("color", Light.color), ("falloff", Light.falloff), ("cutoff_angle", Light.cutoff_angle)):
        if getattr(light, key) != default:
            raise SceneError(source, f"{where}.{key}", "an environment light has none: its light is its image or radiance")
    if (light.image is None) == (light.radiance is None):
        raise SceneError(source, f"{where}.image", "an environment light takes an image or a radiance, one of them")
    if light.image is not None:
        _check_texture(source, f"{where}.image", light.image)
        if light.image.image is None or light.image.image.shape[0] < 3 or light.image.image.shape[1] < 2:
            raise SceneError(source, f"{where}.image", "expected an equirectangular image of at least 2 x 3 pixels")
    else:
        _check_vector(source, f"{where}.radiance", light.radiance, nonneg=True)
    _check_number(source, f"{where}.scale", light.scale)
    _check_vector(source, f"{where}.rotate", light.rotate)
    peak = (light.image.peak if light.image is not None else max(light.radiance)) * float(light.scale)
    if not peak < 1e30:
        raise SceneError(source, f"{where}.scale", f"the radiance it gives ({peak:g}) overflows float32")
    return peak


def _check_light(source, where, light, eye, objects=()):
    """A light of LIGHT_TYPES: a position where it has one (within float32 reach), a direction where it has
    one (not zero), a spot's cone (0 < beam_width <= cutoff_angle < 180 degrees), a falloff of FALLOFFS."""
    if light.type not in LIGHT_TYPES:
        raise SceneError(source, f"{where}.type", f"expected one of {', '.join(map(repr, LIGHT_TYPES))}, got {show(light.type)}")
    if light.type == "area":
        return _check_area_light(source, where, light, eye, objects)
    if light.type == "environment":
        return _check_environment_light(source, where, light)
    for key in ("image", "scale", "rotate"):
        if getattr(light, key) is not None:
            raise SceneError(source, f"{where}.{key}", f"only an environment light has it (this light's type is {light.type})")
    for key in ("radiance", "shape", "object", "center", "normal", "u", "v", "size", "radius"):
        if getattr(light, key) is not None:
            raise SceneError(source, f"{where}.{key}", f"only an area light has it (this light's type is {light.type})")
    if light.falloff not in FALLOFFS:
        raise SceneError(source, f"{where}.falloff", f"expected one of {', '.join(map(repr, FALLOFFS))}, "
                                                     f"got {show(light.falloff)}")
    if light.type == "directional":
        if light.position is not None:
            raise SceneError(source, f"{where}.position", "a directional light has no position (it is infinitely far)")
    else:
        _check_light_reach(source, where, _check_vector(source, f"{where}.position", light.position), eye)
    _check_vector(source, f"{where}.color", light.color, nonneg=True)
    if light.type == "point":
        if light.direction is not None:
            raise SceneError(source, f"{where}.direction", "a point light shines in every direction: a cone is a spot (type = \"spot\")")
    elif not np.any(_check_vector(source, f"{where}.direction", light.direction)):
        raise SceneError(source, f"{where}.direction", "must not be the zero vector")
    cutoff, beam = light.cutoff_angle, light.beam_width
    if light.type == "spot":
        if not _is_real(cutoff) or not 0.0 < cutoff < 180.0:
            raise SceneError(source, f"{where}.cutoff_angle", f"expected a number in (0, 180) degrees, got {_num(cutoff)}")
        if beam is not None and (not _is_real(beam) or not 0.0 <= beam <= cutoff):
            raise SceneError(source, f"{where}.beam_width", f"expected a number in [0, cutoff_angle = {cutoff:g}] "
                                                            f"degrees, got {_num(beam)}")
    else:
        for key, v, default in (("cutoff_angle", cutoff, Light.cutoff_angle), ("beam_width", beam, None)):
            if v != default:
                raise SceneError(source, f"{where}.{key}", f"only a spot light has it (this light's type is {light.type})")


def _check_light_reach(source, where, position, eye, key="position"):
    if np.abs(position - eye).max() > MAX_REACH:
        raise SceneError(source, f"{where}.{key}", f"is more than {MAX_REACH:g} from camera.eye; "
                                                      "float32 ray tests cannot reach it")


def _check_object_reach(source, i, name, lo, hi, eye):
    """|v - eye| over an object's vertices through their bounding box: the largest difference along an axis
    is at the box's low or high side, and float64 subtraction keeps that order, so the same value to the bit."""
    if max(np.abs(lo - eye).max(), np.abs(hi - eye).max()) > MAX_REACH:
        raise SceneError(source, f"objects[{i}]", f"'{name}' reaches more than {MAX_REACH:g} from "
                                                  "camera.eye; float32 ray tests cannot reach it")


def _check_dielectric(source, where, m):
    """ior > 0 makes a dielectric, whose reflection is its Fresnel term; k_t in [0, 1] and sigma >= 0
    belong to a dielectric only, and a dielectric is double-sided (its rays meet its back faces from inside)."""
    if not isinstance(m.double_sided, (bool, np.bool_)):
        raise SceneError(source, f"{where}.double_sided", f"expected true or false, got {_num(m.double_sided)}")
    if m.ior is not None and not m.double_sided:
        raise SceneError(source, f"{where}.double_sided", "a dielectric (ior) is seen from inside through its back "
                                                          "faces; double_sided must be true")
    if m.ior is None:
        if tuple(m.transmittance) != (1.0, 1.0, 1.0):
            raise SceneError(source, f"{where}.transmittance", "only a dielectric has it: give the material an ior")
        if np.any(np.asarray(m.absorption, np.float64) != 0.0):
            raise SceneError(source, f"{where}.absorption", "only a dielectric has it: give the material an ior")
        return
    if not _is_real(m.ior) or not math.isfinite(m.ior) or not m.ior > 0.0:
        raise SceneError(source, f"{where}.ior", f"expected a finite number > 0, got {_num(m.ior)}")
    if np.max(m.reflectivity) > 0.0:
        raise SceneError(source, f"{where}.reflectivity", "a dielectric (ior) reflects by its Fresnel term; "
                                                          "reflectivity must be 0")
    kt = _check_vector(source, f"{where}.transmittance", m.transmittance, nonneg=True)
    if kt.max() > 1.0:
        raise SceneError(source, f"{where}.transmittance", f"expected values in [0, 1], got {list(kt)}")
    _check_vector(source, f"{where}.absorption", m.absorption, nonneg=True)


@dataclass(frozen=True)
class CheckedContent:
    """What validate_scene learned of a scene's lights, materials and objects that the checks depending on
    the camera and the render settings read: validate_view re-checks a scene with other camera.* and render.*
    fields against it without looking at the content again."""

    lights: tuple  # (index, float64 position) of each light that has a position
    light_max: np.ndarray  # the lights' colours summed
    peaks: tuple  # (ka, kd, ks) peaks of each material, in order
    color_max: float  # the brightest vertex colour, at least 1
    kr_max: float
    coef_max: float
    objects: tuple  # (index, name, lowest and highest vertex coordinates) of each object with vertices


def validate_scene(scene: Scene) -> CheckedContent:
    """Everything render() relies on: finite values in range, geometry within float32 reach of the
    eye, and an image that cannot overflow. Returns what validate_view needs to re-check the scene
    with another camera or render settings."""
    src = scene.source
    cam = scene.camera
    validate_camera(cam, src)
    eye = np.asarray(cam.eye, np.float64)
    ambient, background = _check_render(src, scene.render)
    light_max, lights = np.zeros(3), []
    for i, light in enumerate(scene.lights):
        peak = _check_light(src, f"lights[{i}]", light, eye, scene.objects)
        # inverse_square: C_l / r^2 has no bound short of the nearest surface; C_l is the bound at r >= 1.
        # An area light's irradiance is at most pi L_e (the whole hemisphere), and its surface shows L_e;
        # an environment's at most pi times its brightest radiance.
        light_max = light_max + (np.pi * np.asarray(light.radiance, np.float64) if light.type == "area"
                                 else np.full(3, np.pi * peak) if light.environment
                                 else np.asarray(light.color, np.float64))
        if light.environment and any(other.environment for other in scene.lights[:i]):
            raise SceneError(src, f"lights[{i}].type", "a scene has at most one environment light")
        if light.environment and any(background):
            raise SceneError(src, "render.background", f"the environment light (lights[{i}]) is the background: "
                                                       "leave render.background out")
        if light.position is not None:
            lights.append((i, np.asarray(light.position, np.float64)))
    # Vertex colours multiply ka and kd: the brightest of them scales what a material can reflect.
    color_max = max([1.0] + [float(np.max(o.colors, initial=0.0)) for o in scene.objects
                             if getattr(o, "colors", None) is not None and np.all(np.isfinite(o.colors))])
    peaks, kr_max, coef_max = [], 0.0, 0.0
    for name, m in scene.materials.items():
        for key in ("kd", "ks", "reflectivity", "ka"):
            _check_vector(src, f"materials.{name}.{key}", getattr(m, key), nonneg=True)
        _check_number(src, f"materials.{name}.shininess", m.shininess)
        if m.emission is not None:
            _check_vector(src, f"materials.{name}.emission", m.emission, nonneg=True)
        for key in ("ka", "kd", "ks"):
            _check_texture(src, f"materials.{name}.{key}_texture", getattr(m, f"{key}_texture", None))
        _check_dielectric(src, f"materials.{name}", m)
        ka, kd, ks = (m.peak(k) for k in ("ka", "kd", "ks"))
        peaks.append((ka, kd, ks))
        # A dielectric splits a ray's weight w into F w and (1 - F) k_t w: at most w in all.
        kr_max = max(kr_max, float(np.max(m.reflectivity)), 1.0 if m.dielectric else 0.0)
        coef_max = max(coef_max, float(np.max(kd * color_max + ks)), float(np.max(ka)) * color_max)
    objects = []
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
        for key, width, nonneg in (("normals", 3, False), ("uv", 2, False), ("colors", 3, True)):
            a = getattr(obj, key, None)
            if a is None:
                continue
            a = np.asarray(a)
            if a.shape != (len(v), width) or a.dtype.kind not in "fiu" or not np.all(np.isfinite(a)) or (nonneg and (a < 0).any()):
                what = "non-negative " if nonneg else ""
                raise SceneError(src, f"{where}.{key}", f"expected ({len(v)}, {width}) finite {what}values, one per "
                                                        f"vertex ('{obj.name}')")
        if len(v):
            objects.append((i, obj.name, v.min(axis=0), v.max(axis=0)))
            _check_object_reach(src, *objects[-1], eye)
    light_max = light_max + _check_emissive_objects(src, scene)
    content = CheckedContent(tuple(lights), light_max, tuple(peaks), color_max, kr_max, coef_max, tuple(objects))
    _check_overflow(src, scene.render, ambient, background, content)
    return content


def _check_emissive_objects(src, scene: Scene) -> np.ndarray:
    """An emissive material's objects are area lights named by their object names: a name must not also
    name an object that does not emit so, nor the object of a [[lights]] area light (two emitters on one
    surface). Returns pi L_e summed over them (what they can add to a point's irradiance)."""
    emissive = {light.object: light.radiance for light in scene.emissive_lights}
    for i, o in enumerate(scene.objects):
        if o.name in emissive and scene.materials[o.material].emission != emissive[o.name]:
            raise SceneError(src, f"objects[{i}].name", f"'{o.name}' also names an object of an emissive material, "
                                                        f"whose light would cover both; give each emitting object its "
                                                        f"own name")
    for i, light in enumerate(scene.lights):
        if light.area and light.object in emissive:
            raise SceneError(src, f"lights[{i}].object", f"'{light.object}' emits already (its material's emission); "
                                                         f"give it one area light")
    return sum((np.pi * np.asarray(l.radiance, np.float64) for l in scene.emissive_lights), np.zeros(3))


def validate_view(scene: Scene, content: CheckedContent):
    """validate_scene(scene) for a scene whose lights, materials and objects are those ``content`` was
    checked from (validate_scene's return value), with any camera and render settings: the checks that
    depend on those alone, in validate_scene's order, so the first failure is the same SceneError."""
    src = scene.source
    validate_camera(scene.camera, src)
    eye = np.asarray(scene.camera.eye, np.float64)
    ambient, background = _check_render(src, scene.render)
    for i, position in content.lights:
        _check_light_reach(src, f"lights[{i}]", position, eye)
    for obj in content.objects:
        _check_object_reach(src, *obj, eye)
    _check_overflow(src, scene.render, ambient, background, content)


def _check_render(src, r):
    ambient = _check_vector(src, "render.ambient", r.ambient, nonneg=True)
    background = _check_vector(src, "render.background", r.background, nonneg=True)
    for key in ("render.max_depth", "render.spp", "render.light_samples"):
        check_setting(src, key, key, getattr(r, key.split(".")[1]))
    if not _is_real(r.adaptive) or not 0.0 <= r.adaptive < math.inf:
        raise SceneError(src, "render.adaptive", f"expected a number >= 0 (0: off), got {show(r.adaptive)}")
    if r.area_estimator not in AREA_ESTIMATORS:
        raise SceneError(src, "render.area_estimator",
                         f"expected one of {', '.join(map(repr, AREA_ESTIMATORS))}, got {show(r.area_estimator)}")
    if not isinstance(r.light_spread, bool):
        raise SceneError(src, "render.light_spread", f"expected true or false, got {show(r.light_spread)}")
    if r.light_spread and r.spp > r.light_samples:
        raise SceneError(src, "render.light_spread", f"each pixel sample takes its own share of a light's points: it "
                         f"needs render.light_samples >= render.spp, got {r.light_samples} points for {r.spp} samples")
    return ambient, background


def _check_overflow(src, r, ambient, background, content: CheckedContent):
    """The brightest possible pixel: every level of the mirror series fully lit, then the background."""
    light_max, color_max, kr_max, coef_max = content.light_max, content.color_max, content.kr_max, content.coef_max
    lit_max = np.zeros(3)
    for ka, kd, ks in content.peaks:
        lit = (ambient * ka + light_max * kd) * color_max + light_max * ks
        lit_max = np.maximum(lit_max, lit)
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
