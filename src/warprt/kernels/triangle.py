"""One triangle of the scene as the kernels read it: its vertices, its normal as Warp's ray query
reports it, and the query's own ray-triangle test (Woop's watertight one)."""

from __future__ import annotations

from .._warp import wp
from ..geometry import SceneData
from ..geometry.bvh import face_vertices


@wp.func
def triangle(s: SceneData, f: int):
    """The vertices p0, p1, p2 of face f (float32, relative to the frame origin)."""
    i0, i1, i2 = face_vertices(s.indices, f)
    return s.points[i0], s.points[i1], s.points[i2]


@wp.func
def query_normal(p0: wp.vec3, p1: wp.vec3, p2: wp.vec3) -> wp.vec3:
    """The face normal as wp.mesh_query_ray reports it: normalize(cross(p1 - p0, p2 - p0))."""
    return wp.normalize(wp.cross(p1 - p0, p2 - p0))


@wp.func
def unit_normal(p0: wp.vec3, p1: wp.vec3, p2: wp.vec3) -> wp.vec3:
    """normalize(cross(p1 - p0, p2 - p0)), scaled first by its largest component. Warp's query
    normalizes the raw cross product, whose squared length underflows to 0 for triangles under
    about 1e-10 across and overflows above about 1e10: it then reports a zero normal."""
    e = wp.cross(p1 - p0, p2 - p0)
    big = wp.max(wp.abs(e))
    if big > 0.0:
        e = e / big
    return wp.normalize(e)


@wp.func_native("""
float t, u, v, sign;
if (wp::intersect_ray_tri_woop(o, d, p0, p1, p2, t, u, v, sign, nullptr) && t >= 0.0f)
    return wp::vec3(t, u, v);
return wp::vec3(-1.0f, 0.0f, 0.0f);
""")
def woop_hit(o: wp.vec3, d: wp.vec3, p0: wp.vec3, p1: wp.vec3, p2: wp.vec3) -> wp.vec3:
    """(t, u, v) of the ray o + t d on one triangle, t = -1 for a miss: the very test, Woop's watertight
    one, that wp.mesh_query_ray applies to each triangle of a BVH leaf, so on the triangle that query
    returns it gives the query's t, u and v to the bit."""
    ...
