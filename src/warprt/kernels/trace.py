"""The Whitted tracer: one Warp kernel per effect set, launched over bands of pixels.

Per pixel and sample: a camera ray, its nearest hit (wp.mesh_query_ray, or with hybrid rendering the
rasterizer's certain answer), local Phong shading with shadow rays, then an iterative mirror bounce
weighted by k_r, up to max_depth ray levels. With refraction, Whitted's full ray tree: at a
dielectric both the reflected and the refracted ray, depth first, one of them kept on a small stack.
"""

from __future__ import annotations

import functools

from .._warp import wp
from ..errors import SceneError
from ..geometry import SceneData
from .aov import AovBuffers, make_record_first_hit
from .camera import CameraData, camera_ray, sample_offset
from .dielectric import beer, beer_forever, fresnel_dielectric, refract
from .hybrid import uncertain
from .interaction import make_surface, offset_ray_origin, reflect
from .mirror import FROM_CAMERA, NO_CHAIN, Mirrors, mirror_chain, mirror_hit
from .raster import Fragments
from .shading import make_shade
from .triangle import query_normal, triangle, unit_normal, woop_hit

# The ray tree is walked depth first: at a dielectric hit one child waits on the stack while the
# other is followed. A waiting ray is always one level deeper than those below it, so max_depth
# levels need max_depth - 1 entries. The stack lives in registers and local memory, its size fixed
# at compile time: the smallest of these that holds the scene's levels (one variant each).
STACK_SIZES = (4, 8, 16, 32, 64)
MAX_TREE_DEPTH = STACK_SIZES[-1] + 1  # 2^64 paths per sample at most


def stack_size(max_depth: int, source: str = "render") -> int:
    """The stack a ray tree of max_depth levels needs, or a SceneError naming render.max_depth."""
    for size in STACK_SIZES:
        if max_depth - 1 <= size:
            return size
    raise SceneError(source, "render.max_depth", f"a scene with refraction traces at most {MAX_TREE_DEPTH} ray "
                                                 f"levels (up to 2^{MAX_TREE_DEPTH - 1} paths per sample), got {max_depth}")


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
def make_trace_kernel(fx, raster_primary: bool = False, stack: int = 0, report_truncated: bool = False,
                      aovs: tuple = (), shadow_grid: bool = False, mirrors: bool = False):
    """The kernel for one EffectSet; code for disabled effects is removed by wp.static. With
    raster_primary (hybrid rendering), a sample's first hit is the Z-buffer's visible triangle, tested
    with the ray query's own triangle test, wherever the rasterizer's answer is certain to be the
    tracer's (hybrid.uncertain); every other sample is traced. With shadow_grid, shadow rays are
    answered by the light-space grid in s.shadow_grid (kernels/shadow.py). With mirrors, a reflection
    ray's first hit comes from its planar mirrors' virtual camera where that is certain to be the
    query's (kernels/mirror.py); rays a dielectric spawns are traced. The image is the traced image,
    to the bit. With fx.refraction, ``stack`` is the ray tree's stack (stack_size(max_depth)) and
    counts hold refraction rays too (vec4i). With report_truncated, image holds twice width * height
    values: the radiance, then the weight of the paths cut off at max_depth (the energy the image is
    missing), both averaged over the samples. With ``aovs`` (names, aov.py), each camera ray's first
    hit is also recorded into the AOV buffers; without, that code is absent."""
    shade = make_shade(fx, shadow_grid)
    surface = make_surface(fx.smooth, fx.texture, fx.vertex_color)
    record_first_hit = make_record_first_hit(tuple(aovs), fx.texture, fx.vertex_color)
    REFLECTION, SUPERSAMPLING, RASTER, AOVS = fx.reflection, fx.supersampling, raster_primary, bool(aovs)
    REFRACTION, ABSORPTION, TRUNCATED = fx.refraction, fx.absorption, report_truncated
    MEDIUM = REFRACTION or ABSORPTION
    MIRRORS = fx.reflection and mirrors
    if REFRACTION and stack < 1:
        raise ValueError("a kernel with refraction needs a stack: stack_size(max_depth)")
    STACK = max(stack, 1)
    StackVec3 = wp.types.matrix(shape=(STACK, 3), dtype=float)
    StackInt = wp.types.vector(length=STACK, dtype=int)
    COUNTS = wp.vec4i if REFRACTION else wp.vec3i

    @wp.kernel(module="unique", enable_backward=False)
    def trace(s: SceneData, c: CameraData, max_depth: int, k: int, first: int, tile_w: int, tile_h: int,
              frags: Fragments, mir: Mirrors, aov: AovBuffers, image: wp.array(dtype=wp.vec3),
              counts: wp.array(dtype=COUNTS)):
        i = first + wp.tid()  # position in tile order; the image itself is row-major
        xy = tile_order_pixel(i, c.width, c.height, tile_w, tile_h)
        x = xy[0]
        row = xy[1]
        pixel = row * c.width + x
        total = wp.vec3(0.0)
        shadow_rays = int(0)
        reflection_rays = int(0)
        if wp.static(REFRACTION):
            refraction_rays = int(0)
        if wp.static(TRUNCATED):
            truncated = wp.vec3(0.0)
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
            if wp.static(MEDIUM):
                medium = s.eye_medium  # the dielectric material the ray travels in, -1: air
                start = o  # where its segment began: the eye, or its parent's hit point (not offset)
            if wp.static(REFRACTION):
                # The rays waiting to be traced: origin, direction, weight, segment start, level, medium.
                top = int(0)
                stack_o = StackVec3()
                stack_d = StackVec3()
                stack_w = StackVec3()
                stack_start = StackVec3()
                stack_depth = StackInt()
                stack_medium = StackInt()
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
                        mh = mirror_hit(s, mir, depth, o, d, chain, x, row, sample, src)
                        if mh.found:
                            rasterized = True
                            f = mh.face
                            u = mh.u
                            v = mh.v
                            if f >= 0:
                                p0, p1, p2 = triangle(s, f)
                                face_normal = query_normal(p0, p1, p2)
                            mir.decided[i] = mir.decided[i] + 1
                if not rasterized:
                    q = wp.mesh_query_ray(s.mesh, o, d, 1.0e30)
                    if q.result:
                        f = q.face
                        u = q.u
                        v = q.v
                        face_normal = q.normal
                if f < 0:
                    if wp.static(ABSORPTION):
                        if medium >= 0:
                            weight = beer_forever(weight, s.absorption[medium])
                    color = color + wp.cw_mul(weight, s.background)
                    if wp.static(REFRACTION):
                        if top > 0:  # the next waiting ray of the tree
                            top -= 1
                            o = stack_o[top]
                            d = stack_d[top]
                            weight = stack_w[top]
                            start = stack_start[top]
                            depth = stack_depth[top]
                            medium = stack_medium[top]
                            if wp.static(MIRRORS):
                                chain = int(NO_CHAIN)
                            continue
                    break
                hit = surface(s, f, u, v, face_normal, d)
                if wp.static(ABSORPTION):
                    if medium >= 0:
                        weight = beer(weight, s.absorption[medium], wp.length(hit.p - start))
                if wp.static(AOVS):
                    if depth == 0:
                        record_first_hit(aov, s, pixel, sample, f, u, v, hit, o)
                r = shade(s, hit, -d)
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
                        if wp.static(MEDIUM):
                            start = hit.p  # a mirror's ray stays in the medium it came through
                        if wp.static(MIRRORS):
                            chain = mirror_chain(mir, chain, f)
                            src = f
                        continue
                    if wp.static(TRUNCATED):
                        if depth >= max_depth:
                            truncated = truncated + wp.cw_mul(weight, kr)
                if wp.static(REFRACTION):
                    eta = s.ior[hit.material]
                    if eta > 0.0:
                        # hit.ng faces the ray; the ray enters where that is the winding's outward normal.
                        p0, p1, p2 = triangle(s, f)
                        entering = wp.dot(hit.ng, unit_normal(p0, p1, p2)) > 0.0
                        outward = hit.ng
                        eta_rel = eta
                        if not entering:
                            outward = -hit.ng
                            eta_rel = 1.0 / eta
                        # Fresnel and Snell about the shading normal on the ray's side, or the geometric
                        # one where the shading normal is tilted past the ray.
                        m = hit.n
                        if wp.dot(m, hit.ng) < 0.0:
                            m = -m
                        if not (wp.dot(d, m) * wp.dot(d, hit.ng) > 0.0):
                            m = hit.ng
                        cos_i = -wp.dot(d, m)
                        F = fresnel_dielectric(wp.where(entering, cos_i, -cos_i), eta)
                        t, transmits = refract(d, m, eta_rel)
                        w_r = weight * F
                        w_t = wp.cw_mul(weight, s.transmittance[hit.material]) * (1.0 - F)
                        has_r = wp.max(w_r) > 0.0
                        has_t = transmits and wp.max(w_t) > 0.0
                        if depth < max_depth:
                            d_r = wp.normalize(reflect(d, m))
                            # A child is inside the glass where it leaves against the outward normal.
                            medium_r = wp.where(wp.dot(d_r, outward) < 0.0, hit.material, -1)
                            if has_r and has_t:  # the reflected ray waits, the refracted one goes on
                                stack_o[top] = offset_ray_origin(hit.p, hit.err, hit.ng, d_r)
                                stack_d[top] = d_r
                                stack_w[top] = w_r
                                stack_start[top] = hit.p
                                stack_depth[top] = depth
                                stack_medium[top] = medium_r
                                top += 1
                                reflection_rays += 1
                            if has_t:
                                d = wp.normalize(t)
                                o = offset_ray_origin(hit.p, hit.err, hit.ng, d)
                                weight = w_t
                                start = hit.p
                                medium = wp.where(wp.dot(d, outward) < 0.0, hit.material, -1)
                                refraction_rays += 1
                                if wp.static(MIRRORS):
                                    chain = int(NO_CHAIN)
                                continue
                            if has_r:  # total internal reflection, or nothing transmitted
                                d = d_r
                                o = offset_ray_origin(hit.p, hit.err, hit.ng, d)
                                weight = w_r
                                start = hit.p
                                medium = medium_r
                                reflection_rays += 1
                                if wp.static(MIRRORS):
                                    chain = int(NO_CHAIN)
                                continue
                        else:
                            if wp.static(TRUNCATED):
                                if has_r:
                                    truncated = truncated + w_r
                                if has_t:
                                    truncated = truncated + w_t
                    if top > 0:  # this path has ended: the next waiting ray of the tree
                        top -= 1
                        o = stack_o[top]
                        d = stack_d[top]
                        weight = stack_w[top]
                        start = stack_start[top]
                        depth = stack_depth[top]
                        medium = stack_medium[top]
                        if wp.static(MIRRORS):
                            chain = int(NO_CHAIN)
                        continue
                break
            total = total + color
        image[pixel] = total / float(samples)
        if wp.static(TRUNCATED):
            image[c.width * c.height + pixel] = truncated / float(samples)
        if wp.static(REFRACTION):
            counts[i] = COUNTS(samples, shadow_rays, reflection_rays, refraction_rays)
        else:
            counts[i] = wp.vec3i(samples, shadow_rays, reflection_rays)  # in tile order: a band's counts are contiguous

    return trace
