"""A Mitsuba 3 scene file (scene.xml) read by Mitsuba's own parser, so that <default>, $param, <include>,
<ref> and transforms mean what they mean there; the loaded sensor, shapes, BSDFs and emitters become a Scene.
"""

from __future__ import annotations

import math
import os
import re
from pathlib import Path

import numpy as np

from ..diagnostics import warn
from ..errors import SceneError, one_line
from .model import Camera, Light, Material, RenderSettings, Scene, SceneObject
from .placement import euler_xyz, nearest_rotation
from .texture import Texture

# Units. Mitsuba's diffuse BRDF is reflectance / pi and its point and spot lights give radiant intensity
# (directional: irradiance), so kd = reflectance / pi and C_l = the emitter's intensity with inverse-square
# falloff: a diffuse surface under a point light is then the radiance Mitsuba computes, not pi times it.
# No ambient term (C_amb = 0): a `constant` emitter is an environment light of its radiance, occluded as
# Mitsuba's is (a scene has at most one: Mitsuba refuses a second environment emitter, an envmap included).
#
# What is read:
#   sensor    perspective (thinlens as a pinhole, warned): to_world, Mitsuba's x_fov (whatever fov_axis
#             said) -> vertical fovy, film size, near_clip -> camera.near; orthographic and others: an error
#   shapes    every Mesh (ply, obj, serialized, rectangle, cube): positions, faces, normals, uv; sphere,
#             disk and cylinder tessellated through their to_world; others (instances, curves): warned, skipped;
#             flip_normals: the other winding (Mitsuba negates the normals at each hit)
#   bsdfs     diffuse -> kd; plastic -> kd + mirror k_r = F(0); roughplastic -> kd + Phong ks (phong_shininess);
#             conductor, roughconductor -> mirror k_r = specular_reflectance x F(0) from eta, k (roughness
#             ignored); dielectric, thindielectric -> glass, ior = int_ior / ext_ior; twosided -> its front
#             BSDF; mask, bumpmap, normalmap -> the BSDF inside (warned); textures: bitmap (Mitsuba's own
#             texels, to_uv), checkerboard; other BSDFs: one warning each, Mitsuba's default diffuse (0.5)
#   emitters  point, spot, directional -> lights (inverse_square); constant -> an environment light of its
#             radiance (the background, and light through shadow rays); envmap -> an environment light
#             (Mitsuba's texels, scale, to_world's rotation);
#             area (an RGB radiance) -> an area light over its shape's triangles, emitting to the side
#             their winding faces; a textured radiance and others: one warning each, not lights
# Not read: the integrator and sampler (warprt's spp and max_depth apply), media, film crop and filter,
# bitmap filter and wrap modes (warprt's bilinear repeat), textured specular or conductor colours (their
# defaults, warned), mesh attributes (vertex colours), a spot's texture (warned), several sensors (the first).

# Dr.Jit's LLVM backend, if a JIT variant is set later (the reference), must find an LLVM it can drive;
# Debian 12's libLLVM 15 crashes it. The same path as reference/mitsuba_whitted.py's LLVM_PATH.
_LLVM_PATH = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
# Tessellation of Mitsuba's analytic shapes: the sphere's largest chord sagitta is r (1 - cos(pi / 128)).
SPHERE_SEGMENTS = (128, 256)  # rings (pole to pole), sectors
DISK_SECTORS = 256
CYLINDER_SECTORS = 256
# Mitsuba's BSDF classes (as a loaded BSDF describes itself) by the plugin names a file uses.
_BSDF_KIND = {"SmoothDiffuse": "diffuse", "SmoothPlastic": "plastic", "RoughPlastic": "roughplastic",
              "SmoothConductor": "conductor", "RoughConductor": "roughconductor", "SmoothDielectric": "dielectric",
              "ThinDielectric": "thindielectric", "TwoSided": "twosided", "Mask": "mask", "BumpMap": "bumpmap",
              "NormalMap": "normalmap"}
# BSDFs that wrap another: the parameter prefix of the one inside, and what is lost by reading it alone.
_WRAPPERS = {"twosided": ("brdf_0.", None),
             "mask": ("nested_bsdf.", "mask: its opacity is not read (the BSDF inside is, fully opaque)"),
             "bumpmap": ("nested_bsdf.", "bumpmap: the bump map is not read (the BSDF inside is)"),
             "normalmap": ("nested_bsdf.", "normalmap: the normal map is not read (the BSDF inside is)")}


def _class(described) -> str:
    """The class a Mitsuba object's description (str(obj)) begins with: "SmoothDiffuse[...", "Principled BSDF :..."."""
    m = re.match(r"\s*(\w+)", str(described))
    return m.group(1) if m else "?"


def _kind(text: str) -> str:
    """The plugin name of the BSDF a description begins with (its class where it has none here)."""
    return _BSDF_KIND.get(_class(text), _class(text))


def mitsuba_module(source: str = "Mitsuba scene file"):
    """Mitsuba, with a variant set: the one already set (the reference's), else scalar_rgb, which starts
    without compiling anything. A SceneError saying how to install it when it is missing."""
    if os.path.exists(_LLVM_PATH):
        os.environ.setdefault("DRJIT_LIBLLVM_PATH", _LLVM_PATH)
    try:
        import mitsuba as mi
    except ImportError as e:
        raise SceneError(source, None, f"reading a Mitsuba scene file needs Mitsuba 3 "
                                       f"(pip install 'warprt[mitsuba]'): {one_line(e)}") from None
    if mi.variant() is None:
        mi.set_variant("scalar_rgb")
    return mi


def load_mitsuba_file(path, params: dict | None = None):
    """mi.load_file(path, **params) without Mitsuba's scene optimisations (so each shape keeps its own
    identity and order); Mitsuba's error as one SceneError line naming the file."""
    source = str(path)
    mi = mitsuba_module(source)
    if Path(path).is_dir():
        raise SceneError(source, None, "is a folder, not a Mitsuba scene file")
    try:
        scene = mi.load_file(source, optimize=False, **{k: str(v) for k, v in (params or {}).items()})
    except Exception as e:  # Mitsuba raises RuntimeError for every rejection; its text is the message
        message = re.sub(r"^\[[\w.]+:\d+\]\s*", "", one_line(e))
        raise SceneError(source, None, f"Mitsuba rejects it: {message}") from None
    if not isinstance(scene, mi.Scene):
        raise SceneError(source, None, f"is a Mitsuba {type(scene).__name__}, not a <scene>")
    return scene


def read_mitsuba_xml(path, params: dict | None = None) -> Scene:
    """The Scene Mitsuba's loading of ``path`` (``params`` for its $name defaults) describes, not yet
    validated. Anything it cannot render is one warning each; nothing to render is a SceneError."""
    source = str(path)
    mi = mitsuba_module(source)
    ms = load_mitsuba_file(path, params)
    reader = _Reader(mi, source)
    camera = reader.camera(ms.sensors())
    materials: dict[str, Material] = {}
    objects = []
    area_lights = []
    for i, shape in enumerate(ms.shapes()):
        obj = reader.shape(i, shape, materials)
        if obj is not None:
            objects.append(obj)
            light = reader.area_light(shape, obj.name)
            if light is not None:
                area_lights.append(light)
    lights = reader.emitters(ms.emitters())
    if not objects:
        raise SceneError(source, None, "no shape warprt can render (meshes, rectangle, cube, sphere, disk, cylinder)")
    render = RenderSettings(ambient=(0.0, 0.0, 0.0))
    # The Whitted lights first, in scene.emitters() order (reads_mitsuba_light), then the area lights.
    return Scene(camera=camera, render=render, lights=lights + area_lights, materials=materials, objects=objects,
                 source=source)


def mitsuba_camera(mi_scene, source: str) -> Camera:
    """The camera read_mitsuba_xml makes of a loaded Mitsuba scene's first sensor."""
    return _Reader(mitsuba_module(source), source).camera(mi_scene.sensors())


_TESSELLATED = ("Sphere", "Disk", "Cylinder")


def reads_mitsuba_shape(shape) -> bool:
    """Whether the reader makes an object of this loaded Mitsuba shape (the others are warned and skipped)."""
    return bool(shape.is_mesh()) or _class(shape) in _TESSELLATED


_LIGHTS = ("PointLight", "SpotLight", "DirectionalEmitter")  # Mitsuba's point, spot, directional


def reads_mitsuba_light(emitter) -> bool:
    """Whether the reader makes a light of this loaded Mitsuba emitter (in scene.emitters() order)."""
    return _class(emitter) in _LIGHTS


def _array(v) -> np.ndarray:
    return np.array(v, np.float64)


def _scalar(v) -> float:
    """A Mitsuba parameter's one number, whatever the variant holds it in (float, or a JIT array)."""
    return float(np.ravel(_array(v))[0])


def _rgb(v) -> tuple:
    """A Mitsuba spectrum parameter (a float for a uniform one, Color3f for RGB) as three floats."""
    return tuple(float(x) for x in np.broadcast_to(np.ravel(_array(v)), (3,)))


def _matrix(transform) -> np.ndarray:
    return _array(transform.matrix).reshape(4, 4)


def _fresnel_conductor_normal(eta, k) -> np.ndarray:
    """Reflectance of a conductor of complex index eta + i k at normal incidence, per channel."""
    eta, k = np.asarray(eta, np.float64), np.asarray(k, np.float64)
    return ((eta - 1.0) ** 2 + k**2) / ((eta + 1.0) ** 2 + k**2)


def _fresnel_dielectric_normal(eta: float) -> float:
    return ((eta - 1.0) / (eta + 1.0)) ** 2


def phong_shininess(alpha: float) -> float:
    """warprt's Phong exponent for a microfacet roughness alpha: the Blinn-Phong exponent 2 / alpha^2 - 2
    that matches a Beckmann lobe (Walter et al. 2007), a quarter of it, since the Phong lobe (r.v)^n about
    the mirror direction is about twice as wide as Blinn-Phong's (n.h)^n about the normal. roughplastic's
    ks is then F(0) x specular_reflectance x (n + 2) / (2 pi), the normalised Phong lobe's peak."""
    alpha = max(float(alpha), 1e-4)
    return max((2.0 / (alpha * alpha) - 2.0) / 4.0, 1.0)


class _Reader:
    def __init__(self, mi, source: str):
        self.mi = mi
        self.source = source
        self.warned: set = set()
        self.names: set = set()
        self.converted: dict = {}  # (BSDF id, its description) -> material name

    def warn_once(self, key, field, message):
        if key not in self.warned:
            self.warned.add(key)
            warn(self.source, field, message)

    # ---- sensor ----
    def camera(self, sensors) -> Camera:
        if not sensors:
            raise SceneError(self.source, "sensor", "the scene has no sensor")
        if len(sensors) > 1:
            warn(self.source, "sensor", f"{len(sensors)} sensors: the first is used")
        sensor = sensors[0]
        kind = _class(sensor)
        if kind not in ("PerspectiveCamera", "ThinLensCamera"):
            raise SceneError(self.source, "sensor", f"{kind}: warprt's camera is a pinhole (perspective)")
        if kind == "ThinLensCamera":
            warn(self.source, "sensor", "thinlens: read as a pinhole; depth of field is not rendered")
        p = self.mi.traverse(sensor)
        m = _matrix(p["to_world"])
        eye, x, y, z = m[:3, 3], m[:3, 0], m[:3, 1], m[:3, 2]
        # Mitsuba's camera looks along local +z with +y up and +x to the left: x = y cross z. The
        # other handedness is a mirrored image, which a pinhole cannot make.
        if np.dot(x, np.cross(y, z)) < 0.0:
            warn(self.source, "sensor.to_world", "mirrors the image (a negative scale); rendered unmirrored")
        width, height = (int(v) for v in sensor.film().size())
        if tuple(int(v) for v in sensor.film().crop_size()) != (width, height):
            warn(self.source, "sensor.film", "crop window ignored: the whole film is rendered")
        for key in ("principal_point_offset_x", "principal_point_offset_y"):
            if key in p and _scalar(p[key]) != 0.0:
                warn(self.source, f"sensor.{key}", "off-centre principal point ignored")
        # x_fov is Mitsuba's own reading of fov and fov_axis (x, y, diagonal, smaller, larger).
        x_fov = math.radians(_scalar(p["x_fov"]))
        fovy = math.degrees(2.0 * math.atan(math.tan(0.5 * x_fov) * height / width))
        up = y / np.linalg.norm(y)
        forward = z / np.linalg.norm(z)
        return Camera(eye=tuple(eye), center=tuple(eye + forward), up=tuple(up), fovy=fovy,
                      near=_scalar(p["near_clip"]), width=width, height=height)

    # ---- shapes ----
    def shape(self, i: int, shape, materials: dict) -> SceneObject | None:
        kind = _class(shape)
        name = self._name(shape.id() or f"{kind.lower()}_{i}")
        field = f"shape {name}"
        if not reads_mitsuba_shape(shape):
            self.warn_once(("shape", kind), field, f"{kind} is not read (meshes, rectangle, cube, sphere, disk, "
                                                   "cylinder are): skipped")
            return None
        if shape.is_mesh():
            v = _array(shape.vertex_positions_buffer()).reshape(-1, 3)
            f = np.array(shape.faces_buffer(), np.int64).reshape(-1, 3)
            n = _array(shape.vertex_normals_buffer()).reshape(-1, 3) if shape.has_vertex_normals() else None
            uv = _array(shape.vertex_texcoords_buffer()).reshape(-1, 2) if shape.has_vertex_texcoords() else None
        else:
            m = _matrix(self.mi.traverse(shape)["to_world"])
            v, f, n, uv = {"Sphere": _sphere, "Disk": _disk, "Cylinder": _cylinder}[kind]()
            v = v @ m[:3, :3].T + m[:3, 3]
            # Normals transform by the inverse transpose (a scaled sphere is an ellipsoid).
            n = n @ np.linalg.inv(m[:3, :3])
            n /= np.linalg.norm(n, axis=1, keepdims=True)
            if np.linalg.det(m[:3, :3]) < 0.0:  # a mirroring transform turns the winding inside out
                f = f[:, ::-1]
        if shape.has_flipped_normals():
            # Mitsuba keeps the buffers and negates the normals at each hit (so its area emitter shines
            # from the other side, and a dielectric's inside is its outside): the same as the other winding.
            f = f[:, ::-1]
            n = -n if n is not None else None
        material = self.material(shape.bsdf(), field, materials)
        return SceneObject(name=name, vertices=v, faces=f, material=material, smooth=n is not None,
                           normals=n, uv=uv)

    def area_light(self, shape, name: str) -> Light | None:
        """The area light of a shape with an ``area`` emitter: its radiance from the triangles of object
        ``name``, one-sided to the side their winding faces (Mitsuba's normal side, flip_normals read)."""
        if not shape.is_emitter():
            return None
        emitter = shape.emitter()
        kind = _class(emitter)
        if kind != "AreaLight":
            self.warn_once(("emitter", kind), f"shape {name}", f"{kind} is not read: the shape is drawn, its light is not")
            return None
        p = self.mi.traverse(emitter)
        if "radiance.value" not in p:
            self.warn_once("area texture", f"shape {name}", "a textured area emitter radiance is not read: "
                                                          "the shape is drawn, its light is not")
            return None
        return Light(type="area", radiance=_rgb(p["radiance.value"]), object=name, name=name)

    def _name(self, name: str) -> str:
        base, k = name, 1
        while name in self.names:
            k += 1
            name = f"{base}.{k}"
        self.names.add(name)
        return name

    # ---- BSDFs ----
    def material(self, bsdf, field: str, materials: dict) -> str:
        """The name of the material made of this BSDF, converted once however many shapes <ref> it."""
        text = str(bsdf)
        key = (bsdf.id(), text)
        if key in self.converted:
            return self.converted[key]
        kind = _kind(text)
        params = dict(self.mi.traverse(bsdf).items())
        while kind in _WRAPPERS:  # twosided, mask, bumpmap, normalmap: the BSDF inside
            prefix, note = _WRAPPERS[kind]
            if note:
                self.warn_once(("wrapper", kind), field, note)
            if kind == "twosided" and any(k.startswith("brdf_1.") for k in params):
                self.warn_once("twosided2", field, "twosided with a different back BSDF: its front BSDF on both sides")
            inner = re.search(re.escape(prefix.replace("_0.", "[0]").rstrip(".")) + r"\s*=\s*(?=\w+\[)", text)
            text = text[inner.end():] if inner else "?["
            params = {k[len(prefix):]: v for k, v in params.items() if k.startswith(prefix)}
            kind = _kind(text)
        try:
            m = self._convert(kind, params, text, field)
        except _Unread as e:
            self.warn_once(("bsdf", kind), field, f"{e}: Mitsuba's default diffuse (reflectance 0.5) instead")
            m = Material(kd=(0.5 / math.pi,) * 3, ks=(0.0, 0.0, 0.0))
        name = bsdf.id() or kind
        base, k = name, 1
        while name in materials:
            k += 1
            name = f"{base}.{k}"
        materials[name], self.converted[key] = m, name
        return name

    def _convert(self, kind: str, p: dict, text: str, field: str) -> Material:
        black = (0.0, 0.0, 0.0)
        if kind == "diffuse":
            kd, tex = self._texture(p, "reflectance", text, field)
            return Material(kd=tuple(np.array(kd) / math.pi), ks=black, kd_texture=tex)
        if kind in ("plastic", "roughplastic"):
            kd, tex = self._texture(p, "diffuse_reflectance", text, field)
            f0 = _fresnel_dielectric_normal(_scalar(p["eta"]))
            spec = np.array(self._constant(p, "specular_reflectance", (1.0, 1.0, 1.0), field)) * f0
            kd = tuple(np.array(kd) / math.pi)
            if kind == "plastic":  # a smooth coating: a mirror reflection, no highlight from a point light
                return Material(kd=kd, ks=black, reflectivity=tuple(spec), kd_texture=tex)
            n = phong_shininess(_scalar(p["alpha"]))
            return Material(kd=kd, ks=tuple(spec * (n + 2.0) / (2.0 * math.pi)), shininess=n, kd_texture=tex)
        if kind in ("conductor", "roughconductor"):
            # Mitsuba's default conductor (material "none") is eta 0, k 1: F(0) = 1, a perfect mirror.
            f0 = _fresnel_conductor_normal(self._constant(p, "eta", (0.0, 0.0, 0.0), field),
                                           self._constant(p, "k", (1.0, 1.0, 1.0), field))
            spec = np.array(self._constant(p, "specular_reflectance", (1.0, 1.0, 1.0), field))
            return Material(kd=black, ks=black, reflectivity=tuple(np.broadcast_to(f0 * spec, (3,))))
        if kind in ("dielectric", "thindielectric"):
            if kind == "thindielectric":
                self.warn_once("thin", field, "thindielectric: rendered as a solid dielectric of the same index")
            kt = self._constant(p, "specular_transmittance", (1.0, 1.0, 1.0), field)
            return Material(kd=black, ks=black, ior=_scalar(p["eta"]), transmittance=kt)
        raise _Unread(f"BSDF {kind} is not read (diffuse, plastic, roughplastic, conductor, roughconductor, "
                      "dielectric, thindielectric and, through to the BSDF inside, twosided, mask, bumpmap, normalmap are)")

    def _constant(self, p: dict, name: str, default, field) -> tuple:
        if f"{name}.value" in p:
            return _rgb(p[f"{name}.value"])
        if any(k.startswith(name + ".") for k in p):
            self.warn_once(("tex", name), field, f"a textured {name} is read as its default {list(default)}")
        return tuple(default)

    def _texture(self, p: dict, name: str, text: str, field) -> tuple[tuple, Texture | None]:
        """(colour, texture): a constant as the colour, a bitmap or checkerboard as a texture times 1."""
        if f"{name}.value" in p:
            return _rgb(p[f"{name}.value"]), None
        ones = (1.0, 1.0, 1.0)
        if f"{name}.data" in p:
            data = np.array(p[f"{name}.data"])
            raw = re.search(r"raw\s*=\s*(\d)", text)
            if data.dtype.kind in "ui":
                data = data.astype(np.float64) / np.iinfo(data.dtype).max
                if not (raw and raw.group(1) == "1"):  # Mitsuba decodes 8- and 16-bit texels from sRGB
                    from .texture import srgb_to_linear

                    data = srgb_to_linear(data)
            if data.ndim == 2:
                data = data[..., None]
            rgb = data[..., :3] if data.shape[-1] >= 3 else np.repeat(data[..., :1], 3, -1)
            # Mitsuba's texel rows with Mitsuba's uv: row r is sampled at v = (r + 0.5) / H in both.
            source = re.search(r'name\s*=\s*"([^"]*)"', text)
            return ones, Texture(image=np.ascontiguousarray(rgb, np.float32), uv_transform=self._to_uv(p, name),
                                 source=source.group(1) if source else "bitmap")
        if f"{name}.color0.value" in p:
            c0, c1 = _rgb(p[f"{name}.color0.value"]), _rgb(p[f"{name}.color1.value"])
            # Mitsuba's checks are half a unit of its uv: warprt's unit checks of 2 x that uv.
            a = self._to_uv(p, name)
            return ones, Texture(checker=(c0, c1), uv_transform=tuple(2.0 * x for x in a), source="checkerboard")
        self.warn_once(("tex", name), field, f"this {name} texture is not read (bitmap and checkerboard are): "
                                             "reflectance 0.5")
        return (0.5, 0.5, 0.5), None

    def _to_uv(self, p: dict, name: str) -> tuple:
        key = f"{name}.to_uv"
        if key not in p:
            return (1.0, 0.0, 0.0, 0.0, 1.0, 0.0)
        a = _array(p[key].matrix).reshape(3, 3)
        return tuple(float(x) for x in (a[0, 0], a[0, 1], a[0, 2], a[1, 0], a[1, 1], a[1, 2]))

    # ---- emitters ----
    def emitters(self, emitters) -> list[Light]:
        lights = []
        for i, e in enumerate(emitters):
            kind = _class(e)
            name = e.id() or f"emitter_{i}"
            p = self.mi.traverse(e)
            if kind == "PointLight":
                lights.append(Light(position=tuple(_array(p["position"]).ravel()), color=_rgb(p["intensity.value"]),
                                    type="point", falloff="inverse_square", name=name))
            elif kind == "SpotLight":
                m = _matrix(p["to_world"])
                if "texture.value" not in p:
                    self.warn_once("spottex", f"emitter {name}", "a spot's texture is not read")
                axis = m[:3, 2] / np.linalg.norm(m[:3, 2])  # Mitsuba's spot shines along its local +z
                lights.append(Light(position=tuple(m[:3, 3]), color=_rgb(p["intensity.value"]), type="spot",
                                    direction=tuple(axis), cutoff_angle=_scalar(p["cutoff_angle"]),
                                    beam_width=_scalar(p["beam_width"]), falloff="inverse_square", name=name))
            elif kind == "DirectionalEmitter":
                m = _matrix(p["to_world"])
                lights.append(Light(color=_rgb(p["irradiance.value"]), type="directional",
                                    direction=tuple(m[:3, 2] / np.linalg.norm(m[:3, 2])), falloff="none", name=name))
            elif kind == "ConstantBackgroundEmitter":
                lights.append(Light(type="environment", radiance=_rgb(p["radiance.value"]), name=name))
            elif kind == "EnvironmentMapEmitter":
                lights.append(self.environment(e, p, name))
            elif kind == "AreaLight":
                pass  # read with its shape (area_light)
            else:
                self.warn_once(("emitter", kind), f"emitter {name}", f"{kind} is not a Whitted light: skipped")
        return lights

    def environment(self, e, p, name: str) -> Light:
        """An envmap: Mitsuba's own texels (its loaded data, the periodic columns left out), its scale and
        its to_world's rotation as rotate angles (R = Rz Ry Rx); a to_world that is not a rotation is warned
        about and its nearest rotation read."""
        data = np.asarray(p["data"], np.float64)[..., :3]
        width = re.search(r'res = "\[(\d+), ', str(e))
        # Mitsuba pads the image with its periodic columns: 3.9 one either side, later ones a last one only.
        data = data[:, 1:-1] if width and data.shape[1] == int(width[1]) + 2 else data[:, :-1]
        found = re.search(r'filename = "([^"]*)"', str(e))
        image = Texture(image=np.ascontiguousarray(data[::-1], np.float32), source=found[1] if found else name)
        r, exact = nearest_rotation(_matrix(p["to_world"])[:3, :3])
        if not exact:
            self.warn_once(("envmap", name), f"emitter {name}", "its to_world is not a rotation: its nearest "
                                                                "rotation is read")
        return Light(type="environment", image=image, scale=_scalar(p["scale"]), rotate=euler_xyz(r), name=name)


class _Unread(Exception):
    pass


def _ring(sectors: int):
    """cos and sin of sectors + 1 angles around a circle, the last exactly the first (a closed seam)."""
    phi = np.linspace(0.0, 2.0 * math.pi, sectors + 1)
    c, s = np.cos(phi), np.sin(phi)
    c[-1], s[-1] = c[0], s[0]
    return phi, c, s


def _sphere():
    """Mitsuba's unit sphere (pole on z; u = phi / 2 pi from +x towards +y, v = theta / pi from +z) as a
    latitude-longitude mesh, seam and pole vertices split by uv at equal coordinates (so it is closed
    where open_edges welds), wound counter-clockwise from outside."""
    rings, sectors = SPHERE_SEGMENTS
    theta = np.linspace(0.0, math.pi, rings + 1)
    st, ct = np.sin(theta), np.cos(theta)
    st[0], st[-1], ct[0], ct[-1] = 0.0, 0.0, 1.0, -1.0
    phi, cp, sp = _ring(sectors)
    n = np.stack([st[:, None] * cp[None, :], st[:, None] * sp[None, :], np.broadcast_to(ct[:, None], (rings + 1, sectors + 1))],
                 -1).reshape(-1, 3)
    uv = np.stack(np.meshgrid(theta / math.pi, phi / (2.0 * math.pi), indexing="ij")[::-1], -1).reshape(-1, 2)
    idx = np.arange((rings + 1) * (sectors + 1)).reshape(rings + 1, sectors + 1)
    # Quad a (theta_i, phi_j), b (theta_i+1, phi_j), c (theta_i+1, phi_j+1), d (theta_i, phi_j+1):
    # d(theta) x d(phi) points outwards, so (a, b, c) and (a, c, d); the first collapses at the south
    # pole (b = c), the second at the north pole (a = d).
    a, b, c, d = idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]
    f = np.concatenate([np.stack([a, b, c], -1)[:-1].reshape(-1, 3), np.stack([a, c, d], -1)[1:].reshape(-1, 3)])
    return n.copy(), f.astype(np.int64), n, uv


def _disk():
    """Mitsuba's unit disk in z = 0 facing +z (uv = (r, phi / 2 pi)): a fan around the centre."""
    phi, c, s = _ring(DISK_SECTORS)
    v = np.vstack([[0.0, 0.0, 0.0], np.stack([c, s, np.zeros_like(c)], -1)])
    uv = np.vstack([[0.0, 0.0], np.stack([np.ones_like(phi), phi / (2.0 * math.pi)], -1)])
    i = np.arange(1, DISK_SECTORS + 1)
    f = np.stack([np.zeros_like(i), i, i + 1], -1)
    n = np.tile([0.0, 0.0, 1.0], (len(v), 1))
    return v, f.astype(np.int64), n, uv


def _cylinder():
    """Mitsuba's cylinder: radius 1 about z from z = 0 to 1, open (no caps), uv = (phi / 2 pi, z)."""
    phi, c, s = _ring(CYLINDER_SECTORS)
    ring = np.stack([c, s, np.zeros_like(c)], -1)
    v = np.vstack([ring, ring + [0.0, 0.0, 1.0]])
    m = len(phi)
    u = phi / (2.0 * math.pi)
    uv = np.vstack([np.stack([u, np.zeros_like(u)], -1), np.stack([u, np.ones_like(u)], -1)])
    i = np.arange(CYLINDER_SECTORS)
    f = np.concatenate([np.stack([i, i + 1, i + 1 + m], -1), np.stack([i, i + 1 + m, i + m], -1)])
    return v, f.astype(np.int64), np.vstack([ring, ring]), uv
