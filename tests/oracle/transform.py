"""The scene file's object rotation, derived from the README's definition ("degrees about x, then
y, then z") by Rodrigues' formula, independently of warprt's reader."""

from __future__ import annotations

import numpy as np

AXES = np.eye(3)


def axis_rotation(axis, degrees) -> np.ndarray:
    """Rodrigues: the right-handed rotation by ``degrees`` about the unit vector ``axis``,
    R = I + sin(a) K + (1 - cos(a)) K^2 with K the cross-product matrix of the axis (K x = axis x x)."""
    k = np.asarray(axis, np.float64)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    a = np.radians(degrees)
    return np.eye(3) + np.sin(a) * K + (1.0 - np.cos(a)) * (K @ K)


def rotation(degrees) -> np.ndarray:
    """The matrix of ``rotate = [rx, ry, rz]``: about x first, then y, then z, so R = Rz Ry Rx
    (a column vector p becomes R p)."""
    rx, ry, rz = (axis_rotation(AXES[i], float(degrees[i])) for i in range(3))
    return rz @ ry @ rx
