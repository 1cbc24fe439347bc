"""Ray queries and surface normals in float64, written from their textbook formulas: ray-triangle
(Moller-Trumbore), ray-plane, ray-sphere, and the normals a scene's triangles define."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


def _dot(x, y):
    return np.sum(x * y, axis=-1)


class TriangleHit(NamedTuple):
    t: np.ndarray  # ray parameter of the triangle's plane (inf or nan where the ray is parallel to it)
    u: np.ndarray  # barycentric weight of b
    v: np.ndarray  # barycentric weight of c (a's is 1 - u - v)
    margin: np.ndarray  # min(u, v, 1 - u - v): >= 0 inside, the distance (in barycentrics) to the nearest edge

    @property
    def hit(self) -> np.ndarray:
        """Inside the triangle (edges included) and in front of the origin."""
        return (self.margin >= 0) & (self.t > 0)


def ray_triangle(o, d, a, b, c) -> TriangleHit:
    """Moller-Trumbore, every argument (..., 3) and broadcast together (many rays against one
    triangle, one ray against many, or ray i against triangle i):
        e1 = b - a, e2 = c - a, p = d x e2, s = o - a, q = s x e1,
        u = (s.p)/(e1.p), v = (d.q)/(e1.p), t = (e2.q)/(e1.p),
    so that o + t d = (1 - u - v) a + u b + v c. A ray in the triangle's plane, or a triangle of zero
    area, has e1.p = 0: u, v, t are inf or nan there and ``hit`` is False."""
    a, b, c = (np.asarray(x, np.float64) for x in (a, b, c))
    e1, e2 = b - a, c - a
    p = np.cross(d, e2)
    s = np.asarray(o, np.float64) - a
    q = np.cross(s, e1)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / _dot(e1, p)
        u = _dot(s, p) * inv
        v = _dot(d, q) * inv
        t = _dot(e2, q) * inv
        margin = np.minimum(np.minimum(u, v), 1.0 - u - v)
    return TriangleHit(t, u, v, margin)


def nearest_triangle(o, d, tris):
    """The nearest hit of rays (o, d: (..., 3)) among triangles (T, 3, 3): t (inf on a miss), the
    face (-1 on a miss), and each ray's distance (in barycentrics, |margin|) to the nearest edge of
    any triangle whose plane it crosses in front of the origin, to leave out rays too close to call.
    Triangles of zero area are skipped: nothing can hit them."""
    shape = np.shape(d)[:-1]
    o = np.broadcast_to(o, np.shape(d)).reshape(-1, 3)
    d = np.reshape(d, (-1, 3))
    best_t = np.full(len(d), np.inf)
    best_f = np.full(len(d), -1)
    near_edge = np.full(len(d), np.inf)
    for f, (a, b, c) in enumerate(np.asarray(tris, np.float64)):
        if np.linalg.norm(np.cross(b - a, c - a)) == 0:
            continue
        h = ray_triangle(o, d, a, b, c)
        front = np.isfinite(h.t) & (h.t > 0)
        near_edge = np.where(front, np.minimum(near_edge, np.abs(h.margin)), near_edge)
        nearer = front & (h.margin >= 0) & (h.t < best_t)
        best_t = np.where(nearer, h.t, best_t)
        best_f = np.where(nearer, f, best_f)
    return best_t.reshape(shape), best_f.reshape(shape), near_edge.reshape(shape)


def ray_plane(o, d, point, normal):
    """t = ((point - o).n)/(d.n) where positive, inf elsewhere (behind the origin, or parallel)."""
    normal = np.asarray(normal, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((np.asarray(point, np.float64) - o) @ normal) / (d @ normal)
    return np.where(t > 0, t, np.inf)


def ray_sphere_distance(o, d, center):
    """For unit d: the t of closest approach to the centre, t* = (center - o).d, and the distance
    |o + t* d - center| from the centre to the ray's line (the ray hits a sphere of radius r
    about it iff that distance is below r and, for an origin outside, t* > 0)."""
    center = np.asarray(center, np.float64)
    t = np.einsum("...i,i->...", d, center - o)
    closest = o + t[..., None] * d - center
    return np.linalg.norm(closest, axis=-1), t


def face_normals(tris) -> np.ndarray:
    """Unit geometric normals (e1 x e2)/|e1 x e2| of triangles (..., 3, 3); zero for zero area."""
    tris = np.asarray(tris, np.float64)
    n = np.cross(tris[..., 1, :] - tris[..., 0, :], tris[..., 2, :] - tris[..., 0, :])
    return n / np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-300)


def vertex_normals(vertices, faces) -> np.ndarray:
    """Angle-weighted vertex normals (Thurmer and Wuthrich 1998), the smooth normals a scene's
    ``smooth = true`` objects shade with: at each vertex position, the unit sum of the unit normals
    of the faces meeting there, each weighted by the face's angle at that corner, atan2(|e1 x e2|,
    e1.e2) for the two edges leaving it. Vertices at the same position share one normal (a mesh
    split at seams shades smoothly across them); a zero sum stays zero."""
    vertices, faces = np.asarray(vertices, np.float64), np.asarray(faces)
    # + 0.0: -0.0 and 0.0 are one position.
    _, position = np.unique(vertices + 0.0, axis=0, return_inverse=True)
    position = position.reshape(-1)
    corners = vertices[faces]
    n_face = face_normals(corners)
    total = np.zeros((position.max() + 1 if len(position) else 0, 3))
    for k in range(3):
        e1 = corners[:, (k + 1) % 3] - corners[:, k]
        e2 = corners[:, (k + 2) % 3] - corners[:, k]
        angle = np.arctan2(np.linalg.norm(np.cross(e1, e2), axis=-1), _dot(e1, e2))
        np.add.at(total, position[faces[:, k]], angle[:, None] * n_face)
    length = np.linalg.norm(total, axis=-1, keepdims=True)
    return (total / np.maximum(length, 1e-300))[position]


def winding_number(vertices, faces, q) -> float:
    """The generalised winding number of point q: the solid angle the triangles subtend at q over
    4 pi, each triangle's by Van Oosterom and Strackee's formula
        tan(Omega / 2) = a.(b x c) / (|a||b||c| + (a.b)|c| + (b.c)|a| + (c.a)|b|),
    a, b, c the corners relative to q. 1 inside a closed outward-wound mesh, 0 outside."""
    v = np.asarray(vertices, np.float64) - np.asarray(q, np.float64)
    a, b, c = (v[np.asarray(faces)[:, k]] for k in range(3))
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    num = _dot(a, np.cross(b, c))
    den = la * lb * lc + _dot(a, b) * lc + _dot(b, c) * la + _dot(c, a) * lb
    return float(np.arctan2(num, den).sum() / (2.0 * np.pi))
