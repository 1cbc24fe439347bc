"""A ray's hit on a surface: the hit record (Surface), the bound on its floating-point error, and the
offset that spawns a secondary ray off it (pbrt-v4 and Mitsuba keep these with the interaction too).

The offset keeps a secondary ray off the triangle it leaves (pbrt-v4's method, Pharr, Jakob,
Humphreys, "Floating-Point Arithmetic", section 6.8) and must exceed two float32 errors:
 1. the hit point's own: p = b0 p0 + b1 p1 + b2 p2 is off by at most gamma(7) sum_j |b_j p_j|
    per axis (pbrt's bound);
 2. Warp's ray-triangle test's: unlike pbrt's, it rejects no t by its own error bound, and it
    works on the vertices relative to the ray origin, sheared along the ray: a - o (1 rounding),
    the shear (3), the scaled depth (2), the edge functions (2), their weighted sum T (5) and the
    divide (1). That moves the plane it sees, at the hit, by up to gamma(16) sum_j |b_j| |p_j - p|
    (max norm, all axes: the shear mixes them). pbrt's bound alone misses this when the triangle
    is large next to |p|: a floor seen from just above it showed acne on 2% of shadow rays.
OFFSET_SCALE is the margin over both, set from the failure rates the stability suite measures.
"""

from __future__ import annotations

import functools

from .._warp import wp
from ..floats import gamma
from ..geometry import SceneData
from ..geometry.bvh import face_vertices
from .triangle import triangle, unit_normal

GAMMA_POINT = gamma(7)
GAMMA_WOOP = gamma(16)
OFFSET_SCALE = 2.0


@wp.struct
class Surface:
    p: wp.vec3  # hit point, p0 u + p1 v + p2 (1 - u - v)
    err: wp.vec3  # its absolute error bound
    ng: wp.vec3  # geometric normal, turned to face the incoming ray
    n: wp.vec3  # shading normal, on the same side
    material: int
    uv: wp.vec2  # texture coordinates, interpolated as p is (only with the texture effect)
    color: wp.vec3  # vertex colour, likewise (only with the vertex_color effect)


@wp.func
def hit_point_error(p0: wp.vec3, p1: wp.vec3, p2: wp.vec3, b0: float, b1: float, b2: float) -> wp.vec3:
    """Per-axis bound on how far the hit p = b0 p0 + b1 p1 + b2 p2 may lie from the plane the ray
    test sees: the rounding of p, plus the ray test's error relative to the triangle's extent."""
    a = wp.cw_mul(wp.vec3(wp.abs(p0[0]), wp.abs(p0[1]), wp.abs(p0[2])), wp.vec3(wp.abs(b0)))
    a = a + wp.cw_mul(wp.vec3(wp.abs(p1[0]), wp.abs(p1[1]), wp.abs(p1[2])), wp.vec3(wp.abs(b1)))
    a = a + wp.cw_mul(wp.vec3(wp.abs(p2[0]), wp.abs(p2[1]), wp.abs(p2[2])), wp.vec3(wp.abs(b2)))
    p = p0 * b0 + p1 * b1 + p2 * b2
    e = wp.abs(b0) * wp.max(wp.abs(p0 - p)) + wp.abs(b1) * wp.max(wp.abs(p1 - p)) + wp.abs(b2) * wp.max(wp.abs(p2 - p))
    return (a * wp.static(GAMMA_POINT) + wp.vec3(e * wp.static(GAMMA_WOOP))) * wp.static(OFFSET_SCALE)


@wp.func
def offset_ray_origin(p: wp.vec3, err: wp.vec3, ng: wp.vec3, w: wp.vec3) -> wp.vec3:
    """pbrt-v4's OffsetRayOrigin: push p along the geometric normal ng just past its error box,
    to the side that direction w leaves towards, so the new ray cannot re-hit its own surface."""
    d = wp.abs(ng[0]) * err[0] + wp.abs(ng[1]) * err[1] + wp.abs(ng[2]) * err[2]
    offset = ng * d
    if wp.dot(w, ng) < 0.0:
        offset = -offset
    return p + offset


@wp.struct
class Ray:
    o: wp.vec3
    d: wp.vec3  # unit


@wp.func
def spawn_ray(hit: Surface, d: wp.vec3) -> Ray:
    """pbrt's SpawnRay, Mitsuba's spawn_ray: the ray leaving the hit along d, its origin offset
    off the surface so it cannot find the triangle it leaves."""
    r = Ray()
    r.o = offset_ray_origin(hit.p, hit.err, hit.ng, d)
    r.d = d
    return r


@wp.func
def reflect(d: wp.vec3, n: wp.vec3) -> wp.vec3:
    """d mirrored about the plane of normal n: d - 2 (d.n) n."""
    return d - 2.0 * wp.dot(d, n) * n


@wp.func
def mirror_ray(hit: Surface, d: wp.vec3) -> Ray:
    """A mirror's bounce: the ray arriving along d reflected about the hit's shading normal, spawned off it."""
    return spawn_ray(hit, wp.normalize(reflect(d, hit.n)))


@functools.cache
def make_surface(smooth: bool, texture: bool = False, vertex_color: bool = False):
    """The hit record for face f at barycentrics (u, v), seen along direction d; with ``smooth``,
    interpolated vertex normals where the face's object is smooth; with ``texture`` and
    ``vertex_color``, the interpolated uv and colour."""

    @wp.func
    def surface(s: SceneData, f: int, u: float, v: float, face_normal: wp.vec3, d: wp.vec3) -> Surface:
        p0, p1, p2 = triangle(s, f)
        w = 1.0 - u - v
        out = Surface()
        out.p = p0 * u + p1 * v + p2 * w
        out.err = hit_point_error(p0, p1, p2, u, v, w)
        ng = face_normal
        if not (wp.length(ng) > 0.0):
            ng = unit_normal(p0, p1, p2)
        side = 1.0
        # Two-sided surfaces: Warp's face normal follows the winding; turn it to face the ray.
        if wp.dot(ng, d) > 0.0:
            side = -1.0
        out.ng = ng * side
        out.n = out.ng
        if wp.static(smooth):
            if s.tri_smooth[f] != 0:
                i0, i1, i2 = face_vertices(s.indices, f)
                ns = s.normals[i0] * u + s.normals[i1] * v + s.normals[i2] * w
                if wp.length(ns) > 0.0:
                    out.n = wp.normalize(ns) * side
        if wp.static(texture or vertex_color):
            # Warp's barycentrics, as for p: weight u on the face's first vertex, v on its second.
            j0, j1, j2 = face_vertices(s.indices, f)
            if wp.static(texture):
                out.uv = s.uvs[j0] * u + s.uvs[j1] * v + s.uvs[j2] * w
            if wp.static(vertex_color):
                out.color = s.colors[j0] * u + s.colors[j1] * v + s.colors[j2] * w
        out.material = s.tri_material[f]
        return out

    return surface
