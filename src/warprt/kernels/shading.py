"""Phong shading, the seed's Figure 3, per colour channel and light l, shared by every renderer:
    I = C_amb ka + sum_l vis_l C_l (kd max(0, n.L) + ks max(0, r.v)^n),   r = L mirrored about n
"""

from __future__ import annotations

import functools

from .._warp import wp
from ..geometry import SceneData
from .interaction import offset_ray_origin, reflect
from .shadow import make_occluded


@wp.func
def phong_diffuse(kd: wp.vec3, n_dot_l: float) -> wp.vec3:
    """kd max(0, n.L)."""
    return kd * wp.max(n_dot_l, 0.0)


@wp.func
def phong_specular(ks: wp.vec3, shininess: float, n: wp.vec3, l: wp.vec3, v: wp.vec3, n_dot_l: float) -> wp.vec3:
    """ks max(0, r.v)^n with r = L mirrored about n (= 2 (n.L) n - L)."""
    r = reflect(-l, n)
    r_dot_v = wp.max(wp.dot(r, v), 0.0)
    if r_dot_v <= 0.0:
        return wp.vec3(0.0)
    return ks * wp.pow(r_dot_v, shininess)


@wp.struct
class ShadeResult:
    color: wp.vec3
    shadow_rays: int


def make_shade(fx, shadow_grid: bool = False):
    """The local shading function for one effect set (its ambient, diffuse, specular and shadow
    switches): ambient + the lit terms of every light, with shadow rays when fx.shadows, answered by
    the BVH or, with ``shadow_grid``, by the light-space grid (the same answers: kernels/shadow.py)."""
    return _make_shade(fx.ambient, fx.diffuse, fx.specular, fx.shadows, fx.shadows and shadow_grid)


@functools.cache
def _make_shade(AMBIENT: bool, DIFFUSE: bool, SPECULAR: bool, SHADOWS: bool, GRID: bool):
    # Disabled terms are absent from the generated code (wp.static).
    occluded = make_occluded(GRID)

    @wp.func
    def shade(s: SceneData, m: int, p: wp.vec3, err: wp.vec3, ng: wp.vec3, n: wp.vec3, v: wp.vec3) -> ShadeResult:
        out = ShadeResult()
        out.color = wp.vec3(0.0)
        out.shadow_rays = 0
        if wp.static(AMBIENT):
            out.color = wp.cw_mul(s.ambient, s.ka[m])
        if wp.static(DIFFUSE or SPECULAR):
            for l in range(s.num_lights):
                to_light = s.light_pos[l] - p
                L = wp.normalize(to_light)
                n_dot_l = wp.dot(n, L)
                if n_dot_l > 0.0:
                    visible = True
                    if wp.static(SHADOWS):
                        o = offset_ray_origin(p, err, ng, L)
                        to_light_o = s.light_pos[l] - o
                        dist = wp.length(to_light_o)
                        out.shadow_rays += 1
                        visible = not occluded(s, l, o, to_light_o / dist, dist)
                    if visible:
                        lit = wp.vec3(0.0)
                        if wp.static(DIFFUSE):
                            lit = lit + phong_diffuse(s.kd[m], n_dot_l)
                        if wp.static(SPECULAR):
                            lit = lit + phong_specular(s.ks[m], s.shininess[m], n, L, v, n_dot_l)
                        out.color = out.color + wp.cw_mul(s.light_color[l], lit)
        return out

    return shade
