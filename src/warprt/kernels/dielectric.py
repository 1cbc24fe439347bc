"""A dielectric interface, Whitted's transmitted ray: the exact unpolarized Fresnel reflectance and
Snell's law in vector form (pbrt-v4's FrDielectric and Refract), the two children a hit spawns, and
Beer's law inside the medium.

eta is always n_t / n_i, the index past the surface over the index before it. Both functions compute
sin^2(theta_t) = (1 - cos_i^2) / eta^2 the same way, so they agree on total internal reflection.
"""

from __future__ import annotations

from .._warp import wp
from ..geometry import SceneData
from .interaction import Surface, reflect
from .triangle import triangle, unit_normal


@wp.func
def fresnel_dielectric(cos_i: float, eta: float) -> float:
    """F(cos_i, eta): the share of light reflected, (r_parallel^2 + r_perpendicular^2) / 2, for light
    arriving at cos_i > 0 from the side the normal points to (n_t / n_i = eta), or at cos_i < 0 from
    the other side (then 1 / eta); 1 past the critical angle (total internal reflection)."""
    c = wp.clamp(cos_i, -1.0, 1.0)
    e = eta
    if c < 0.0:
        e = 1.0 / eta
        c = -c
    sin2_t = (1.0 - c * c) / (e * e)
    if sin2_t >= 1.0:
        return 1.0
    cos_t = wp.sqrt(1.0 - sin2_t)
    r_parallel = (e * c - cos_t) / (e * c + cos_t)
    r_perpendicular = (c - e * cos_t) / (c + e * cos_t)
    return 0.5 * (r_parallel * r_parallel + r_perpendicular * r_perpendicular)


@wp.func
def refract(d: wp.vec3, n: wp.vec3, eta: float):
    """Snell's law, eta_i sin(theta_i) = eta_t sin(theta_t): the direction d (unit, towards the
    surface) takes past a surface of unit normal n on d's side (d.n <= 0) and relative index
    eta = n_t / n_i, d / eta + (cos_i / eta - cos_t) n, and whether it exists (false past the
    critical angle)."""
    cos_i = -wp.dot(d, n)
    sin2_t = (1.0 - cos_i * cos_i) / (eta * eta)
    if sin2_t >= 1.0:
        return d, False
    cos_t = wp.sqrt(1.0 - sin2_t)
    return d / eta + (cos_i / eta - cos_t) * n, True


@wp.struct
class Children:
    """The reflected and the refracted ray of a dielectric hit: direction, weight, the medium each
    travels in (the hit's material inside the glass, -1 outside) and whether it carries anything; and the
    Fresnel reflectance F that splits the weight (the gradient's record follows the rays by it too)."""

    d_r: wp.vec3
    w_r: wp.vec3
    medium_r: int
    has_r: bool
    d_t: wp.vec3
    w_t: wp.vec3
    medium_t: int
    has_t: bool
    F: float


@wp.func
def dielectric_children(s: SceneData, f: int, hit: Surface, d: wp.vec3, weight: wp.vec3, eta: float) -> Children:
    """pbrt's SpecularReflect and SpecularTransmit at once: the Fresnel split of ``weight`` arriving
    along d at face f (material index eta) between the mirrored and the Snell-refracted direction."""
    # hit.ng faces the ray; the ray enters where that is the winding's outward normal.
    p0, p1, p2 = triangle(s, f)
    entering = wp.dot(hit.ng, unit_normal(p0, p1, p2)) > 0.0
    outward = hit.ng
    eta_rel = eta
    if not entering:
        outward = -hit.ng
        eta_rel = 1.0 / eta
    # Fresnel and Snell about the shading normal on the ray's side, or the geometric one where the
    # shading normal is tilted past the ray.
    m = hit.n
    if wp.dot(m, hit.ng) < 0.0:
        m = -m
    if not (wp.dot(d, m) * wp.dot(d, hit.ng) > 0.0):
        m = hit.ng
    cos_i = -wp.dot(d, m)
    F = fresnel_dielectric(wp.where(entering, cos_i, -cos_i), eta)
    t, transmits = refract(d, m, eta_rel)
    out = Children()
    out.F = F
    out.w_r = weight * F
    out.w_t = wp.cw_mul(weight, s.transmittance[hit.material]) * (1.0 - F)
    out.has_r = wp.max(out.w_r) > 0.0
    out.has_t = transmits and wp.max(out.w_t) > 0.0
    # A child is inside the glass where it leaves against the outward normal.
    out.d_r = wp.normalize(reflect(d, m))
    out.medium_r = wp.where(wp.dot(out.d_r, outward) < 0.0, hit.material, -1)
    out.d_t = wp.normalize(t)
    out.medium_t = wp.where(wp.dot(out.d_t, outward) < 0.0, hit.material, -1)
    return out


@wp.func
def beer(weight: wp.vec3, sigma: wp.vec3, distance: float) -> wp.vec3:
    """Beer's law: weight exp(-sigma distance) per channel."""
    return wp.vec3(weight[0] * wp.exp(-sigma[0] * distance), weight[1] * wp.exp(-sigma[1] * distance),
                   weight[2] * wp.exp(-sigma[2] * distance))


@wp.func
def beer_forever(weight: wp.vec3, sigma: wp.vec3) -> wp.vec3:
    """Beer's law for a ray that leaves the scene inside the medium: exp(-sigma * infinity), 0 in
    every channel that absorbs at all."""
    return wp.vec3(wp.where(sigma[0] > 0.0, 0.0, weight[0]), wp.where(sigma[1] > 0.0, 0.0, weight[1]),
                   wp.where(sigma[2] > 0.0, 0.0, weight[2]))


@wp.func
def absorbed(s: SceneData, weight: wp.vec3, medium: int, start: wp.vec3, hit: Surface) -> wp.vec3:
    """The weight of a ray that went from start to the hit through medium (-1: air, which absorbs nothing)."""
    if medium >= 0:
        weight = beer(weight, s.absorption[medium], wp.length(hit.p - start))
    return weight


@wp.func
def absorbed_forever(s: SceneData, weight: wp.vec3, medium: int) -> wp.vec3:
    """The weight of a ray that leaves through medium (-1: air) and meets nothing: Beer's law to infinity."""
    if medium >= 0:
        weight = beer_forever(weight, s.absorption[medium])
    return weight
