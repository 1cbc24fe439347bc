"""Planar mirrors: the coplanar groups of flat reflective triangles, and the scene in front of a mirror
reflected through a chain of them (MirroredGeometry), which the real camera then sees as a virtual one.

Every ray reflected off one plane passes through the mirrored eye, so a ray that has bounced off planar
groups g1, ..., gk lies on the camera's own ray through its sample in the unfolded scene M1 ... Mk (P):
P the triangles in front of gk, M_i the reflection about g_i's plane. Rasterizing that scene from the
camera gives each such ray's first hit wherever the rasterizer is certain (image/mirrors.py).
"""

from __future__ import annotations

import numpy as np

from .._warp import wp
from .scene_data import SceneData

COPLANAR = 1.0e-7  # relative to the scene's size: triangles this close to one plane form a group
MAX_GROUPS = 64  # the largest by area, where a flat-shaded curved mirror would make a group of each triangle
KEEP_BYTES = 256 * 2**20  # the unfolded scenes kept with a Geometry for the next frames


def planar_groups(geom, reflective_slots, memo: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(group per triangle, -1 for none; planes (G, 4) float64 as (n, offset), n . x = offset on the
    plane) of ``geom``'s flat triangles whose material slot is reflective, by object; kept in ``memo``
    (a Renderer's FrameCaches.planar_groups) for the next frames of these triangles."""
    key = tuple(bool(r) for r in reflective_slots)
    memo = {} if memo is None else memo
    if key in memo:
        return memo[key]
    tri = geom.points_np.astype(np.float64)[geom.indices_np.reshape(-1, 3)][: geom.triangle_count]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = np.linalg.norm(normal, axis=1)
    normal /= np.where(area > 0, area, 1.0)[:, None]
    size = float(np.linalg.norm(tri.reshape(-1, 3).max(0) - tri.reshape(-1, 3).min(0))) if len(tri) else 0.0
    mirror = np.asarray(key, bool)[geom.tri_material_np[: geom.triangle_count]] & (geom.tri_smooth_np[: geom.triangle_count] == 0) & (area > 0)
    group = np.full(len(tri), -1, np.int32)
    planes, areas = [], []
    for obj in np.unique(geom.tri_object_np[: geom.triangle_count][mirror]):
        left = np.nonzero(mirror & (geom.tri_object_np[: geom.triangle_count] == obj))[0]
        while len(left):
            n0 = normal[left[0]]
            off = float(n0 @ tri[left[0], 0])
            same = (np.abs(normal[left] @ n0) > 1 - 1e-9) & np.all(np.abs(tri[left] @ n0 - off) <= COPLANAR * size, axis=1)
            group[left[same]] = len(planes)
            planes.append(np.append(n0, off))
            areas.append(float(area[left[same]].sum()))
            left = left[~same]
    planes = np.asarray(planes, np.float64).reshape(-1, 4)
    if len(planes) > MAX_GROUPS:
        keep = np.argsort(areas)[::-1][:MAX_GROUPS]
        renumber = np.full(len(planes), -1, np.int32)
        renumber[keep] = np.arange(MAX_GROUPS, dtype=np.int32)
        group = np.where(group >= 0, renumber[np.maximum(group, 0)], -1).astype(np.int32)
        planes = planes[keep]
    memo[key] = (group, planes)
    return group, planes


def reflect_points(p: np.ndarray, plane: np.ndarray) -> np.ndarray:
    """Points (..., 3) mirrored about the plane (n, offset): p - 2 (n . p - offset) n."""
    n, off = plane[:3], plane[3]
    return p - 2.0 * ((p @ n) - off)[..., None] * n


def reflect_plane(plane: np.ndarray, about: np.ndarray) -> np.ndarray:
    """The plane (n, offset) mirrored about the plane ``about``."""
    n = plane[:3] - 2.0 * (plane[:3] @ about[:3]) * about[:3]
    return np.append(n, n @ reflect_points(plane[:3] * plane[3], about))


def clip_in_front(tri: np.ndarray, plane: np.ndarray, side: float, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """The parts of triangles (T, 3, 3) on the ``side`` (+1 or -1) of the plane, as triangles, and the
    index of the triangle each came from. Triangles within tol of the plane (the mirror itself and what
    lies on it) are dropped, and so are cut pieces of (near) zero area."""
    dist = side * (tri @ plane[:3] - plane[3])
    inside = dist >= 0.0
    count = np.where(np.all(np.abs(dist) <= tol, axis=1), 0, inside.sum(axis=1))
    keep = count == 3
    pieces, source = [tri[keep]], [np.nonzero(keep)[0]]
    for n_in in (1, 2):
        f = np.nonzero(count == n_in)[0]
        if not len(f):
            continue
        # Rotate each triangle so that the lone vertex (inside for one, outside for two) comes first.
        lone = np.argmax(inside[f] if n_in == 1 else ~inside[f], axis=1)
        order = (lone[:, None] + np.arange(3)) % 3
        t = tri[f[:, None], order]
        d = dist[f[:, None], order]
        cut = lambda i, j: t[:, i] + (d[:, i] / (d[:, i] - d[:, j]))[:, None] * (t[:, j] - t[:, i])
        a_b, a_c = cut(0, 1), cut(0, 2)
        if n_in == 1:
            new = [np.stack([t[:, 0], a_b, a_c], 1)]
        else:
            new = [np.stack([t[:, 1], t[:, 2], a_c], 1), np.stack([t[:, 1], a_c, a_b], 1)]
        ref = np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)
        for piece in new:
            big = np.linalg.norm(np.cross(piece[:, 1] - piece[:, 0], piece[:, 2] - piece[:, 0]), axis=1) > 1e-9 * ref
            pieces.append(piece[big])
            source.append(f[big])
    return np.concatenate(pieces), np.concatenate(source).astype(np.int32)


class MirroredGeometry:
    """The scene as seen through a chain of planar groups (planes in order of the bounces): the
    triangles on ``side`` of the last plane, reflected about the planes last to first, float32 in the
    parent Geometry's frame; ``source_face`` maps each back to the parent's face. It has what the
    Z-buffer reads of a Geometry."""

    def __init__(self, geom, planes: np.ndarray, side: float):
        tri = geom.points_np.astype(np.float64)[geom.indices_np.reshape(-1, 3)][: geom.triangle_count]
        size = float(np.linalg.norm(tri.reshape(-1, 3).max(0) - tri.reshape(-1, 3).min(0))) if len(tri) else 0.0
        pieces, self.source_face = clip_in_front(tri, planes[-1], side, COPLANAR * size)
        for plane in planes[::-1]:
            pieces = reflect_points(pieces, plane)
        self.parent = geom
        self.triangle_count = len(pieces)
        self.points_np = np.ascontiguousarray(pieces.reshape(-1, 3), np.float32)
        if not len(pieces):  # kernels need an array: one degenerate triangle that covers no sample
            self.points_np = np.zeros((3, 3), np.float32)
        self.indices_np = np.arange(len(self.points_np), dtype=np.int32)
        self.reach = float(np.abs(self.points_np).max(initial=0.0))  # the largest |coordinate|, as Geometry's
        d = SceneData()
        d.points = wp.array(self.points_np, dtype=wp.vec3, device=geom.device)
        d.indices = wp.array(self.indices_np, dtype=wp.int32, device=geom.device)
        self.source = wp.array(np.append(self.source_face, 0).astype(np.int32), dtype=wp.int32, device=geom.device)
        self.data = d
        self.nbytes = int(d.points.capacity + d.indices.capacity + self.source.capacity)

    def eye_offset(self, eye) -> np.ndarray:
        return self.parent.eye_offset(eye)


def mirrored_geometry(geom, planes: np.ndarray, side: float, memo: dict | None = None) -> MirroredGeometry:
    """MirroredGeometry of ``geom``, kept in ``memo`` (a Renderer's FrameCaches.mirrored): it depends on
    the triangles and mirrors, not the camera."""
    key = (np.asarray(planes, np.float64).tobytes(), float(side))
    memo = {} if memo is None else memo
    if key not in memo:
        memo[key] = MirroredGeometry(geom, np.asarray(planes, np.float64).reshape(-1, 4), side)
        while len(memo) > 1 and sum(m.nbytes for m in memo.values()) > KEEP_BYTES:  # the oldest go first
            memo.pop(next(iter(memo)))
    return memo[key]
