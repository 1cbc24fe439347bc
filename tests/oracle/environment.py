"""Light from a constant environment (radiance L from every direction at infinity) at a point, closed forms
in float64: E = pi L over the whole hemisphere, less what a blocker's form factor takes."""

from __future__ import annotations

import math

from .area import disk_on_axis_irradiance


def sky_irradiance(L: float) -> float:
    """An unoccluded surface under a constant sky: E = integral of L cos over the hemisphere = pi L."""
    return math.pi * L


def sky_irradiance_under_a_disk(L: float, r: float, d: float) -> float:
    """A point under a black disk of radius r at height d on its axis: pi L less the disk's share,
    pi L r^2 / (r^2 + d^2) (Howell B-13), so pi L d^2 / (r^2 + d^2)."""
    return sky_irradiance(L) - disk_on_axis_irradiance(L, r, d)


def linear_sky_irradiance(c: float, b, n) -> float:
    """An unoccluded surface of unit normal n under a sky whose radiance is linear in the direction,
    L(d) = c + b.d (|b| <= c): the hemisphere's integral of cos is pi and of d cos is (2 pi / 3) n, so
    E = pi c + (2 pi / 3) b.n."""
    return math.pi * c + 2.0 * math.pi / 3.0 * sum(float(x) * float(y) for x, y in zip(b, n))
