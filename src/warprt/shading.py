"""Phong shading and robust secondary-ray origins, as Warp functions shared by every renderer.

The local model (the seed's Figure 3), per colour channel and light l:
    I = C_amb ka + sum_l vis_l C_l (kd max(0, n.L) + ks max(0, r.v)^n),   r = 2 (n.L) n - L
"""

from __future__ import annotations

import warp as wp

from .geometry import SceneData

# Error bound of a point interpolated from float32 barycentrics, pbrt-v4's gamma(7)
# (Pharr, Jakob, Humphreys, "Floating-Point Arithmetic", section 6.8): |b0 p0| + |b1 p1| + |b2 p2|
# times 7 eps / (1 - 7 eps). Two more roundings are not covered by that bound: adding the offset to
# the point, and the plane distance inside Warp's ray-triangle test, which (unlike pbrt's) rejects
# no t by its own error bound. OFFSET_SCALE covers both with a margin, measured by the stability suite.
EPS32 = 2.0**-24
GAMMA7 = 7.0 * EPS32 / (1.0 - 7.0 * EPS32)
OFFSET_SCALE = 4.0


@wp.func
def hit_point_error(p0: wp.vec3, p1: wp.vec3, p2: wp.vec3, b0: float, b1: float, b2: float) -> wp.vec3:
    """Per-axis absolute error bound of p = b0 p0 + b1 p1 + b2 p2."""
    a = wp.cw_mul(wp.vec3(wp.abs(p0[0]), wp.abs(p0[1]), wp.abs(p0[2])), wp.vec3(wp.abs(b0)))
    a = a + wp.cw_mul(wp.vec3(wp.abs(p1[0]), wp.abs(p1[1]), wp.abs(p1[2])), wp.vec3(wp.abs(b1)))
    a = a + wp.cw_mul(wp.vec3(wp.abs(p2[0]), wp.abs(p2[1]), wp.abs(p2[2])), wp.vec3(wp.abs(b2)))
    return a * wp.static(GAMMA7 * OFFSET_SCALE)


@wp.func
def offset_ray_origin(p: wp.vec3, err: wp.vec3, ng: wp.vec3, w: wp.vec3) -> wp.vec3:
    """pbrt-v4's OffsetRayOrigin: push p along the geometric normal ng just past its error box,
    to the side that direction w leaves towards, so the new ray cannot re-hit its own surface."""
    d = wp.abs(ng[0]) * err[0] + wp.abs(ng[1]) * err[1] + wp.abs(ng[2]) * err[2]
    offset = ng * d
    if wp.dot(w, ng) < 0.0:
        offset = -offset
    return p + offset


@wp.func
def phong_diffuse(kd: wp.vec3, n_dot_l: float) -> wp.vec3:
    """kd max(0, n.L)."""
    return kd * wp.max(n_dot_l, 0.0)


@wp.func
def phong_specular(ks: wp.vec3, shininess: float, n: wp.vec3, l: wp.vec3, v: wp.vec3, n_dot_l: float) -> wp.vec3:
    """ks max(0, r.v)^n with r = L mirrored about n."""
    r = 2.0 * n_dot_l * n - l
    r_dot_v = wp.max(wp.dot(r, v), 0.0)
    if r_dot_v <= 0.0:
        return wp.vec3(0.0)
    return ks * wp.pow(r_dot_v, shininess)


@wp.struct
class ShadeResult:
    color: wp.vec3
    shadow_rays: int


_shade_cache: dict = {}


def make_shade(fx):
    """The local shading function for one effect set: ambient + the lit terms of every light,
    with shadow rays when fx.shadows. Disabled terms are absent from the generated code."""
    key = (fx.ambient, fx.diffuse, fx.specular, fx.shadows)
    if key in _shade_cache:
        return _shade_cache[key]
    AMBIENT, DIFFUSE, SPECULAR, SHADOWS = key

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
                        visible = not wp.mesh_query_ray_anyhit(s.mesh, o, to_light_o / dist, dist)
                    if visible:
                        lit = wp.vec3(0.0)
                        if wp.static(DIFFUSE):
                            lit = lit + phong_diffuse(s.kd[m], n_dot_l)
                        if wp.static(SPECULAR):
                            lit = lit + phong_specular(s.ks[m], s.shininess[m], n, L, v, n_dot_l)
                        out.color = out.color + wp.cw_mul(s.light_color[l], lit)
        return out

    _shade_cache[key] = shade
    return shade
