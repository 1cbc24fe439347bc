"""The gradient's parameters (grad.py says what is differentiated): the r.params names backward() differentiates,
why one is refused, and the tape's adjoint arrays turned into a gradient per name."""
from __future__ import annotations

import numpy as np

from ..errors import ArgumentError
from ..kernels import MAX_GRAD_LIGHTS
from ..scene import scene_effects
from .grad_area_shape import gradients_of, shape_keys
from .grad_record import Record
from .params import POSE_KEYS, object_names

SOURCE = "Renderer.backward"
MATERIAL_KEYS = ("ka", "kd", "ks", "shininess", "reflectivity")
DIELECTRIC_KEYS = ("ior", "transmittance", "absorption")  # a dielectric's, through the ray tree
TEXTURE_KEYS = ("ka_texture", "kd_texture", "ks_texture")  # an image texture's texels, as r.params has them
MAX_GRAD_DEPTH = 16  # ray levels, unrolled as the lights are
LIGHT_KEYS = ("color", "position", "direction")
CAMERA_KEYS = ("eye", "center", "up", "fovy")


def refusal(scene, fx, mirrored=()) -> str | None:
    """Why render(grad=True) cannot differentiate this scene yet (None: it can); ``mirrored``: the
    materials whose mirror rays are recorded whatever their reflectivity (mirrored_materials)."""
    # The replay shades every Phong term. One the scene's values leave out (every ks 0) is right to shade:
    # its derivative is not 0. One switched off (render.effects, effects=, disable=) would give another
    # image's gradient.
    called = scene_effects(scene)
    off = [name for name in ("ambient", "diffuse", "specular") if getattr(called, name) and not getattr(fx, name)]
    if off:
        return f"the gradient's replay shades every Phong term: {', '.join(off)} switched off is not differentiated yet"
    if (fx.reflection or mirrored) and not fx.refraction and scene.render.max_depth > MAX_GRAD_DEPTH:
        return f"at most {MAX_GRAD_DEPTH} ray levels (render.max_depth) are differentiated (Warp's unrolled loop)"
    if fx.environment:
        return ("an environment light is not differentiated yet: the gradient's replay has neither the light it "
                "adds nor the background it shows, so no parameter's gradient would be right")
    if len(scene.whitted_lights) > MAX_GRAD_LIGHTS:
        return f"at most {MAX_GRAD_LIGHTS} lights are differentiated (Warp's unrolled loop)"
    if scene.render.adaptive > 0 and fx.supersampling:
        return ("render.adaptive picks the pixels it refines by the frame's own image: a gradient is that of a frame "
                "of every pixel's strata (render.adaptive = 0)")
    if fx.area_analytic:
        return ("render.area_estimator = 'analytic' is not differentiated yet (the closed form and its ratio "
                "estimator): render the gradient with 'samples'")
    if fx.light_spread:
        return "render.light_spread is not differentiated yet: render the gradient without it"
    return None


def named_parameters(scene, names) -> list[str]:
    """render(grad=[names])'s names, checked: each one backward() can differentiate in this scene (else
    one ArgumentError naming it)."""
    known = set(parameter_names(scene))
    for name in names:
        if name not in known:
            raise ArgumentError("render", "grad", f"{name!r}: " + (_name_refusal(scene, str(name)) or
                                "not a parameter backward() differentiates (Renderer.backward lists them)"))
    return list(names)


def mirrored_materials(scene, named, switched=None) -> tuple:
    """The materials whose mirror rays a grad frame records whatever their reflectivity: those whose
    ``materials.<name>.reflectivity`` the caller names (render(grad=[names])), so that a reflectivity of 0,
    which switches the mirror rays off, still gets its derivative (the colour the mirror would show); none
    where the frame cannot reflect (render.max_depth 1, or reflection switched off: ``switched``, the
    effects the caller's options leave on), its image then truly independent of the reflectivity."""
    if scene.render.max_depth <= 1 or (switched is not None and "reflection" not in switched):
        return ()
    return tuple(m for m in scene.materials if f"materials.{m}.reflectivity" in named)


def parameter_names(scene) -> list[str]:
    """The r.params names backward() can differentiate with respect to: the objects' vertices and poses
    (translation, rotation) too (a smooth object's computed vertex normals moving with them), but not an area
    light's own object's (its sample points are held fixed), and their vertex colours where they have them;
    an area light's radiance and an emitting material's emission, a rectangle, disk or sphere light's own
    shape (grad_area_shape.shape_keys: its center, normal, size or radius, a rectangle's u and v);
    the camera's eye, center, up and fovy."""
    names = [f"materials.{m}.{k}" for m in scene.materials for k in MATERIAL_KEYS]
    names += [f"materials.{name}.{k}" for name, m in scene.materials.items() if m.dielectric for k in DIELECTRIC_KEYS]
    names += [f"materials.{name}.{k}" for name, m in scene.materials.items() for k in TEXTURE_KEYS
              if getattr(m, k) is not None and getattr(m, k).image is not None]
    names += [f"materials.{name}.emission" for name, m in scene.materials.items() if _emits(m)]
    names += [f"lights.{i}.{k}" for i, light in enumerate(scene.lights) if not (light.area or light.environment)
              for k in LIGHT_KEYS
              if getattr(light, k) is not None]  # as r.params has them: no position for a directional light
    names += [f"lights.{i}.radiance" for i, light in enumerate(scene.lights) if light.area]
    names += [f"lights.{i}.{k}" for i, light in enumerate(scene.lights) for k in shape_keys(light)]
    emitters = _emitter_objects(scene)
    names += [f"objects.{name}.vertices" for name, i in object_names(scene).items()
              if scene.objects[i].name not in emitters]
    names += [f"objects.{name}.{k}" for name, i in object_names(scene).items()
              if scene.objects[i].name not in emitters for k in POSE_KEYS]
    names += [f"objects.{name}.colors" for name, i in object_names(scene).items()
              if scene.objects[i].colors is not None]
    names += [f"camera.{k}" for k in CAMERA_KEYS]
    return names


def _emits(material) -> bool:
    """Whether a material's emission makes its objects area lights (Scene.emissive_lights' rule)."""
    return material.emission is not None and max(material.emission) > 0.0


def _emitter_objects(scene) -> set:
    """The names of the objects that are area lights (a light's ``object``, an emitting material's)."""
    return {light.object for light in scene.area_lights if light.object is not None}


def area_sources(scene) -> list[str]:
    """Per area light (scene.area_lights' order, the kernels' table's), the r.params name its radiance is:
    an area light's lights.<i>.radiance, an emitting material's materials.<name>.emission (one light per
    object name of that material, Scene.emissive_lights)."""
    out = [f"lights.{i}.radiance" for i, light in enumerate(scene.lights) if light.area]
    named = set()
    for o in scene.objects:  # Scene.emissive_lights' loop, to name each light's material
        m = scene.materials.get(o.material)
        if m is not None and _emits(m) and o.name not in named:
            named.add(o.name)
            out.append(f"materials.{o.material}.emission")
    assert len(out) == len(scene.area_lights)
    return out


def _name_refusal(scene, name: str) -> str | None:
    """Why backward() cannot differentiate r.params' ``name`` in this scene (None: it can or it is unknown)."""
    section, owner, key = (name.split(".") + ["", "", ""])[:3]
    if section == "lights" and owner.isdigit() and int(owner) < len(scene.lights) and scene.lights[int(owner)].environment:
        return f"an environment light's {key or 'parameters'} is not differentiated yet (nor is any gradient of a scene with one)"
    if section == "objects" and owner in object_names(scene) and \
            scene.objects[object_names(scene)[owner]].name in _emitter_objects(scene):
        return ("the object is an area light: its sample points (the light's position and shape) are held fixed, "
                "not differentiated yet")
    if section == "materials" and key == "emission" and owner in scene.materials and \
            scene.materials[owner].emission is not None and not _emits(scene.materials[owner]):
        return ("an emission of 0 makes no area light (no sample points to differentiate): give it a positive "
                "value")
    return None


def not_differentiated(scene, name, known=None) -> str | None:
    """Why backward() refuses ``name`` in every frame of ``scene``, in the words it refuses it with (None: a name
    it differentiates, parameter_names; ``known``: those names, where the caller has them)."""
    if name in (parameter_names(scene) if known is None else known):
        return None
    return _name_refusal(scene, str(name)) or (
        "not a parameter backward() differentiates yet (materials.<name>.ka | kd | ks | shininess | "
        "reflectivity | ka_texture | kd_texture | ks_texture | emission, a dielectric's ior | "
        "transmittance | absorption, lights.<i>.color | position | direction | radiance | center | normal | "
        "size | radius | u | v (an area light's of its own shape, as it has them), objects.<name>.vertices | translation | rotation | colors (vertex "
        "colours), camera.eye | center | up | fovy)")


def _unrecorded(scene, geom, hits: Record, name: str) -> bool:
    """Whether ``name`` is a reflectivity of 0 (every component) of a material the frame's objects use, whose
    mirror rays the frame did not record though it could reflect: its derivative, the mirrored colour, is
    not in the record (render(grad=[name]) records it)."""
    section, owner, key = (name.split(".") + ["", "", ""])[:3]
    if section != "materials" or key != "reflectivity" or owner not in geom.material_names:
        return False
    m = scene.materials[owner]
    if hits.fx.refraction and m.dielectric:  # a k_r > 0 makes glass a mirror: a jump, not a slope
        return False
    return hits.reflects and owner not in hits.mirrored and max(m.reflectivity) <= 0.0


def _frame_refusal(scene, geom, hits, name: str) -> str | None:
    """Why backward() cannot differentiate ``name`` at this recorded frame (None: it can): a reflectivity
    of 0 the record holds no mirror rays for."""
    if _unrecorded(scene, geom, hits, name):
        return (f"a reflectivity of 0 switches the mirror rays off, and this frame did not record them: render "
                f"with grad=[{name!r}] (its mirror rays recorded for its derivative)")
    return None


def checked_names(scene, geom, hits, wrt) -> list[str]:
    """backward()'s ``wrt``, checked: each name one backward() can differentiate at this recorded frame
    (else one ArgumentError naming it and why); None: every such name (parameter_names)."""
    known = parameter_names(scene)
    if wrt is None:  # everything this frame can be differentiated in
        wrt = [n for n in known if _frame_refusal(scene, geom, hits, n) is None]
    wrt = list(wrt)
    for name in wrt:
        why = not_differentiated(scene, name, known)
        if why is not None:
            raise ArgumentError("backward", str(name), why)
        why = _frame_refusal(scene, geom, hits, name)
        if why is not None:
            raise ArgumentError("backward", str(name), why)
    return wrt


def gradients_by_name(scene, geom, launched, wrt) -> dict:
    """{name: gradient} for each r.params name in ``wrt``, from the adjoints a wp.Tape left in the replay's
    differentiable arrays (``launched``: grad.py's Replay, its ``arrays`` by key and its ``images``),
    each shaped as the parameter, float64: per material slot, light, area light, vertex, object (a pose) and
    camera row the one the name stands for, summed where r.params ties two together (ka following kd) and
    projected where the scene keeps a unit vector (a light's direction)."""
    arrays = launched.arrays
    slot = {name: i for i, name in enumerate(geom.material_names)}
    whitted = [i for i, light in enumerate(scene.lights) if not light.area]
    grads = {k: a.grad.numpy() for k, a in arrays.items() if k not in ("points", "shape") and a.grad is not None}
    shapes = gradients_of(scene, arrays["shape"]) if "shape" in arrays else {}
    grads["direction"] = grads["direction"]["direction"]  # the lights' LightShape rows' direction field
    camera_rows = {key: i for i, key in enumerate(CAMERA_KEYS[:3])}

    def texels(slot: int, key: str) -> np.ndarray:  # a texture's adjoint, (H, W, 3) with row 0 at the top
        offset, h, w = launched.images[(slot, key)]
        return grads["texels"][offset:offset + h * w].reshape(h, w, 3)[::-1].astype(np.float64)

    starts = np.cumsum([0] + [len(o.vertices) for o in scene.objects])
    if "points" in arrays:  # the replay moved the vertices
        point_grads = arrays["points"].grad.numpy().astype(np.float64)
    out = {}
    for name in wrt:
        section, owner, key = (name.split(".") + [""])[:3]  # camera.<key>: two parts
        if section == "objects":  # the points are the objects' vertices in order, less the frame origin
            i = object_names(scene)[owner]
            if key == "colors":  # the colours likewise, one per vertex
                out[name] = grads["colors"][starts[i]:starts[i + 1]].astype(np.float64)
                continue
            if key in POSE_KEYS:  # one row per object (grad.pose_points)
                out[name] = grads[key][i].astype(np.float64)
                continue
            out[name] = point_grads[starts[i]:starts[i + 1]]
        elif section == "camera":  # eye and center less the frame origin (a shift: the same derivative), up
            out[name] = (grads["fovy"][0] if owner == "fovy" else grads["camera"][camera_rows[owner]]).astype(np.float64)
        elif name in shapes:  # a shape light's center, normal, size, radius, u or v
            out[name] = shapes[name]
        elif key in ("radiance", "emission"):  # the area lights whose radiance it is
            rows = [j for j, source in enumerate(area_sources(scene)) if source == name]
            out[name] = grads["radiance"][rows].astype(np.float64).sum(0) if rows else np.zeros(3)
        elif section == "materials":
            if owner not in slot:  # a material no object uses
                texture = getattr(scene.materials[owner], key, None) if key in TEXTURE_KEYS else None
                out[name] = np.zeros(() if key in ("shininess", "ior") else texture.image.shape if texture else (3,))
                continue
            if key in DIELECTRIC_KEYS and key not in grads:  # a frame without the tree (max_depth 1): no glass
                out[name] = np.zeros(() if key == "ior" else (3,))
                continue
            if key in TEXTURE_KEYS:
                out[name] = texels(slot[owner], key[:2])
                if key == "kd_texture" and scene.materials[owner].ka_texture_follows_kd:  # as ka follows kd
                    out[name] = out[name] + texels(slot[owner], "ka")
                continue
            out[name] = grads[key][slot[owner]].astype(np.float64)
            if key == "kd" and scene.materials[owner].ka_follows_kd:  # ka is kd there (r.params keeps it so)
                out[name] = out[name] + grads["ka"][slot[owner]]
        else:
            out[name] = grads[key][whitted.index(int(owner))].astype(np.float64)
            if key == "direction":  # Light keeps d / |d| of the d it is given, |d| = 1: (I - d d^T) adjoint
                unit = np.asarray(scene.lights[int(owner)].direction, np.float64)
                out[name] = out[name] - unit * (unit @ out[name])
    return out
