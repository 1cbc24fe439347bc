"""A smooth object's vertex normals made from its moving points, as the forward's Geometry makes them
(scene/normals.py: angle-weighted face normals summed per position, normalised), differentiable in the points:
what the gradient's replay shades with where the vertices move."""

from __future__ import annotations

from .._warp import wp
from ..geometry.bvh import face_vertices

@wp.func
def corner_angle(a: wp.vec3, b: wp.vec3, c: wp.vec3) -> float:
    """The angle at corner a of the triangle (a, b, c): atan2(|e1 x e2|, e1.e2), e1 = b - a, e2 = c - a, the
    angle normals.face_normals_and_angles takes as arccos of the cosine (the same value, and a derivative
    that stays finite where the cosine nears +-1)."""
    e1 = b - a
    e2 = c - a
    return wp.atan2(wp.length(wp.cross(e1, e2)), wp.dot(e1, e2))


@wp.kernel(module="unique")
def vertex_normal_sums(points: wp.array(dtype=wp.vec3), indices: wp.array(dtype=int), faces: wp.array(dtype=int),
                       position: wp.array(dtype=int), sums: wp.array(dtype=wp.vec3)):
    """normals.vertex_normals' sums, differentiable in ``points``: per face ``faces[tid]`` (the smooth
    objects' whose normals are computed from their triangles), its unit normal (zero where degenerate) times
    each corner's angle (corner_angle) added by wp.atomic_add to the sum of the corner's position
    (``position``: one id per distinct position of an object, normals.position_ids, so that vertices a seam
    splits share one normal)."""
    i0, i1, i2 = face_vertices(indices, faces[wp.tid()])
    p0 = points[i0]
    p1 = points[i1]
    p2 = points[i2]
    fn = wp.normalize(wp.cross(p1 - p0, p2 - p0))
    wp.atomic_add(sums, position[i0], fn * corner_angle(p0, p1, p2))
    wp.atomic_add(sums, position[i1], fn * corner_angle(p1, p2, p0))
    wp.atomic_add(sums, position[i2], fn * corner_angle(p2, p0, p1))


@wp.kernel(module="unique")
def smooth_vertex_normals(sums: wp.array(dtype=wp.vec3), position: wp.array(dtype=int),
                          given: wp.array(dtype=wp.vec3), normals: wp.array(dtype=wp.vec3)):
    """Each vertex's normal as the forward's Geometry has it: where its object's normals are computed from
    its triangles (``position`` >= 0), its position's sum (vertex_normal_sums) normalised, differentiable;
    elsewhere (a file's or a crease's normals, which stay when the vertices move; a flat object's zeros) the
    ``given`` one."""
    v = wp.tid()
    q = position[v]
    if q >= 0:
        normals[v] = wp.normalize(sums[q])
    else:
        normals[v] = given[v]
