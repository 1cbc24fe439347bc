"""Render a Scene: the Whitted tracer (render) or the Z-buffer (render_zbuffer). render() checks its
options once (RenderOptions), plans the frame (FramePlan: samples, depth, stack, the shortcuts' policies),
then runs named phases: geometry (BVH), the shortcuts (rasterized first hits, the shadow rays' grid, the
mirrors' virtual cameras), the kernel variant, the bands of pixels, and what it cost (stats)."""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field, fields, replace

import numpy as np

from .._warp import init_warp, wp
from ..errors import ArgumentError
from ..geometry import Geometry, kept_shadow_grid, shadow_grid
from ..kernels import (aov_buffers, aov_bytes, aov_sums, camera_data, empty_aov_buffers, make_shade_kernel,
                       make_trace_kernel, raster_kernel, stack_size)
from ..scene import EffectSet, ObjectCache, camera_basis, resolve_effects, validate_camera, validate_scene, zbuffer_effects
from ..timing import timed
from .aovs import check_aovs, finish_aovs
from .launch import bands_of, launch_bands, launch_plan
from .memory import RASTER_BYTES_PER_SAMPLE, check_frame_memory, frame_estimate, frame_memory
from .mirrors import empty_mirrors, kept_mirror_frame, mirror_frame as virtual_cameras, record_view, view_key
from .samples import SampleGrid, sample_grid
from .stats import RenderResult, RenderStats
from .zbuffer import RASTER_TILE, ZBuffer, culled_faces, empty_fragments, eye_on_surface

ALGORITHMS = ("raytrace", "zbuffer")
PRIMARY = ("auto", "raytrace", "zbuffer")
SHADOWS = ("auto", "bvh", "grid")
REFLECTIONS = ("auto", "bvh", "mirrors")


@dataclass
class Defaults:
    """render()'s defaults for what it is not told; the test suite sets them to run whole suites on
    every path (tests/conftest.py)."""

    primary: str = "auto"
    shadows: str = "auto"
    reflections: str = "auto"


DEFAULTS = Defaults()

# Pixel order: bands walk the image in 8x8 tiles, so the rays of a band stay close together and
# reuse the BVH nodes in cache (measured against row-major order in benchmarks/ATTEMPTS.md).
PIXEL_TILE = (8, 8)

# primary="auto" rasterizes only while those buffers stay under this: 19 million samples, 1920x1080
# at 9 spp. Tracing needs no per-sample memory, so a bigger frame (4K at 16 spp would need 3.7 GB)
# is traced rather than made to pay for its speed-up in memory.
AUTO_RASTER_MAX_BYTES = 512 * 2**20


@dataclass(frozen=True)
class RenderOptions:
    """How render() renders a scene, checked once, when made; each field is render()'s argument of the
    same name (render's docstring). None for primary, shadows and reflections: DEFAULTS'."""

    threads: int | None = None
    device: str = "cpu"
    effects: object = None
    disable: object = ()
    bands: int | None = None
    algorithm: str = "raytrace"
    tile: tuple[int, int] | None = None
    primary: str | None = None
    shadows: str | None = None
    reflections: str | None = None
    report_truncated: bool = False
    aovs: tuple = field(default=())

    def __post_init__(self):
        put = lambda name, value: object.__setattr__(self, name, value)  # noqa: E731 (frozen)
        for name in ("primary", "shadows", "reflections"):
            put(name, getattr(DEFAULTS, name) if getattr(self, name) is None else getattr(self, name))
        for name, choices, what in (("primary", PRIMARY, "primary visibility"), ("shadows", SHADOWS, "shadow-ray query"),
                                    ("reflections", REFLECTIONS, "reflection-ray query"),
                                    ("algorithm", ALGORITHMS, "algorithm")):
            if getattr(self, name) not in choices:
                raise ArgumentError("render", name, f"unknown {what} '{getattr(self, name)}'; "
                                                    f"expected one of: {', '.join(choices)}")
        put("aovs", check_aovs(self.aovs))
        if self.aovs and self.algorithm == "zbuffer":
            raise ArgumentError("render", "aovs", "AOVs come from the tracer's camera rays: not with {algorithm}",
                                {"algorithm": "zbuffer"})
        if self.threads is not None:
            put("threads", int(self.threads))
            if self.threads < 1:
                raise ArgumentError("render", "threads", f"expected an integer >= 1, got {self.threads}")

    @classmethod
    def of(cls, options: "RenderOptions | None", kwargs: dict) -> "RenderOptions":
        """``options`` with ``kwargs`` (render()'s keyword arguments) over it."""
        unknown = set(kwargs) - {f.name for f in fields(cls)}
        if unknown:
            raise TypeError(f"render() got an unexpected keyword argument '{sorted(unknown)[0]}'")
        if options is None:
            return cls(**kwargs)
        return replace(options, **kwargs) if kwargs else options


def raster_is_cheaper(triangles: int, samples: int, device: str = "cpu") -> bool:
    """Whether rasterizing the primary hits beats tracing them. Rasterization costs about a fixed
    amount per triangle plus per covered sample, tracing about log(triangles) per sample, so the
    raster wins with few triangles per sample: below one triangle per ten samples it did on every scene
    measured (benchmarks/ATTEMPTS.md), on the CPU only (on a GPU the primaries are traced), and within
    AUTO_RASTER_MAX_BYTES of buffers."""
    return (device == "cpu" and 0 < triangles <= samples // 10
            and samples * RASTER_BYTES_PER_SAMPLE <= AUTO_RASTER_MAX_BYTES)


def raster_wanted(primary: str, triangles: int, samples: int, device: str) -> bool:
    """The hybrid policy before the eye is known to be off every surface: "zbuffer" asks for the
    Z-buffer's first hits, "auto" takes them where they are the cheaper."""
    return primary == "zbuffer" or (primary == "auto" and raster_is_cheaper(triangles, samples, device))


# What the light-space grid costs and saves, measured on the scenes on a quiet 2-core machine: a shadow
# ray's any-hit query about 200 ns of thread time, the grid's answer about 70 ns; a build about 10 ms per
# light plus 0.8 us per triangle and light (0.024 s for the default scene, 0.83 s for the 524k-triangle knot).
GRID_SAVES_PER_RAY = 130e-9
GRID_BUILD_PER_LIGHT = 10e-3
GRID_BUILD_PER_TRIANGLE_LIGHT = 780e-9
GRID_HORIZON = 20  # frames a second frame with the same lights is taken to promise
LIGHT_SETS_KEPT = 64  # lights moving every frame: no set of them stays long enough to amortize a grid


class LightHistory:
    """How many frames a Geometry has served with each set of light positions: a grid built for
    them is kept with the Geometry, so its build is paid once by all of those frames."""

    def __init__(self):
        self.frames: dict[bytes, int] = {}

    def record(self, lights: np.ndarray) -> int:
        """Count one more frame with ``lights``; how many there have been, this one included."""
        if len(self.frames) >= LIGHT_SETS_KEPT:
            self.frames.clear()
        key = lights.tobytes()
        self.frames[key] = self.frames.get(key, 0) + 1
        return self.frames[key]


_light_histories: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # Geometry -> LightHistory


def light_history(geom: Geometry) -> LightHistory:
    """The frames ``geom`` has served with shadow rays, by light set (kept as long as the Geometry)."""
    return _light_histories.setdefault(geom, LightHistory())


def shadows_from_grid(shadows: str, fx, geom: Geometry, lights: np.ndarray, samples: int, threads: int,
                      device: str, frames: int) -> bool:
    """The shadow rays' policy: whether the light-space grid answers them. "grid" asks for it; "auto"
    takes it on the CPU where it is the cheaper: on a first frame when its build costs less than the
    frame's shadow rays save (about one per sample and light), and from the second frame with the same
    lights on (``frames``: light_history's count, this frame included) when it costs less than
    GRID_HORIZON such frames save; a grid kept for these lights costs nothing. Either way the image is
    the traced one, to the bit."""
    if not fx.shadows or geom.triangle_count == 0 or shadows == "bvh":
        return False
    if shadows == "grid":
        return True
    if device != "cpu":
        return False
    if kept_shadow_grid(geom, lights) is not None:
        return True
    build = (GRID_BUILD_PER_LIGHT + GRID_BUILD_PER_TRIANGLE_LIGHT * geom.triangle_count) * len(lights)
    per_frame = GRID_SAVES_PER_RAY * samples * len(lights) / threads
    return build <= per_frame * (GRID_HORIZON if frames >= 2 else 1)


def mirrors_from_rasters(reflections: str, fx, triangles: int, samples: int, device: str, kept: bool,
                         frames: int) -> bool:
    """The reflection rays' policy: whether the planar mirrors' virtual cameras answer them. "mirrors" asks
    for them; "auto" takes them on the CPU where rasterizing the scene beats tracing it (raster_is_cheaper,
    the first hits' rule) once they are kept: building them (probes, a raster per chain) costs about what a
    few frames' queries save, and kept for a static view they cost nothing. So a view's second frame (``frames``: record_view's count, this one included)
    builds them, as a second frame with the same lights builds the shadow grid, for the frames after it;
    a moving camera's are traced. Either way the image is the traced one, to the bit."""
    if not fx.reflection or reflections == "bvh":
        return False
    if reflections == "mirrors":
        return True
    return device == "cpu" and raster_is_cheaper(triangles, samples, device) and (kept or frames >= 2)


geometry_cache = ObjectCache(size=4)  # the Geometries kept for the next frames of the same objects


def frame_geometry(scene, device: str = "cpu") -> tuple[Geometry, dict]:
    """The Geometry (triangles, normals, BVH) for a frame of ``scene``, and how it came: built, or
    reused from an earlier frame of the same objects, as Mitsuba reuses a loaded scene. Keyed by the
    objects alone (Scene.with_camera/with_render share them): another eye, lights or materials reuse
    it while the eye keeps the frame origin it was built with (bvh.frame_origin: the objects' centre,
    for any eye in the region its BVH's padding covers), so a frame's image is a fresh build's to the
    bit; the tables of lights and materials are the frame's own (Geometry.scene_data)."""
    key = (id(scene.objects), tuple(id(o.vertices) for o in scene.objects),
           tuple((o.material, o.smooth, id(o.normals), id(o.uv), id(o.colors)) for o in scene.objects), str(device))
    eye = scene.camera.eye
    found = geometry_cache.peek(key, scene.objects)
    if found is not None:
        if np.array_equal(found.origin_for(eye), found.planned_origin) and found.covers(eye):
            return found, {"bvh": "reused", "reason": geometry_reason(found, eye)}
        reason = f"the eye left the region the cached BVH covers ({geometry_reason(found, eye)})"
    else:
        reason = "no geometry was built for these objects"
    return geometry_cache.put(key, scene.objects, Geometry(scene, device=device)), {"bvh": "built", "reason": reason}


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


@dataclass(frozen=True)
class FramePlan:
    """What a traced frame will do, decided once from the scene and the options before any buffer."""

    fx: EffectSet
    threads: int
    bands: int
    grid: SampleGrid  # the samples a pixel takes
    n_pixels: int
    max_depth: int  # ray levels the kernel follows: 1 without reflection and refraction
    stack: int  # the ray tree's stack: 0 without refraction
    raster: bool  # the hybrid policy wants the Z-buffer's first hits (a camera on a surface still traces)
    mirrors: bool  # the reflection rays' virtual cameras are asked for, or auto may take them

    @property
    def samples(self) -> int:
        return self.n_pixels * self.grid.per_pixel


def plan_frame(scene, o: RenderOptions) -> FramePlan:
    threads, bands = launch_plan(o.threads, o.bands, o.device)
    fx = resolve_effects(scene, o.effects, o.disable)
    cam, grid = scene.camera, sample_grid(scene, fx)
    return FramePlan(fx, threads, bands, grid, cam.width * cam.height,
                     max_depth=scene.render.max_depth if fx.reflection or fx.refraction else 1,
                     stack=stack_size(scene.render.max_depth, scene.source) if fx.refraction else 0,
                     # Neither the Z-buffer nor the mirrors' virtual cameras know a face's side: with
                     # single-sided materials every first hit is traced, so the image stays the traced one.
                     raster=not fx.culling and raster_wanted(o.primary, scene.triangle_count,
                                                             cam.width * cam.height * grid.per_pixel, o.device),
                     mirrors=fx.reflection and o.reflections != "bvh" and not fx.culling)


@dataclass(frozen=True)
class TraceVariant:
    """make_trace_kernel's arguments for a frame, and the name the stats give the kernel they make."""

    fx: EffectSet
    raster_primary: bool
    stack: int
    report_truncated: bool
    aovs: tuple
    shadow_grid: bool
    mirrors: bool

    @property
    def name(self) -> str:
        return (f"trace_{self.fx.variant}" + ("_zprimary" if self.raster_primary else "")
                + ("_gshadow" if self.shadow_grid else "") + ("_mreflect" if self.mirrors else "")
                + ("_aov_" + "_".join(self.aovs) if self.aovs else ""))

    def kernel(self):
        return make_trace_kernel(self.fx, raster_primary=self.raster_primary, stack=self.stack,
                                 report_truncated=self.report_truncated, aovs=self.aovs,
                                 shadow_grid=self.shadow_grid, mirrors=self.mirrors)


def render(scene, options: RenderOptions | None = None, *, geometry: Geometry | None = None, progress=None,
           **kwargs) -> RenderResult:
    """Render ``scene`` with the Whitted tracer (or, algorithm="zbuffer", by rasterization with the same
    local shading), as ``options`` (a RenderOptions) and keyword arguments (its fields) say:
    ``effects`` (names) limits the effect set, ``disable`` removes effects; neither can add one the
    scene has nothing for. ``primary`` says where the tracer's first hits come from: "raytrace";
    "zbuffer" (hybrid rendering: the Z-buffer's visible triangle wherever it is certain to be the traced
    one, the other samples traced; the image is the traced image to the bit); or "auto", the default,
    which rasterizes where that is the cheaper of the two (raster_is_cheaper). ``shadows`` says what
    answers the shadow rays: "bvh" (Warp's any-hit query), "grid" (the exact light-space grid: the same
    answers), or "auto", the default, the grid where it is the cheaper. ``reflections`` says what answers
    the reflection rays: "bvh" (Warp's closest-hit query), "mirrors" (off planar mirrors, their virtual
    cameras' rasters wherever certain to give the query's answer, the rest traced), or "auto", the
    default, which takes the virtual cameras from a view's second frame on (mirrors_from_rasters): their
    build costs about what one frame's queries save, kept they cost nothing. With ``report_truncated``,
    stats.truncated is the weight per pixel (H, W, 3) of the reflected and refracted rays max_depth cut
    off: the share of their radiance the image is missing. ``aovs`` (names from image.aovs.AOVS) come back
    as the result's ``.aovs``, from the camera rays' first hits; the image is the same with or without
    them. ``geometry``: a Geometry built for
    this scene, used as it is; ``progress``: a progress.Progress told of each band done."""
    o = RenderOptions.of(options, kwargs)
    validate_scene(scene)  # a Scene built in Python gets the file's checks too, before any kernel
    if o.algorithm == "zbuffer":
        return render_zbuffer(scene, o, geometry=geometry)
    init_warp()
    times: dict = {}
    with timed(times, "total"):
        plan = plan_frame(scene, o)
        stats = RenderStats.begin(scene, plan.fx, threads=plan.threads, bands=plan.bands, device=o.device,
                                  algorithm="raytrace", variant="", max_depth=plan.max_depth)
        # Before any buffer: the most this frame can need, against what the machine has.
        check_frame_memory(scene, _without_geometry(frame_estimate(scene, plan.grid.per_pixel, plan.raster), geometry))
        with stats.phase("bvh"):
            geom, stats.geometry = frame_geometry(scene, o.device) if geometry is None else given_geometry(geometry, scene.camera.eye)
        stats.triangles = geom.triangle_count
        raster, grid, mirror_frame = _shortcuts(scene, o, plan, geom, stats)
        variant = TraceVariant(plan.fx, raster, plan.stack, o.report_truncated, o.aovs, grid is not None,
                               mirror_frame is not None)
        stats.variant = variant.name
        with stats.phase("compile"):
            kernel = variant.kernel()
            wp.load_module(kernel.module, device=o.device)
            if raster or mirror_frame is not None:
                wp.load_module(raster_kernel.module, device=o.device)
        zb = None
        if raster:
            with stats.phase("raster"):
                zb = ZBuffer(scene, geom, replace(plan.fx, shadows=False, reflection=False), device=o.device)
                zb.rasterize(plan.threads, plan.bands)
        data = geom.scene_data(scene, grid)
        with stats.phase("trace"):
            frame = _trace(scene, o, plan, geom, data, kernel, zb, mirror_frame, progress)
        result = _finish(scene, o, plan, geom, stats, frame, zb, grid, mirror_frame)
    stats.times["total"] = times["total"]
    stats.memory["estimate"] = frame_estimate(scene, plan.grid.per_pixel, raster)
    return result


def _shortcuts(scene, o: RenderOptions, plan: FramePlan, geom: Geometry, stats: RenderStats):
    """The shortcuts this frame takes, each giving the traced answer to the bit: first hits from the
    Z-buffer (True or False), the shadow rays' grid (or None) and the mirrors' virtual cameras (or None)."""
    raster = plan.raster and not eye_on_surface(geom, camera_basis(scene.camera))
    stats.primary = "zbuffer" if raster else "raytrace"
    grid = None
    lights = geom.light_positions(scene)
    frames = light_history(geom).record(lights) if plan.fx.shadows and geom.triangle_count else 0
    if shadows_from_grid(o.shadows, plan.fx, geom, lights, plan.samples, plan.threads, o.device, frames):
        kept = kept_shadow_grid(geom, lights) is not None
        with stats.phase("shadow_grid"):
            build = shadow_grid(geom, lights)
        grid = build.grid  # None: over the memory budget, or every light has geometry at it
        stats.shadow_grid = {"grid": "reused" if kept else "built", **build.stats}
    stats.shadows = "grid" if grid is not None else "bvh"
    mirror_frame = None
    if plan.mirrors:
        data = geom.scene_data(scene, grid)
        view = view_key(scene, data, plan.fx)
        frames = record_view(geom, view)
        if mirrors_from_rasters(o.reflections, plan.fx, geom.triangle_count, plan.samples, o.device,
                                kept_mirror_frame(geom, view) is not None, frames):
            with stats.phase("mirrors"):
                mirror_frame, kept = virtual_cameras(scene, geom, data, plan.fx, view, plan.threads, plan.bands, o.device)
            stats.mirrors = {"rasters": "reused" if kept else "built", **mirror_frame.stats}
            if mirror_frame.mirrors is None:
                mirror_frame = None
    stats.reflections = "mirrors" if mirror_frame is not None else "bvh"
    return raster, grid, mirror_frame


def _trace(scene, o: RenderOptions, plan: FramePlan, geom: Geometry, data, kernel, zb, mirror_frame, progress) -> dict:
    """Launch the kernel over the image: the image, the truncated weights after it (report_truncated),
    each pixel's ray counts and the AOV buffers."""
    cam, device = scene.camera, o.device
    # With report_truncated the kernel writes the truncated weights after the image.
    image = wp.empty(plan.n_pixels * (2 if o.report_truncated else 1), dtype=wp.vec3, device=device)
    counts = wp.empty(plan.n_pixels, dtype=wp.vec4i if plan.fx.refraction else wp.vec3i, device=device)
    buffers = aov_buffers(o.aovs, geom, plan.n_pixels, plan.grid.side, device) if o.aovs else empty_aov_buffers(device)
    c = camera_data(camera_basis(cam), geom.eye_offset(cam.eye))
    frags = zb.fragments if zb is not None else empty_fragments(device)
    mirrors = mirror_frame.mirrors if mirror_frame is not None else empty_mirrors(device)
    tile_w, tile_h = o.tile or PIXEL_TILE
    inputs = lambda first: [data, c, plan.max_depth, plan.grid.k, first, tile_w, tile_h, frags, mirrors,  # noqa: E731
                            buffers, image, counts]
    _launch_with_progress(kernel, inputs, plan.n_pixels, plan.threads, plan.bands, device, counts, progress)
    pixels = image.numpy().reshape(-1, cam.height, cam.width, 3)
    return {"pixels": pixels, "image": pixels[0].copy(), "buffers": buffers, "mirrors": mirrors,
            "per_kind": counts.numpy().sum(0, dtype=np.int64),  # no int64 copy of every pixel's counts
            "bytes": image.capacity + counts.capacity}


def _finish(scene, o: RenderOptions, plan: FramePlan, geom: Geometry, stats: RenderStats, frame: dict, zb, grid,
            mirror_frame) -> RenderResult:
    """The result: the image checked, the AOVs, the truncated weights, and the ray counts and memory in the stats."""
    cam, out, per_kind = scene.camera, frame["image"], frame["per_kind"]
    check_finite(out)
    if o.report_truncated:
        stats.truncated = frame["pixels"][1].copy()
    aov_arrays = {}
    if o.aovs:
        aov_arrays = finish_aovs(o.aovs, aov_sums(frame["buffers"], o.aovs), plan.grid.per_pixel, geom.origin,
                                 cam.height, cam.width)
        if "material" in aov_arrays:  # the kernel's material slots, as indices in scene.materials
            slots = aov_arrays["material"]
            aov_arrays["material"] = np.where(slots >= 0, geom.material_indices(scene)[np.maximum(slots, 0)], -1).astype(np.int32)
    stats.rays = {"primary": int(per_kind[0]), "shadow": int(per_kind[1]), "reflection": int(per_kind[2]),
                  "refraction": int(per_kind[3]) if plan.fx.refraction else 0}
    stats.rays["total"] = sum(stats.rays.values())
    if mirror_frame is not None:
        decided = int(frame["mirrors"].decided.numpy().sum())
        stats.mirrors.update(decided=decided, share=decided / max(stats.rays["reflection"], 1))
    stats.rays_per_second = stats.rays["total"] / max(stats.times["trace"], 1e-9)
    stats.memory = frame_memory(geom, frame["bytes"], zb.nbytes if zb is not None else 0,
                                aov_bytes=aov_bytes(frame["buffers"]),
                                shadow_grid_bytes=stats.shadow_grid.get("bytes", 0) if grid is not None else 0,
                                mirrors_bytes=mirror_frame.nbytes if mirror_frame is not None else 0)
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


def render_zbuffer(scene, options: RenderOptions | None = None, *, geometry: Geometry | None = None,
                   tile: int = RASTER_TILE, return_faces: bool = False, **kwargs):
    """Render ``scene`` by rasterization with the tracer's local shading (no shadows, no reflections),
    as ``options`` and keyword arguments say (render()'s threads, device, effects, disable, bands);
    ``tile``: the raster tiles' side in pixels. Returns a RenderResult, and with return_faces also the
    visible face per sample (H, W, samples)."""
    o = RenderOptions.of(options, kwargs)
    init_warp()
    validate_camera(scene.camera, scene.source)
    times: dict = {}
    with timed(times, "total"):
        threads, bands = launch_plan(o.threads, o.bands, o.device)
        fx = zbuffer_effects(scene, o.effects, o.disable)
        estimate = frame_estimate(scene, sample_grid(scene, fx).per_pixel, True, algorithm="zbuffer")
        check_frame_memory(scene, _without_geometry(estimate, geometry))
        stats = RenderStats.begin(scene, fx, threads=threads, bands=bands, device=o.device, algorithm="zbuffer",
                                  variant=f"zbuffer_{fx.variant}", max_depth=1)
        stats.rays = {"primary": 0, "shadow": 0, "reflection": 0, "refraction": 0, "total": 0}  # visibility is rasterized
        with stats.phase("geometry"):
            geom = geometry or Geometry(scene, device=o.device, build_bvh=False)
            data = geom.scene_data(scene)
        stats.triangles = geom.triangle_count
        with stats.phase("compile"):
            kernel = make_shade_kernel(fx)
            for m in (kernel.module, raster_kernel.module):
                wp.load_module(m, device=o.device)
        with stats.phase("render"):  # project + bin + raster + shade
            zb = ZBuffer(scene, geom, fx, device=o.device, tile=tile, track_uncertain=False)
            zb.rasterize(threads, bands, skip=culled_faces(scene, geom, zb.eye) if fx.culling else None)
            stats.times.update(zb.times)
            with stats.phase("shade"):
                cam = scene.camera
                image = wp.empty(cam.width * cam.height, dtype=wp.vec3, device=o.device)
                c, k, frags = camera_data(zb.basis, zb.eye), zb.k, zb.fragments
                launch_bands(kernel, lambda first: [data, c, k, first, frags, image], cam.width * cam.height,
                             threads, bands, o.device)
                out = image.numpy().reshape(cam.height, cam.width, 3).copy()
        check_finite(out, "zbuffer")
    stats.times["total"] = times["total"]
    stats.memory["estimate"] = estimate
    result = RenderResult(out, stats)
    return (result, zb.faces()) if return_faces else result
