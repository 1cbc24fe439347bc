"""Every reflection ray of a frame, as the tracer spawns it, answered by its planar mirrors' virtual
camera where that decides it and by Warp's closest-hit query always, for the mismatch counters."""

from __future__ import annotations

import numpy as np

from shortcuts import probe_camera, probe_ray, probe_samples
from warprt.geometry import SceneData
from warprt.kernels import (CameraData, Mirrors, init_warp, make_surface, mirror_chain, mirror_hit, offset_ray_origin,
                            reflect, wp)

init_warp()
surface = make_surface(True)
LEVELS = 8


@wp.kernel
def reflection_rays(s: SceneData, c: CameraData, m: Mirrors, max_depth: int, k: int, samples: int,
                    out: wp.array3d(dtype=wp.int32)):
    """Per pixel sample and ray level 1..: (reflection rays, decided by the mirrors, of those not the
    query's face, u and v to the bit)."""
    i = wp.tid()
    x = i % c.width
    row = i / c.width
    for sample in range(samples):
        o = c.eye
        d = probe_ray(c, x, row, sample, samples, k)
        chain = int(-1)
        src = int(-1)
        for depth in range(max_depth):
            if depth > 0:
                mh = mirror_hit(s, m, depth, o, d, chain, x, row, sample, src)
                q = wp.mesh_query_ray(s.mesh, o, d, 1.0e30)
                f = int(-1)
                if q.result:
                    f = q.face
                out[i, depth - 1, 0] = out[i, depth - 1, 0] + 1
                if mh.found:
                    out[i, depth - 1, 1] = out[i, depth - 1, 1] + 1
                    same = mh.face == f
                    if f >= 0:
                        same = same and mh.u == q.u and mh.v == q.v
                    if not same:
                        out[i, depth - 1, 2] = out[i, depth - 1, 2] + 1
            q = wp.mesh_query_ray(s.mesh, o, d, 1.0e30)
            if not q.result:
                break
            hit = surface(s, q.face, q.u, q.v, q.normal, d)
            if wp.max(s.kr[hit.material]) <= 0.0 or depth + 1 >= max_depth:
                break
            d = wp.normalize(reflect(d, hit.n))
            o = offset_ray_origin(hit.p, hit.err, hit.ng, d)
            chain = mirror_chain(m, chain, q.face)
            src = q.face


def level_counts(scene, geom, data: SceneData, mirrors: Mirrors) -> np.ndarray:
    """(levels, 3): per reflection level, the rays, those the mirrors decided, and the mismatches."""
    cam = scene.camera
    k, samples = probe_samples(scene)
    out = wp.zeros((cam.width * cam.height, LEVELS, 3), dtype=wp.int32)
    wp.launch(reflection_rays, dim=cam.width * cam.height,
              inputs=[data, probe_camera(scene, geom), mirrors, min(scene.render.max_depth, LEVELS + 1), k, samples, out])
    return out.numpy().astype(np.int64).sum(axis=0)
