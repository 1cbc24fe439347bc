"""A warprt Scene's AOVs as Mitsuba 3's own ``aov`` integrator reports them, on the reference's scene
conversion (mitsuba_whitted.MitsubaScene: the same meshes, vertex normals, sensor and sampler).

    aovs = render_mitsuba_aovs(scene)   # depth, sh_normal, geo_normal, position, uv, object, face, hit
"""

from __future__ import annotations

import numpy as np

from .mitsuba_whitted import mitsuba_scene

# Mitsuba's AOV names for what warprt calls depth, the normals, position, uv, object and face.
_MITSUBA_AOVS = (("depth", "depth", 1), ("sh_normal", "sh_normal", 3), ("geo_normal", "geo_normal", 3),
                 ("position", "position", 3), ("uv", "uv", 2), ("object", "shape_index", 1), ("face", "prim_index", 1))


def render_mitsuba_aovs(scene, spp: int = 1) -> dict:
    """Mitsuba's first-hit AOVs of ``scene`` with its own camera, ``spp`` stratified samples at the
    stratum centres and a box filter (so for spp > 1 each is the mean over all samples, misses as 0).
    Returned as warprt names them, NumPy (H, W[, C]) float64, with two translations into warprt's
    conventions: ``depth`` is measured from the eye (Mitsuba starts camera rays on its near clip plane,
    and measures si.t from there: near_clip / cos(theta) is added back), and ``object`` is the index in
    scene.objects (Mitsuba reports the shape's registry index). ``hit``: where the sample hit (spp 1).
    The normals are Mitsuba's, not turned to face the camera."""
    from warprt.scene import resolve_effects

    ms = mitsuba_scene(scene, resolve_effects(scene).smooth)
    mi, dr = ms.mi, ms.dr
    if not dr.is_jit_v(mi.Float):
        raise RuntimeError(f"Mitsuba's shape index is a registry index only in its JIT variants, not {mi.variant()}")
    integrator = mi.load_dict({"type": "aov", "aovs": ",".join(f"{name}:{kind}" for name, kind, _ in _MITSUBA_AOVS)})
    sensor = ms.sensor(scene.camera, spp)
    image = np.array(mi.render(ms.mi_scene, sensor=sensor, integrator=integrator, spp=spp, seed=0), np.float64)
    out, c = {}, 0
    for name, _, n in _MITSUBA_AOVS:
        out[name] = image[..., c] if n == 1 else image[..., c:c + n]
        c += n
    out["hit"] = out["depth"] > 0.0  # a miss reports 0 for every AOV

    eye = np.asarray(scene.camera.eye, np.float64)
    forward = np.asarray(scene.camera.center, np.float64) - eye
    forward /= np.linalg.norm(forward)
    to_hit = out["position"] - eye
    cos_theta = (to_hit @ forward) / np.maximum(np.linalg.norm(to_hit, axis=-1), 1e-300)
    out["depth"] = np.where(out["hit"], out["depth"] + sensor.near_clip() / np.where(out["hit"], cos_theta, 1.0), 0.0)

    registry = {}
    for shape in ms.mi_scene.shapes():  # object_00007 is scene.objects[7]; a file's unread shapes are not objects
        if shape.id().startswith("object_"):
            registry[int(dr.reinterpret_array(mi.UInt32, mi.ShapePtr(shape))[0])] = int(shape.id().split("_")[1])
    index = np.rint(out["object"]).astype(np.int64)
    out["object"] = np.where(out["hit"], np.vectorize(lambda i: registry.get(i, -2))(index), -1)
    out["face"] = np.where(out["hit"], np.rint(out["face"]).astype(np.int64), -1)
    return out
