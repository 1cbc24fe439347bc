"""The seed's shading in float64 from closed-form geometry: the stability suite's expected values."""

from __future__ import annotations

import numpy as np


def phong(p, n, v, lights, mat, c_amb, visible=None):
    """I = C_amb ka + sum_l vis_l C_l (kd max(0, n.L) + ks max(0, r.v)^shininess), n facing v.
    p, n, v: (..., 3); lights: [(position, colour)]; visible: optional (..., n_lights) booleans."""
    ka = np.asarray(mat.get("ka", mat["kd"]), float)
    out = np.broadcast_to(np.asarray(c_amb, float) * ka, p.shape).copy()
    for i, (position, colour) in enumerate(lights):
        L = np.asarray(position, float) - p
        L /= np.linalg.norm(L, axis=-1, keepdims=True)
        n_dot_l = np.sum(n * L, -1)
        r = 2 * n_dot_l[..., None] * n - L
        r_dot_v = np.maximum(np.sum(r * v, -1), 0.0)
        lit = np.asarray(mat["kd"], float) * np.maximum(n_dot_l, 0)[..., None]
        lit = lit + np.asarray(mat.get("ks", [0.0] * 3), float) * (r_dot_v ** mat.get("shininess", 32.0))[..., None]
        on = n_dot_l > 0
        if visible is not None:
            on = on & visible[..., i]
        out += np.asarray(colour, float) * lit * on[..., None]
    return out


def rotation(degrees) -> np.ndarray:
    """The scene file's rotate: about x, then y, then z (R = Rz Ry Rx), in degrees."""
    ax, ay, az = np.radians(degrees)
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def grid(n: int, half: float):
    """A square of side 2 half in y = 0 facing +y, as n x n quads split along their diagonals."""
    s = np.linspace(-half, half, n + 1)
    x, z = np.meshgrid(s, s, indexing="ij")
    vertices = np.stack([x, np.zeros_like(x), z], -1).reshape(-1, 3)
    i = np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]
    a, b, c, d = i, i + 1, i + n + 2, i + n + 1
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return vertices, faces


def trace_triangles(o, d, tris):
    """Nearest hit of rays (o, d: (..., 3)) on float64 triangles (T, 3, 3), Moller-Trumbore:
    t (inf on a miss), the face, and each ray's distance (in barycentrics) to the nearest edge of
    any triangle it passes through or near, to leave out rays too close to call."""
    shape = d.shape[:-1]
    o = np.broadcast_to(o, d.shape).reshape(-1, 3)
    d = d.reshape(-1, 3)
    best_t = np.full(len(d), np.inf)
    best_f = np.full(len(d), -1)
    near_edge = np.full(len(d), np.inf)
    for f, (a, b, c) in enumerate(tris):
        e1, e2 = b - a, c - a
        if np.linalg.norm(np.cross(e1, e2)) == 0:  # zero area: nothing to hit
            continue
        p = np.cross(d, e2)
        det = p @ e1
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            s = o - a
            u = np.sum(s * p, -1) * inv
            q = np.cross(s, e1)
            v = np.sum(d * q, -1) * inv
            t = (q @ e2) * inv
        margin = np.minimum(np.minimum(u, v), 1 - u - v)
        front = np.isfinite(t) & (t > 0)
        near_edge = np.where(front, np.minimum(near_edge, np.abs(margin)), near_edge)
        hit = front & (margin >= 0) & (t < best_t)
        best_t = np.where(hit, t, best_t)
        best_f = np.where(hit, f, best_f)
    return best_t.reshape(shape), best_f.reshape(shape), near_edge.reshape(shape)


def shade_triangles(o, d, tris, face_mats, materials, lights, c_amb, background):
    """The seed's model on a flat triangle scene (one level, shadows on), in float64: per pixel,
    the colour for the nearest face. Returns colour, face, edge margin."""
    t, face, margin = trace_triangles(o, d, tris)
    p = o + np.where(np.isfinite(t), t, 0.0)[..., None] * d
    out = np.broadcast_to(np.asarray(background, float), p.shape).copy()
    tri_n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    tri_n /= np.maximum(np.linalg.norm(tri_n, axis=-1, keepdims=True), 1e-300)
    n = tri_n[face]
    n *= -np.sign(np.sum(n * d, -1))[..., None]  # two-sided: the normal faces the incoming ray
    visible = np.ones(p.shape[:-1] + (len(lights),), bool)
    for i, (position, _) in enumerate(lights):
        to_light = np.asarray(position, float) - p
        dist = np.linalg.norm(to_light, axis=-1)
        start = p + n * 1e-9 * (1.0 + np.abs(p).max(-1, keepdims=True))
        tl, _, _ = trace_triangles(start, to_light / dist[..., None], tris)
        visible[..., i] = tl >= dist
    for m, mat in enumerate(materials):
        here = (np.asarray(face_mats)[face] == m) & (face >= 0)
        out[here] = phong(p[here], n[here], -d[here], lights, mat, c_amb, visible[here])
    return out, face, margin
