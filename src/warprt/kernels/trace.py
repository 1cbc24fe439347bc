"""The Whitted tracer: one Warp kernel per effect set, launched over bands of pixels.

Per pixel and sample: a camera ray, its nearest hit (wp.mesh_query_ray, or with hybrid rendering the
rasterizer's certain answer), local Phong shading with shadow rays, then an iterative mirror bounce
weighted by k_r, up to max_depth ray levels. With refraction, Whitted's full ray tree: at a
dielectric both the reflected and the refracted ray, depth first, one of them kept on a small stack.
"""

import functools  # no "from __future__ import annotations": the ray stack's types are a factory's locals

from .._warp import wp
from ..errors import SceneError
from ..geometry import SceneData
from .aov import AovBuffers, make_record_first_hit
from .camera import CameraData, camera_ray, sample_offset
from .dielectric import absorbed, absorbed_forever, dielectric_children
from .environment import environment_radiance
from .hybrid import uncertain
from .interaction import Ray, Surface, hit_point_error, make_surface, mirror_ray, offset_ray_origin, spawn_ray
from .mirror import FROM_CAMERA, NO_CHAIN, Mirrors, mirror_chain, mirror_hit
from .raster import Fragments
from .record import (NO_PARENT, GradRecord, Reaches, dielectric_reaches, make_follows_mirror, make_record_hit,
                     make_record_stack, mirror_reach)
from .shading import emitted, emitter_met, make_shade
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


@wp.struct
class TreeRay:
    """A ray of the tree and what it carries: its weight, where its segment began (the eye or its
    parent's hit point, not offset: Beer's law measures from there), its level, its medium (-1: air),
    and with planar mirrors the chain of them it bounced off and the face it leaves."""

    ray: Ray
    weight: wp.vec3
    start: wp.vec3
    depth: int
    medium: int
    chain: int
    src: int


@wp.struct
class Hit:
    """A ray's nearest hit, whichever way it was found: face (-1: none), Warp's barycentrics, and the
    face normal as wp.mesh_query_ray reports it."""

    face: int
    u: float
    v: float
    normal: wp.vec3


@wp.func
def culled(s: SceneData, f: int, d: wp.vec3) -> bool:
    """Whether a ray along d passes through face f: its material is single-sided and d leaves the side
    its winding's normal points to (glTF's back-face culling; Mitsuba's si.n is that normal too)."""
    if s.cull[s.tri_material[f]] == 0:
        return False
    p0, p1, p2 = triangle(s, f)
    return wp.dot(d, unit_normal(p0, p1, p2)) > 0.0


@wp.func
def past(s: SceneData, f: int, u: float, v: float, d: wp.vec3) -> wp.vec3:
    """The origin that continues a ray along d beyond its hit on face f at (u, v): spawned off the hit
    point past its error bound, as pbrt's SkipIntersection and Mitsuba's si.spawn_ray do."""
    p0, p1, p2 = triangle(s, f)
    w = 1.0 - u - v
    return offset_ray_origin(p0 * u + p1 * v + p2 * w, hit_point_error(p0, p1, p2, u, v, w), unit_normal(p0, p1, p2), d)


@functools.cache
def make_first_hit(raster: bool, mirrors: bool, cull: bool = False):
    """The nearest hit of a ray: with ``raster``, a camera ray's from the Z-buffer where that is certain
    to be the query's (hybrid.uncertain); with ``mirrors``, a reflection ray's from its chain's virtual
    camera where certain (kernels/mirror.py); every other ray's from the BVH. The same record to the bit.
    With ``cull``, the BVH's answer skips the back faces of single-sided materials; neither shortcut
    knows sidedness, so the renderer never asks for them then."""
    if cull and (raster or mirrors):
        raise ValueError("back-face culling is traced: no Z-buffer or virtual-camera first hits with it")

    @wp.func
    def first_hit(s: SceneData, frags: Fragments, mir: Mirrors, r: TreeRay, i: int, n_s: int, x: int, row: int,
                  sample: int) -> Hit:
        ray = r.ray
        out = Hit()
        out.face = -1
        found = False
        if wp.static(raster):
            if r.depth == 0 and not uncertain(frags.inv_depth[n_s], frags.rival_inv_depth[n_s]):
                f = frags.face[n_s]
                found = f < 0  # a certain miss
                if f >= 0:
                    p0, p1, p2 = triangle(s, f)
                    h = woop_hit(ray.o, ray.d, p0, p1, p2)
                    if h[0] >= 0.0:  # else never seen: a certain sample is well inside its triangle
                        found = True
                        out = Hit(f, h[1], h[2], query_normal(p0, p1, p2))
        if wp.static(mirrors):
            if r.depth > 0:
                mh = mirror_hit(s, mir, r.depth, ray.o, ray.d, r.chain, x, row, sample, r.src)
                if mh.found:
                    found = True
                    out = Hit(mh.face, mh.u, mh.v, wp.vec3(0.0))
                    if mh.face >= 0:
                        p0, p1, p2 = triangle(s, mh.face)
                        out.normal = query_normal(p0, p1, p2)
                    mir.decided[i] = mir.decided[i] + 1
        if not found:
            q = wp.mesh_query_ray(s.mesh, ray.o, ray.d, 1.0e30)
            if wp.static(cull):
                while q.result and culled(s, q.face, ray.d):  # on through it, to the next surface
                    q = wp.mesh_query_ray(s.mesh, past(s, q.face, q.u, q.v, ray.d), ray.d, 1.0e30)
            if q.result:
                out = Hit(q.face, q.u, q.v, q.normal)
        return out

    return first_hit


@functools.cache
def make_ray_stack(size: int):
    """The rays of the tree waiting to be traced, ``size`` at most, in registers and local memory:
    RayRows, a matrix whose row j is waiting ray j, and the functions that make a ray a row and a row
    a ray again. The kernel writes a row in place (``stack[top] = waiting(r)``) because Warp passes
    structs and matrices to a function by value: a push returning the stack would copy all of it in and
    out, and again at every branch that might have pushed (benchmarks/ATTEMPTS.md, "The kernel at its floor").
    A row holds the ray's integers too, as floats: a level and a medium index are exact in float32."""
    RayRows = wp.types.matrix(shape=(size, 14), dtype=float)
    Row = wp.types.vector(length=14, dtype=float)

    @wp.func
    def waiting(r: TreeRay) -> Row:
        o, d, w, p = r.ray.o, r.ray.d, r.weight, r.start
        return Row(o[0], o[1], o[2], d[0], d[1], d[2], w[0], w[1], w[2], p[0], p[1], p[2], float(r.depth),
                   float(r.medium))

    @wp.func
    def resumed(row: Row) -> TreeRay:
        return TreeRay(Ray(wp.vec3(row[0], row[1], row[2]), wp.vec3(row[3], row[4], row[5])),
                       wp.vec3(row[6], row[7], row[8]), wp.vec3(row[9], row[10], row[11]), int(row[12]),
                       int(row[13]), NO_CHAIN, -1)

    return RayRows, waiting, resumed


@functools.cache
def make_next_chain(MIRRORS: bool):
    """next_chain(mir, chain, face): the chain of planar mirrors a mirror ray leaving ``face`` bounces along
    (kernels/mirror.py), with MIRRORS (the virtual cameras' shortcut); else NO_CHAIN."""

    @wp.func(inline=True)
    def next_chain(mir: Mirrors, chain: int, face: int) -> int:
        if wp.static(MIRRORS):
            return mirror_chain(mir, chain, face)
        return int(NO_CHAIN)

    return next_chain


@functools.cache
def make_escaped(ABSORPTION: bool, ENVIRONMENT: bool = False):
    """escaped(s, weight, medium, d): the colour a ray along d that meets nothing adds: its weight (with
    ABSORPTION, through its medium to infinity: absorbed_forever) times the background, or with ENVIRONMENT
    times the environment's radiance along d."""

    @wp.func(inline=True)
    def escaped(s: SceneData, weight: wp.vec3, medium: int, d: wp.vec3) -> wp.vec3:
        w = weight
        if wp.static(ABSORPTION):
            w = absorbed_forever(s, weight, medium)
        if wp.static(ENVIRONMENT):
            return wp.cw_mul(w, environment_radiance(s.env, d))
        return wp.cw_mul(w, s.background)

    return escaped


@functools.cache
def make_children(TREE: bool):
    """children(s, f, hit, d, weight, reach, eta) -> (Children, Reaches): a dielectric hit's reflected and
    refracted rays (dielectric_children); with TREE (glass's record) also those it leaves out for carrying
    nothing that the derivative follows, by their reach (record.dielectric_reaches), which is then theirs."""

    @wp.func(inline=True)
    def children(s: SceneData, f: int, hit: Surface, d: wp.vec3, weight: wp.vec3, reach: wp.vec3, eta: float):
        ch = dielectric_children(s, f, hit, d, weight, eta)
        kids = Reaches()
        if wp.static(TREE):
            kids = dielectric_reaches(s, hit, reach, ch.F)
            ch.has_r = ch.has_r or wp.max(kids.r) > 0.0
            ch.has_t = ch.has_t or wp.max(kids.t) > 0.0
        return ch, kids

    return children


@functools.cache
def make_local(fx, shadow_grid: bool, aovs: tuple, record: bool):
    """local(s, aov, rec, j, r, h, hit, pixel, sample, color) -> (color, shadow rays): what a ray ``r`` sees at
    its hit ``h`` (its hit record ``hit``), added to ``color``: with the AOVs a camera ray's first hit recorded,
    an area light's own emitting surface (emitted) and the local shading with its shadow rays (make_shade),
    each times the ray's weight; with ``record``, what the hit sees written at entry j."""
    shade = make_shade(fx, shadow_grid, record)
    record_first_hit = make_record_first_hit(tuple(aovs), fx.texture, fx.vertex_color)
    AOVS, AREA, RECORD = bool(aovs), fx.area_lights, record

    @wp.func(inline=True)
    def local(s: SceneData, aov: AovBuffers, rec: GradRecord, j: int, r: TreeRay, h: Hit, hit: Surface, pixel: int,
              sample: int, color: wp.vec3):
        if wp.static(AOVS):
            if r.depth == 0:
                record_first_hit(aov, s, pixel, sample, h.face, h.u, h.v, hit, r.ray.o)
        # ---- emitted: an area light's own surface ----
        if wp.static(AREA):
            if wp.static(RECORD):
                rec.emit[j] = emitter_met(s, h.face, r.ray.d)
            color = color + wp.cw_mul(r.weight, emitted(s, h.face, r.ray.d))
        # ---- local shading ----
        lit = shade(s, hit, -r.ray.d, rec, j, sample)  # the sample: its share of the area lights' points (spread)
        return color + wp.cw_mul(r.weight, lit.color), lit.shadow_rays

    return local


@functools.cache
def make_path(fx, raster_primary: bool, stack: int, report_truncated: bool, aovs: tuple, shadow_grid: bool,
              mirrors: bool, record: bool = False):
    """The walk of one camera ray's tree, make_trace_kernel's inner loop: ``path(s, frags, mir, aov, rec, r,
    max_depth, i, pixel, samples, sample, x, row, truncated, rays)`` follows ``r`` (the camera ray) and
    the rays it spawns to max_depth levels and returns (its colour, ``truncated`` plus the weight it cut
    off, ``rays`` plus the rays it cast). ``truncated`` and ``rays`` go in and out, not a sum per sample,
    so the kernel adds them in the order a single loop does: the image is the same to the bit. With
    ``record``, each ray's entry (its hit, where it came from, the lights and area-light points it sees, the
    emitter it meets) is written into ``rec`` as it is found (kernels/record.py), and the rays the image
    does not need but its derivative does are followed too, with weight 0 (the image the same): the mirror
    rays of the materials ``rec.mirrored`` flags, and with glass the children a transmittance of 0 leaves
    out (followed by their reach: the weight with such transmittances taken as 1). Inlined into the kernel:
    Warp passes structs by value, and the walk's five would be copied once a sample (1.2x the atrium's warm
    frame, issue 37)."""
    local = make_local(fx, shadow_grid, tuple(aovs), record)
    surface = make_surface(fx.smooth, fx.texture, fx.vertex_color)
    MIRRORS = fx.reflection and mirrors
    first_hit = make_first_hit(raster_primary, MIRRORS, fx.culling)
    REFLECTION, REFRACTION, ABSORPTION, TRUNCATED = fx.reflection, fx.refraction, fx.absorption, report_truncated
    RECORD, TREE = record, record and fx.refraction
    RayRows, waiting, resumed = make_ray_stack(max(stack, 1))
    ParentRows, ReachRows = make_record_stack(max(stack, 1))
    follows_mirror = make_follows_mirror(RECORD)
    record_hit = make_record_hit(TREE)
    children = make_children(TREE)
    escaped = make_escaped(ABSORPTION, fx.environment)
    next_chain = make_next_chain(MIRRORS)
    COUNTS_T = wp.vec4i if REFRACTION else wp.vec3i

    @wp.func(inline=True)
    def path(s: SceneData, frags: Fragments, mir: Mirrors, aov: AovBuffers, rec: GradRecord, camera: TreeRay,
             max_depth: int, i: int, pixel: int, samples: int, sample: int, x: int, row: int, truncated_in: wp.vec3,
             rays_in: COUNTS_T):
        r = camera
        truncated = truncated_in
        rays = rays_in
        color = wp.vec3(0.0)
        top = int(0)  # rays waiting on the stack
        j, parent = int(0), int(NO_PARENT)  # with the record: this ray's entry, its parent's (2 entry + branch)
        if wp.static(REFRACTION):
            stack = RayRows()
        reach = wp.vec3(1.0)  # with glass's record: this ray's weight with a transmittance of 0 taken as 1
        if wp.static(TREE):
            parents, reaches = ParentRows(), ReachRows()  # the waiting rays'
        while r.depth < max_depth:
            # ---- nearest hit ----
            h = first_hit(s, frags, mir, r, i, pixel * samples + sample, x, row, sample)
            if wp.static(RECORD):
                j = record_hit(rec, r.depth, pixel * samples + sample, parent, r.medium, h.face, h.u, h.v)
            if h.face < 0:
                color = color + escaped(s, r.weight, r.medium, r.ray.d)
            else:
                hit = surface(s, h.face, h.u, h.v, h.normal, r.ray.d)
                if wp.static(ABSORPTION):
                    r.weight = absorbed(s, r.weight, r.medium, r.start, hit)
                    if wp.static(TREE):
                        reach = absorbed(s, reach, r.medium, r.start, hit)
                color, shadow_rays = local(s, aov, rec, j, r, h, hit, pixel, sample, color)
                rays[1] += shadow_rays
                level = r.depth + 1  # the children's
                # ---- mirror ----
                if wp.static(REFLECTION):
                    kr = s.kr[hit.material]
                    if level < max_depth and follows_mirror(kr, rec, hit.material):
                        # a mirror's ray stays in the medium it came through
                        r = TreeRay(mirror_ray(hit, r.ray.d), wp.cw_mul(r.weight, kr), hit.p, level, r.medium,
                                    next_chain(mir, r.chain, h.face), h.face)
                        parent = 2 * j
                        if wp.static(TREE):
                            reach = mirror_reach(reach, kr)
                        rays[2] += 1
                        continue
                    if wp.static(TRUNCATED):
                        if level >= max_depth:
                            truncated = truncated + wp.cw_mul(r.weight, kr)
                # ---- dielectric ----
                if wp.static(REFRACTION):
                    eta = s.ior[hit.material]
                    if eta > 0.0 and (level < max_depth or wp.static(TRUNCATED)):  # traced, or counted
                        ch, kids = children(s, h.face, hit, r.ray.d, r.weight, reach, eta)
                        if level < max_depth and (ch.has_r or ch.has_t):
                            r = TreeRay(spawn_ray(hit, ch.d_r), ch.w_r, hit.p, level, ch.medium_r, NO_CHAIN, -1)
                            parent = 2 * j
                            if ch.has_t:  # else total internal reflection, or nothing transmitted
                                if ch.has_r:  # the reflected ray waits, the refracted one goes on
                                    stack[top] = waiting(r)
                                    if wp.static(TREE):
                                        parents[top] = parent
                                        reaches[top] = kids.r
                                    top += 1
                                r = TreeRay(spawn_ray(hit, ch.d_t), ch.w_t, hit.p, level, ch.medium_t, NO_CHAIN, -1)
                                parent = 2 * j + 1
                            reach = wp.where(ch.has_t, kids.t, kids.r)  # read by glass's record alone
                            rays[2] += wp.where(ch.has_r, 1, 0)
                            rays[3] += wp.where(ch.has_t, 1, 0)
                            continue
                        if wp.static(TRUNCATED):
                            if level >= max_depth:  # a child that carries nothing has weight +0
                                truncated = truncated + ch.w_r + ch.w_t
            # ---- next ray ----
            if wp.static(REFRACTION):
                if top > 0:  # this path has ended: the next waiting ray of the tree
                    top -= 1
                    r = resumed(stack[top])
                    if wp.static(TREE):
                        parent, reach = parents[top], reaches[top]
                    continue
            break
        return color, truncated, rays

    return path


@wp.func(inline=True)  # inlined: Warp passes the structs by value (make_path's note)
def camera_tree_ray(s: SceneData, c: CameraData, x: int, row: int, offset: wp.vec2) -> TreeRay:
    """The camera ray through ``offset`` of pixel (x, row) as the walk takes it (make_path): weight 1, at level 0, in
    the eye's medium, from the camera: the trace kernel's and the pixel-list kernel's (make_pixels_kernel) alike."""
    return TreeRay(Ray(c.eye, camera_ray(c, x, row, offset[0], offset[1])), wp.vec3(1.0), c.eye, 0, s.eye_medium,
                   FROM_CAMERA, -1)


@functools.cache
def make_trace_kernel(fx, raster_primary: bool = False, stack: int = 0, report_truncated: bool = False,
                      aovs: tuple = (), shadow_grid: bool = False, mirrors: bool = False, record: bool = False):
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
    hit is also recorded into the AOV buffers; without, that code is absent. With fx.culling, camera,
    reflection and refraction rays pass through single-sided materials' back faces (shadow rays do not).
    With ``record``, a grad=True frame's: what its derivative holds fixed is written into ``rec`` as the
    rays are traced (make_path); without, ``rec`` is a stand-in never read (kernels/record.py)."""
    if fx.refraction and stack < 1:
        raise ValueError("a kernel with refraction needs a stack: stack_size(max_depth)")
    path = make_path(fx, raster_primary, stack, report_truncated, tuple(aovs), shadow_grid, mirrors, record)
    SUPERSAMPLING, TRUNCATED = fx.supersampling, report_truncated
    COUNTS = wp.vec4i if fx.refraction else wp.vec3i

    @wp.kernel(module="unique", enable_backward=False)
    def trace(s: SceneData, c: CameraData, max_depth: int, k: int, first: int, tile_w: int, tile_h: int,
              frags: Fragments, mir: Mirrors, aov: AovBuffers, rec: GradRecord, image: wp.array(dtype=wp.vec3),
              counts: wp.array(dtype=COUNTS)):
        i = first + wp.tid()  # position in tile order; the image itself is row-major
        xy = tile_order_pixel(i, c.width, c.height, tile_w, tile_h)
        x = xy[0]
        row = xy[1]
        pixel = row * c.width + x
        total = wp.vec3(0.0)
        truncated = wp.vec3(0.0)  # the weight cut off at max_depth (with report_truncated)
        rays = COUNTS()  # samples, shadow, reflection and (with refraction) refraction rays
        samples = int(1)
        if wp.static(SUPERSAMPLING):
            samples = k * k
        for sample in range(samples):
            offset = wp.vec2(0.5, 0.5)  # the pixel's centre, or with supersampling a k x k grid
            if wp.static(SUPERSAMPLING):
                offset = sample_offset(sample, k)
            color, truncated, rays = path(s, frags, mir, aov, rec, camera_tree_ray(s, c, x, row, offset), max_depth, i,
                                          pixel, samples, sample, x, row, truncated, rays)
            total = total + color
        image[pixel] = total / float(samples)
        if wp.static(TRUNCATED):
            image[c.width * c.height + pixel] = truncated / float(samples)
        rays[0] = samples
        counts[i] = rays  # in tile order: a band's counts are contiguous

    return trace


@functools.cache
def make_pixels_kernel(fx, stack: int = 0, shadow_grid: bool = False):
    """make_trace_kernel's image at k x k samples a pixel over a list of pixels (image/adaptive.py: those Whitted's
    adaptive supersampling refines), each ray traced (no Z-buffer, no virtual camera: the shortcuts give the same
    bits): the colour of ``pixels[first + tid]`` at ``image[first + tid]``, the trace kernel's for that pixel at
    that spp to the bit, its ray counts at ``counts[first + tid]``."""
    if fx.refraction and stack < 1:
        raise ValueError("a kernel with refraction needs a stack: stack_size(max_depth)")
    path = make_path(fx, False, stack, False, (), shadow_grid, False, False)
    COUNTS = wp.vec4i if fx.refraction else wp.vec3i

    @wp.kernel(module="unique", enable_backward=False)
    def trace_pixels(s: SceneData, c: CameraData, max_depth: int, k: int, first: int, pixels: wp.array(dtype=int),
                     frags: Fragments, mir: Mirrors, aov: AovBuffers, rec: GradRecord, image: wp.array(dtype=wp.vec3),
                     counts: wp.array(dtype=COUNTS)):
        i = first + wp.tid()
        pixel = pixels[i]
        x = pixel % c.width
        row = pixel / c.width
        total = wp.vec3(0.0)
        truncated = wp.vec3(0.0)
        rays = COUNTS()
        samples = k * k
        for sample in range(samples):
            offset = sample_offset(sample, k)
            color, truncated, rays = path(s, frags, mir, aov, rec, camera_tree_ray(s, c, x, row, offset), max_depth, i,
                                          pixel, samples, sample, x, row, truncated, rays)
            total = total + color
        image[i] = total / float(samples)
        rays[0] = samples
        counts[i] = rays

    return trace_pixels
