"""A smooth object's vertex normals as functions of its moving points, for the gradient: the replay shades with
them where the vertices move (grad.build_replay), and the boundary term of what smooth glass bends takes the
adjoint of the normals its crossings' rays turned about back to the points (normals_to_points,
grad_glass_edges.glass_terms)."""
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


def normals_to_points(scene, geom, device: str):
    """adjoint -> (points, 3) float64: the adjoint of ``geom``'s vertex normals ((points, 3), rows past the drawn
    objects' vertices ignored) taken back to the points through moving_normals' launches, made again on a tape of
    their own at each call (their sums are atomic adds: launched twice they would hold twice the sums); the
    forward's normals at the frame's points, a vertex whose normals are given, or a flat one's, taking nothing.
    None where no smooth object's normals are made from its points."""
    if not moving_normals(scene, geom, geom.points, device)[1]:
        return None

    def to_points(adjoint: np.ndarray) -> np.ndarray:
        points = wp.array(np.asarray(geom.points_np, np.float32), dtype=wp.vec3, device=device, requires_grad=True)
        normals, launches = moving_normals(scene, geom, points, device)
        tape = wp.Tape()
        with tape:
            for kernel, dim, inputs, outputs in launches:
                wp.launch(kernel, dim=dim, inputs=inputs, outputs=outputs, device=device)
        rows = np.asarray(adjoint[:len(normals)], np.float32)
        tape.backward(grads={normals: wp.array(rows, dtype=wp.vec3, device=device)})
        out = points.grad.numpy().astype(np.float64)
        tape.zero()
        return out

    return to_points
