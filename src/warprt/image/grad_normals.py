"""A smooth object's vertex normals as functions of its moving points, for the gradient: the replay shades with
them where the vertices move (grad.build_replay)."""
from __future__ import annotations

import numpy as np

from .._warp import wp
from ..kernels import smooth_vertex_normals, vertex_normal_sums
from ..scene import drawn_objects, position_ids


def moving_normals(scene, geom, points, device: str) -> tuple:
    """(normals, launches): the vertex normals the forward's Geometry makes from the objects' vertices
    (Geometry._placed: normals.vertex_normals, angle-weighted and shared by the vertices at one position,
    where a smooth object has no normals of its own; the given ones, a file's or a crease's, kept as they
    are when the vertices move), differentiable in ``points`` through the launches (vertex_normal_sums, then
    smooth_vertex_normals) that make them. Which vertices share a position is held as it is: a direction
    that parts two vertices at one position (a seam's) moves the forward's normals by a jump, not a slope."""
    objects = drawn_objects(scene)
    position, faces, base, face_base, unique = [], [], 0, 0, 0
    for obj in objects:
        count = len(obj.vertices)
        if obj.smooth and getattr(obj, "normals", None) is None:
            ids = position_ids(obj.vertices)
            position.append(ids + unique)
            unique += int(ids.max()) + 1 if count else 0
            faces.append(np.arange(face_base, face_base + len(obj.faces)))
        else:
            position.append(np.full(count, -1))
        base += count
        face_base += len(obj.faces)
    if not faces:
        return geom.normals, []
    position = wp.array(np.concatenate(position).astype(np.int32), dtype=int, device=device)
    faces = wp.array(np.concatenate(faces).astype(np.int32), dtype=int, device=device)
    sums = wp.zeros(unique, dtype=wp.vec3, device=device, requires_grad=True)
    normals = wp.zeros(base, dtype=wp.vec3, device=device, requires_grad=True)
    return normals, [(vertex_normal_sums, len(faces), [points, geom.indices, faces, position], [sums]),
                     (smooth_vertex_normals, base, [sums, position, geom.normals], [normals])]

