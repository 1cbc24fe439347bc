"""Mitsuba's AD of the reference's own Whitted model (mitsuba_whitted.py), the independent check of warprt's
image gradients and the engine its cost is measured against (benchmarks/gradient_cost.py).

The reference integrator's levels (integ.level: its material(), local() with Mitsuba's emitters'
sample_direction and ray_test shadows, its area_light() and emitted(), mirror rays by si.spawn_ray) are
unrolled in Python at the camera rays through the pixel centres: straight-line code, with no symbolic
loop for reverse mode to replay. dr.enable_grad on the tables material() gathers from (ka, kd, ks,
shininess, kr per shape), on each point, spot or directional emitter's intensity (a directional one's
irradiance) and on each area emitter's radiance; dr.backward of sum(weights * image). Each ray's hit
follows the shapes' parameters (none enabled here), and each shadow ray's answer is a boolean: faces and
visibility are held fixed, as warprt's gradient holds them.
"""

from __future__ import annotations

import numpy as np

from . import mitsuba_variant
from .mitsuba_whitted import Switches, mitsuba_scene

COLOURS = ("ka", "kd", "ks", "shininess", "kr")  # the reference's tables; kr is r.params' reflectivity


def backpropagated(ms, s, weights, detach: bool = False):
    """Mitsuba's image of ``s`` (its MitsubaScene ``ms``) at the pixel centres, the reference's sample() with
    its levels (integ.level) unrolled in Python; dr.backward of sum(weights * image) done (``weights``:
    (H, W, 3)). With ``detach``, the hits do not follow the shapes (RayFlags.DetachShape). Returns the image
    (a Color3f per pixel)."""
    import drjit as dr
    import mitsuba as mi

    integ = ms.integrator
    width, height = s.camera.width, s.camera.height
    idx = dr.arange(mi.UInt32, height * width)
    pos = mi.Point2f((mi.Float(idx % width) + 0.5) / width, (mi.Float(idx // width) + 0.5) / height)
    ray, _ = ms.sensor(s.camera, 1).sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
    color, weight, active = mi.Color3f(0.0), mi.Color3f(1.0), mi.Bool(True)
    for depth in range(integ.max_depth()):
        ray, color, weight, active = integ.level(ms.mi_scene, ray, depth, color, weight, active, detach)
    w = np.asarray(weights, np.float32).reshape(-1, 3)
    dr.backward(dr.sum(color.x * mi.Float(w[:, 0]) + color.y * mi.Float(w[:, 1]) + color.z * mi.Float(w[:, 2])))
    return color


def ad_gradients(s, weights, shadows: bool = True) -> tuple[np.ndarray, dict]:
    """Mitsuba's image (H, W, 3) and its AD gradients of sum(weights * image), by r.params name: every
    material's ka, kd, ks, shininess and reflectivity (summed over the table rows of its objects; kd carries
    ka's where ka follows kd, as r.params keeps it following), each point, spot or directional light's
    ``lights.<i>.color`` and each area light's radiance as ``area.<j>.radiance`` (j in scene.area_lights'
    order; an object light's gradient summed over the scene's emitter, which emitted() evaluates, and its
    sampler's, which area_light() samples). ``shadows=False``: the model without shadows (a control)."""
    mitsuba_variant()
    import drjit as dr
    import mitsuba as mi
    from warprt.scene import resolve_effects

    ms = mitsuba_scene(s)
    integ = ms.integrator
    integ.switches = Switches(**{**Switches.for_effects(resolve_effects(s), s.render).__dict__, "shadows": shadows})
    t = integ.tables
    # mitsuba_scene keeps a converted scene for the next calls on the same Scene: start from no gradient
    for table in (t.ka, t.kd, t.ks, t.shininess, t.kr):
        dr.enable_grad(table)
        dr.clear_grad(table)
    whitted = [mi.traverse(e) for e, _ in t.lights]
    # C_l: a point or spot emitter's intensity, a directional one's irradiance
    keys = ["irradiance.value" if "irradiance.value" in p.keys() else "intensity.value" for p in whitted]
    for p, key in zip(whitted, keys):
        dr.enable_grad(p[key])
        dr.clear_grad(p[key])
        p.update()
    # Per area light, the emitters that are its radiance: the scene's (a shape light's own shape, an object
    # light's mesh) and the sampler's (t.area, the same emitter for a shape light).
    drawn = {shape.id(): shape.emitter() for shape in ms.mi_scene.shapes() if shape.emitter() is not None}
    area = []
    for j, sampler in enumerate(t.area):
        key = f"area_{j:03d}" if s.area_lights[j].shape is not None else next(
            f"object_{i:05d}" for i, o in enumerate(s.objects) if o.name == s.area_lights[j].object)
        emitters = [sampler] + ([drawn[key]] if key in drawn and drawn[key] is not sampler else [])
        area.append([mi.traverse(e) for e in emitters])
        for p in area[-1]:
            dr.enable_grad(p["radiance.value"])
            dr.clear_grad(p["radiance.value"])
            p.update()
    color = backpropagated(ms, s, weights)
    image = np.stack([np.array(c) for c in (color.x, color.y, color.z)], -1).reshape(s.camera.height, s.camera.width, 3)
    table = {k: np.array(dr.grad(getattr(t, k)), np.float64).reshape(len(np.array(t.shininess)), -1) for k in COLOURS}
    out = {}
    for name, m in s.materials.items():
        rows = [t.row_of_object[i] for i, o in enumerate(s.objects) if o.material == name]
        for k in COLOURS:
            g = table[k][rows].sum(0)
            if k == "kd" and m.ka_follows_kd:  # warprt's kd carries ka with it (r.params keeps ka following kd)
                g = g + table["ka"][rows].sum(0)
            out[f"materials.{name}.{'reflectivity' if k == 'kr' else k}"] = g[0] if k == "shininess" else g
    index = [i for i, light in enumerate(s.lights) if light.type != "area"]  # whitted_lights' order
    for i, p, key in zip(index, whitted, keys):
        out[f"lights.{i}.color"] = np.array(dr.grad(p[key]), np.float64).ravel()
    for j, params in enumerate(area):
        out[f"area.{j}.radiance"] = sum(np.array(dr.grad(p["radiance.value"]), np.float64).ravel() for p in params)
    return image, out
