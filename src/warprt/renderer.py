"""Render a Scene: build the BVH, pick the kernel variant for its effect set, launch bands of
pixels from a thread pool, and report what it cost (time per phase, exact ray counts)."""

from __future__ import annotations

import dataclasses
import math
import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass, field
from typing import NamedTuple

import numpy as np
from ._warp import wp

from .camera import camera_basis
from .effects import EffectSet, resolve_effects
from .errors import SceneError
from .geometry import Geometry
from .scene import validate_scene

_initialized = False


def init_warp():
    """Initialize Warp once. Its native layer warns on stderr when a machine has no CUDA driver,
    which is the normal case for this CPU renderer: that one line is dropped, anything else kept."""
    global _initialized
    if _initialized:
        return
    import sys
    import tempfile

    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as captured:
        os.dup2(captured.fileno(), 2)
        try:
            wp.init()
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        captured.seek(0)
        for line in captured.read().decode(errors="replace").splitlines():
            if "Could not find or load the NVIDIA CUDA driver" not in line:
                print(line, file=sys.stderr)
    _initialized = True


@dataclass
class RenderStats:
    width: int = 0
    height: int = 0
    spp: int = 1
    max_depth: int = 1
    triangles: int = 0
    lights: int = 0
    device: str = "cpu"
    threads: int = 1
    bands: int = 1
    algorithm: str = "raytrace"
    primary: str = "raytrace"  # where the first hits came from: "raytrace", or "zbuffer" (hybrid; same image)
    effects: str = ""
    variant: str = ""
    rays: dict = field(default_factory=dict)  # primary, shadow, reflection, total
    times: dict = field(default_factory=dict)  # seconds: load, bvh, compile, trace, write, total
    rays_per_second: float = 0.0
    memory: dict = field(default_factory=dict)  # bytes: geometry arrays and BVH by role, image, peak_rss

    def to_dict(self) -> dict:
        return asdict(self)


class RenderResult(NamedTuple):
    image: np.ndarray  # float32 (H, W, 3), linear RGB, row 0 at the top
    stats: RenderStats


def default_threads() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def launch_plan(threads: int | None, bands: int | None, device: str) -> tuple[int, int]:
    """Threads and bands for a render: on the CPU each band is one launch, and 8 per thread (16 at
    least) balance the load between threads; a GPU takes the whole image in one launch."""
    threads = default_threads() if threads is None else int(threads)
    if threads < 1:
        raise SceneError("command line", "--threads", f"expected an integer >= 1, got {threads}")
    return threads, bands or (1 if device != "cpu" else max(16, 8 * threads))


def _bands(n_pixels: int, n_bands: int) -> list[tuple[int, int]]:
    """Split [0, n_pixels) into n_bands contiguous ranges (first pixel, count)."""
    n_bands = max(1, min(n_bands, n_pixels))
    edges = np.linspace(0, n_pixels, n_bands + 1).round().astype(int)
    return [(int(a), int(b - a)) for a, b in zip(edges[:-1], edges[1:]) if b > a]


_pools: dict = {}


def _pool(threads: int) -> ThreadPoolExecutor:
    """One long-lived pool per thread count: starting threads for every frame costs more than a
    small frame's trace."""
    if threads not in _pools:
        _pools[threads] = ThreadPoolExecutor(max_workers=threads, thread_name_prefix="warprt")
    return _pools[threads]


def launch_bands(kernel, inputs_for, n_pixels: int, threads: int, bands: int, device: str, on_band=None):
    """Launch ``kernel`` over pixel ranges; on the CPU each launch runs on one thread and releases
    the GIL, so a pool of ``threads`` workers runs that many bands at once. ``on_band(first, count)``
    is called when a band has finished, on the worker thread that ran it."""
    ranges = _bands(n_pixels, bands)

    def run(r):
        first, count = r
        wp.launch(kernel, dim=count, inputs=inputs_for(first), device=device)
        if on_band is not None:
            if device != "cpu":  # a GPU launch returns before the band is done
                wp.synchronize_device(device)
            on_band(first, count)

    if threads <= 1 or len(ranges) == 1 or device != "cpu":
        for r in ranges:
            run(r)
    else:
        list(_pool(threads).map(run, ranges))
    wp.synchronize_device(device)


def check_finite(image: np.ndarray, what: str = "render"):
    """The renderer checks its own output: a NaN or Inf pixel is a bug, never an image."""
    bad = ~np.isfinite(image)
    if bad.any():
        rows, cols = np.nonzero(bad.any(-1))
        raise RuntimeError(f"{what} produced {len(rows)} non-finite pixels (first at row {rows[0]}, column {cols[0]})")


ALGORITHMS = ("raytrace", "zbuffer")
PRIMARY = ("auto", "raytrace", "zbuffer")


# The Z-buffer's buffers per sample: 1/z and its nearest rival (float64 each), the face (int32), (u, v).
RASTER_BYTES_PER_SAMPLE = 8 + 8 + 4 + 8
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
# Pixel order: bands walk the image in 8x8 tiles, so the rays of a band stay close together and
# reuse the BVH nodes in cache. Measured at 1024x768 against row-major order: 0.83 to 0.96 of the
# trace time on six of eight scenes, 1.01 and 1.03 on two (benchmarks/ATTEMPTS.md).
TILE = (8, 8)

_geometry_cache: dict = {}
_GEOMETRY_CACHE_SIZE = 4


def cached_geometry(scene, device: str = "cpu") -> Geometry:
    """The scene's Geometry (BVH, normals, tables), built once and reused by the next frames of the
    same scene from the same eye, as Mitsuba reuses a loaded scene. Keyed by the objects' identity
    (Scene.with_camera/with_render share them) and every value the Geometry is made of."""
    key = (id(scene.objects), tuple(id(o.vertices) for o in scene.objects), tuple(scene.camera.eye),
           tuple(scene.materials.items()), tuple(scene.lights), scene.render.ambient, scene.render.background, str(device))
    entry = _geometry_cache.pop(key, None)
    if entry is None or entry[0] is not scene.objects:  # a new list may reuse a dead one's id
        entry = (scene.objects, Geometry(scene, device=device))
    _geometry_cache[key] = entry  # most recently used last
    while len(_geometry_cache) > _GEOMETRY_CACHE_SIZE:
        _geometry_cache.pop(next(iter(_geometry_cache)))
    return entry[1]


def render(scene, *, threads: int | None = None, device: str = "cpu", effects=None, disable=(),
           bands: int | None = None, geometry: Geometry | None = None, algorithm: str = "raytrace",
           progress=None, tile: tuple[int, int] | None = None, primary: str = "auto") -> RenderResult:
    """Render ``scene`` with the Whitted tracer (or, algorithm="zbuffer", by rasterization with the same
    local shading). ``effects`` (names) limits the effect set, ``disable`` removes effects; neither
    can add one the scene has nothing for. ``primary`` says where the tracer's first hits come from:
    "raytrace"; "zbuffer" (hybrid rendering: the Z-buffer's visible triangle wherever it is certain
    to be the traced one, the other samples traced; the image is the traced image to the bit); or
    "auto", the default, which rasterizes where that is the cheaper of the two (raster_is_cheaper)."""
    if primary not in PRIMARY:
        raise SceneError("command line", "--primary", f"unknown primary visibility '{primary}'; expected one of: {', '.join(PRIMARY)}")
    if algorithm not in ALGORITHMS:
        raise SceneError("command line", "--algorithm", f"unknown algorithm '{algorithm}'; expected one of: {', '.join(ALGORITHMS)}")
    validate_scene(scene)  # a Scene built in Python gets the file's checks too, before any kernel
    if algorithm == "zbuffer":
        from .zbuffer import render_zbuffer

        return render_zbuffer(scene, threads=threads, device=device, effects=effects, disable=disable,
                              bands=bands, geometry=geometry)
    init_warp()
    t_start = time.perf_counter()
    threads, bands = launch_plan(threads, bands, device)
    cam = scene.camera
    n_pixels = cam.width * cam.height
    tile_w, tile_h = tile or TILE
    fx: EffectSet = resolve_effects(scene, effects, disable)
    stats = RenderStats(width=cam.width, height=cam.height, spp=scene.render.spp,
                        max_depth=scene.render.max_depth if fx.reflection else 1,
                        lights=len(scene.lights), device=str(device), threads=threads, bands=bands,
                        effects=str(fx), variant=f"trace_{fx.variant}")
    if getattr(scene, "load_seconds", None) is not None:
        stats.times["load"] = scene.load_seconds

    t = time.perf_counter()
    geom = geometry or cached_geometry(scene, device)
    stats.triangles = geom.triangle_count
    stats.times["bvh"] = time.perf_counter() - t

    from .tracer import camera_data, make_trace_kernel

    samples = n_pixels * (scene.render.spp if fx.supersampling else 1)
    raster = primary == "zbuffer" or (primary == "auto" and raster_is_cheaper(geom.triangle_count, samples, device))
    if raster:
        from .zbuffer import eye_on_surface

        raster = not eye_on_surface(geom, camera_basis(cam))  # the traced image is the promise: trace such a view
    stats.primary = "zbuffer" if raster else "raytrace"
    t = time.perf_counter()
    kernel = make_trace_kernel(fx, raster_primary=raster)
    wp.load_module(kernel.module, device=device)
    if raster:
        from .zbuffer import raster_kernel

        wp.load_module(raster_kernel.module, device=device)
    stats.times["compile"] = time.perf_counter() - t
    stats.variant += "_zprimary" if raster else ""

    if raster:
        from .zbuffer import ZBuffer

        t = time.perf_counter()
        zb = ZBuffer(scene, geom, dataclasses.replace(fx, shadows=False, reflection=False), device=device)
        zb.rasterize(threads, bands)
        raster_inputs = (zb.face, zb.depth, zb.near)
        stats.times["raster"] = time.perf_counter() - t
    else:
        raster_inputs = (wp.empty(0, dtype=wp.int32, device=device), wp.empty(0, dtype=wp.float64, device=device),
                         wp.empty(0, dtype=wp.float64, device=device))

    t = time.perf_counter()
    image = wp.empty(n_pixels, dtype=wp.vec3, device=device)
    counts = wp.empty(n_pixels, dtype=wp.vec3i, device=device)
    c = camera_data(camera_basis(cam))
    k = math.isqrt(scene.render.spp)
    max_depth = stats.max_depth
    data = geom.data
    on_band = None
    if progress is not None:  # a progress.Progress: tiles done and their exact ray counts
        # On the CPU the counts live in host memory and a finished band's counts are final.
        counts_host = counts.numpy() if device == "cpu" else None

        def on_band(first, count):
            rays = int(counts_host[first:first + count].sum(dtype=np.int64)) if counts_host is not None else 0
            progress.band_done(count, rays)

        progress.begin(len(_bands(n_pixels, bands)), n_pixels)
    try:
        launch_bands(kernel, lambda first: [data, c, max_depth, k, first, tile_w, tile_h, *raster_inputs, image, counts],
                     n_pixels, threads, bands, device, on_band)
    finally:
        if progress is not None:
            progress.end()
    out = image.numpy().reshape(cam.height, cam.width, 3).copy()
    per_kind = counts.numpy().astype(np.int64).sum(0)
    stats.times["trace"] = time.perf_counter() - t
    check_finite(out)

    stats.rays = {"primary": int(per_kind[0]), "shadow": int(per_kind[1]), "reflection": int(per_kind[2])}
    stats.rays["total"] = sum(stats.rays.values())
    stats.rays_per_second = stats.rays["total"] / max(stats.times["trace"], 1e-9)
    stats.times["total"] = time.perf_counter() - t_start
    from .memory import geometry_memory, peak_rss

    stats.memory = {"geometry": geometry_memory(geom), "image": int(image.capacity + counts.capacity),
                    "raster": int(sum(a.capacity for a in raster_inputs) + (zb.uv.capacity if raster else 0)),
                    "peak_rss": peak_rss()}
    return RenderResult(out, stats)
