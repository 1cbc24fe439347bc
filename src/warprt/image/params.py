"""A Renderer's scene parameters by name (SceneParameters, as Mitsuba's ``mi.traverse``): the values a
frame may change without loading the scene again, each read and written as NumPy arrays.

    materials.<name>.ka | kd | ks | reflectivity | transmittance | absorption   (3,)
    materials.<name>.emission                   (3,), where the material emits (an area light's L_e)
    materials.<name>.shininess | ior                                            ()
    materials.<name>.ka_texture | kd_texture | ks_texture     (H, W, 3) linear float32, row 0 the image's top
    lights.<i>.position | color | direction | radiance (an area light's)         (3,)
    lights.<i>.center | normal | u | v   (3,), an area light's of its own shape (rectangle, disk, sphere), as given
    lights.<i>.size          (2,), a rectangle light's (width, height) about its normal
    lights.<i>.radius        (), a disk or sphere light's
    objects.<name>.vertices                                                     (N, 3), world space
    objects.<name>.translation | rotation          (3,), the object's pose (Pose), 0 at load
    objects.<name>.colors                      (N, 3) linear RGB, where the object has vertex colours
    camera.eye | center | up                                                    (3,)
    camera.fovy                                                                 ()

Setting one makes the next frame render the changed scene exactly as a fresh load of a file saying the
same would: the new scene is checked as a loaded one is, and the Renderer keeps what the change leaves
valid (moved vertices refit the BVH; new vertex colours are written over the kept ones). ior, transmittance
and absorption are a dielectric's, a texture's texels an image texture's; a material whose ka follows kd
(a file that leaves ka out) keeps following it.

An object's pose (Pose) is two parameters: the vertices are R(rotation) (v_rest - c) + c + translation, the
rotation vector's axis times its angle in radians (Rodrigues' formula: scipy's Rotation.from_rotvec, Mitsuba's
convention), c the centre of the rest vertices' bounding box, in float64. The pose is absolute (each set
replaces its part, the rest shape kept) and lives in the Renderer (Renderer.poses), not in the scene: reading
objects.<name>.vertices gives the posed vertices, which the scene holds; setting them makes them the rest
shape with the pose 0 (so does anything else that gives the object other vertices, set_scene among them);
a pose set in the same update as the vertices is then applied to them.
"""

from __future__ import annotations

from collections.abc import MutableMapping
from dataclasses import dataclass, replace

import numpy as np

from ..errors import SceneError

MATERIAL_COLOURS = ("ka", "kd", "ks", "reflectivity")
DIELECTRIC_COLOURS = ("transmittance", "absorption")
TEXTURES = ("ka_texture", "kd_texture", "ks_texture")
LIGHT_VECTORS = ("position", "color", "direction", "radiance", "center", "normal", "u", "v", "rotate")
LIGHT_SHAPES = {"size": (2,), "radius": (), "scale": ()}  # an area light's shape's other parameters (an
# environment's scale), and their shapes
CAMERA_VECTORS = ("eye", "center", "up")
POSE_KEYS = ("translation", "rotation")
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
        out += [f"lights.{i}.{k}" for k in (*LIGHT_VECTORS, *LIGHT_SHAPES) if getattr(light, k) is not None
                and not ((light.area or light.environment) and k == "color")]  # its light is its radiance
    out += [f"objects.{name}.vertices" for name in object_names(scene)]
    out += [f"objects.{name}.{k}" for name in object_names(scene) for k in POSE_KEYS]
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
            if key in POSE_KEYS:
                return np.array(getattr(object_pose(scene, self._renderer.poses, owner), key), np.float64)
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
        moves: dict = {}  # object index -> {translation | rotation: value}
        for name, value in values.items():
            section, owner, key = _split(name, scene)
            if section == "objects" and key in POSE_KEYS:
                moves.setdefault(owner, {})[key] = _vector(name, value, (3,))
            elif section == "materials":
                materials[owner] = _set_material(materials[owner], key, name, value)
            elif section == "lights":
                v = _vector(name, value, LIGHT_SHAPES.get(key, (3,)))
                lights[owner] = replace(lights[owner], **{key: float(v) if v.ndim == 0 else tuple(v)})
            elif section == "objects":
                old = objects[owner]
                objects[owner] = replace(old, **{key: _vector(name, value, getattr(old, key).shape)})
            elif key == "fovy":
                camera = replace(camera, fovy=float(_vector(name, value, ())))
            else:
                camera = replace(camera, **{key: tuple(_vector(name, value, (3,)))})
        poses = {}
        for i, move in moves.items():  # on the rest shape kept, or on vertices set in this update
            poses[i] = object_pose(scene, self._renderer.poses, i, objects[i].vertices).moved(**move)
            objects[i] = replace(objects[i], vertices=poses[i].posed)
        changed = replace(scene, camera=camera, lights=lights, materials=materials, objects=objects)
        self._renderer.set_scene(changed)  # checked first: a SceneError leaves the poses as they were
        self._renderer.poses.update(poses)

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


@dataclass(frozen=True, eq=False)
class Pose:
    """An object's pose (the module's docstring): its rest vertices (N, 3) and their bounding box's centre c
    (float64, world), its translation t and rotation vector w (3,), and ``posed``, the vertices
    R(w) (v_rest - c) + c + t they make (posed_vertices): the array the scene's object holds while this is
    its pose (object_pose tells by identity)."""

    rest: np.ndarray
    centre: np.ndarray
    translation: np.ndarray
    rotation: np.ndarray
    posed: np.ndarray

    @classmethod
    def at_rest(cls, vertices: np.ndarray) -> "Pose":
        """The pose 0 of an object with ``vertices``: those its rest shape, t = w = 0."""
        v = np.asarray(vertices, np.float64)
        centre = (v.min(0) + v.max(0)) / 2.0 if len(v) else np.zeros(3)
        return cls(v, centre, np.zeros(3), np.zeros(3), v)

    def moved(self, translation=None, rotation=None) -> "Pose":
        """This pose with its translation or rotation replaced (a pose is absolute: the rest shape is kept)."""
        t = self.translation if translation is None else np.asarray(translation, np.float64)
        w = self.rotation if rotation is None else np.asarray(rotation, np.float64)
        return Pose(self.rest, self.centre, t, w, posed_vertices(self.rest, self.centre, t, w))


def rotation_minus_identity(w) -> np.ndarray:
    """R(w) - I (3, 3), float64, R(w) the rotation by |w| radians about w / |w| (Rodrigues' formula,
    R = I + sin(a)/a K + (1 - cos a)/a^2 K^2, K the cross-product matrix of w; 1 - cos a taken as
    2 sin^2(a/2), without its cancellation): exactly 0 at w = 0."""
    w = np.asarray(w, np.float64)
    a = float(np.linalg.norm(w))
    if a == 0.0:
        return np.zeros((3, 3))
    K = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
    return np.sin(a) / a * K + 2.0 * np.sin(a / 2.0) ** 2 / a ** 2 * (K @ K)


def posed_vertices(rest, centre, t, w) -> np.ndarray:
    """R(w) (rest - centre) + centre + t, float64, written rest + t + (R(w) - I)(rest - centre): at w = 0 the
    rest vertices plus t, and at t = w = 0 the rest vertices themselves (a copy), to the bit."""
    rest = np.asarray(rest, np.float64)
    if not np.any(w) and not np.any(t):
        return rest.copy()
    return rest + np.asarray(t, np.float64) + (rest - centre) @ rotation_minus_identity(w).T


def object_pose(scene, poses: dict, i: int, vertices=None) -> Pose:
    """The pose of ``scene``'s object i: ``poses[i]`` (a Renderer's poses) while the object's vertices (or
    ``vertices``, those it is about to have) are the array that pose made, else the pose 0 of them."""
    v = scene.objects[i].vertices if vertices is None else vertices
    kept = poses.get(i)
    return kept if kept is not None and kept.posed is v else Pose.at_rest(v)


def object_poses(scene, poses: dict) -> list:
    """object_pose of each of ``scene``'s objects, in order."""
    return [object_pose(scene, poses, i) for i in range(len(scene.objects))]
