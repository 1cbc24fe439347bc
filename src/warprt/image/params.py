"""A Renderer's scene parameters by name (SceneParameters, as Mitsuba's ``mi.traverse``): the values a
frame may change without loading the scene again, each read and written as NumPy arrays.

    materials.<name>.ka | kd | ks | reflectivity | transmittance | absorption   (3,)
    materials.<name>.emission                   (3,), where the material emits (an area light's L_e)
    materials.<name>.shininess | ior                                            ()
    materials.<name>.ka_texture | kd_texture | ks_texture     (H, W, 3) linear float32, row 0 the image's top
    lights.<i>.position | color | direction | radiance (an area light's)         (3,)
    lights.<i>.center        (3,), an area light's of its own shape (rectangle, disk, sphere) given one
    objects.<name>.vertices                                                     (N, 3), world space
    objects.<name>.colors                      (N, 3) linear RGB, where the object has vertex colours
    camera.eye | center | up                                                    (3,)
    camera.fovy                                                                 ()

Setting one makes the next frame render the changed scene exactly as a fresh load of a file saying the
same would: the new scene is checked as a loaded one is, and the Renderer keeps what the change leaves
valid (moved vertices refit the BVH; new vertex colours are written over the kept ones). ior, transmittance
and absorption are a dielectric's, a texture's texels an image texture's; a material whose ka follows kd
(a file that leaves ka out) keeps following it.
"""

from __future__ import annotations

from collections.abc import MutableMapping
from dataclasses import replace

import numpy as np

from ..errors import SceneError

MATERIAL_COLOURS = ("ka", "kd", "ks", "reflectivity")
DIELECTRIC_COLOURS = ("transmittance", "absorption")
TEXTURES = ("ka_texture", "kd_texture", "ks_texture")
LIGHT_VECTORS = ("position", "color", "direction", "radiance", "center")
CAMERA_VECTORS = ("eye", "center", "up")
SOURCE = "Renderer.params"


def _names(scene) -> list[str]:
    """Every parameter name ``scene`` has, in the order of the module's table."""
    out = []
    for name, m in scene.materials.items():
        out += [f"materials.{name}.{k}" for k in MATERIAL_COLOURS + ("shininess",)]
        if m.dielectric:
            out += [f"materials.{name}.{k}" for k in ("ior",) + DIELECTRIC_COLOURS]
        out += [f"materials.{name}.{k}" for k in TEXTURES if _image_texture(m, k) is not None]
        if m.emission is not None:
            out.append(f"materials.{name}.emission")
    for i, light in enumerate(scene.lights):
        out += [f"lights.{i}.{k}" for k in LIGHT_VECTORS if getattr(light, k) is not None
                and not (light.area and k == "color")]  # an area light's light is its radiance
    out += [f"objects.{name}.vertices" for name in object_names(scene)]
    out += [f"objects.{name}.colors" for name, i in object_names(scene).items() if scene.objects[i].colors is not None]
    out += [f"camera.{k}" for k in CAMERA_VECTORS + ("fovy",)]
    return out


def _image_texture(material, key: str):
    t = getattr(material, key)
    return t if t is not None and t.image is not None else None


def object_names(scene) -> dict:
    """Object name -> index in scene.objects; an object whose name is not its own (several objects share
    it) is named by its index."""
    names = [o.name for o in scene.objects]
    return {(n if names.count(n) == 1 else str(i)): i for i, n in enumerate(names)}


class SceneParameters(MutableMapping):
    """The parameters of ``renderer``'s scene by name (the module's table). Reading one gives a copy;
    setting one (or several with ``update``, checked together) gives the Renderer a changed scene.
    A name the scene does not have, or a value of the wrong shape, is a SceneError naming the parameter."""

    def __init__(self, renderer):
        self._renderer = renderer

    def __iter__(self):
        return iter(_names(self._renderer.scene))

    def __len__(self) -> int:
        return len(_names(self._renderer.scene))

    def __contains__(self, name) -> bool:
        return name in _names(self._renderer.scene)

    def __getitem__(self, name: str) -> np.ndarray:
        scene = self._renderer.scene
        section, owner, key = _split(name, scene)
        if section == "materials":
            m = scene.materials[owner]
            if key in TEXTURES:
                return np.ascontiguousarray(getattr(m, key).image[::-1], np.float32)  # row 0 at the top
            return np.array(getattr(m, key), np.float64)
        if section == "lights":
            return np.array(getattr(scene.lights[owner], key), np.float64)
        if section == "objects":
            return np.array(getattr(scene.objects[owner], key), np.float64)
        return np.array(getattr(scene.camera, key), np.float64)

    def __setitem__(self, name: str, value):
        self.update({name: value})

    def __delitem__(self, name):
        raise SceneError(SOURCE, name, "a parameter cannot be removed, only set")

    def update(self, values=(), **kw):
        """Set several parameters at once: the scene is made and checked once, with all of them."""
        values = dict(values, **kw)
        scene = self._renderer.scene
        materials, lights, objects = dict(scene.materials), list(scene.lights), list(scene.objects)
        camera = scene.camera
        for name, value in values.items():
            section, owner, key = _split(name, scene)
            if section == "materials":
                materials[owner] = _set_material(materials[owner], key, name, value)
            elif section == "lights":
                lights[owner] = replace(lights[owner], **{key: tuple(_vector(name, value, (3,)))})
            elif section == "objects":
                old = objects[owner]
                objects[owner] = replace(old, **{key: _vector(name, value, getattr(old, key).shape)})
            elif key == "fovy":
                camera = replace(camera, fovy=float(_vector(name, value, ())))
            else:
                camera = replace(camera, **{key: tuple(_vector(name, value, (3,)))})
        changed = replace(scene, camera=camera, lights=lights, materials=materials, objects=objects)
        self._renderer.set_scene(changed)

    def __repr__(self) -> str:
        return f"SceneParameters({', '.join(self)})"


def _split(name, scene) -> tuple[str, object, str]:
    """(section, the material name / light index / object index / None, key) of a parameter name."""
    if not isinstance(name, str) or name not in _names(scene):
        known = _names(scene)
        import difflib

        close = difflib.get_close_matches(str(name), known, n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else f" (names: {', '.join(known[:8])}{', ...' if len(known) > 8 else ''})"
        raise SceneError(SOURCE, str(name), f"unknown parameter{hint}")
    section, rest = name.split(".", 1)
    if section == "camera":
        return section, None, rest
    owner, key = rest.rsplit(".", 1)
    if section == "lights":
        return section, int(owner), key
    if section == "objects":
        return section, object_names(scene)[owner], key
    return section, owner, key


def _vector(name: str, value, shape: tuple) -> np.ndarray:
    """``value`` as a finite float64 array of ``shape``, or a SceneError naming the parameter."""
    try:
        a = np.asarray(value, np.float64)
    except (TypeError, ValueError):
        raise SceneError(SOURCE, name, f"expected numbers of shape {shape}, got {type(value).__name__}") from None
    if a.shape != tuple(shape):
        raise SceneError(SOURCE, name, f"expected shape {tuple(shape)}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise SceneError(SOURCE, name, "expected finite numbers")
    return a.copy()


def _set_material(m, key: str, name: str, value):
    """Material ``m`` with ``key`` set, made again by its constructor, so that it is what a file saying the
    same would give: ka and its texture, where they followed kd (left out of the file), still follow it."""
    if key in TEXTURES:
        t = getattr(m, key)
        a = np.asarray(value, np.float32)
        if a.ndim != 3 or a.shape[2] != t.image.shape[2] or a.shape[0] < 1 or a.shape[1] < 1:
            raise SceneError(SOURCE, name, f"expected texels of shape (H, W, {t.image.shape[2]}), got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise SceneError(SOURCE, name, "expected finite texels")
        new = {key: replace(t, image=np.ascontiguousarray(a[::-1]))}  # stored with row 0 at v = 0
    else:
        v = _vector(name, value, () if key in ("shininess", "ior") else (3,))
        new = {key: float(v) if v.ndim == 0 else tuple(v)}
    # The constructor fills a ka or ka_texture given as None from kd's.
    if m.ka_follows_kd and key != "ka":
        new["ka"] = None
    if m.ka_texture_follows_kd and key != "ka_texture":
        new["ka_texture"] = None
    return replace(m, **new)
