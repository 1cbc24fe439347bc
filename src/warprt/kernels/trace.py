"""The Whitted tracer: one Warp kernel per effect set, launched over bands of pixels.

Per pixel and sample: a camera ray, its nearest hit (wp.mesh_query_ray, or with hybrid rendering the
rasterizer's certain answer), local Phong shading with shadow rays, then an iterative mirror bounce
weighted by k_r, up to max_depth ray levels.
"""

from __future__ import annotations

import functools

from .._warp import wp
from ..geometry import SceneData
from .camera import CameraData, camera_ray, sample_offset
from .hybrid import uncertain
from .interaction import make_surface, offset_ray_origin, reflect
from .mirror import FROM_CAMERA, Mirrors, mirror_chain, mirror_hit
from .raster import Fragments
from .shading import make_shade
from .triangle import query_normal, triangle, woop_hit


@wp.func
def tile_order_pixel(i: int, width: int, height: int, tile_w: int, tile_h: int) -> wp.vec2i:
    """The (x, row) of the i-th pixel when the image is walked tile by tile: strips of tile_h rows
    top to bottom, each cut into tiles tile_w wide, left to right, row-major inside a tile; the
    right column and bottom strip of tiles may be narrower. Neighbouring rays then stay together
    in a band, so they walk the same BVH nodes while those are in cache."""
    strip = i / (width * tile_h)
    local = i - strip * width * tile_h
    th = wp.min(tile_h, height - strip * tile_h)
    col = local / (tile_w * th)
    within = local - col * tile_w * th
    tw = wp.min(tile_w, width - col * tile_w)
    return wp.vec2i(col * tile_w + within % tw, strip * tile_h + within / tw)


@functools.cache
def make_trace_kernel(fx, raster_primary: bool = False, shadow_grid: bool = False, mirrors: bool = False):
    """The kernel for one EffectSet; code for disabled effects is removed by wp.static. With
    raster_primary (hybrid rendering), a sample's first hit is the Z-buffer's visible triangle, tested
    with the ray query's own triangle test, wherever the rasterizer's answer is certain to be the
    tracer's (hybrid.uncertain); every other sample is traced. With shadow_grid, shadow rays are
    answered by the light-space grid in s.shadow_grid (kernels/shadow.py). With mirrors, a reflection
    ray's first hit comes from its planar mirrors' virtual camera where that is certain to be the
    query's (kernels/mirror.py). The image is the traced image, to the bit."""
    shade = make_shade(fx, shadow_grid)
    surface = make_surface(fx.smooth)
    REFLECTION, SUPERSAMPLING, RASTER = fx.reflection, fx.supersampling, raster_primary
    MIRRORS = fx.reflection and mirrors

    @wp.kernel(module="unique", enable_backward=False)
    def trace(s: SceneData, c: CameraData, max_depth: int, k: int, first: int, tile_w: int, tile_h: int,
              frags: Fragments, m: Mirrors, image: wp.array(dtype=wp.vec3), counts: wp.array(dtype=wp.vec3i)):
        i = first + wp.tid()  # position in tile order; the image itself is row-major
        xy = tile_order_pixel(i, c.width, c.height, tile_w, tile_h)
        x = xy[0]
        row = xy[1]
        pixel = row * c.width + x
        total = wp.vec3(0.0)
        shadow_rays = int(0)
        reflection_rays = int(0)
        samples = int(1)
        if wp.static(SUPERSAMPLING):
            samples = k * k
        for sample in range(samples):
            offset = wp.vec2(0.5, 0.5)
            if wp.static(SUPERSAMPLING):
                offset = sample_offset(sample, k)
            o = c.eye
            d = camera_ray(c, x, row, offset[0], offset[1])
            weight = wp.vec3(1.0)
            color = wp.vec3(0.0)
            depth = int(0)
            if wp.static(MIRRORS):
                src = int(-1)  # the face a reflection ray leaves
                chain = int(FROM_CAMERA)  # the planar mirrors it bounced off
            while depth < max_depth:
                f = int(-1)
                u = float(0.0)
                v = float(0.0)
                face_normal = wp.vec3(0.0)
                rasterized = False
                if wp.static(RASTER):
                    n_s = pixel * samples + sample
                    if depth == 0 and not uncertain(frags.inv_depth[n_s], frags.rival_inv_depth[n_s]):
                        rasterized = True
                        f = frags.face[n_s]
                        if f >= 0:
                            p0, p1, p2 = triangle(s, f)
                            h = woop_hit(o, d, p0, p1, p2)
                            if h[0] >= 0.0:
                                u = h[1]
                                v = h[2]
                                face_normal = query_normal(p0, p1, p2)
                            else:  # never seen: a certain sample is well inside its triangle
                                rasterized = False
                                f = -1
                if wp.static(MIRRORS):
                    if depth > 0:
                        mh = mirror_hit(s, m, depth, o, d, chain, x, row, sample, src)
                        if mh.found:
                            rasterized = True
                            f = mh.face
                            u = mh.u
                            v = mh.v
                            if f >= 0:
                                p0, p1, p2 = triangle(s, f)
                                face_normal = query_normal(p0, p1, p2)
                            m.decided[i] = m.decided[i] + 1
                if not rasterized:
                    q = wp.mesh_query_ray(s.mesh, o, d, 1.0e30)
                    if q.result:
                        f = q.face
                        u = q.u
                        v = q.v
                        face_normal = q.normal
                if f < 0:
                    color = color + wp.cw_mul(weight, s.background)
                    break
                hit = surface(s, f, u, v, face_normal, d)
                r = shade(s, hit.material, hit.p, hit.err, hit.ng, hit.n, -d)
                color = color + wp.cw_mul(weight, r.color)
                shadow_rays += r.shadow_rays
                depth += 1
                if wp.static(REFLECTION):
                    kr = s.kr[hit.material]
                    if depth < max_depth and wp.max(kr) > 0.0:
                        weight = wp.cw_mul(weight, kr)
                        d = wp.normalize(reflect(d, hit.n))
                        o = offset_ray_origin(hit.p, hit.err, hit.ng, d)
                        reflection_rays += 1
                        if wp.static(MIRRORS):
                            chain = mirror_chain(m, chain, f)
                            src = f
                        continue
                break
            total = total + color
        image[pixel] = total / float(samples)
        counts[i] = wp.vec3i(samples, shadow_rays, reflection_rays)  # in tile order: a band's counts are contiguous

    return trace


@wp.kernel(enable_backward=False)
def primary_faces_kernel(s: SceneData, c: CameraData, k: int, samples: int, first_pixel: int,
                         face: wp.array(dtype=wp.int32)):
    """The face the trace kernel's first query hits at every sample (-1: a miss): the same camera ray,
    origin and max_t, without shading, so the comparison with the Z-buffer leaves the tracer as it is."""
    pixel = first_pixel + wp.tid()
    x = pixel % c.width
    row = pixel / c.width
    for sample in range(samples):
        offset = wp.vec2(0.5, 0.5)
        if samples > 1:
            offset = sample_offset(sample, k)
        q = wp.mesh_query_ray(s.mesh, c.eye, camera_ray(c, x, row, offset[0], offset[1]), 1.0e30)
        f = int(-1)
        if q.result:
            f = q.face
        face[pixel * samples + sample] = f
