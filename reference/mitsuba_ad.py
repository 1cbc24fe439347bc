"""Mitsuba's AD of the reference's own Whitted model (mitsuba_whitted.py), the independent check of warprt's
image gradients and the engine its cost is measured against (benchmarks/gradient_cost.py).

The reference integrator's levels (integ.level: its material(), local() with Mitsuba's emitters'
sample_direction and ray_test shadows, its area_light() and emitted(), mirror rays by si.spawn_ray) are
unrolled in Python at the camera rays through the pixel centres: straight-line code, with no symbolic
loop for reverse mode to replay. dr.enable_grad on the tables material() gathers from (ka, kd, ks,
shininess, kr per shape), on each point, spot or directional emitter's intensity (a directional one's
irradiance) and on each area emitter's radiance; dr.backward of sum(weights * image). Each ray's hit
follows the shapes' parameters (none enabled here), and each shadow ray's answer is a boolean: faces and
visibility are held fixed, as warprt's gradient holds them. With glass, tree_ad_gradients: Whitted's whole ray
tree (reference/ray_tree.py's model) with its rays kept in the AD graph from level to level.
"""

from __future__ import annotations

import numpy as np

from . import mitsuba_variant
from .mitsuba_whitted import Switches, mitsuba_scene
from .ray_tree import eye_medium_row, primary_rays

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


def light_colours_with_grad(tables) -> tuple[list, list]:
    """Each point, spot or directional emitter of the reference's ``tables`` traversed (mi.traverse) with
    its C_l (a point or spot emitter's intensity, a directional one's irradiance) under AD, its gradient
    cleared (mitsuba_scene keeps a converted scene for the next calls on the same Scene): (parameters, keys)."""
    import drjit as dr
    import mitsuba as mi

    emitters = [mi.traverse(e) for e, _ in tables.lights]
    keys = ["irradiance.value" if "irradiance.value" in p.keys() else "intensity.value" for p in emitters]
    for p, key in zip(emitters, keys):
        dr.enable_grad(p[key])
        dr.clear_grad(p[key])
        p.update()
    return emitters, keys


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
    whitted, keys = light_colours_with_grad(t)
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


TABLES = {"ior": "eta", "transmittance": "kt", "absorption": "sigma", "kd": "kd", "ka": "ka"}


def tree_ad_gradients(s, weights, detach_fresnel: bool = False) -> tuple[np.ndarray, dict]:
    """Mitsuba's image of ``s`` at the pixel centres through Whitted's whole ray tree (reference/ray_tree.py's,
    level by level: Mitsuba's intersection, Beer's law over each segment, the integrator's own local(),
    mi.fresnel, mi.reflect, mi.refract and si.spawn_ray) with its rays kept in Dr.Jit's AD graph from level to
    level (the children gathered by index), and its AD gradients of sum(weights * image), by r.params name (the
    materials' ior, transmittance, absorption and kd, summed over their objects' table rows; the lights'
    colours). ``detach_fresnel``: F detached (a control)."""
    mitsuba_variant()
    import drjit as dr
    import mitsuba as mi
    from warprt.scene import resolve_effects

    ms = mitsuba_scene(s)
    integ = ms.integrator
    sw = Switches.for_effects(resolve_effects(s), s.render)
    integ.switches = sw
    t = integ.tables
    for key in TABLES.values():
        dr.enable_grad(getattr(t, key))
        dr.clear_grad(getattr(t, key))
    emitters, keys = light_colours_with_grad(t)
    W, H = s.camera.width, s.camera.height
    o, d, maxt, pixel, _ = primary_rays(ms, s.camera, 1)
    n = len(o)
    ray = mi.Ray3f(mi.Point3f(o.T), mi.Vector3f(d.T))
    ray.maxt = mi.Float(maxt)
    start = mi.Point3f(o.T)
    w = mi.Color3f(dr.ones(mi.Float, n))
    med = mi.UInt32(np.full(n, eye_medium_row(ms, s.camera.eye) if sw.absorption else 0, np.uint32))
    flags = mi.RayFlags.Minimal | mi.RayFlags.ShadingFrame
    if t.attributes or t.own_textures:
        flags = flags | mi.RayFlags.UV
    image, loss = np.zeros((W * H, 3)), mi.Float(0.0)
    wrows = weights.reshape(-1, 3).astype(np.float32)
    for level in range(sw.max_depth):
        si = integ.intersect(ms.mi_scene, ray, flags, level == 0, mi.Bool(True))
        hit = si.is_valid()
        row = dr.reinterpret_array(mi.UInt32, si.shape)
        wgt = w
        if sw.absorption:  # Beer's law from the parent's hit point; a miss travels for ever (0 or 1: no derivative)
            sig = dr.gather(mi.Color3f, t.sigma, med)
            dist = dr.select(hit, dr.norm(si.p - start), 0.0)
            wgt = w * dr.select(hit, dr.exp(-sig * dist), dr.select(sig > 0.0, 0.0, 1.0))
        side = dr.select(dr.dot(si.n, ray.d) > 0.0, -1.0, 1.0)
        sh = dr.select(dr.isfinite(si.sh_frame.n.x), si.sh_frame.n, si.n)
        mat = integ.material(si, hit)
        local = integ.local(ms.mi_scene, si, mat, sh * side, -ray.d, hit)
        contrib = dr.select(hit, wgt * local, wgt * t.background)
        wp_ = mi.Color3f(wrows[pixel].T)
        loss += dr.sum(contrib.x * wp_.x + contrib.y * wp_.y + contrib.z * wp_.z)
        np.add.at(image, pixel, np.array(dr.detach(contrib)).T)
        eta = dr.gather(mi.Float, t.eta, row, hit)
        glass = hit & (eta > 0.0)
        kr = mat[3] if sw.reflection else mi.Color3f(0.0)
        mirror = hit & ~glass & (dr.max(kr) > 0.0)
        m = dr.mulsign(sh, dr.dot(sh, si.n))
        cos_w, cos_g = dr.dot(-ray.d, m), dr.dot(-ray.d, si.n)
        fallback = glass & ~(cos_w * cos_g > 0.0)
        m = dr.select(fallback, si.n, m)
        cos_w = dr.select(fallback, cos_g, cos_w)
        F, cos_t, _, eta_ti = mi.fresnel(cos_w, dr.select(glass, eta, 1.0))
        if detach_fresnel:
            F = dr.detach(F)
        kt = dr.gather(mi.Color3f, t.kt, row, hit)
        dir_r = dr.select(glass, dr.normalize(mi.reflect(-ray.d, m)),
                          dr.normalize(ray.d - 2.0 * dr.dot(ray.d, sh * side) * sh * side))
        dir_t = dr.normalize(mi.refract(-ray.d, m, cos_t, eta_ti))
        w_r = wgt * dr.select(glass, mi.Color3f(F), kr)
        w_t = wgt * (1.0 - F) * kt
        has_r = (glass | mirror) & (dr.max(w_r) > 0.0)
        has_t = glass & (F < 1.0) & (dr.max(w_t) > 0.0)
        ray_r, ray_t = si.spawn_ray(dir_r), si.spawn_ray(dir_t)
        med_r = dr.select(glass, dr.select(dr.dot(dir_r, si.n) < 0.0, row, 0), med)
        med_t = dr.select(dr.dot(dir_t, si.n) < 0.0, row, 0)
        hr, ht = np.array(has_r), np.array(has_t)
        if level + 1 >= sw.max_depth or not (hr.any() or ht.any()):
            break
        # The next level: the reflected children, then the refracted ones, gathered in the AD graph.
        ir, it = np.nonzero(hr)[0], np.nonzero(ht)[0]
        index = mi.UInt32(np.concatenate([ir, it]).astype(np.uint32))
        refracted = mi.Bool(np.concatenate([np.zeros(len(ir), bool), np.ones(len(it), bool)]))

        def pick(tp, a_r, a_t):
            return dr.select(refracted, dr.gather(tp, a_t, index), dr.gather(tp, a_r, index))

        ray = mi.Ray3f(pick(mi.Point3f, ray_r.o, ray_t.o), pick(mi.Vector3f, ray_r.d, ray_t.d))
        w = pick(mi.Color3f, w_r, w_t)
        start = dr.gather(mi.Point3f, si.p, index)
        med = pick(mi.UInt32, med_r, med_t)
        pixel = pixel[np.concatenate([ir, it])]
    dr.backward(loss)
    rows = len(np.array(t.eta))
    grads = {k: np.array(dr.grad(getattr(t, v)), np.float64).reshape(rows, -1) for k, v in TABLES.items()}
    out = {}
    for name, mat in s.materials.items():
        objects = [t.row_of_object[i] for i, obj in enumerate(s.objects) if obj.material == name]
        out[f"materials.{name}.kd"] = grads["kd"][objects].sum(0)
        if mat.ka_follows_kd:  # warprt's kd carries ka with it (r.params keeps ka following kd)
            out[f"materials.{name}.kd"] = out[f"materials.{name}.kd"] + grads["ka"][objects].sum(0)
        if mat.dielectric:
            for key in ("ior", "transmittance", "absorption"):
                g = grads[key][objects].sum(0)
                out[f"materials.{name}.{key}"] = g[0] if key == "ior" else g
    for i, (p, key) in enumerate(zip(emitters, keys)):
        out[f"lights.{i}.color"] = np.array(dr.grad(p[key]), np.float64).ravel()
    return image.reshape(H, W, 3).astype(np.float32), out
