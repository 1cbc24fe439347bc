"""Irradiance from Lambertian (constant radiance) area emitters at a point, closed forms in float64
(Howell's catalog of configuration factors): E = pi L F, F the point's form factor to the emitter."""

from __future__ import annotations

import math


def disk_on_axis_irradiance(L: float, r: float, d: float) -> float:
    """A disk of radius r and radiance L, facing a point on its axis at distance d, the point facing it:
    E = L pi r^2 / (r^2 + d^2) (Howell B-13: F = r^2 / (r^2 + d^2))."""
    return L * math.pi * r * r / (r * r + d * d)


def disk_on_axis_without_emitter_cosine(L: float, r: float, d: float) -> float:
    """The negative control: the integral of L cos / rho^2 dA over the same disk, the cosine at the
    emitter left out: 2 pi L (1 - d / sqrt(r^2 + d^2))."""
    return 2.0 * math.pi * L * (1.0 - d / math.sqrt(r * r + d * d))


def corner_rectangle_form_factor(a: float, b: float, c: float) -> float:
    """A differential area facing a parallel a x b rectangle at distance c, one of its corners on the
    area's normal (Howell B-3): F = 1/(2 pi) [A/sqrt(1+A^2) atan(B/sqrt(1+A^2)) + B/sqrt(1+B^2) atan(A/sqrt(1+B^2))],
    A = a / c, B = b / c."""
    A, B = a / c, b / c
    sa, sb = math.sqrt(1.0 + A * A), math.sqrt(1.0 + B * B)
    return (A / sa * math.atan(B / sa) + B / sb * math.atan(A / sb)) / (2.0 * math.pi)


def corner_rectangle_irradiance(L: float, a: float, b: float, c: float) -> float:
    return math.pi * L * corner_rectangle_form_factor(a, b, c)


def corner_rectangle_without_emitter_cosine(L: float, a: float, b: float, c: float) -> float:
    """The negative control: the integral of L cos / rho^2 dA over the same rectangle without the cosine at
    the emitter, which is L times the solid angle the rectangle subtends: L atan(a b / (c sqrt(a^2 + b^2 + c^2)))."""
    return L * math.atan(a * b / (c * math.sqrt(a * a + b * b + c * c)))


def cylinder_below_irradiance(L: float, r: float, length: float, h: float, n_phi: int = 2048,
                              n_s: int = 2048) -> float:
    """An open cylinder of radius r and length `length`, emitting L outwards from its side, its axis at
    height h above a point facing it (the point's normal through the axis, perpendicular to it, below its
    middle): E = integral of L cos cos' / rho^2 dA over the side's points that face the point (a convex
    surface: those are the ones it sees), by the midpoint rule in phi around the axis and in
    alpha = atan(s / h) along it (ds = h / cos^2 alpha). Numerical: its own check is the infinite
    cylinder's closed form pi L r / h (Howell: F = r / h)."""
    import numpy as np

    phi = (np.arange(n_phi) + 0.5) * (2.0 * math.pi / n_phi)
    top = math.atan(0.5 * length / h)
    alpha = (np.arange(n_s) + 0.5) * (2.0 * top / n_s) - top
    s = h * np.tan(alpha)
    ds = h / np.cos(alpha) ** 2 * (2.0 * top / n_s)
    # The point at the origin, normal +y; the side at (s, h + r cos phi, r sin phi), normal (0, cos phi, sin phi).
    cp, sp = np.cos(phi)[:, None], np.sin(phi)[:, None]
    height = h + r * cp
    rho2 = s[None, :] ** 2 + height ** 2 + (r * sp) ** 2
    cos_point = height / np.sqrt(rho2)
    cos_emitter = np.maximum(-(h * cp + r), 0.0) / np.sqrt(rho2)
    return float(L * (cos_point * cos_emitter / rho2 * ds[None, :]).sum() * r * (2.0 * math.pi / n_phi))
