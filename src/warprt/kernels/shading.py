"""Phong shading, the seed's Figure 3, per colour channel and light l, shared by every renderer:
    I = C_amb ka + sum_l vis_l C_l (kd max(0, n.L) + ks max(0, r.v)^n),   r = L mirrored about n
with ka, kd and ks read at the hit by one function (coefficients): the material's, times its
textures and the vertex colour where the scene has them. The general light model (spot and
directional lights, inverse-square falloff) scales C_l by light_weight; the seed's lights compile without it.

Area lights (compiled only for scenes with some: EffectSet.area_lights) are integrated over their fixed
sample points q (scene/area.py), each a point light of intensity L_e cos_q dA_q with inverse-square falloff:
    sum_q vis_q L_e cos_q / r_q^2 dA_q (kd max(0, n.L_q) + ks max(0, r_q.v)^n),   dA_q = A / N,
cos_q the cosine at the emitter (0 behind it: one-sided, as Mitsuba's ``area``). kd and ks are thus read
as BRDF values, as for a point light with inverse_square falloff (whose radiance is C_l / r^2 kd n.L,
Mitsuba's point emitter on a diffuse BSDF with kd = reflectance / pi): a Lambertian kd = reflectance / pi
under an area emitter of radiance L_e gives Mitsuba's (reflectance / pi) integral L_e cos cos' / r^2 dA.
A shadow ray runs to each sample on the BVH, stopping SHADOW_EPSILON of the way short of the emitter
(Mitsuba's spawn_ray_to does likewise), so that the emitter's own triangles do not block it.

An environment light (compiled only for scenes with one: EffectSet.environment) adds over its fixed directions
w_q (scene/environment.py), each with a shadow ray to infinity:
    sum_q vis_q W_q (kd max(0, n.w_q) + ks max(0, r_q.v)^n),   W_q = L(w_q) / (pdf(w_q) N),
kd and ks again BRDF values: a Lambertian kd = reflectance / pi under a constant radiance L gives reflectance x L.
"""

from __future__ import annotations

import functools
import math

from .._warp import wp
from ..geometry import LIGHT_DIRECTIONAL, LIGHT_SPOT, LightShape, SceneData
from .clearance import SHADOW_EPSILON, light_clear
from .interaction import Surface, reflect, spawn_ray
from .record import GradRecord, record_area_point
from .shadow import make_occluded
from .texture import texel
from .triangle import triangle, unit_normal


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
def emitter_met(s: SceneData, f: int, d: wp.vec3) -> int:
    """The area light a ray along d sees emitting at face f (-1: none): face f's, from the side its
    winding's normal points to (Mitsuba's area emitter: one-sided, si.n the winding's normal)."""
    e = s.area.tri_emitter[f]
    if e < 0:
        return -1
    p0, p1, p2 = triangle(s, f)
    if wp.dot(d, unit_normal(p0, p1, p2)) >= 0.0:
        return -1
    return e


@wp.func
def emitted(s: SceneData, f: int, d: wp.vec3) -> wp.vec3:
    """The radiance a ray along d sees at face f: its area light's L_e (emitter_met), else nothing."""
    e = emitter_met(s, f, d)
    if e < 0:
        return wp.vec3(0.0)
    return s.area.radiance[e]


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
            c.ka = wp.cw_mul(c.ka, texel(s.texels, s.ka_map[m], hit.uv))
            c.kd = wp.cw_mul(c.kd, texel(s.texels, s.kd_map[m], hit.uv))
            c.ks = wp.cw_mul(c.ks, texel(s.texels, s.ks_map[m], hit.uv))
        if wp.static(VERTEX_COLOR):
            c.ka = wp.cw_mul(c.ka, hit.color)
            c.kd = wp.cw_mul(c.kd, hit.color)
        return c

    return coefficients


def make_shade(fx, shadow_grid: bool = False, record: bool = False):
    """The local shading function for one effect set (its ambient, diffuse, specular and shadow
    switches, and how ka, kd and ks are read): ambient + the lit terms of every light, with shadow
    rays when fx.shadows, answered by the BVH or, with ``shadow_grid``, by the light-space grid (the
    same answers: kernels/shadow.py). shade(s, hit, v, rec, j, stratum): ``stratum`` the pixel sample's share of
    the area lights' points under render.light_spread (fx.light_spread), else unread; with ``record``, also which lights and
    area-light sample points the hit sees, written into the GradRecord ``rec`` at its entry ``j``
    (kernels/record.py); without, ``rec`` is never read. Inlined: its arguments are not copied."""
    return _make_shade(fx.ambient, fx.diffuse, fx.specular, fx.shadows, fx.texture, fx.vertex_color,
                       fx.shadows and shadow_grid, fx.light_model, fx.area_lights, record, fx.area_analytic,
                       fx.light_spread, fx.environment)


@wp.struct
class LightArrival:
    """How one Whitted light arrives at a hit (make_light_arrival): the unit direction L to it, n.L, its colour
    times its weight (a spot's cone, 1 / r^2 falloff) and whether it reaches the point at all (0: outside a
    spot's cone). A differentiable function of the hit and the light: what the gradient's replay shades with
    (kernels/replay.py), the shadow ray's answer being the record's."""

    L: wp.vec3
    n_dot_l: float
    C: wp.vec3
    reaches: int


@functools.cache
def make_light_arrival(LIGHT_MODEL: bool):
    """light_arrival(s, hit, l): how light l arrives at the hit (LightArrival). With LIGHT_MODEL, the general
    light model: a directional light lies along -direction, a spot outside its cone gives nothing; without,
    the seed's point lights."""

    @wp.func(inline=True)
    def light_arrival(s: SceneData, hit: Surface, l: int) -> LightArrival:
        out = LightArrival()
        out.reaches = 1
        C_l = s.light_color[l]
        p = hit.p
        if wp.static(LIGHT_MODEL):
            shape = s.light_shape[l]
            to_light = -shape.direction
            if shape.kind != wp.static(LIGHT_DIRECTIONAL):
                to_light = s.light_pos[l] - p
            L = wp.normalize(to_light)
            weight = light_weight(shape, to_light, L)
            if weight <= 0.0:  # outside a spot's cone: no light, so no shadow ray
                out.reaches = 0
                return out
            C_l = C_l * weight
        else:
            to_light = s.light_pos[l] - p
            L = wp.normalize(to_light)
        out.L = L
        out.n_dot_l = wp.dot(hit.n, L)
        out.C = C_l
        return out

    return light_arrival


@wp.struct
class LightTest:
    """What one Whitted light gives a hit (make_light_test): how it arrives (LightArrival), whether a shadow ray
    was traced (1: the light faces the point) and whether the light is seen (lit: in its cone, n.L > 0 and no
    shadow ray blocked)."""

    arrival: LightArrival
    shadow_ray: int
    lit: int


@functools.cache
def make_light_test(LIGHT_MODEL: bool, SHADOWS: bool, GRID: bool = False):
    """light_test(s, hit, l): whether light l lights the hit, and with what (LightTest): its arrival
    (make_light_arrival) and, where it reaches the point from the front, the shadow ray (SHADOWS), which
    leaves spawn_ray's origin for the light (a directional light's unbounded), answered by the BVH or the grid
    (GRID). The one test the forward's shade makes, and with it writes the gradient's record."""
    occluded = make_occluded(GRID)
    light_arrival = make_light_arrival(LIGHT_MODEL)

    @wp.func(inline=True)
    def light_test(s: SceneData, hit: Surface, l: int) -> LightTest:
        out = LightTest()
        out.shadow_ray = 0
        out.lit = 0
        a = light_arrival(s, hit, l)
        out.arrival = a
        if a.reaches != 0 and a.n_dot_l > 0.0:
            visible = True
            if wp.static(SHADOWS):
                o = spawn_ray(hit, a.L).o  # towards the light, from its origin
                to_light_o = s.light_pos[l] - o
                dist = wp.length(to_light_o)
                d = to_light_o / dist
                if wp.static(LIGHT_MODEL):
                    if s.light_shape[l].kind == wp.static(LIGHT_DIRECTIONAL):  # its position is NaN: replaced
                        d = a.L
                        dist = FAR
                out.shadow_ray = 1
                visible = not occluded(s, l, o, d, dist)
            if visible:
                out.lit = 1
        return out

    return light_test


@wp.struct
class AreaTest:
    """What one area-light sample point gives a hit: how it arrives (make_area_sample_test's area_arrival: the
    unit direction L to it, r^2, n.L, the emitter's cosine cos_q there), whether a shadow ray was traced (1:
    the point and the hit face each other) and whether the point is seen (lit: r^2 > 0, n.L > 0, cos_q > 0,
    shadow ray unblocked)."""

    L: wp.vec3
    r2: float
    n_dot_l: float
    cos_q: float
    shadow_ray: int
    lit: int


@wp.func
def point_arrival(point: wp.vec3, normal: wp.vec3, hit: Surface) -> AreaTest:
    """How a point of an emitter (its unit normal on the emitting side) arrives at the hit: L, r^2, n.L and
    cos_q (AreaTest's; no shadow ray, lit 0), a differentiable function of the hit and the point."""
    out = AreaTest()
    out.shadow_ray = 0
    out.lit = 0
    to_q = point - hit.p
    r2 = wp.dot(to_q, to_q)
    out.r2 = r2
    if not (r2 > 0.0):
        return out
    L = to_q / wp.sqrt(r2)
    out.L = L
    out.n_dot_l = wp.dot(hit.n, L)
    out.cos_q = -wp.dot(normal, L)
    return out


@wp.func
def area_arrival(s: SceneData, hit: Surface, q: int) -> AreaTest:
    """How the area lights' sample point q arrives at the hit (point_arrival): what the gradient's replay
    differentiates, the shadow ray's answer being the record's."""
    return point_arrival(s.area.points[q], s.area.normals[q], hit)


@functools.cache
def make_area_sample_test(SHADOWS: bool):
    """area_sample_test(s, hit, q, clear): whether the area lights' sample point q lights the hit (AreaTest): its
    arrival and, where the point and the hit face each other, the shadow ray (SHADOWS, the BVH's any-hit
    query), stopping SHADOW_EPSILON of the way short of the point; with ``clear`` 1 (kernels/clearance.py: no
    triangle can stop it) seen without it."""
    occluded = make_occluded(False)

    @wp.func
    def area_sample_test(s: SceneData, hit: Surface, q: int, clear: int) -> AreaTest:
        out = area_arrival(s, hit, q)
        if out.r2 > 0.0 and out.n_dot_l > 0.0 and out.cos_q > 0.0:
            visible = True
            if wp.static(SHADOWS) and clear == 0:
                o = spawn_ray(hit, out.L).o
                to_q_o = s.area.points[q] - o
                dist = wp.length(to_q_o)
                out.shadow_ray = 1
                visible = not occluded(s, -1, o, to_q_o / dist, dist * wp.static(1.0 - SHADOW_EPSILON))
            if visible:
                out.lit = 1
        return out

    return area_sample_test


@functools.cache
def make_phong_lit(DIFFUSE: bool, SPECULAR: bool):
    """phong_lit(k, shininess, n, L, v, n_dot_l): the Phong terms one light's direction L lights, per unit
    of its colour: kd n.L + ks max(0, r.v)^n, each only where its switch is on (point and area lights alike)."""

    @wp.func
    def phong_lit(k: Coefficients, shininess: float, n: wp.vec3, L: wp.vec3, v: wp.vec3, n_dot_l: float) -> wp.vec3:
        lit = wp.vec3(0.0)
        if wp.static(DIFFUSE):
            lit = lit + phong_diffuse(k.kd, n_dot_l)
        if wp.static(SPECULAR):
            lit = lit + phong_specular(k.ks, shininess, n, L, v, n_dot_l)
        return lit

    return phong_lit


@functools.cache
def make_light_terms(DIFFUSE: bool, SPECULAR: bool):
    """(whitted_term, area_term): what a light the hit sees adds, per its switches (phong_lit).
    whitted_term(a, k, shininess, n, v): C_l (kd n.L + ks max(0, r.v)^n) of a Whitted light's LightArrival a;
    area_term(t, L_e, dA, k, shininess, n, v): L_e (kd n.L + ks max(0, r.v)^n) cos_q dA / r^2 of an area-light
    sample point's AreaTest t. The forward's shade and the gradient's replay both add them."""
    phong_lit = make_phong_lit(DIFFUSE, SPECULAR)

    @wp.func
    def whitted_term(a: LightArrival, k: Coefficients, shininess: float, n: wp.vec3, v: wp.vec3) -> wp.vec3:
        return wp.cw_mul(a.C, phong_lit(k, shininess, n, a.L, v, a.n_dot_l))

    @wp.func
    def area_term(t: AreaTest, L_e: wp.vec3, dA: float, k: Coefficients, shininess: float, n: wp.vec3,
                  v: wp.vec3) -> wp.vec3:
        lit = phong_lit(k, shininess, n, t.L, v, t.n_dot_l)
        return wp.cw_mul(L_e, lit) * (t.cos_q * dA / t.r2)

    return whitted_term, area_term


@wp.func
def edge_term(a: wp.vec3, b: wp.vec3, n: wp.vec3) -> float:
    """An edge a -> b's term of Arvo's polygon integral: theta (n . unit(a x b)), theta the angle it subtends."""
    c = wp.cross(a, b)
    sin = wp.length(c)
    if sin <= 0.0:
        return 0.0
    return wp.atan2(sin, wp.dot(a, b)) * wp.dot(n, c) / sin


@wp.func
def triangle_integral(a: wp.vec3, b: wp.vec3, c: wp.vec3, hit: Surface) -> float:
    """The unshadowed integral of n.L cos_q / r^2 dA over an emitting triangle (its corners relative to the
    hit, wound counter-clockwise about its emitting normal) seen from the hit: Lambert's and Arvo's polygon
    irradiance over pi, -1/2 sum_i theta_i (n . unit(v_i x v_i+1)) over the triangle clipped to the hit's
    hemisphere (Sutherland-Hodgman: the edges' parts above it and the horizon's edge from where the boundary
    leaves to where it comes back); 0 behind it (one-sided)."""
    if wp.dot(a, wp.cross(b - a, c - a)) >= 0.0:
        return 0.0
    n = hit.n
    h = wp.vec3(wp.dot(n, a), wp.dot(n, b), wp.dot(n, c))
    m = wp.matrix_from_rows(a, b, c)
    total = float(0.0)
    leave = wp.vec3(0.0)
    enter = wp.vec3(0.0)
    clipped = False
    for i in range(3):
        p, q = m[i], m[(i + 1) % 3]
        hp, hq = h[i], h[(i + 1) % 3]
        if hp >= 0.0 and hq >= 0.0:
            total += edge_term(p, q, n)
        elif hp >= 0.0 or hq >= 0.0:
            x = p + (q - p) * (hp / (hp - hq))  # where the edge crosses the horizon
            clipped = True
            if hp >= 0.0:
                total += edge_term(p, x, n)
                leave = x
            else:
                total += edge_term(x, q, n)
                enter = x
    if clipped:
        total += edge_term(leave, enter, n)
    return -0.5 * total


@wp.func
def polygon_integral(s: SceneData, e: int, hit: Surface) -> float:
    """triangle_integral over area light e's emitting triangles (AreaLights.corners)."""
    total = float(0.0)
    for t in range(s.area.polygon[e], s.area.polygon[e + 1]):
        total += triangle_integral(s.area.corners[3 * t] - hit.p, s.area.corners[3 * t + 1] - hit.p,
                                   s.area.corners[3 * t + 2] - hit.p, hit)
    return wp.max(total, 0.0)


@wp.func
def sphere_integral(sphere: wp.vec4, hit: Surface) -> float:
    """The unshadowed integral of n.L cos_q / r^2 dA over a sphere light (centre, radius) that lies wholly
    above the hit's horizon: pi sin^2(alpha) cos(theta) = pi R^2 (n . d) / |d|^3, d the way to its centre,
    alpha its angular radius; -1 where part of it is below the horizon or the hit inside it (no closed
    form here: its points integrate it)."""
    d = wp.vec3(sphere[0], sphere[1], sphere[2]) - hit.p
    r = sphere[3]
    dist2 = wp.dot(d, d)
    n_dot_d = wp.dot(hit.n, d)
    if dist2 <= r * r or n_dot_d <= 0.0 or n_dot_d * n_dot_d < r * r:  # cos(theta) >= sin(alpha) above it
        return -1.0
    return wp.static(math.pi) * r * r * n_dot_d / (dist2 * wp.sqrt(dist2))


@wp.func
def closed_integral(s: SceneData, e: int, hit: Surface) -> float:
    """Area light e's unshadowed diffuse integral in closed form: its triangles' (polygon_integral), a sphere's
    wholly above the horizon (sphere_integral); -1 where none applies (a disk; a sphere the horizon cuts)."""
    if s.area.polygon[e + 1] > s.area.polygon[e]:
        return polygon_integral(s, e, hit)
    sphere = s.area.spheres[e]
    if sphere[3] > 0.0:
        return sphere_integral(sphere, hit)
    return -1.0


@functools.cache
def make_area_light(DIFFUSE: bool, SPECULAR: bool, SHADOWS: bool, RECORD: bool = False, ANALYTIC: bool = False,
                    SPREAD: bool = False):
    """area_light(s, hit, k, v, out, rec, j, stratum): ``out`` plus the light of every area light at the hit, over
    its sample points, one shadow ray (the BVH's any-hit query) each where the point faces both ways
    (make_area_sample_test); with RECORD, a bit per point seen set in ``rec``'s entry j (record_area_point).
    With SPREAD, over the points of the pixel sample's ``stratum`` only (render.light_spread: AreaLights).
    With ANALYTIC, a polygonal or sphere light's diffuse term is its unshadowed closed form (closed_integral) times the ratio
    estimate of its visibility over the points, sum_q vis_q f_q / sum_q f_q with f_q = n.L_q cos_q / r_q^2 each
    point's unshadowed share (Heitz et al. 2018): exact where every point is seen, the points' own estimate in
    a penumbra; 1 where no point faces the hit (the light then only grazes its horizon). The specular term
    stays on the points, and so does the whole of a disk's, and of a sphere's where the horizon cuts it.
    A light the hit is proven to see whole (kernels/clearance.py light_clear, where the frame
    asked for it, AreaLights.hulled, and the hit takes CLEAR_MIN_POINTS of its points or more: the proof costs
    about two shadow rays) has its points' shadow rays skipped, and with ANALYTIC and no specular
    term its points too: the ratio is then 1 exactly."""
    area_sample_test = make_area_sample_test(SHADOWS)
    _, area_term = make_light_terms(DIFFUSE, SPECULAR)
    _, specular_term = make_light_terms(False, SPECULAR)
    DIFFUSE_CLOSED = ANALYTIC and DIFFUSE

    if not (ANALYTIC or SPREAD):
        @wp.func(inline=True)
        def area_light(s: SceneData, hit: Surface, k: Coefficients, v: wp.vec3, out: ShadeResult, rec: GradRecord,
                       j: int, stratum: int) -> ShadeResult:
            a = s.area
            n = hit.n
            for e in range(a.num):
                L_e = a.radiance[e]
                clear = int(0)
                if wp.static(SHADOWS):
                    clear = light_clear(s, hit, e, a.first[e + 1] - a.first[e])
                for q in range(a.first[e], a.first[e + 1]):
                    t = area_sample_test(s, hit, q, clear)
                    out.shadow_rays += t.shadow_ray
                    if wp.static(RECORD):
                        if t.lit != 0:
                            record_area_point(rec, j, q)
                    if t.lit != 0:
                        out.color = out.color + area_term(t, L_e, a.dA[q], k, s.shininess[hit.material], n, v)
            return out

        return area_light

    @wp.func(inline=True)
    def area_light_split(s: SceneData, hit: Surface, k: Coefficients, v: wp.vec3, out: ShadeResult,
                         rec: GradRecord, j: int, stratum: int) -> ShadeResult:
        a = s.area
        n = hit.n
        for e in range(a.num):
            L_e = a.radiance[e]
            lo, hi = int(a.first[e]), int(a.first[e + 1])
            if wp.static(SPREAD):
                lo, hi = int(a.first[e * a.strata + stratum]), int(a.first[e * a.strata + stratum + 1])
            closed = int(0)
            U = float(0.0)
            if wp.static(DIFFUSE_CLOSED):
                U = closed_integral(s, e, hit)
                closed = wp.where(U >= 0.0, 1, 0)
            clear = int(0)
            if wp.static(SHADOWS):
                clear = light_clear(s, hit, e, hi - lo)
                if wp.static(not SPECULAR):
                    if closed != 0 and clear != 0:
                        hi = lo  # every point seen: the ratio is 1, the closed form alone
            seen, facing = float(0.0), float(0.0)
            for q in range(lo, hi):
                t = area_sample_test(s, hit, q, clear)
                out.shadow_rays += t.shadow_ray
                if closed != 0:
                    if t.r2 > 0.0 and t.n_dot_l > 0.0 and t.cos_q > 0.0:
                        f = t.n_dot_l * t.cos_q / t.r2
                        facing += f
                        if t.lit != 0:
                            seen += f
                    if wp.static(SPECULAR):
                        if t.lit != 0:
                            out.color = out.color + specular_term(t, L_e, a.dA[q], k, s.shininess[hit.material], n, v)
                elif t.lit != 0:
                    out.color = out.color + area_term(t, L_e, a.dA[q], k, s.shininess[hit.material], n, v)
            if closed != 0:
                ratio = wp.where(facing > 0.0, seen / facing, 1.0)
                out.color = out.color + wp.cw_mul(k.kd, L_e) * (U * ratio)
        return out

    return area_light_split


@wp.func
def environment_share(num: int, strata: int, s: int):
    """[lo, hi) of the directions pixel-sample stratum ``s`` takes under render.light_spread: the lattice's
    points n = s mod strata, ordered by stratum (geometry.scene_data's Environment), num // strata of them, one
    more where s < num mod strata."""
    q, r = num // strata, num % strata
    lo = s * q + wp.min(s, r)
    return lo, lo + q + wp.where(s < r, 1, 0)


@functools.cache
def make_environment_light(DIFFUSE: bool, SPECULAR: bool, SHADOWS: bool, SPREAD: bool = False):
    """environment_light(s, hit, k, v, out, stratum) -> ``out`` plus the light of the environment's fixed
    directions at the hit (the module docstring), a shadow ray each (the BVH's any-hit query, to infinity) where
    the direction faces the hit's normal. With SPREAD, over the directions of the pixel sample's ``stratum``
    only (render.light_spread: environment_share)."""
    occluded = make_occluded(False)
    phong_lit = make_phong_lit(DIFFUSE, SPECULAR)

    @wp.func(inline=True)
    def environment_light(s: SceneData, hit: Surface, k: Coefficients, v: wp.vec3, out: ShadeResult,
                          stratum: int) -> ShadeResult:
        e = s.env
        n = hit.n
        shininess = s.shininess[hit.material]
        lo, hi = int(0), int(e.num)
        if wp.static(SPREAD):  # share s: directions s, s + strata, ... of the lattice, stored together
            lo, hi = environment_share(e.num, e.strata, stratum)
        for q in range(lo, hi):
            w = e.directions[q]
            n_dot_l = wp.dot(n, w)
            if n_dot_l > 0.0:
                visible = True
                if wp.static(SHADOWS):
                    out.shadow_rays += 1
                    visible = not occluded(s, -1, spawn_ray(hit, w).o, w, FAR)
                if visible:
                    out.color = out.color + wp.cw_mul(e.weights[q], phong_lit(k, shininess, n, w, v, n_dot_l))
        return out

    return environment_light


@functools.cache
def _make_shade(AMBIENT: bool, DIFFUSE: bool, SPECULAR: bool, SHADOWS: bool, TEXTURE: bool, VERTEX_COLOR: bool,
                GRID: bool = False, LIGHT_MODEL: bool = False, AREA: bool = False, RECORD: bool = False,
                ANALYTIC: bool = False, SPREAD: bool = False, ENVIRONMENT: bool = False):
    coefficients = make_coefficients(TEXTURE, VERTEX_COLOR)
    environment_light = make_environment_light(DIFFUSE, SPECULAR, SHADOWS, SPREAD)

    # Disabled terms are absent from the generated code (wp.static).
    light_test = make_light_test(LIGHT_MODEL, SHADOWS, GRID)
    whitted_term, _ = make_light_terms(DIFFUSE, SPECULAR)
    area_light = make_area_light(DIFFUSE, SPECULAR, SHADOWS, RECORD, ANALYTIC, SPREAD)

    @wp.func(inline=True)
    def shade(s: SceneData, hit: Surface, v: wp.vec3, rec: GradRecord, j: int, stratum: int) -> ShadeResult:
        out = ShadeResult()
        out.color = wp.vec3(0.0)
        out.shadow_rays = 0
        k = coefficients(s, hit)
        m = hit.material
        n = hit.n
        if wp.static(AMBIENT):
            out.color = wp.cw_mul(s.ambient, k.ka)
        if wp.static(DIFFUSE or SPECULAR):
            if wp.static(RECORD):
                seen = int(0)  # a bit per light the hit sees
            for l in range(s.num_lights):
                t = light_test(s, hit, l)
                out.shadow_rays += t.shadow_ray
                if wp.static(RECORD):
                    seen = seen | (t.lit << l)
                if t.lit != 0:
                    out.color = out.color + whitted_term(t.arrival, k, s.shininess[m], n, v)
            if wp.static(RECORD):
                rec.visible[j] = seen
        if wp.static(AREA and (DIFFUSE or SPECULAR)):
            out = area_light(s, hit, k, v, out, rec, j, stratum)
        if wp.static(ENVIRONMENT and (DIFFUSE or SPECULAR)):
            out = environment_light(s, hit, k, v, out, stratum)
        return out

    return shade
