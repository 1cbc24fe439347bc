"""Procedural shapes a scene file can name with ``shape = "..."``.

Each builder returns float64 vertices (N, 3) and int64 faces (M, 3), counter-clockwise seen from
outside, in the object's own space (centred at the origin; the plane lies in y = 0 facing +y).
"""

from __future__ import annotations

import numpy as np
import trimesh


def sphere(radius: float = 1.0, subdivisions: int = 3):
    """An icosphere: 20 * 4**subdivisions near-equal triangles."""
    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return np.asarray(m.vertices, np.float64), np.asarray(m.faces, np.int64)


def uv_sphere(radius: float = 1.0, segments=(32, 64)):
    """A latitude-longitude sphere with exactly shared seam and pole vertices."""
    rings, sectors = int(segments[0]), int(segments[1])
    theta = np.linspace(0.0, np.pi, rings + 1)[1:-1]
    phi = np.arange(sectors) * (2.0 * np.pi / sectors)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring_v = np.stack([np.sin(t) * np.cos(p), np.cos(t), -np.sin(t) * np.sin(p)], -1).reshape(-1, 3)
    v = np.vstack([[0.0, 1.0, 0.0], ring_v, [0.0, -1.0, 0.0]]) * radius
    south = len(v) - 1

    def idx(r, s):
        return 1 + r * sectors + (s % sectors)

    faces = []
    for s in range(sectors):
        faces.append((0, idx(0, s), idx(0, s + 1)))
        faces.append((south, idx(rings - 2, s + 1), idx(rings - 2, s)))
    for r in range(rings - 2):
        for s in range(sectors):
            a, b, c, d = idx(r, s), idx(r + 1, s), idx(r + 1, s + 1), idx(r, s + 1)
            faces.append((a, b, c))
            faces.append((a, c, d))
    return v, np.asarray(faces, np.int64)


def box(size=(1.0, 1.0, 1.0)):
    """An axis-aligned box of the given edge lengths, 12 triangles."""
    m = trimesh.creation.box(extents=np.broadcast_to(np.asarray(size, np.float64), (3,)))
    return np.asarray(m.vertices, np.float64), np.asarray(m.faces, np.int64)


def plane(size=(10.0, 10.0)):
    """A rectangle in y = 0 facing +y, two triangles split along one diagonal."""
    sx, sz = np.broadcast_to(np.asarray(size, np.float64), (2,)) * 0.5
    v = np.array([[-sx, 0, -sz], [-sx, 0, sz], [sx, 0, sz], [sx, 0, -sz]], np.float64)
    return v, np.array([[0, 1, 2], [0, 2, 3]], np.int64)


def cylinder(radius: float = 0.5, height: float = 1.0, sections: int = 64):
    """A capped cylinder along y, centred at the origin."""
    m = trimesh.creation.cylinder(radius=radius, height=height, sections=sections)
    v = np.asarray(m.vertices, np.float64)[:, [0, 2, 1]] * [1.0, 1.0, -1.0]  # z-up to y-up
    return v, np.asarray(m.faces, np.int64)


def triangles(vertices, faces):
    """Explicit vertices and faces, as given."""
    return np.asarray(vertices, np.float64).reshape(-1, 3), np.asarray(faces, np.int64).reshape(-1, 3)


# name -> (builder, {parameter: (kind, default)}); kinds are checked by the scene reader.
SHAPES = {
    "sphere": (sphere, {"radius": ("positive", 1.0), "subdivisions": ("int0", 3)}),
    "uv_sphere": (uv_sphere, {"radius": ("positive", 1.0), "segments": ("int2", [32, 64])}),
    "box": (box, {"size": ("size3", [1.0, 1.0, 1.0])}),
    "plane": (plane, {"size": ("size2", [10.0, 10.0])}),
    "cylinder": (cylinder, {"radius": ("positive", 0.5), "height": ("positive", 1.0), "sections": ("int3", 64)}),
    "triangles": (triangles, {"vertices": ("points", None), "faces": ("faces", None)}),
}
