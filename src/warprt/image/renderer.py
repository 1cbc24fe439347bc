"""Render a Scene: the Whitted tracer (render) or the Z-buffer (render_zbuffer), each a few named
phases: geometry (BVH), kernel variant, rasterized first hits where the hybrid policy says so, the
bands of pixels, and what it cost (time per phase, exact ray counts, memory)."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np

from .._warp import init_warp, wp
from ..errors import SceneError
from ..geometry import Geometry, frame_origin, kept_shadow_grid, objects_center, shadow_grid
from ..kernels import (aov_buffers, aov_bytes, aov_sums, camera_data, empty_aov_buffers, make_shade_kernel,
                       make_trace_kernel, raster_kernel, stack_size)
from ..scene import EffectSet, ObjectCache, camera_basis, resolve_effects, validate_camera, validate_scene, zbuffer_effects
from .aovs import check_aovs, finish_aovs
from .launch import bands_of, launch_bands, launch_plan
from .memory import RASTER_BYTES_PER_SAMPLE, check_frame_memory, frame_estimate, frame_memory
from .mirrors import MirrorFrame, empty_mirrors
from .stats import RenderResult, RenderStats
from .zbuffer import RASTER_TILE, ZBuffer, empty_fragments, eye_on_surface

ALGORITHMS = ("raytrace", "zbuffer")
PRIMARY = ("auto", "raytrace", "zbuffer")
SHADOWS = ("auto", "bvh", "grid")
REFLECTIONS = ("auto", "bvh", "mirrors")


@dataclass
class Defaults:
    """render()'s defaults for what it is not told; the test suite sets them to run whole suites on
    every path (tests/conftest.py). ``origin_shift`` (tests only) builds each cached Geometry that
    fraction of the scene's reach away from its frame origin, so that camera rays start far from the
    coordinates' zero."""

    primary: str = "auto"
    shadows: str = "auto"
    reflections: str = "auto"
    origin_shift: float = 0.0


DEFAULTS = Defaults()

# Pixel order: bands walk the image in 8x8 tiles, so the rays of a band stay close together and
# reuse the BVH nodes in cache. Measured at 1024x768 against row-major order: 0.83 to 0.96 of the
# trace time on six of eight scenes, 1.01 and 1.03 on two (benchmarks/ATTEMPTS.md).
PIXEL_TILE = (8, 8)

# primary="auto" rasterizes only while those buffers stay under this: 19 million samples, 1920x1080
# at 9 spp. Tracing needs no per-sample memory, so a bigger frame (4K at 16 spp would need 3.7 GB)
# is traced rather than made to pay for its speed-up in memory.
AUTO_RASTER_MAX_BYTES = 512 * 2**20


def raster_is_cheaper(triangles: int, samples: int, device: str = "cpu") -> bool:
    """Whether rasterizing the primary hits beats tracing them. Rasterization costs about a fixed
    amount per triangle plus per covered sample, tracing about log(triangles) per sample; at
    1024x768 the Z-buffer found the first hits in 0.36-0.41x of the traced time with 5k-9k
    triangles and in 2.7x with 524k (benchmarks/ATTEMPTS.md). Below one triangle per ten samples
    the raster wins on every scene measured. Measured on the CPU only: on a GPU the primaries are
    traced. Within AUTO_RASTER_MAX_BYTES of buffers only."""
    return (device == "cpu" and 0 < triangles <= samples // 10
            and samples * RASTER_BYTES_PER_SAMPLE <= AUTO_RASTER_MAX_BYTES)


def primary_from_zbuffer(primary: str, geom: Geometry, basis, samples: int, device: str) -> bool:
    """The hybrid policy: whether the first hits come from the Z-buffer. "zbuffer" asks for it, "auto"
    where it is the cheaper; a camera on a surface is traced either way (the traced image is the promise)."""
    wanted = primary == "zbuffer" or (primary == "auto" and raster_is_cheaper(geom.triangle_count, samples, device))
    return wanted and not eye_on_surface(geom, basis)


# What the light-space grid costs and saves, measured on the scenes on a quiet 2-core machine (the
# research prototype, ../shared/research/exact-secondary-rays): a shadow ray's any-hit query about
# 200 ns of thread time, the grid's answer about 70 ns; a build about 10 ms per light plus 0.8 us per
# triangle and light (0.024 s for the default scene, 0.83 s for the 524k-triangle knot).
GRID_SAVES_PER_RAY = 130e-9
GRID_BUILD_PER_LIGHT = 10e-3
GRID_BUILD_PER_TRIANGLE_LIGHT = 780e-9
GRID_HORIZON = 20  # frames a second frame with the same lights is taken to promise


def shadows_from_grid(shadows: str, geom: Geometry, scene, fx, samples: int, threads: int, device: str) -> bool:
    """The shadow rays' policy: whether the light-space grid answers them. "grid" asks for it; "auto"
    takes it on the CPU where it is the cheaper: on a first frame when its build costs less than the
    frame's shadow rays save (about one per sample and light), and from the second frame with the same
    lights on when it costs less than GRID_HORIZON such frames save (it is kept with the geometry for
    the next frames, as the BVH is). Either way the image is the traced one, to the bit."""
    if not fx.shadows or geom.triangle_count == 0 or shadows == "bvh":
        return False
    if shadows == "grid":
        return True
    if device != "cpu":
        return False
    lights = geom.light_positions(scene)
    frames = geom.__dict__.setdefault("_frames_with_lights", {})
    if len(frames) >= 64:  # lights moving every frame: no set of them stays long enough to amortize
        frames.clear()
    key = lights.tobytes()
    frames[key] = frames.get(key, 0) + 1
    if kept_shadow_grid(geom, lights) is not None:
        return True
    build = (GRID_BUILD_PER_LIGHT + GRID_BUILD_PER_TRIANGLE_LIGHT * geom.triangle_count) * len(lights)
    per_frame = GRID_SAVES_PER_RAY * samples * len(lights) / threads
    return build <= per_frame * (GRID_HORIZON if frames[key] >= 2 else 1)


_geometries = ObjectCache(size=4)


def frame_geometry(scene, device: str = "cpu") -> tuple[Geometry, dict]:
    """The Geometry (triangles, normals, BVH) for a frame of ``scene``, and how it came: built, or
    reused from an earlier frame of the same objects, as Mitsuba reuses a loaded scene. Keyed by the
    objects alone (Scene.with_camera/with_render share them): another eye, lights or materials reuse
    it while the eye keeps the frame origin it was built with (bvh.frame_origin: the objects' centre,
    for any eye in the region its BVH's padding covers), so a frame's image is a fresh build's to the
    bit; the tables of lights and materials are the frame's own (Geometry.scene_data)."""
    key = (id(scene.objects), tuple(id(o.vertices) for o in scene.objects),
           tuple((o.material, o.smooth, id(o.normals), id(o.uv), id(o.colors)) for o in scene.objects), str(device),
           DEFAULTS.origin_shift)
    eye = scene.camera.eye
    found = _geometries.peek(key, scene.objects)
    if found is not None:
        if np.array_equal(found.origin_for(eye), found.planned_origin) and found.covers(eye):
            return found, {"bvh": "reused", "reason": geometry_reason(found, eye)}
        reason = f"the eye left the region the cached BVH covers ({geometry_reason(found, eye)})"
    else:
        reason = "no geometry was built for these objects"
    origin = None
    if DEFAULTS.origin_shift:
        origin = shifted_origin(scene, frame_origin(*objects_center(scene.objects), eye))
    geom = Geometry(scene, device=device, origin=origin)
    if not geom.covers(eye):  # a shifted origin too far for this eye
        geom = Geometry(scene, device=device)
    return _geometries.put(key, scene.objects, geom), {"bvh": "built", "reason": reason}


def shifted_origin(scene, origin):
    """Tests only (DEFAULTS.origin_shift = s): ``origin`` moved s R along a fixed slant (R: the largest
    coordinate of the scene relative to it), so that camera rays start far from the coordinates' zero."""
    origin = np.asarray(origin, np.float64)
    if not scene.objects:
        return origin
    reach = max(float(np.abs(o.vertices - origin).max(initial=0.0)) for o in scene.objects)
    slant = np.array([1.0, -0.75, 0.5])  # not along an axis: every coordinate moves
    return origin + DEFAULTS.origin_shift * reach * slant


def geometry_reason(geom: Geometry, eye) -> str:
    """Where ``eye`` lies in the region ``geom``'s BVH covers, in words for the stats."""
    moved = float(np.abs(np.asarray(eye, np.float64) - geom.origin).max())
    if moved == 0.0:
        return "eye at the BVH's origin (an eye beyond the region one built at the objects' centre covers)"
    share = moved / geom.eye_reach if geom.eye_reach > 0 else float("inf")
    return f"eye {moved:.4g} from the BVH's origin on its farthest axis, {share:.2f} of the {geom.eye_reach:.4g} its padding covers"


def cached_geometry(scene, device: str = "cpu") -> Geometry:
    """frame_geometry's Geometry."""
    return frame_geometry(scene, device)[0]


def check_finite(image: np.ndarray, what: str = "render"):
    """The renderer checks its own output: a NaN or Inf pixel is a bug, never an image."""
    bad = ~np.isfinite(image)
    if bad.any():
        rows, cols = np.nonzero(bad.any(-1))
        raise RuntimeError(f"{what} produced {len(rows)} non-finite pixels (first at row {rows[0]}, column {cols[0]})")


def _check_choice(value: str, choices, flag: str, what: str):
    if value not in choices:
        raise SceneError("command line", flag, f"unknown {what} '{value}'; expected one of: {', '.join(choices)}")


def render(scene, *, threads: int | None = None, device: str = "cpu", effects=None, disable=(),
           bands: int | None = None, geometry: Geometry | None = None, algorithm: str = "raytrace",
           progress=None, tile: tuple[int, int] | None = None, primary: str | None = None,
           report_truncated: bool = False, aovs=None, shadows: str | None = None,
           reflections: str | None = None) -> RenderResult:
    """Render ``scene`` with the Whitted tracer (or, algorithm="zbuffer", by rasterization with the same
    local shading). ``effects`` (names) limits the effect set, ``disable`` removes effects; neither
    can add one the scene has nothing for. ``primary`` says where the tracer's first hits come from:
    "raytrace"; "zbuffer" (hybrid rendering: the Z-buffer's visible triangle wherever it is certain
    to be the traced one, the other samples traced; the image is the traced image to the bit); or
    "auto", the default, which rasterizes where that is the cheaper of the two (raster_is_cheaper).
    ``shadows`` says what answers the shadow rays: "bvh" (Warp's any-hit query), "grid" (the exact
    light-space grid: the same answers), or "auto", the default, the grid where it is the cheaper.
    ``reflections`` says what answers the reflection rays: "bvh" (Warp's closest-hit query), "mirrors"
    (off planar mirrors, their virtual cameras' rasters wherever certain to give the query's answer,
    the rest traced), or "auto", the default, which traces them: measured on every scene here, the
    virtual cameras' rasters cost about what the queries they replace do (benchmarks/ATTEMPTS.md).
    With ``report_truncated``, stats.truncated is the weight per pixel (H, W, 3) of the reflected and
    refracted rays max_depth cut off: the share of their radiance the image is missing.
    ``aovs`` (names from image.aovs.AOVS) come back as the result's ``.aovs``, from the camera rays'
    first hits; the image is the same with or without them."""
    primary = DEFAULTS.primary if primary is None else primary
    shadows = DEFAULTS.shadows if shadows is None else shadows
    reflections = DEFAULTS.reflections if reflections is None else reflections
    _check_choice(primary, PRIMARY, "--primary", "primary visibility")
    _check_choice(shadows, SHADOWS, "--shadow-rays", "shadow-ray query")
    _check_choice(reflections, REFLECTIONS, "--reflection-rays", "reflection-ray query")
    _check_choice(algorithm, ALGORITHMS, "--algorithm", "algorithm")
    aovs = check_aovs(aovs)
    validate_scene(scene)  # a Scene built in Python gets the file's checks too, before any kernel
    if algorithm == "zbuffer":
        if aovs:
            raise SceneError("command line", "--aov", "AOVs come from the tracer's camera rays: not with --algorithm zbuffer")
        return render_zbuffer(scene, threads=threads, device=device, effects=effects, disable=disable,
                              bands=bands, geometry=geometry)
    init_warp()
    t_start = time.perf_counter()
    threads, bands = launch_plan(threads, bands, device)
    cam = scene.camera
    basis = camera_basis(cam)
    fx: EffectSet = resolve_effects(scene, effects, disable)
    stats = RenderStats.begin(scene, fx, threads=threads, bands=bands, device=device, algorithm="raytrace",
                              variant=f"trace_{fx.variant}",
                              max_depth=scene.render.max_depth if fx.reflection or fx.refraction else 1)
    stack = stack_size(scene.render.max_depth, scene.source) if fx.refraction else 0
    n_pixels = cam.width * cam.height
    spp = scene.render.spp if fx.supersampling else 1
    samples = n_pixels * spp
    # Before any buffer: the most this frame can need (the Z-buffer's buffers wherever the policy may
    # ask for them; a camera on a surface may still trace), against what the machine has.
    may_raster = primary == "zbuffer" or (primary == "auto" and raster_is_cheaper(scene.triangle_count, samples, device))
    check_frame_memory(scene, _without_geometry(frame_estimate(scene, spp, may_raster), geometry))

    with stats.phase("bvh"):
        geom, stats.geometry = frame_geometry(scene, device) if geometry is None else given_geometry(geometry, cam.eye)
    stats.triangles = geom.triangle_count
    raster = primary_from_zbuffer(primary, geom, basis, samples, device)
    stats.primary = "zbuffer" if raster else "raytrace"

    grid = None
    if shadows_from_grid(shadows, geom, scene, fx, samples, threads, device):
        lights = geom.light_positions(scene)
        kept = kept_shadow_grid(geom, lights) is not None
        with stats.phase("shadow_grid"):
            build = shadow_grid(geom, lights)
        grid = build.grid  # None: over the memory budget, or every light has geometry at it
        stats.shadow_grid = {"grid": "reused" if kept else "built", **build.stats}
    stats.shadows = "grid" if grid is not None else "bvh"
    data = geom.scene_data(scene, grid)  # this frame's lights and materials: small tables, the BVH shared

    mirror_frame = None
    if fx.reflection and reflections == "mirrors":
        with stats.phase("mirrors"):
            mirror_frame = MirrorFrame(scene, geom, data, fx, threads, bands, device)
        stats.mirrors = mirror_frame.stats
        if mirror_frame.mirrors is None:
            mirror_frame = None
    stats.reflections = "mirrors" if mirror_frame is not None else "bvh"
    mirrors = mirror_frame.mirrors if mirror_frame is not None else empty_mirrors(device)

    with stats.phase("compile"):
        kernel = make_trace_kernel(fx, raster_primary=raster, stack=stack, report_truncated=report_truncated,
                                   aovs=aovs, shadow_grid=grid is not None, mirrors=mirror_frame is not None)
        wp.load_module(kernel.module, device=device)
        if raster or mirror_frame is not None:
            wp.load_module(raster_kernel.module, device=device)
    stats.variant += (("_zprimary" if raster else "") + ("_gshadow" if grid is not None else "")
                      + ("_mreflect" if mirror_frame is not None else "") + ("_aov_" + "_".join(aovs) if aovs else ""))

    zb = None
    if raster:
        with stats.phase("raster"):
            zb = ZBuffer(scene, geom, replace(fx, shadows=False, reflection=False), device=device)
            zb.rasterize(threads, bands)
    frags = zb.fragments if zb is not None else empty_fragments(device)

    with stats.phase("trace"):
        # With report_truncated the kernel writes the truncated weights after the image.
        image = wp.empty(n_pixels * (2 if report_truncated else 1), dtype=wp.vec3, device=device)
        counts = wp.empty(n_pixels, dtype=wp.vec4i if fx.refraction else wp.vec3i, device=device)
        c, k, max_depth = camera_data(basis, geom.eye_offset(cam.eye)), math.isqrt(scene.render.spp), stats.max_depth
        per_pixel = k * k if fx.supersampling else 1
        buffers = aov_buffers(aovs, geom, n_pixels, math.isqrt(per_pixel), device) if aovs else empty_aov_buffers(device)
        tile_w, tile_h = tile or PIXEL_TILE
        inputs = lambda first: [data, c, max_depth, k, first, tile_w, tile_h, frags, mirrors, buffers, image, counts]
        _launch_with_progress(kernel, inputs, n_pixels, threads, bands, device, counts, progress)
        pixels = image.numpy().reshape(-1, cam.height, cam.width, 3)
        out = pixels[0].copy()
        per_kind = counts.numpy().sum(0, dtype=np.int64)  # no int64 copy of every pixel's counts
    check_finite(out)
    if report_truncated:
        stats.truncated = pixels[1].copy()
    aov_arrays = {}
    if aovs:
        aov_arrays = finish_aovs(aovs, aov_sums(buffers, aovs), per_pixel, geom.origin, cam.height, cam.width)
        if "material" in aov_arrays:  # the kernel's material slots, as indices in scene.materials
            slots = aov_arrays["material"]
            aov_arrays["material"] = np.where(slots >= 0, geom.material_indices(scene)[np.maximum(slots, 0)], -1).astype(np.int32)

    stats.rays = {"primary": int(per_kind[0]), "shadow": int(per_kind[1]), "reflection": int(per_kind[2]),
                  "refraction": int(per_kind[3]) if fx.refraction else 0}
    stats.rays["total"] = sum(stats.rays.values())
    if mirror_frame is not None:
        decided = int(mirrors.decided.numpy().sum())
        stats.mirrors.update(decided=decided, share=decided / max(stats.rays["reflection"], 1))
    stats.rays_per_second = stats.rays["total"] / max(stats.times["trace"], 1e-9)
    stats.times["total"] = time.perf_counter() - t_start
    stats.memory = frame_memory(geom, image.capacity + counts.capacity, zb.nbytes if zb is not None else 0,
                                aov_bytes=aov_bytes(buffers),
                                shadow_grid_bytes=stats.shadow_grid.get("bytes", 0) if grid is not None else 0,
                                mirrors_bytes=mirror_frame.nbytes if mirror_frame is not None else 0)
    stats.memory["estimate"] = frame_estimate(scene, spp, raster)
    return RenderResult(out, stats, aov_arrays)


def _without_geometry(estimate: dict, geometry) -> dict:
    """The estimate less the geometry when the caller hands over a Geometry already built."""
    if geometry is None:
        return estimate
    return {**estimate, "geometry": 0, "total": estimate["total"] - estimate["geometry"]}


def given_geometry(geom: Geometry, eye) -> tuple[Geometry, dict]:
    """A Geometry passed to render(): used as it is, if its BVH covers the eye."""
    if not geom.covers(eye):
        raise ValueError(f"the Geometry passed to render() does not cover the eye {list(eye)}: "
                         f"{geometry_reason(geom, eye)}; build one for this eye")
    return geom, {"bvh": "given", "reason": geometry_reason(geom, eye)}


def _launch_with_progress(kernel, inputs, n_pixels, threads, bands, device, counts, progress):
    """launch_bands, telling ``progress`` (a progress.Progress) of each band done and its exact ray count."""
    on_band = None
    if progress is not None:
        # On the CPU the counts live in host memory and a finished band's counts are final.
        counts_host = counts.numpy() if device == "cpu" else None

        def report(first, count):
            rays = int(counts_host[first:first + count].sum(dtype=np.int64)) if counts_host is not None else 0
            progress.band_done(count, rays)

        on_band = report

    try:
        if progress is not None:
            # Inside the try: a Ctrl-C landing while begin() waits for its thread to start must still
            # clear the line the thread may already have drawn.
            progress.begin(len(bands_of(n_pixels, bands)), n_pixels)
        launch_bands(kernel, inputs, n_pixels, threads, bands, device, on_band)
    finally:
        if progress is not None:
            progress.end()


def render_zbuffer(scene, *, threads: int | None = None, device: str = "cpu", effects=None, disable=(),
                   bands: int | None = None, geometry: Geometry | None = None, tile: int = RASTER_TILE,
                   return_faces: bool = False):
    """Render ``scene`` by rasterization with the tracer's local shading (no shadows, no reflections).
    Returns a RenderResult, and with return_faces also the visible face per sample (H, W, samples)."""
    init_warp()
    validate_camera(scene.camera, scene.source)
    t_start = time.perf_counter()
    threads, bands = launch_plan(threads, bands, device)
    cam = scene.camera
    fx = zbuffer_effects(scene, effects, disable)
    samples = scene.render.spp if fx.supersampling else 1
    estimate = frame_estimate(scene, samples, True, algorithm="zbuffer")
    check_frame_memory(scene, _without_geometry(estimate, geometry))
    stats = RenderStats.begin(scene, fx, threads=threads, bands=bands, device=device, algorithm="zbuffer",
                              variant=f"zbuffer_{fx.variant}", max_depth=1)
    stats.rays = {"primary": 0, "shadow": 0, "reflection": 0, "refraction": 0, "total": 0}  # none: visibility is rasterized

    with stats.phase("geometry"):
        geom = geometry or Geometry(scene, device=device, build_bvh=False)
        data = geom.scene_data(scene)
    stats.triangles = geom.triangle_count

    with stats.phase("compile"):
        kernel = make_shade_kernel(fx)
        for m in (kernel.module, raster_kernel.module):
            wp.load_module(m, device=device)

    with stats.phase("render"):  # project + bin + raster + shade
        zb = ZBuffer(scene, geom, fx, device=device, tile=tile, track_uncertain=False)
        zb.rasterize(threads, bands)
        stats.times.update(zb.times)
        with stats.phase("shade"):
            n_pixels = cam.width * cam.height
            image = wp.empty(n_pixels, dtype=wp.vec3, device=device)
            c, k, frags = camera_data(zb.basis, zb.eye), zb.k, zb.fragments
            launch_bands(kernel, lambda first: [data, c, k, first, frags, image], n_pixels, threads, bands, device)
            out = image.numpy().reshape(cam.height, cam.width, 3).copy()
    check_finite(out, "zbuffer")
    stats.times["total"] = time.perf_counter() - t_start
    stats.memory["estimate"] = estimate
    result = RenderResult(out, stats)
    return (result, zb.faces()) if return_faces else result
