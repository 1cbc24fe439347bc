"""What a traced frame will do, decided once: FramePlan from the scene and the options (samples, depth,
stack, which shortcuts are wanted), then Shortcuts once the Geometry is known (which are taken, and
why). Every shortcut gives the traced image to the bit; the policies only weigh what each costs."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry import Geometry, kept_shadow_grid
from ..kernels import stack_size
from ..options import RenderOptions
from ..scene import EffectSet, camera_basis, resolve_effects
from .caches import FrameCaches
from .launch import launch_plan
from .memory import RASTER_BYTES_PER_SAMPLE
from .mirrors import kept_mirror_frame, view_key
from .samples import SampleGrid, sample_grid
from .zbuffer import eye_on_surface

# primary_query="auto" rasterizes only while those buffers stay under this: 19 million samples, 1920x1080
# at 9 spp. Tracing needs no per-sample memory, so a bigger frame (4K at 16 spp would need 3.7 GB)
# is traced rather than made to pay for its speed-up in memory.
AUTO_RASTER_MAX_BYTES = 512 * 2**20

# The light-space grid's cost model (benchmarks/ATTEMPTS.md has the measurements behind each figure):
# what the grid saves on one shadow ray against Warp's any-hit query, and what a build costs per light
# and per triangle and light, in seconds of thread time.
GRID_SAVES_PER_RAY = 130e-9
GRID_BUILD_PER_LIGHT = 10e-3
GRID_BUILD_PER_TRIANGLE_LIGHT = 780e-9
GRID_HORIZON = 20  # frames a second frame with the same lights is taken to promise


def raster_is_cheaper(triangles: int, samples: int, device: str = "cpu") -> bool:
    """Whether rasterizing the primary hits beats tracing them. Rasterization costs about a fixed
    amount per triangle plus per covered sample, tracing about log(triangles) per sample, so the
    raster wins with few triangles per sample: below one triangle per ten samples (the threshold
    benchmarks/ATTEMPTS.md measured on every scene), on the CPU only (on a GPU the primaries are
    traced), and within AUTO_RASTER_MAX_BYTES of buffers."""
    return (device == "cpu" and 0 < triangles <= samples // 10
            and samples * RASTER_BYTES_PER_SAMPLE <= AUTO_RASTER_MAX_BYTES)


def raster_wanted(primary_query: str, triangles: int, samples: int, device: str) -> bool:
    """The hybrid policy before the eye is known to be off every surface: "zbuffer" asks for the
    Z-buffer's first hits, "auto" takes them where they are the cheaper."""
    return primary_query == "zbuffer" or (primary_query == "auto" and raster_is_cheaper(triangles, samples, device))


def shadows_from_grid(shadow_query: str, fx, geom: Geometry, lights: np.ndarray, samples: int, threads: int,
                      device: str, frames: int, kept: bool = False) -> bool:
    """The shadow rays' policy: whether the light-space grid answers them. "grid" asks for it; "auto"
    takes it on the CPU where it is the cheaper: on a first frame when its build costs less than the
    frame's shadow rays save (about one per sample and light), and from the second frame with the same
    lights on (``frames``: the LightHistory count, this frame included) when it costs less than
    GRID_HORIZON such frames save; a grid ``kept`` for these lights costs nothing. Either way the image
    is the traced one, to the bit. A scene with area lights traces every shadow ray: the grid is built
    around point lights, and an area light's rays run to many points of it. One without point, spot or
    directional lights (an environment light's alone) has nothing to build it around."""
    if not fx.shadows or geom.triangle_count == 0 or shadow_query == "bvh" or fx.area_lights or not len(lights):
        return False
    if shadow_query == "grid":
        return True
    if device != "cpu":
        return False
    if kept:
        return True
    build = (GRID_BUILD_PER_LIGHT + GRID_BUILD_PER_TRIANGLE_LIGHT * geom.triangle_count) * len(lights)
    per_frame = GRID_SAVES_PER_RAY * samples * len(lights) / threads
    return build <= per_frame * (GRID_HORIZON if frames >= 2 else 1)


def mirrors_from_rasters(reflection_query: str, fx, triangles: int, samples: int, device: str, kept: bool,
                         frames: int) -> bool:
    """The reflection rays' policy: whether the planar mirrors' virtual cameras answer them. "mirrors" asks
    for them; "auto" takes them on the CPU where rasterizing the scene beats tracing it (raster_is_cheaper,
    the first hits' rule) once they are kept: building them (probes, a raster per chain) costs about what a
    few frames' queries save, and kept for a static view they cost nothing. So a view's second frame
    (``frames``: the view's count, this one included) builds them, as a second frame with the same lights
    builds the shadow grid, for the frames after it; a moving camera's are traced. Either way the image
    is the traced one, to the bit."""
    if not fx.reflection or reflection_query == "bvh":
        return False
    if reflection_query == "mirrors":
        return True
    return device == "cpu" and raster_is_cheaper(triangles, samples, device) and (kept or frames >= 2)


@dataclass(frozen=True)
class FramePlan:
    """What a traced frame will do, decided from the scene and the options before any buffer."""

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
                     raster=not fx.culling and raster_wanted(o.primary_query, scene.triangle_count,
                                                             cam.width * cam.height * grid.per_pixel, o.device),
                     mirrors=fx.reflection and o.reflection_query != "bvh" and not fx.culling)


@dataclass(frozen=True)
class Shortcuts:
    """The shortcuts a frame takes, each with the reason in words (the stats report them): first hits
    from the Z-buffer, shadow rays from the light-space grid (or, to area lights, skipped where proven clear:
    kernels/clearance.py), reflection rays from the virtual cameras;
    ``lights`` (the kernels' light positions) and ``view`` (view_key, or None) are what the grid and
    the virtual cameras were chosen for, and ``grid_kept`` / ``mirrors_kept`` whether the caches had them."""

    raster: bool
    shadow_grid: bool
    mirrors: bool
    area_clear: bool  # area lights' shadow rays skipped where a hit is proven to see the whole light
    lights: np.ndarray
    view: tuple | None
    grid_kept: bool
    mirrors_kept: bool
    reasons: dict


def choose_shortcuts(scene, o: RenderOptions, plan: FramePlan, geom: Geometry, caches: FrameCaches) -> Shortcuts:
    """The shortcuts for this frame of ``scene`` on ``geom``, counting the frame in ``caches``' histories
    (the auto policies pay a build once a light set or a view has come back)."""
    reasons = {}
    on_surface = plan.raster and eye_on_surface(geom, camera_basis(scene.camera), caches.eye_on_surface)
    raster = plan.raster and not on_surface
    reasons["primary"] = ("the eye is on a surface the rasterizer would clip" if on_surface else
                          f"primary_query={o.primary_query}" + ("" if raster or o.primary_query != "auto" else
                                                                 " and tracing is the cheaper"))
    lights = geom.light_positions(scene)
    traces_shadows = plan.fx.shadows and geom.triangle_count > 0
    frames = caches.light_history.record(lights) if traces_shadows else 0
    grid_kept = kept_shadow_grid(caches.shadow_grids, lights) is not None
    grid = shadows_from_grid(o.shadow_query, plan.fx, geom, lights, plan.samples, plan.threads, o.device, frames,
                             grid_kept)
    reasons["shadows"] = (f"shadow_query={o.shadow_query}" + (f", frame {frames} with these lights" if traces_shadows
                                                               else ", no shadow rays"))
    area_clear = traces_shadows and plan.fx.area_lights and o.shadow_query != "bvh"
    if traces_shadows and plan.fx.area_lights:
        reasons["shadows"] += (", traced: the grid serves point lights, and the scene has area lights"
                               + (", whose rays are skipped where a hit is proven to see the whole light"
                                  if area_clear else ""))
    mirrors, view, mirrors_kept = False, None, False
    if plan.mirrors:
        view = view_key(scene, geom, plan.fx)
        views = caches.view_frames.record(view)
        mirrors_kept = kept_mirror_frame(caches, view) is not None
        mirrors = mirrors_from_rasters(o.reflection_query, plan.fx, geom.triangle_count, plan.samples, o.device,
                                       mirrors_kept, views)
        reasons["reflections"] = f"reflection_query={o.reflection_query}, frame {views} of this view"
    else:
        reasons["reflections"] = (f"reflection_query={o.reflection_query}" if plan.fx.reflection and not plan.fx.culling
                                  else "single-sided materials: reflections traced" if plan.fx.culling
                                  else "no reflection rays")
    return Shortcuts(raster, grid, mirrors, area_clear, lights, view, grid_kept, mirrors_kept, reasons)
