"""The environment light's radiance in the kernels (compiled only for scenes with one: EffectSet.environment):
what a ray that meets nothing sees, Mitsuba's envmap eval (its local direction's latitude-longitude uv, bilinear
over the texels; scene/environment.py has the conventions). What its fixed directions add at a hit is shading's
(make_environment_light).
"""

from __future__ import annotations

from .._warp import wp
from ..geometry import Environment

INV_PI = 0.3183098861837907
INV_TWO_PI = 0.15915494309189535


@wp.func
def environment_radiance(e: Environment, d: wp.vec3) -> wp.vec3:
    """The radiance arriving along -d from the environment in direction d (unit, world)."""
    v = e.to_local * d
    u = wp.atan2(v[0], -v[2]) * INV_TWO_PI - 0.5 / float(e.width - 1)
    u = (u - wp.floor(u)) * float(e.width - 1)
    t = wp.acos(wp.clamp(v[1], -1.0, 1.0)) * INV_PI * float(e.height - 1)
    x = wp.min(int(u), e.width - 2)
    y = wp.min(int(t), e.height - 2)
    fx = u - float(x)
    fy = t - float(y)
    i = y * e.width + x
    top = e.texels[i] * (1.0 - fx) + e.texels[i + 1] * fx
    bottom = e.texels[i + e.width] * (1.0 - fx) + e.texels[i + e.width + 1] * fx
    return top * (1.0 - fy) + bottom * fy
