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
