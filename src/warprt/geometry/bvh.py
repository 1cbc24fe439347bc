"""The BVH over the scene's triangles, built from padded bounds so that a ray through a shared vertex
or edge can never slip between two triangles' boxes, from any eye in the region the padding covers.

Why: Warp's ray-box slab test (intersect_ray_aabb) rounds, and Warp bounds each triangle by its
exact box. A ray aimed at a vertex enters the boxes of the triangles around it exactly at their
faces, so one rounding step can reject every one of them and the ray escapes a closed mesh
(measured: 23 to 79 of ~60,000 rays aimed at vertices and edge midpoints, tests/stability).
pbrt-v4 widens the slab interval by 2 gamma(3) for the same reason (Pharr et al., section 6.8.2);
Warp's traversal is native code, so here the boxes are widened instead, by more than that error.

How: wp.Mesh bounds each triangle by the box of its three points[indices] at construction and
at a refit only. So the mesh is built with indices that name two proxy
points per triangle, the corners of its padded box, and the real indices are written into the
same array afterwards: the BVH keeps the padded boxes, the triangle tests read the real vertices.
"""

from __future__ import annotations

import numpy as np

from .._warp import wp
from ..floats import EPS32

# The slab test computes t = (bound - o) * (1/d): three roundings, so |t error| <= gamma(3) |t|,
# i.e. the box face seen by the ray moves by at most gamma(3) |bound - o| along that axis. On axis a,
# |bound| <= R_a, the reach of the coordinates (relative to the frame origin), and |o| <= max(R_a, E):
# secondary rays start at hit points in the scene, camera rays at the eye, which may be anywhere
# within E of the origin on each axis. A pad of 2 gamma(3) (R_a + max(R_a, E)) covers the entry and
# exit faces; BOUNDS_PAD (R_a + max(R_a, E)) / 2 is 1.3 times that (16 eps R_a with the eye at the
# origin, E = 0).
BOUNDS_PAD = 16.0 * EPS32
# E = EYE_REACH times the largest reach R about the frame origin (the objects' centre, frame_origin):
# a camera may orbit the scene at several times its size, or cross it, and reuse the BVH. The pad is
# then 16 eps (R + 8 R) / 2 = 72 eps R, about 4e-6 of the scene, and traversal costs the same.
EYE_REACH = 8.0


@wp.func
def face_vertices(indices: wp.array(dtype=wp.int32), f: int):
    """The vertex indices i0, i1, i2 of face f of the triangle set (its points are points[i0] ...):
    the one definition of the layout every kernel reads a triangle through."""
    return indices[f * 3 + 0], indices[f * 3 + 1], indices[f * 3 + 2]


def eye_reach(points: np.ndarray) -> float:
    """E: how far (per axis) from the frame origin an eye may be for padded_bounds to hold."""
    return EYE_REACH * float(np.abs(np.asarray(points, np.float64)).max(initial=0.0))


def objects_center(objects) -> tuple[np.ndarray, float]:
    """The centre of the objects' bounding box in float64, and their reach about it (the largest
    |coordinate - centre|); (None, 0) for no vertices."""
    parts = [np.asarray(o.vertices, np.float64) for o in objects if len(o.vertices)]
    if not parts:
        return None, 0.0
    lo = np.min([p.min(axis=0) for p in parts], axis=0)
    hi = np.max([p.max(axis=0) for p in parts], axis=0)
    center = 0.5 * (lo + hi)
    return center, float(max(np.max(hi - center), np.max(center - lo)))


def frame_origin(center, reach: float, eye) -> np.ndarray:
    """The world point a Geometry's float32 coordinates are made relative to, a function of the objects
    and the eye alone, so that a frame's image never depends on which earlier frame built the BVH it
    runs on: the objects' centre where the eye lies in the region a BVH built there covers (EYE_REACH
    times the reach, less a margin for the float32 cast of the coordinates), else the eye itself (a
    camera far from the scene keeps exact camera-ray origins, 0)."""
    eye = np.asarray(eye, np.float64)
    if center is None or not np.abs(eye - center).max() <= EYE_REACH * reach * (1.0 - 1e-6):
        return eye
    return np.asarray(center, np.float64)


def padded_bounds(points: np.ndarray, faces: np.ndarray, pad: float = BOUNDS_PAD,
                  eye: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Each triangle's box, widened on each axis by pad (R + max(R, eye)) / 2, R the largest
    |coordinate| on that axis, for ray origins in the scene or within ``eye`` (E) of the origin on
    every axis; rounded outwards to float32."""
    tri = points.astype(np.float64)[faces]
    reach = np.abs(points.astype(np.float64)).max(axis=0) if len(points) else np.zeros(3)
    widen = pad * 0.5 * (reach + np.maximum(reach, eye))
    lower = (tri.min(axis=1) - widen).astype(np.float32)
    upper = (tri.max(axis=1) + widen).astype(np.float32)
    if pad > 0.0:  # the float32 cast rounds to nearest: step once outwards so the box only grows
        lower = np.nextafter(lower, np.float32(-np.inf))
        upper = np.nextafter(upper, np.float32(np.inf))
    return lower, upper


def build_mesh(points: np.ndarray, indices: np.ndarray, device="cpu", bvh_constructor: str = "sah",
               pad: float = BOUNDS_PAD, groups: np.ndarray | None = None, eye: float | None = None):
    """A wp.Mesh over float32 ``points`` (V, 3) and flat int32 ``indices`` (3T,) whose BVH uses
    padded_bounds. Returns (mesh, points array, indices array): the points array holds the V real
    points first, then the 2T proxy corners; the indices array holds the real indices. pad = 0
    gives Warp's own exact boxes (the stability suite measures what that loses); ``groups`` (one
    int per triangle) gives each group its own subtree, for queries from wp.mesh_get_group_root;
    ``eye`` is E, how far from the origin the camera rays may start (default: eye_reach(points))."""
    points = np.asarray(points, np.float32).reshape(-1, 3)
    faces = np.asarray(indices, np.int32).reshape(-1, 3)
    v, t = len(points), len(faces)
    lower, upper = padded_bounds(points, faces, pad, eye_reach(points) if eye is None else eye)
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


def refit_mesh(mesh, points_wp, indices_wp, points: np.ndarray, indices: np.ndarray, eye: float,
               pad: float = BOUNDS_PAD):
    """Refit a build_mesh() BVH to new ``points`` (V, 3) float32 over the same triangles ``indices``:
    the proxy corners of the new padded boxes written after the real points, the mesh refit while its
    indices name the corners (so the tree bounds the padded boxes, as built), the real indices written
    back. The tree's shape stays the one built for the old points."""
    points = np.asarray(points, np.float32).reshape(-1, 3)
    faces = np.asarray(indices, np.int32).reshape(-1, 3)
    v, t = len(points), len(faces)
    lower, upper = padded_bounds(points, faces, pad, eye)
    corner = np.arange(t, dtype=np.int32)
    proxy = np.stack([v + corner, v + t + corner, v + corner], axis=1)
    points_wp.assign(np.ascontiguousarray(np.concatenate([points, lower, upper]), np.float32))
    indices_wp.assign(np.ascontiguousarray(proxy.reshape(-1)))
    mesh.refit()
    indices_wp.assign(np.ascontiguousarray(faces.reshape(-1)))
