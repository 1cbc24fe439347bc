"""The Z-buffer's shading pass: per pixel, the tracer's own hit record and local shading at each
sample's visible point (the rasterizer's Fragments), box-filtered. No shadows, no reflections. An area
light's own surface shows its radiance, and an environment light is the background, as the tracer's camera
rays see them."""

from __future__ import annotations

import functools

from .._warp import wp
from ..geometry import SceneData
from .camera import CameraData, camera_ray, sample_offset
from .environment import environment_radiance
from .interaction import make_surface
from .raster import Fragments
from .record import GradRecord
from .shading import emitted, make_shade
from .triangle import query_normal, triangle


@functools.cache
def make_shade_kernel(fx):
    """The shading kernel for one EffectSet (shadows and reflection are ignored: a Z-buffer has neither)."""
    shade = make_shade(fx)
    surface = make_surface(fx.smooth, fx.texture, fx.vertex_color)
    SUPERSAMPLING, AREA, ENVIRONMENT = fx.supersampling, fx.area_lights, fx.environment

    @wp.kernel(module="unique", enable_backward=False)
    def shade_zbuffer(s: SceneData, c: CameraData, k: int, first_pixel: int, frags: Fragments,
                      image: wp.array(dtype=wp.vec3)):
        pixel = first_pixel + wp.tid()
        x = pixel % c.width
        row = pixel / c.width
        samples = int(1)
        if wp.static(SUPERSAMPLING):
            samples = k * k
        total = wp.vec3(0.0)
        for sample in range(samples):
            i = pixel * samples + sample
            f = frags.face[i]
            if wp.static(not ENVIRONMENT):
                if f < 0:
                    total = total + s.background
                    continue
            offset = wp.vec2(0.5, 0.5)
            if wp.static(SUPERSAMPLING):
                offset = sample_offset(sample, k)
            d = camera_ray(c, x, row, offset[0], offset[1])
            if wp.static(ENVIRONMENT):
                if f < 0:
                    total = total + environment_radiance(s.env, d)
                    continue
            p0, p1, p2 = triangle(s, f)
            # The normal Warp's ray query reports, so make_surface turns smooth normals to the same
            # side as in the tracer.
            uv = frags.uv[i]
            hit = surface(s, f, uv[0], uv[1], query_normal(p0, p1, p2), d)
            if wp.static(AREA):
                total = total + emitted(s, f, d)
            r = shade(s, hit, -d, GradRecord(), 0, sample)  # no record: a Z-buffer frame has no gradient
            total = total + r.color
        image[pixel] = total / float(samples)

    return shade_zbuffer
