"""Warm-render timing and the triangle-count sweep, shared by the figures (Z-buffer against ray
tracing) and the cost-growth benchmark, so both measure the same scenes the same way.
"""

from __future__ import annotations

import platform
import statistics
import time
import tomllib
from pathlib import Path

import warprt
from warprt.geometry import Geometry

SCENES = Path(__file__).resolve().parent.parent / "scenes"
NO_SHADOWS_OR_REFLECTIONS = ["shadows", "reflection"]
TRACED = "raytrace"  # every ray traced, primaries too: what "ray tracing" means beside the Z-buffer


def timed(scene, geometry, repeat: int, **kw):
    """(image, median seconds) of warm renders: the first call compiles or loads the variant."""
    result, seconds = timed_result(scene, geometry, repeat, **kw)
    return result.image, seconds


def timed_result(scene, geometry, repeat: int, warmup_size: tuple[int, int] | None = None, **kw):
    """(the last RenderResult, median seconds) of ``repeat`` >= 1 warm renders. For an expensive frame,
    ``warmup_size`` (width, height) makes the first, untimed call a small image instead of the frame."""
    warmup = scene if warmup_size is None else scene.with_camera(width=warmup_size[0], height=warmup_size[1])
    renderer = warprt.Renderer(warmup, geometry=geometry, **kw)  # warm frames of one Renderer, as a user's
    renderer.render()
    renderer.set_scene(scene, checked=True)
    times = []
    for _ in range(max(1, repeat)):
        t = time.perf_counter()
        result = renderer.render()
        times.append(time.perf_counter() - t)
    return result, statistics.median(times)


def once(fn):
    """(fn(), seconds it took)."""
    t = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t


def ms(seconds: float) -> str:
    return f"{seconds * 1000:.0f} ms" if seconds >= 0.1 else f"{seconds * 1000:.1f} ms"


def cpu_name() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def growth_scene(subdivisions: int, width: int, height: int):
    """scenes/seed.toml with its sphere replaced by an icosphere of 20 * 4^subdivisions flat triangles
    (flat: smooth normals would add the same NumPy cost to both renderers' scene preparation)."""
    doc = tomllib.loads((SCENES / "seed.toml").read_text())
    for obj in doc["objects"]:
        if obj.get("name") == "sphere":
            obj.pop("segments", None)
            obj.update(shape="sphere", subdivisions=subdivisions, smooth=False)
    return warprt.load_dict(doc, SCENES, "scenes/seed.toml (sphere subdivided)").with_camera(width=width, height=height)


def growth_runs(repeat: int, sizes, subdivisions, threads: int | None = None, full: bool = False,
                log=print) -> list[dict]:
    """For each image size and icosphere subdivision level: scene preparation timed once without and
    with the BVH (prepare_flat, prepare_bvh), then warm frames of the Z-buffer and of the tracer with
    local shading only, the same image the Z-buffer makes (zbuffer, raytrace); with ``full``, also the
    tracer with the scene's shadows and ray levels (raytrace_full). Seconds; ``threads`` None: all cores."""
    runs = []
    for width, height in sizes:
        for s in subdivisions:
            scene = growth_scene(s, width, height)
            flat, t_flat = once(lambda: Geometry(scene, build_bvh=False))
            with_bvh, t_bvh = once(lambda: Geometry(scene))
            _, t_zb = timed(scene, flat, repeat, algorithm="zbuffer", threads=threads)
            _, t_rt = timed(scene, with_bvh, repeat, disable=NO_SHADOWS_OR_REFLECTIONS, threads=threads, primary_query=TRACED)
            run = {"width": width, "height": height, "triangles": flat.triangle_count, "zbuffer": t_zb,
                   "raytrace": t_rt, "prepare_flat": t_flat, "prepare_bvh": t_bvh}
            if full:
                run["raytrace_full"] = timed(scene, with_bvh, repeat, threads=threads, primary_query=TRACED)[1]
            runs.append(run)
            log(f"  {width}x{height} {flat.triangle_count:>9,} triangles: Z-buffer {ms(t_zb)}, ray tracing {ms(t_rt)}"
                + (f" (full {ms(run['raytrace_full'])})" if full else "")
                + f", flatten {ms(t_flat)}, flatten + BVH {ms(t_bvh)}")
    return runs
