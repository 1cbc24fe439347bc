"""Phong shading, the seed's Figure 3, per colour channel and light l, shared by every renderer:
    I = C_amb ka + sum_l vis_l C_l (kd max(0, n.L) + ks max(0, r.v)^n),   r = L mirrored about n
with ka, kd and ks read at the hit by one function (coefficients): the material's, times its
textures and the vertex colour where the scene has them. The general light model (spot and
directional lights, inverse-square falloff) scales C_l by light_weight; the seed's lights compile without it.
"""

from __future__ import annotations

import functools

from .._warp import wp
from ..geometry import LIGHT_DIRECTIONAL, LIGHT_SPOT, LightShape, SceneData
from .interaction import Surface, reflect, spawn_ray
from .shadow import make_occluded
from .texture import texel


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


FAR = 1.0e30  # a shadow ray towards a directional light ends nowhere (the tracer's no-limit convention)


@wp.func
def spot_profile(shape: LightShape, cos_theta: float) -> float:
    """Mitsuba's ``spot`` falloff curve at angle theta off the axis: 1 within the beam, then linear in
    theta down to 0 at the cutoff (beyond which nothing)."""
    if cos_theta <= shape.cos_cutoff:
        return 0.0
    if cos_theta >= shape.cos_beam:
        return 1.0
    return (shape.cutoff - wp.acos(cos_theta)) * shape.inv_ramp


@wp.func
def light_weight(shape: LightShape, to_light: wp.vec3, L: wp.vec3) -> float:
    """The factor of C_l at the point ``to_light`` away from the light (L its direction): the spot's
    profile times 1 / r^2 for inverse_square, r measured from the hit point itself, as Mitsuba does."""
    w = 1.0
    if shape.kind == LIGHT_SPOT:
        w = spot_profile(shape, -wp.dot(L, shape.direction))
    if shape.inverse_square != 0:
        w = w / wp.dot(to_light, to_light)
    return w


@wp.struct
class ShadeResult:
    color: wp.vec3
    shadow_rays: int


@wp.struct
class Coefficients:
    """The Phong coefficients at one hit."""

    ka: wp.vec3
    kd: wp.vec3
    ks: wp.vec3


@functools.cache
def make_coefficients(TEXTURE: bool, VERTEX_COLOR: bool):
    """ka, kd and ks at a hit: the material's, times its texture at the hit's uv (TEXTURE) and, for
    ka and kd, the hit's vertex colour (VERTEX_COLOR)."""

    @wp.func
    def coefficients(s: SceneData, hit: Surface) -> Coefficients:
        m = hit.material
        c = Coefficients()
        c.ka = s.ka[m]
        c.kd = s.kd[m]
        c.ks = s.ks[m]
        if wp.static(TEXTURE):
            c.ka = wp.cw_mul(c.ka, texel(s.textures, s.ka_map[m], hit.uv))
            c.kd = wp.cw_mul(c.kd, texel(s.textures, s.kd_map[m], hit.uv))
            c.ks = wp.cw_mul(c.ks, texel(s.textures, s.ks_map[m], hit.uv))
        if wp.static(VERTEX_COLOR):
            c.ka = wp.cw_mul(c.ka, hit.color)
            c.kd = wp.cw_mul(c.kd, hit.color)
        return c

    return coefficients


def make_shade(fx, shadow_grid: bool = False):
    """The local shading function for one effect set (its ambient, diffuse, specular and shadow
    switches, and how ka, kd and ks are read): ambient + the lit terms of every light, with shadow
    rays when fx.shadows, answered by the BVH or, with ``shadow_grid``, by the light-space grid (the
    same answers: kernels/shadow.py)."""
    return _make_shade(fx.ambient, fx.diffuse, fx.specular, fx.shadows, fx.texture, fx.vertex_color,
                       fx.shadows and shadow_grid, fx.light_model)


@functools.cache
def _make_shade(AMBIENT: bool, DIFFUSE: bool, SPECULAR: bool, SHADOWS: bool, TEXTURE: bool, VERTEX_COLOR: bool,
                GRID: bool = False, LIGHT_MODEL: bool = False):
    coefficients = make_coefficients(TEXTURE, VERTEX_COLOR)

    # Disabled terms are absent from the generated code (wp.static).
    occluded = make_occluded(GRID)

    @wp.func
    def shade(s: SceneData, hit: Surface, v: wp.vec3) -> ShadeResult:
        out = ShadeResult()
        out.color = wp.vec3(0.0)
        out.shadow_rays = 0
        k = coefficients(s, hit)
        m = hit.material
        p = hit.p
        n = hit.n
        if wp.static(AMBIENT):
            out.color = wp.cw_mul(s.ambient, k.ka)
        if wp.static(DIFFUSE or SPECULAR):
            for l in range(s.num_lights):
                C_l = s.light_color[l]
                if wp.static(LIGHT_MODEL):
                    shape = s.light_shape[l]
                    directional = shape.kind == LIGHT_DIRECTIONAL
                    to_light = -shape.direction
                    if not directional:
                        to_light = s.light_pos[l] - p
                    L = wp.normalize(to_light)
                    weight = light_weight(shape, to_light, L)
                    if weight <= 0.0:  # outside a spot's cone: no light, so no shadow ray
                        continue
                    C_l = C_l * weight
                else:
                    to_light = s.light_pos[l] - p
                    L = wp.normalize(to_light)
                n_dot_l = wp.dot(n, L)
                if n_dot_l > 0.0:
                    visible = True
                    if wp.static(SHADOWS):
                        o = spawn_ray(hit, L).o  # towards the light, from its origin
                        to_light_o = s.light_pos[l] - o
                        dist = wp.length(to_light_o)
                        d = to_light_o / dist
                        if wp.static(LIGHT_MODEL):
                            if directional:  # its position is NaN: the ray above is replaced
                                d = L
                                dist = FAR
                        out.shadow_rays += 1
                        visible = not occluded(s, l, o, d, dist)
                    if visible:
                        lit = wp.vec3(0.0)
                        if wp.static(DIFFUSE):
                            lit = lit + phong_diffuse(k.kd, n_dot_l)
                        if wp.static(SPECULAR):
                            lit = lit + phong_specular(k.ks, s.shininess[m], n, L, v, n_dot_l)
                        out.color = out.color + wp.cw_mul(C_l, lit)
        return out

    return shade
