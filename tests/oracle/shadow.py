"""Hard shadows and where a point shows in the image, in float64 from their textbook formulas: a point's
shadow on a plane, cast from a point light (central projection) or along a light's direction (parallel
projection), a point's image in a planar mirror (where the eye sees it through the mirror), and the pinhole's
projection of a point to pixels."""

from __future__ import annotations

import numpy as np

from .camera import pinhole
from .geometry import ray_plane


def shadow_point(p, light, plane_point, plane_normal, directional: bool = False) -> np.ndarray:
    """Where the light's ray through p meets the plane (point, normal): from a point light at ``light``
    along p - light, or for a light travelling along ``light``, from p along it."""
    p, light = np.asarray(p, np.float64), np.asarray(light, np.float64)
    d = light if directional else p - light
    o = p if directional else light
    return o + ray_plane(o, d, plane_point, plane_normal) * d


def mirror_point(p, plane_point, plane_normal) -> np.ndarray:
    """The point p reflected across the plane (point, normal): p - 2 ((p - point) . n) n, n the unit normal.
    An eye sees p in a planar mirror on that plane where it would see this point with no mirror."""
    p, n = np.asarray(p, np.float64), np.asarray(plane_normal, np.float64)
    n = n / np.linalg.norm(n)
    return p - 2.0 * ((p - np.asarray(plane_point, np.float64)) @ n) * n


def image_point(cam, q) -> np.ndarray:
    """The image point (x, y), pixels from the lower-left corner, of the world point q in front of the
    pinhole: its ray d = q - eye scaled to the image plane (d . -z_e = d_f), read along x_e and y_e."""
    c = pinhole(cam)
    d = np.asarray(q, np.float64) - c.eye
    d = d * (c.d_f / -(d @ c.z_e))
    return np.array([c.width * (0.5 + (d @ c.x_e) / c.w), c.height * (0.5 + (d @ c.y_e) / c.h)])


def line_distance(x, a, b) -> float:
    """The signed distance of the image point x from the line through image points a and b, positive to
    the left of a -> b."""
    u, v = np.asarray(b) - np.asarray(a), np.asarray(x) - np.asarray(a)
    return float((u[0] * v[1] - u[1] * v[0]) / np.hypot(*u))
