"""The edges of hard shadows seen by camera rays, for the gradient's boundary term (image/grad_shadow_edges.py
launches them): a shadow edge's signed distance in the image as a differentiable function of its occluder's
edge, its receiver, the light and the camera (shadow_plane, shadow_edge_distances), and one light's term
either side of it, seen directly or through mirrors, by the forward's own functions (make_light_sides_kernel)."""

import functools  # no "from __future__ import annotations": a kernel factory's types are its locals

from .._warp import wp
from ..geometry import SceneData
from .edges import make_mirror_path, plane_distance
from .mirror import Mirrors
from .raster import Fragments
from .shading import make_area_sample_test, make_coefficients, make_light_terms, make_light_test

SOURCE_LIGHT = 0  # a light sides kernel's source: a Whitted light l (shading's light_test)
SOURCE_SAMPLE = 1  # an area light e's sample point q (shading's area_sample_test)


@wp.func
def shadow_plane(v0: wp.vec3, v1: wp.vec3, light: wp.vec3, directional: int, p0: wp.vec3, p1: wp.vec3,
                 p2: wp.vec3, eye: wp.vec3) -> wp.vec3:
    """The normal of the plane through the eye and the edge of the shadow that an occluder's edge v0 v1 casts
    from a light at ``light`` (with ``directional``, a light travelling along ``light``) on the receiver
    triangle p0 p1 p2. The shadow's edge is where the wedge plane N . (y - v0) = 0 (N = (v0 - light) x
    (v1 - v0), or light x (v1 - v0)) meets the receiver's plane n_r . (y - p0) = 0; a camera ray y = eye + t d
    meets that plane at t = n_r . (p0 - eye) / n_r . d, so g = N . (y(x) - v0) = M . d / n_r . d with M =
    (N . (eye - v0)) n_r + (n_r . (p0 - eye)) N: M . d(x) is the edge function, linear in x, whose zeros are
    the shadow edge's image."""
    e = v1 - v0
    w = light
    if directional == 0:
        w = v0 - light
    n = wp.cross(w, e)
    n_r = wp.cross(p1 - p0, p2 - p0)
    return wp.dot(n, eye - v0) * n_r + wp.dot(n_r, p0 - eye) * n


@wp.kernel(module="unique")
def shadow_edge_distances(geometry: wp.array(dtype=wp.vec3), directional: wp.array(dtype=int),
                          camera: wp.array(dtype=wp.vec3), fovy: wp.array(dtype=float), near: float, width: int,
                          height: int, at: wp.array(dtype=wp.vec2), distance: wp.array(dtype=float)):
    """Per point j of a shadow's edge, plane_distance of ``at[j]`` from the image of that edge (shadow_plane
    of ``geometry[6 j:6 j + 6]``: the occluder edge's v0 and v1, the light, the receiver's p0, p1, p2) seen by
    the camera ``camera[3 j:3 j + 3]`` (eye, center, up) with fovy[j]: each point its own copies, so that
    each adjoint is a point's alone and the host sums them in a fixed order."""
    j = wp.tid()
    eye = camera[3 * j]
    n = shadow_plane(geometry[6 * j], geometry[6 * j + 1], geometry[6 * j + 2], directional[j], geometry[6 * j + 3],
                     geometry[6 * j + 4], geometry[6 * j + 5], eye)
    distance[j] = plane_distance(n, eye, camera[3 * j + 1], camera[3 * j + 2], fovy[j], near, width, height,
                                 at[j][0], at[j][1])


@functools.cache
def make_light_sides_kernel(fx):
    """The kernel that follows camera rays along given directions (``dirs``, unit) to the hit of their ray of
    level ``level`` (0: their nearest hit; k: through k mirrors, edges.make_mirror_path: the forward's hits and
    bounces) and writes what one light source gives there (``source``: (SOURCE_LIGHT, l, -1) a Whitted light,
    (SOURCE_SAMPLE, q, e) area light e's sample point q), by shading's own test and term (light_test and
    whitted_term, area_sample_test and area_term: its shadow ray included), as shade adds it, times the
    ray's weight (the mirrors' k_r): the jump of that source's light alone across its shadow's edge, seen
    directly or in mirrors."""
    mirror_path = make_mirror_path(fx)
    coefficients = make_coefficients(fx.texture, fx.vertex_color)
    light_test = make_light_test(fx.light_model, fx.shadows)  # a hard spot's cone: its shadow rays if traced
    area_sample_test = make_area_sample_test(True)
    whitted_term, area_term = make_light_terms(fx.diffuse, fx.specular)

    @wp.kernel(module="unique", enable_backward=False)
    def light_sides(s: SceneData, eye: wp.vec3, frags: Fragments, mir: Mirrors, dirs: wp.array(dtype=wp.vec3),
                    source: wp.array(dtype=wp.vec3i), level: wp.array(dtype=int), color: wp.array(dtype=wp.vec3)):
        j = wp.tid()
        end = mirror_path(s, frags, mir, eye, dirs[j], level[j])
        c = wp.vec3(0.0)
        if end.face >= 0:
            hit = end.hit
            k = coefficients(s, hit)
            shininess = s.shininess[hit.material]
            src = source[j]
            if src[0] == wp.static(SOURCE_LIGHT):
                t = light_test(s, hit, src[1])
                if t.lit != 0:
                    c = whitted_term(t.arrival, k, shininess, hit.n, -end.d)
            else:
                a = area_sample_test(s, hit, src[1], 0)
                if a.lit != 0:
                    c = area_term(a, s.area.radiance[src[2]], s.area.dA[src[1]], k, shininess, hit.n, -end.d)
            c = wp.cw_mul(end.weight, c)
        color[j] = c

    return light_sides
