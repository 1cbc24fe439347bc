"""Phong shading and robust secondary-ray origins, as Warp functions shared by every renderer.

The local model (the seed's Figure 3), per colour channel and light l:
    I = C_amb ka + sum_l vis_l C_l (kd max(0, n.L) + ks max(0, r.v)^n),   r = 2 (n.L) n - L
"""

from __future__ import annotations

from ._warp import wp

from .geometry import SceneData

# The offset that keeps a secondary ray off the triangle it leaves (pbrt-v4's method, Pharr, Jakob,
# Humphreys, "Floating-Point Arithmetic", section 6.8) must exceed two float32 errors:
#  1. the hit point's own: p = b0 p0 + b1 p1 + b2 p2 is off by at most gamma(7) sum_j |b_j p_j|
#     per axis (pbrt's bound);
#  2. Warp's ray-triangle test's: unlike pbrt's, it rejects no t by its own error bound, and it
#     works on the vertices relative to the ray origin, sheared along the ray: a - o (1 rounding),
#     the shear (3), the scaled depth (2), the edge functions (2), their weighted sum T (5) and the
#     divide (1). That moves the plane it sees, at the hit, by up to gamma(16) sum_j |b_j| |p_j - p|
#     (max norm, all axes: the shear mixes them). pbrt's bound alone misses this when the triangle
#     is large next to |p|: a floor seen from just above it showed acne on 2% of shadow rays.
# OFFSET_SCALE is the margin over both, set from the failure rates the stability suite measures.
EPS32 = 2.0**-24


def gamma(n: int) -> float:
    return n * EPS32 / (1.0 - n * EPS32)


GAMMA_POINT = gamma(7)
GAMMA_WOOP = gamma(16)
OFFSET_SCALE = 2.0


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
