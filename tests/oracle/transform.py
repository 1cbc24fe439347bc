"""The scene file's object rotation, derived from the README's definition ("degrees about x, then
y, then z") by Rodrigues' formula, independently of warprt's reader; an object's pose (a rotation vector
about its centre, then a translation: r.params' objects.<name>.rotation and translation) and its Jacobian."""

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


def cross_matrix(v) -> np.ndarray:
    """[v]x: the matrix of v x ., so that cross_matrix(v) @ u = v x u."""
    v = np.asarray(v, np.float64)
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rotation_vector(w) -> np.ndarray:
    """The rotation of a rotation vector (axis times angle in radians, as scipy's Rotation.from_rotvec and
    Mitsuba's have it): axis_rotation about w / |w| by |w| radians; I at w = 0."""
    w = np.asarray(w, np.float64)
    a = float(np.linalg.norm(w))
    return np.eye(3) if a == 0.0 else axis_rotation(w / a, np.degrees(a))


def posed(rest, centre, t, w) -> np.ndarray:
    """An object's vertices at pose (t, w): R(w) (rest - centre) + centre + t, each row a vertex."""
    return (np.asarray(rest, np.float64) - centre) @ rotation_vector(w).T + centre + np.asarray(t, np.float64)


def pose_jacobian(rest, centre, w) -> np.ndarray:
    """d posed / d w, (N, 3, 3) (vertex, coordinate, component of w), by Gallego and Yezzi's compact formula
    ("A compact formula for the derivative of a 3-D rotation in exponential coordinates", 2015):
    d(R u)/dw = -R [u]x (w w^T + (R^T - I) [w]x) / |w|^2, u = rest - centre; at w = 0, -[u]x (d(w x u)/dw).
    The translation's Jacobian is the identity."""
    w = np.asarray(w, np.float64)
    u = np.asarray(rest, np.float64) - centre
    a2 = float(w @ w)
    if a2 == 0.0:
        return np.stack([-cross_matrix(x) for x in u])
    R = rotation_vector(w)
    tail = (np.outer(w, w) + (R.T - np.eye(3)) @ cross_matrix(w)) / a2
    return np.stack([-R @ cross_matrix(x) @ tail for x in u])


def pose_gradients(vertex_gradients, rest, centre, w) -> tuple[np.ndarray, np.ndarray]:
    """(d loss / d t, d loss / d w) of an object's pose from the loss's gradient with respect to its posed
    vertices (N, 3), chained through pose_jacobian: the sum of the vertices' gradients, and sum_i J_i^T g_i."""
    g = np.asarray(vertex_gradients, np.float64)
    return g.sum(0), np.einsum("nij,ni->j", pose_jacobian(rest, centre, w), g)
