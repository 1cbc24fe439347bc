"""The BVH over the scene's triangles, built from conservative (padded) bounds so that a ray which
passes exactly through a shared vertex or edge can never slip between two triangles' boxes.

Why: Warp's ray-box slab test (intersect_ray_aabb) rounds, and Warp bounds each triangle by its
exact box. A ray aimed at a vertex enters the boxes of the triangles around it exactly at their
faces, so one rounding step can reject every one of them and the ray escapes a closed mesh
(measured: 23 to 79 of ~60,000 rays aimed at vertices and edge midpoints, tests/stability).
pbrt-v4 widens the slab interval by 2 gamma(3) for the same reason (Pharr et al., section 6.8.2);
Warp's traversal is native code, so here the boxes are widened instead, by more than that error.

How: wp.Mesh bounds each triangle by the box of its three points[indices] at construction and
never recomputes it (we never refit). So the mesh is built with indices that name two proxy
points per triangle, the corners of its padded box, and the real indices are written into the
same array afterwards: the BVH keeps the padded boxes, the triangle tests read the real vertices.
"""

from __future__ import annotations

import numpy as np

from .._warp import wp
from ..floats import EPS32

# The slab test computes t = (bound - o) * (1/d): three roundings, so |t error| <= gamma(3) |t|,
# i.e. the box face seen by the ray moves by at most gamma(3) |bound - o| along that axis. Both
# |bound| and |o| are at most R (ray origins are the eye, at 0, or hit points in the scene), so a
# pad of 2 gamma(3) 2 R covers the entry and exit faces; 16 eps R is 1.3 times that.
BOUNDS_PAD = 16.0 * EPS32


def padded_bounds(points: np.ndarray, faces: np.ndarray, pad: float = BOUNDS_PAD) -> tuple[np.ndarray, np.ndarray]:
    """Each triangle's box, widened per axis by BOUNDS_PAD times the largest |coordinate| on that
    axis (the eye at 0 included), rounded outwards to float32."""
    tri = points.astype(np.float64)[faces]
    reach = np.abs(points.astype(np.float64)).max(axis=0) if len(points) else np.zeros(3)
    lower = (tri.min(axis=1) - pad * reach).astype(np.float32)
    upper = (tri.max(axis=1) + pad * reach).astype(np.float32)
    if pad > 0.0:  # the float32 cast rounds to nearest: step once outwards so the box only grows
        lower = np.nextafter(lower, np.float32(-np.inf))
        upper = np.nextafter(upper, np.float32(np.inf))
    return lower, upper


def build_mesh(points: np.ndarray, indices: np.ndarray, device="cpu", bvh_constructor: str = "sah",
               pad: float = BOUNDS_PAD, groups: np.ndarray | None = None):
    """A wp.Mesh over float32 ``points`` (V, 3) and flat int32 ``indices`` (3T,) whose BVH uses
    padded_bounds. Returns (mesh, points array, indices array): the points array holds the V real
    points first, then the 2T proxy corners; the indices array holds the real indices. pad = 0
    gives Warp's own exact boxes (the stability suite measures what that loses); ``groups`` (one
    int per triangle) gives each group its own subtree, for queries from wp.mesh_get_group_root."""
    points = np.asarray(points, np.float32).reshape(-1, 3)
    faces = np.asarray(indices, np.int32).reshape(-1, 3)
    v, t = len(points), len(faces)
    lower, upper = padded_bounds(points, faces, pad)
    all_points = np.ascontiguousarray(np.concatenate([points, lower, upper]), np.float32)
    corner = np.arange(t, dtype=np.int32)
    proxy = np.stack([v + corner, v + t + corner, v + corner], axis=1)  # box of (lower, upper, lower)
    points_wp = wp.array(all_points, dtype=wp.vec3, device=device)
    indices_wp = wp.array(np.ascontiguousarray(proxy.reshape(-1)), dtype=wp.int32, device=device)
    if groups is not None:
        groups = wp.array(np.ascontiguousarray(groups, np.int32), dtype=wp.int32, device=device)
    mesh = wp.Mesh(points=points_wp, indices=indices_wp, bvh_constructor=bvh_constructor, groups=groups)
    # The mesh reads indices through the same buffer: from here on its triangles are the real ones.
    indices_wp.assign(np.ascontiguousarray(faces.reshape(-1)))
    return mesh, points_wp, indices_wp
