"""Vertex normals for smooth shading, in NumPy float64: no Warp needed, so the Mitsuba reference
and the scene reader can use the same normals without importing Warp."""

from __future__ import annotations

import numpy as np


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Angle-weighted vertex normals (float64), shared by vertices at the same position so that
    a mesh with split seams (OBJ texture seams) still shades smoothly across them."""
    # Positions compared as raw bytes (much faster than np.unique(axis=0)); + 0.0 makes -0.0 equal 0.0.
    keys = np.ascontiguousarray(vertices + 0.0, np.float64).view(np.dtype((np.void, 24))).ravel()
    _, inverse = np.unique(keys, return_inverse=True)
    inverse = inverse.reshape(-1)
    n_unique = int(inverse.max()) + 1 if len(inverse) else 0
    p = vertices[faces]
    fn = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    length = np.linalg.norm(fn, axis=1, keepdims=True)
    fn = np.divide(fn, length, out=np.zeros_like(fn), where=length > 0)
    acc = np.zeros((n_unique, 3))
    for k in range(3):
        e1 = p[:, (k + 1) % 3] - p[:, k]
        e2 = p[:, (k + 2) % 3] - p[:, k]
        n1, n2 = np.linalg.norm(e1, axis=1), np.linalg.norm(e2, axis=1)
        cos = np.einsum("ij,ij->i", e1, e2) / np.maximum(n1 * n2, 1e-300)
        angle = np.arccos(np.clip(cos, -1.0, 1.0))
        target = inverse[faces[:, k]]
        for axis in range(3):
            acc[:, axis] += np.bincount(target, weights=fn[:, axis] * angle, minlength=n_unique)
    length = np.linalg.norm(acc, axis=1, keepdims=True)
    acc = np.divide(acc, length, out=np.zeros_like(acc), where=length > 0)
    return acc[inverse]
