"""Refracted rays never re-hit the triangle they pass through: over 170,000 of them through the renderer's
own surface(), refract() and offset_ray_origin(), on the self-intersection suite's triangles (sizes 1e-4
to 1e4, up to 1e6 from the eye, hits near edges and vertices, floors seen from just above) entering and
leaving glass, and on rays leaving glass just under the critical angle, whose refracted rays graze the
surface (down to about 0.1 degree). Each triangle sits alone in its own BVH group, so any hit of a
refracted ray is the triangle itself. With the error bound scaled down the same rays self-intersect:
the probe can fail."""

import numpy as np

from marks import slow
from warprt.geometry import build_mesh
from warprt.kernels import OFFSET_SCALE

from stability.probes import record, run_refraction_probe, surface_tables
from stability.test_self_intersection import SCALES, probe_set, random_triangles, unit

ETA = 1.5
CRITICAL = np.arcsin(1.0 / ETA)


def grazing_exits(n: int, seed: int):
    """Rays inside the glass (behind the winding normal) meeting random triangles at the critical angle
    less 1e-6 to 1e-1 radians: their refracted rays leave within a few degrees of the surface."""
    rng = np.random.default_rng(seed)
    v, b, size = random_triangles(rng, n)
    v64 = v.astype(np.float64)
    normal = np.cross(v64[:, 1] - v64[:, 0], v64[:, 2] - v64[:, 0])
    length = np.linalg.norm(normal, axis=1)
    usable = length > 0
    normal /= np.where(usable, length, 1.0)[:, None]
    target = np.einsum("nj,nji->ni", b, v64)
    tangent = unit(rng, n)
    tangent -= np.einsum("ni,ni->n", tangent, normal)[:, None] * normal
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    theta = CRITICAL - 10 ** rng.uniform(-6, -1, n)
    d = np.cos(theta)[:, None] * normal + np.sin(theta)[:, None] * tangent  # along the normal: from inside
    origin = (target - d * (size * 10 ** rng.uniform(-2, 2, n))[:, None]).astype(np.float32)
    posed = usable & (np.einsum("ni,ni->n", origin.astype(np.float64) - v64[:, 0], normal) < 0)
    mesh, points, indices = build_mesh(v.reshape(-1, 3), np.arange(3 * n, dtype=np.int32), groups=np.arange(n, dtype=np.int32))
    return (mesh, points, indices, surface_tables(mesh, points, indices, n)), origin, target.astype(np.float32), posed


@slow
def test_refracted_rays_never_hit_their_own_triangle():
    sets = {}
    for kind, n, seed in (("random", 135_000, 11), ("floor", 115_000, 12)):
        keep, origin, target, _, posed, _ = probe_set(kind, n, seed)
        sets[kind] = (keep, origin, target, posed)
    sets["grazing exits"] = grazing_exits(125_000, 13)
    rows = {}
    for kind, (keep, origin, target, posed) in sets.items():
        for scale in SCALES:
            out = run_refraction_probe(keep[3], origin, target, ETA, scale)
            hit = (out[:, 0] == 1) & posed
            refracted = hit & (out[:, 1] == 1)
            rows[(kind, scale)] = {"hit_points": int(hit.sum()), "refraction_rays": int(refracted.sum()),
                                   "self_hits": int(out[refracted, 2].sum())}
    record("refraction_offsets", {f"{kind}, {s:g}x bound": r for (kind, s), r in rows.items()} | {"OFFSET_SCALE": OFFSET_SCALE})
    rendered = [rows[(kind, OFFSET_SCALE)] for kind in sets]
    assert sum(r["refraction_rays"] for r in rendered) >= 150_000
    assert rows[("grazing exits", OFFSET_SCALE)]["refraction_rays"] >= 100_000
    assert all(r["self_hits"] == 0 for r in rendered), rendered
    # Without the offset the same rays re-hit their triangle: the probe sees self-intersection.
    assert rows[("random", 0.0)]["self_hits"] > 1000 and rows[("grazing exits", 0.0)]["self_hits"] > 1000
