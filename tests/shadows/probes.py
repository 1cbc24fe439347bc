"""Every shadow ray of a frame, as the tracer spawns it (its own camera, hit record, offset, mirror
bounce, and at glass the refracted ray, or the reflected one past the critical angle), each answered by
Warp's any-hit query and by the light-space grid, for the mismatch counters."""

from __future__ import annotations

import numpy as np

from shortcuts import probe_camera
from warprt.geometry import LIGHT_DIRECTIONAL, SceneData
from warprt.kernels import (CameraData, camera_ray, grid_occluded, init_warp, make_surface, offset_ray_origin, reflect,
                            refract, triangle, unit_normal, wp)

init_warp()
surface = make_surface(True)


@wp.kernel
def frame_shadow_rays(s: SceneData, c: CameraData, max_depth: int, counts: wp.array(dtype=wp.vec3i)):
    """Per pixel centre: (shadow rays, blocked by the BVH, grid answers that differ from the BVH's)."""
    i = wp.tid()
    o = c.eye
    d = camera_ray(c, i % c.width, i / c.width, 0.5, 0.5)
    rays = int(0)
    blocked = int(0)
    differ = int(0)
    for depth in range(max_depth):
        q = wp.mesh_query_ray(s.mesh, o, d, 1.0e30)
        if not q.result:
            break
        hit = surface(s, q.face, q.u, q.v, q.normal, d)
        for l in range(s.num_lights):
            directional = s.light_shape[l].kind == LIGHT_DIRECTIONAL
            L = -s.light_shape[l].direction
            if not directional:
                L = wp.normalize(s.light_pos[l] - hit.p)
            if wp.dot(hit.n, L) > 0.0:
                so = offset_ray_origin(hit.p, hit.err, hit.ng, L)
                # A spot's rays are a point light's (inside its cone or not: more rays to check); a
                # directional light's go to infinity.
                d = L
                dist = 1.0e30
                if not directional:
                    to_light = s.light_pos[l] - so
                    dist = wp.length(to_light)
                    d = to_light / dist
                bvh = wp.mesh_query_ray_anyhit(s.mesh, so, d, dist)
                grid = grid_occluded(s, l, so, d, dist)
                rays += 1
                blocked += wp.where(bvh, 1, 0)
                differ += wp.where(bvh != grid, 1, 0)
        if wp.max(s.kr[hit.material]) > 0.0:
            d = wp.normalize(reflect(d, hit.n))
        elif s.ior[hit.material] > 0.0:  # one path of the ray tree: the refracted ray where there is one
            p0, p1, p2 = triangle(s, q.face)
            eta = s.ior[hit.material]
            eta_rel = wp.where(wp.dot(hit.ng, unit_normal(p0, p1, p2)) > 0.0, eta, 1.0 / eta)
            t, transmits = refract(d, hit.ng, eta_rel)
            if transmits:
                d = wp.normalize(t)
            else:
                d = wp.normalize(reflect(d, hit.ng))
        else:
            break
        o = offset_ray_origin(hit.p, hit.err, hit.ng, d)
    counts[i] = wp.vec3i(rays, blocked, differ)


@wp.kernel
def given_rays(s: SceneData, lights: wp.array(dtype=wp.int32), origins: wp.array(dtype=wp.vec3),
               out: wp.array(dtype=wp.vec2i)):
    """Shadow rays from given origins to given lights: (BVH blocked, grid blocked)."""
    i = wp.tid()
    l = lights[i]
    to_light = s.light_pos[l] - origins[i]
    dist = wp.length(to_light)
    d = to_light / dist
    out[i] = wp.vec2i(wp.where(wp.mesh_query_ray_anyhit(s.mesh, origins[i], d, dist), 1, 0),
                      wp.where(grid_occluded(s, l, origins[i], d, dist), 1, 0))


def frame_counts(scene, geom, data: SceneData, max_depth: int) -> dict:
    """The frame's shadow rays (pixel centres, every ray level): how many, blocked, mismatches."""
    cam = scene.camera
    counts = wp.zeros(cam.width * cam.height, dtype=wp.vec3i)
    wp.launch(frame_shadow_rays, dim=cam.width * cam.height, inputs=[data, probe_camera(scene, geom), max_depth, counts])
    rays, blocked, differ = counts.numpy().astype(np.int64).sum(0)
    return {"rays": int(rays), "blocked": int(blocked), "mismatches": int(differ)}


def through_every_vertex_and_edge(geom, rng, limit: int = 20_000) -> np.ndarray:
    """Points (float64) where a shadow ray is hardest to decide: every vertex and edge midpoint (of
    ``limit`` triangles at most), a third of them jittered by a few ulp."""
    tri = geom.points_np.astype(np.float64)[geom.indices_np.reshape(-1, 3)][: max(geom.triangle_count, 0)]
    if len(tri) > limit:
        tri = tri[rng.choice(len(tri), limit, replace=False)]
    at = np.concatenate([tri[:, 0], tri[:, 1], tri[:, 2], (tri[:, 0] + tri[:, 1]) / 2, (tri[:, 1] + tri[:, 2]) / 2,
                         (tri[:, 2] + tri[:, 0]) / 2])
    jittered = at.copy()
    jittered[::3] += rng.normal(size=jittered[::3].shape) * np.abs(jittered[::3]) * 2e-7
    return np.concatenate([at, jittered])


def stress_counts(geom, data: SceneData, lights: np.ndarray, targets: np.ndarray) -> dict:
    """Shadow rays aimed from behind each target, through it, at every light (origins 1.05, 1.5 and 3
    times as far from the light as the target): how many, and how many answers differ."""
    origins, which = [], []
    for l, light in enumerate(np.asarray(lights, np.float64)):
        if not np.all(np.isfinite(light)):  # a directional light: no position to aim from
            continue
        for scale in (1.05, 1.5, 3.0):
            o = (light + (targets - light) * scale).astype(np.float32)
            keep = np.linalg.norm(light.astype(np.float32) - o, axis=1) > 0
            origins.append(o[keep])
            which.append(np.full(int(keep.sum()), l, np.int32))
    o, w = np.concatenate(origins), np.concatenate(which)
    out = wp.zeros(len(o), dtype=wp.vec2i)
    wp.launch(given_rays, dim=len(o), inputs=[data, wp.array(w, dtype=wp.int32), wp.array(o, dtype=wp.vec3), out])
    a = out.numpy()
    return {"rays": len(o), "blocked": int(a[:, 0].sum()), "mismatches": int((a[:, 0] != a[:, 1]).sum())}
