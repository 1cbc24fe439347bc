"""What a dielectric object needs from the scene alone: a closed, outward-wound mesh (the side a ray is
on is the winding's), and which one, if any, holds the eye (the medium its first rays travel in).

A mesh is closed when, its vertices welded by position, every edge is shared by exactly two faces
that run along it in opposite directions; it is outward when its signed volume is positive.
"""

from __future__ import annotations

import numpy as np

from ..diagnostics import warn
from ..errors import SceneError


def open_edges(vertices: np.ndarray, faces: np.ndarray) -> int:
    """The number of edges (vertices welded where their coordinates are equal) not shared by exactly
    two faces running along them in opposite directions: 0 for a closed, consistently wound mesh."""
    _, weld = np.unique(np.asarray(vertices, np.float64), axis=0, return_inverse=True)
    f = weld.reshape(-1)[np.asarray(faces)]
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    directed = directed[directed[:, 0] != directed[:, 1]]  # a collapsed edge borders nothing
    key = np.sort(directed, axis=1)
    forward = np.where(directed[:, 0] < directed[:, 1], 1, -1)
    edges, inverse, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    balance = np.zeros(len(edges), np.int64)
    np.add.at(balance, inverse.reshape(-1), forward)
    return int(((count != 2) | (balance != 0)).sum())


def signed_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """The volume the faces enclose, positive when they are wound counter-clockwise seen from outside."""
    p = np.asarray(vertices, np.float64)[np.asarray(faces)]
    return float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0)


def winding_number(vertices: np.ndarray, faces: np.ndarray, q) -> float:
    """The generalised winding number of point q (the solid angle the faces subtend at q over 4 pi,
    Van Oosterom and Strackee's formula): 1 inside a closed outward mesh, 0 outside."""
    a, b, c = (np.asarray(vertices, np.float64)[np.asarray(faces)[:, k]] - np.asarray(q, np.float64) for k in range(3))
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    dot = lambda x, y: np.einsum("ij,ij->i", x, y)
    num = dot(a, np.cross(b, c))
    den = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb
    return float(np.arctan2(num, den).sum() / (2.0 * np.pi))


def warn_unclosed(scene):
    """One warning per dielectric object that is not closed or is wound inward. It still renders:
    each crossing of its surface switches the ray's medium by the winding, so a ray that leaves
    through a hole is taken to be inside it for the rest of its path."""
    for i, obj in enumerate(scene.objects):
        material = scene.materials.get(obj.material)
        if material is None or not material.dielectric:
            continue
        holes = open_edges(obj.vertices, obj.faces)
        if holes:
            warn(scene.source, f"objects[{i}]", f"'{obj.name}' has ior but is not closed ({holes} open or "
                                                "inconsistently wound edges): rays leaving through them stay inside")
        elif signed_volume(obj.vertices, obj.faces) < 0.0:
            warn(scene.source, f"objects[{i}]", f"'{obj.name}' has ior but is wound inward (negative volume): "
                                                "its outside is taken for the glass")


def eye_medium(scene) -> str | None:
    """The name of the dielectric material whose object holds the eye, or None (air). Nested media
    are not modelled: an eye inside two dielectric objects is an error."""
    eye = np.asarray(scene.camera.eye, np.float64)
    inside = [obj for obj in scene.objects if scene.materials[obj.material].dielectric
              and winding_number(obj.vertices, obj.faces, eye) > 0.5]
    if len(inside) > 1:
        raise SceneError(scene.source, "camera.eye", f"is inside more than one object with ior ('{inside[0].name}', "
                                                     f"'{inside[1].name}'): nested media are not modelled")
    return inside[0].material if inside else None
