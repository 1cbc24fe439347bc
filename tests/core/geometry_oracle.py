"""Closed-form ray geometry in float64, independent of the renderer: the tests' oracle."""

from __future__ import annotations

import numpy as np

from warprt.scene import camera_basis, pixel_ray_directions


def camera_rays(cam):
    """Eye and unit directions (H, W, 3) through pixel centres, from the seed's formula."""
    b = camera_basis(cam)
    d = pixel_ray_directions(b)
    return b.eye, d / np.linalg.norm(d, axis=-1, keepdims=True)


def ray_triangle(o, d, a, b, c):
    """Moller-Trumbore for many rays: t (inf on a miss) and the smallest barycentric (edge margin)."""
    dot = lambda x, y: np.sum(x * y, axis=-1)
    e1, e2 = b - a, c - a
    p = np.cross(d, e2)
    det = dot(p, e1)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
    s = np.broadcast_to(o - a, d.shape)
    u = dot(s, p) * inv
    q = np.cross(s, e1)
    v = dot(d, q) * inv
    t = dot(e2, q) * inv
    margin = np.minimum(np.minimum(u, v), 1 - u - v)
    hit = (margin >= 0) & (t > 0)
    return np.where(hit, t, np.inf), margin


def ray_plane(o, d, point, normal):
    denom = d @ normal
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((np.asarray(point) - o) @ normal) / denom
    return np.where(t > 0, t, np.inf)


def ray_sphere_distance(o, d, center):
    """Distance from the sphere centre to each ray's line (d unit), and the t of closest approach."""
    oc = np.asarray(center) - o
    t = d @ oc if d.ndim == 1 else np.einsum("...i,i->...", d, oc)
    closest = o + t[..., None] * d - center
    return np.linalg.norm(closest, axis=-1), t
