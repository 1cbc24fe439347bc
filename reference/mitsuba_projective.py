"""Mitsuba 3's ``direct_projective`` integrator, issue 38's reference for the boundary term of an image's
derivative: the converged gradient of sum(weights * image) in an object's vertices, silhouettes included
(Mitsuba samples the camera's silhouette edges at random) and with ``shadows`` the edges of the shadows cast
on the way to an area light (its indirect term, guided), for the scenes warprt and Mitsuba shade alike: flat
triangles of diffuse kd (no ka, ks, reflectivity), lit by directional lights or rectangle and disk area
lights (Mitsuba's continuous emitter: warprt's sample points converge to it), on a black background.

    mean, stderr = projective_vertex_gradients(scene, weights, "tri", passes=32)
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from . import mitsuba_variant
from .mitsuba_whitted import _shape_light


def projective_scene(s, spp: int = 256):
    """The Mitsuba scene of ``s``: each object a flat mesh with a diffuse BSDF of its kd, each directional
    light a directional emitter of irradiance pi * colour (Mitsuba's diffuse is kd / pi: warprt's kd n . L C),
    each rectangle or disk area light Mitsuba's own shape with an area emitter (mitsuba_whitted's) of radiance
    pi L_e (warprt's kd L_e cos cos' / r^2 dA, Mitsuba's kd / pi; seen directly it would be pi times warprt's, so
    keep it out of view), the camera
    as mitsuba_whitted's sensor (look_at, vertical fov, box filter) with an independent sampler."""
    mitsuba_variant()
    import drjit as dr
    import mitsuba as mi

    cam = s.camera
    for light in s.lights:
        if light.type != "directional" and light.shape not in ("rectangle", "disk"):
            raise ValueError("projective_scene: directional and shape area lights only (a point light has no "
                             "area for Mitsuba)")
    used = [s.materials[o.material] for o in s.objects]
    if any(max(m.ks) > 0 or max(m.reflectivity) > 0 for m in used) or \
            max(s.render.ambient) > 0 or max(s.render.background) > 0:
        raise ValueError("projective_scene: diffuse kd only, no ambient, a black background")
    d = {"type": "scene",
         "sensor": {"type": "perspective", "fov_axis": "y", "fov": float(cam.fovy), "near_clip": 1e-4,
                    "far_clip": 1e4,
                    "to_world": mi.ScalarTransform4f().look_at(origin=list(map(float, cam.eye)),
                                                              target=list(map(float, cam.center)),
                                                              up=list(map(float, cam.up))),
                    "film": {"type": "hdrfilm", "width": int(cam.width), "height": int(cam.height),
                             "rfilter": {"type": "box"}, "pixel_format": "rgb"},
                    "sampler": {"type": "independent", "sample_count": int(spp)}}}
    for i, light in enumerate(s.lights):
        if light.area:  # of radiance pi L_e, as the directional's irradiance is pi C (shading.py: kd a BRDF value)
            d[f"light_{i}"] = _shape_light(mi, replace(light, radiance=tuple(math.pi * c for c in light.radiance)))
            continue
        d[f"light_{i}"] = {"type": "directional", "direction": list(map(float, light.direction)),
                           "irradiance": {"type": "rgb", "value": [math.pi * float(c) for c in light.color]}}
    for o in s.objects:
        mesh = mi.Mesh(o.name, len(o.vertices), len(o.faces))
        p = mi.traverse(mesh)
        p["vertex_positions"] = dr.ravel(mi.Point3f(np.ascontiguousarray(np.asarray(o.vertices, np.float32).T)))
        p["faces"] = dr.ravel(mi.Vector3u(np.ascontiguousarray(np.asarray(o.faces, np.uint32).T)))
        p.update()
        mesh.set_bsdf(mi.load_dict({"type": "diffuse", "reflectance": {
            "type": "rgb", "value": [float(c) for c in s.materials[o.material].kd]}}))
        d[o.name] = mesh
    scene = mi.load_dict(d)
    return scene, mi.traverse(scene)


def projective_vertex_gradients(s, weights, name: str, passes: int = 32, spp: int = 256,
                                shadows: bool = False) -> tuple:
    """(mean, standard error), each (V, 3) float64: Mitsuba's direct_projective gradient of sum(weights *
    image) in object ``name``'s vertices, over ``passes`` independent renders of ``spp`` samples a pixel;
    with ``shadows``, its indirect term too (the edges of shadows), else only the camera's silhouettes."""
    mitsuba_variant()
    import drjit as dr
    import mitsuba as mi

    scene, params = projective_scene(s, spp)
    # sppi 0: no indirect edges, the camera's only; else as many samples as the others (render's spp)
    integrator = mi.load_dict({"type": "direct_projective", **({} if shadows else {"sppi": 0})})
    key, w, runs = f"{name}.vertex_positions", mi.TensorXf(np.asarray(weights, np.float32)), []
    for seed in range(passes):
        dr.enable_grad(params[key])
        params.update()
        image = mi.render(scene, params, integrator=integrator, spp=spp, seed=seed + 1)
        dr.backward(dr.sum(image * w, axis=None))
        runs.append(np.array(dr.grad(params[key]), np.float64).reshape(-1, 3))
        dr.disable_grad(params[key])
        params.update()
    runs = np.asarray(runs)
    return runs.mean(0), runs.std(0, ddof=1) / math.sqrt(passes)
