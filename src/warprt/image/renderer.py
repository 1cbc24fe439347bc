"""Render a Scene: a Renderer owns one scene's frames (the device, the Geometry with its BVH, the frame
caches, the parameters changed between frames); render() is one frame of a new Renderer. A traced frame
plans once (plan.py: FramePlan, then Shortcuts), runs named phases (geometry, shadow grid, virtual
cameras, kernel, raster, trace) that each return a typed result, and fills the stats from them at the end."""

from __future__ import annotations

import weakref
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace

import numpy as np

from .._warp import init_warp, wp
from ..geometry import Geometry, ShadowGridBuild, light_strata, shadow_grid
from ..kernels import (aov_buffers, aov_bytes, aov_sums, camera_data, empty_aov_buffers, empty_record, make_shade_kernel,
                       make_trace_kernel, raster_kernel, total_kernel)
from ..errors import ArgumentError
from ..options import RenderOptions
from ..scene import (EffectSet, camera_basis, drawn_objects, switched_on, validate_camera, validate_scene, validate_view,
                     zbuffer_effects)
from ..timing import timed
from .adaptive import adaptive_spp, refine
from .aovs import finish_aovs
from .caches import SHADOW_GRIDS_KEPT, FrameCaches
from .grad import backward as grad_backward
from .grad_edges import EdgeFrame
from .grad_params import mirrored_materials, named_parameters, refusal as grad_refusal
from .grad_record import check_record_memory, record_arrays, recording_plan
from .launch import band_pool, bands_of, launch_bands, launch_plan
from .memory import check_frame_memory, frame_estimate, frame_memory
from .mirrors import MirrorFrame, empty_mirrors, mirror_frame
from .params import SceneParameters, object_poses
from .plan import FramePlan, Shortcuts, choose_shortcuts, plan_frame
from .samples import sample_grid
from .stats import RenderResult, RenderStats
from .zbuffer import ZBuffer, culled_faces, empty_fragments

# Pixel order: bands walk the image in 8x8 tiles, so the rays of a band stay close together and reuse
# the BVH nodes in cache (benchmarks/ATTEMPTS.md compares it with row-major order).
PIXEL_TILE = (8, 8)


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
    record: bool = False  # a grad=True frame's: the trace writes the gradient's record

    @property
    def name(self) -> str:
        return (f"trace_{self.fx.variant}" + ("_zprimary" if self.raster_primary else "")
                + ("_gshadow" if self.shadow_grid else "") + ("_mreflect" if self.mirrors else "")
                + ("_aov_" + "_".join(self.aovs) if self.aovs else "") + ("_record" if self.record else ""))

    def kernel(self):
        return make_trace_kernel(self.fx, raster_primary=self.raster_primary, stack=self.stack,
                                 report_truncated=self.report_truncated, aovs=self.aovs,
                                 shadow_grid=self.shadow_grid, mirrors=self.mirrors, record=self.record)


@dataclass
class TracedFrame:
    """What the trace phase returns: the image, the truncated weights (report_truncated), the rays per
    kind summed over the pixels, the AOV buffers, how many reflection rays the virtual cameras decided,
    and the bytes of the frame's buffers."""

    image: np.ndarray
    truncated: np.ndarray | None
    per_kind: np.ndarray
    buffers: object
    mirrors_decided: int
    nbytes: int


def check_finite(image: np.ndarray, what: str = "render"):
    """The renderer checks its own output: a NaN or Inf pixel is a bug, never an image."""
    bad = ~np.isfinite(image)
    if bad.any():
        rows, cols = np.nonzero(bad.any(-1))
        raise RuntimeError(f"{what} produced {len(rows)} non-finite pixels (first at row {rows[0]}, column {cols[0]})")


def _object_keys(objects) -> list:
    """What a Geometry is built from, per object: the object, its arrays (by identity), material and
    smoothness. Compared with objects_match, never hashed, so an id cannot be reused while it is kept."""
    return [(o, o.vertices, o.faces, o.material, o.smooth, o.normals, o.uv, o.colors) for o in objects]


def objects_match(a: list, b: list, but_vertices: bool = False, but_colors: bool = False) -> bool:
    """Whether two _object_keys lists name the same objects and arrays (all but the vertices, with
    ``but_vertices``, whose shape must still agree; all but the objects and their vertex colours, with
    ``but_colors``, the colours present on the same objects and of the same shape)."""
    if len(a) != len(b):
        return False
    for x, y in zip(a, b):
        same = [x[i] is y[i] for i in (2, 5, 6)] + [x[3] == y[3], x[4] == y[4]]
        if but_colors:
            same += [x[1] is y[1], x[7] is y[7] or (x[7] is not None and y[7] is not None and x[7].shape == y[7].shape)]
            if not all(same):
                return False
            continue
        same.append(x[7] is y[7])
        if but_vertices:
            same.append(x[1].shape == y[1].shape)
        else:
            same += [x[0] is y[0], x[1] is y[1]]
        if not all(same):
            return False
    return True


def geometry_reason(geom: Geometry, eye) -> str:
    """Where ``eye`` lies in the region ``geom``'s BVH covers, in words for the stats."""
    moved = float(np.abs(np.asarray(eye, np.float64) - geom.origin).max())
    if moved == 0.0:
        return "eye at the BVH's origin (an eye beyond the region one built at the objects' centre covers)"
    share = moved / geom.eye_reach if geom.eye_reach > 0 else float("inf")
    return f"eye {moved:.4g} from the BVH's origin on its farthest axis, {share:.2f} of the {geom.eye_reach:.4g} its padding covers"


class Renderer:
    """Renders frames of one scene and owns what they share: the device, the Geometry (the triangles in
    float32 and their BVH), the frame caches (FrameCaches: shadow grids, virtual cameras, the histories
    their policies read) and the scene's parameters (``params``). A frame is the image a fresh render()
    of the same scene gives, to the bit, whatever frames came before it.

        r = warprt.Renderer(scene, spp=...)          # options: RenderOptions' fields
        image, stats = r.render()
        r.params["materials.red.kd"] = [0.9, 0.1, 0.1]
        image, stats = r.render()                    # the triangles and the BVH kept

    ``geometry``: a Geometry built for this scene, used as it is for every frame (tests and benchmarks)."""

    def __init__(self, scene, options: RenderOptions | None = None, *, geometry: Geometry | None = None, **kwargs):
        self.options = RenderOptions.of(options, kwargs, "Renderer")
        self.caches = FrameCaches()
        self._given = geometry
        self._geometry: Geometry | None = None
        self._built_from: list = []  # _object_keys of the objects self._geometry holds
        self._scene, self._checked, self._checked_for = None, None, None
        self._pool: ThreadPoolExecutor | None = None  # the frames' band threads, from the first that needs them
        self._first_hits = None  # (scene, Geometry, grad_record.Record) of the last grad=True frame, for backward()
        self._record = None  # that frame's Record: its arrays taken again by the next grad frame of their size
        self._record_used = None  # glass: the entries its rays used per (band, level), for the next frame's regions
        self._grad_frames = 0  # the grad=True frames rendered: grad_frame's number
        self._edge_frame = None  # its EdgeFrame (the plain frame's effects, stack, levels), for backward(edges=True)
        self._pool_threads = 0
        # The objects' poses set through params (params.Pose), by index in scene.objects: each one that
        # object's while its vertices are the array the pose made (set_scene lets the others go).
        self.poses: dict = {}
        self.set_scene(scene)

    def close(self):
        """Stop the threads the frames' bands ran on (a next frame starts them again) and let the last grad
        frame's record go (backward() then needs a new one). ``with warprt.Renderer(scene) as r:`` closes at
        the end; a Renderer let go closes when collected."""
        self._first_hits = self._record = self._record_used = None
        if self._pool is not None:
            self._pool.shutdown(wait=True)  # idle threads: they end at once
            self._pool = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _bands_pool(self, threads: int) -> ThreadPoolExecutor | None:
        """The pool a frame's bands run on where they run on several CPU threads: kept from frame to frame,
        since handing bands to threads already started is what a small frame can afford
        (benchmarks/ATTEMPTS.md, "A Renderer's threads")."""
        if threads <= 1 or self.options.device != "cpu":
            return None
        if self._pool is None or self._pool_threads != threads:
            self.close()
            self._pool, self._pool_threads = band_pool(threads), threads
            weakref.finalize(self, self._pool.shutdown, wait=False)
        return self._pool

    @property
    def scene(self):
        """The scene the next frame renders (set_scene, or changed through params)."""
        return self._scene

    def _centres_scene(self):
        """The scene at one sample a pixel (its centre) that an adaptive frame traces first (image/adaptive.py),
        kept while the scene is the same object: the frame caches then see one scene from frame to frame."""
        kept = getattr(self, "_centres", None)
        if kept is None or kept[0] is not self._scene:
            self._centres = kept = (self._scene, self._scene.with_render(spp=1))
        return kept[1]

    @property
    def geometry(self) -> Geometry | None:
        """The Geometry of the last frame (None before the first)."""
        return self._given if self._given is not None else self._geometry

    @property
    def grad_frame(self) -> int | None:
        """The number of the grad=True frame backward() differentiates now, which every later frame changes (None:
        none to differentiate, after a plain frame or close()): who holds an image of a grad frame compares it
        before backward(), whose record a later frame replaces (warprt.torch)."""
        return self._grad_frames if self._first_hits is not None else None

    @property
    def params(self):
        """The scene's parameters by name, as NumPy values: set one and the next frame renders the changed
        scene (image/params.py lists the names)."""
        return SceneParameters(self)

    def set_scene(self, scene, checked: bool = False):
        """Render ``scene`` from the next frame on, checked (validate_scene; only what its camera and
        render settings change where its lights, materials and objects are the last scene's, validate_view)
        unless ``checked`` says its reader has done so (load_scene, with_overrides). The Geometry and the
        caches stay while the objects are the same objects and the eye keeps the Geometry's frame origin."""
        if not checked:
            content = (list(scene.lights), list(scene.materials.items()), _object_keys(scene.objects))
            if self._checked is not None and self._same_content(content):
                validate_view(scene, self._checked)
            else:
                self._checked, self._checked_for = validate_scene(scene), content
        self._scene = scene
        self.poses = {i: p for i, p in self.poses.items()
                      if i < len(scene.objects) and scene.objects[i].vertices is p.posed}

    def _same_content(self, content) -> bool:
        lights, materials, objects = self._checked_for
        return (len(lights) == len(content[0]) and all(a is b for a, b in zip(lights, content[0]))
                and len(materials) == len(content[1])
                and all(a[0] == b[0] and a[1] is b[1] for a, b in zip(materials, content[1]))
                and objects_match(objects, content[2]))

    def render(self, *, progress=None, grad: bool | list = False) -> RenderResult:
        """One frame of the scene, with the Whitted tracer (or, algorithm="zbuffer", by rasterization with
        the same local shading); ``progress``: a progress.Progress told of each band done. With ``grad``,
        the same image, and what backward() needs is recorded (image/grad.py says what is differentiated).
        ``grad=[names]`` (r.params names) is grad=True with those parameters' effects recorded even where
        their values switch them off: a named ``materials.<name>.reflectivity`` of 0 has its mirror rays
        recorded (over render.max_depth levels), so that backward() gives its derivative, the mirrored
        colour; backward() refuses a reflectivity of 0 the frame did not record so."""
        self._first_hits = None
        named = list(grad) if isinstance(grad, (list, tuple)) else []
        grad = bool(grad) or isinstance(grad, (list, tuple))
        if grad and self.options.algorithm == "zbuffer":
            raise ArgumentError("render", "grad", "gradients follow the ray tracer: use algorithm='raytrace'")
        if self.options.algorithm == "zbuffer":
            return self._render_zbuffer(progress)
        init_warp()
        scene, o, times = self._scene, self.options, {}
        with timed(times, "total"):
            plan = plan_frame(scene, o)
            refine_k, effects = adaptive_spp(scene, plan.fx, grad), plan.fx
            if refine_k:  # traced at the pixels' centres, then refined where they differ (image/adaptive.py)
                scene = self._centres_scene()
                plan = plan_frame(scene, o)
            switched, mirrored = _grad_frame_checked(scene, o, plan, named) if grad else (None, ())
            edge_frame = EdgeFrame(plan.fx, plan.stack, plan.max_depth, plan.threads)
            if grad:  # the trace writes the record as it goes
                plan = recording_plan(scene, plan, switched, mirrored)
            pool = self._bands_pool(plan.threads)
            estimate = frame_estimate(scene, plan.grid.per_pixel, plan.raster)
            check_frame_memory(scene, _without_geometry(estimate, self._given), o.device)  # before any buffer
            with timed(times, "bvh"):
                geom, geometry_info = self._frame_geometry(scene)
            shortcuts = choose_shortcuts(scene, o, plan, geom, self.caches)
            grid = self._shadow_grid(geom, shortcuts, times)
            data = geom.scene_data(scene, grid.grid if grid is not None else None, light_strata(scene, plan.fx),
                                   shortcuts.area_clear)
            mirrors = self._virtual_cameras(scene, plan, geom, data, shortcuts, times, pool)
            used = mirrors if mirrors is not None and mirrors.mirrors is not None else None  # None: no chain rasterized
            variant = TraceVariant(plan.fx, shortcuts.raster, plan.stack, o.report_truncated, o.aovs,
                                   grid is not None and grid.grid is not None, used is not None, grad)
            with timed(times, "compile"):
                kernel = variant.kernel()
                wp.load_module(kernel.module, device=o.device)
                if shortcuts.raster or used is not None:
                    wp.load_module(raster_kernel.module, device=o.device)
            zb = None
            if shortcuts.raster:
                with timed(times, "raster"):
                    zb = ZBuffer(scene, geom, replace(plan.fx, shadows=False, reflection=False), device=o.device)
                    zb.rasterize(plan.threads, plan.bands, pool=pool)
            hits = None
            if grad:
                hits = record_arrays(scene, geom, data, plan.fx, plan.max_depth, o.device,
                                     bands_of(plan.n_pixels, plan.bands), mirrored, switched, self._record,
                                     self._record_used)
            with timed(times, "trace"):
                frame = _trace(scene, o, plan, geom, data, kernel, zb, used, progress, pool, hits)
                while hits is not None and hits.overflowed():  # glass's regions too small: made larger, again
                    self._record_used = hits.used()
                    hits = record_arrays(scene, geom, data, plan.fx, plan.max_depth, o.device, hits.bands, mirrored,
                                         switched, hits, self._record_used)
                    frame = _trace(scene, o, plan, geom, data, kernel, zb, used, progress, pool, hits)
            result = _finish(scene, o, plan, geom, frame)
            if refine_k:
                with timed(times, "refine"):  # the frame's own effect set: its spread lights' table too
                    fine = data if not effects.light_spread else geom.scene_data(
                        self._scene, strata=light_strata(self._scene, effects), clearance=shortcuts.area_clear)
                    image, extra, refined = refine(self._scene, replace(plan, fx=effects), geom, fine, result[0],
                                                   refine_k, o.device, pool)
                result, frame = (image, result[1]), replace(frame, per_kind=frame.per_kind + extra)
            if grad:
                self._keep_grad_frame(scene, geom, hits, edge_frame)
        stats = _frame_stats(scene, o, plan, shortcuts, variant, geom, geometry_info, grid, mirrors, zb, frame, times)
        stats.memory["estimate"] = estimate
        if refine_k:
            stats.spp, stats.effects, stats.adaptive = self._scene.render.spp, str(effects), {
                "threshold": scene.render.adaptive, "refined": refined, "share": refined / max(plan.n_pixels, 1)}
        return RenderResult(result[0], stats, result[1])

    def _keep_grad_frame(self, scene, geom, hits, edge_frame):
        """What backward() reads of a grad=True frame, and what the next grad frame takes again (its record)."""
        self._record = hits
        if hits.tree:
            self._record_used = hits.used()
        self._first_hits = (scene, geom, hits)
        self._grad_frames += 1
        self._edge_frame = edge_frame

    def backward(self, d_image, wrt=None, *, arrays: bool = False, edges: bool = True) -> dict:
        """d(sum(d_image * image)) / d(param) at the last frame, rendered with grad=True, for each name in
        ``wrt`` (r.params names: materials.<name>.ka | kd | ks | shininess | reflectivity | ka_texture |
        kd_texture | ks_texture (image textures' texels) | emission, a dielectric's ior | transmittance |
        absorption (through the ray tree), lights.<i>.color | position | direction | radiance | center | normal |
        size | radius | u | v (a shape light's own shape), objects.<name>.vertices | translation | rotation (its pose) | colors (vertex
        colours), camera.eye | center | up | fovy;
        all of them by default, less a reflectivity of 0 the frame did not record): a dict of float64 NumPy
        arrays shaped as the parameters; kd's carries ka's where ka follows kd (as r.params keeps it following).
        A reflectivity of 0 named here is refused unless the frame was rendered with grad=[that name] (its
        mirror rays recorded). ``d_image``: the derivative of a loss with respect to the image,
        (height, width, 3), a NumPy or Warp array. With ``arrays``, each gradient a float32 wp.array on the
        renderer's device (a () parameter's of shape (1,)), to hand to a wp.Tape's backward(grads={...}) in
        the Warp program that made the parameter (docs/gradients.md).

        By default (``edges``) the derivative is that of the box-filtered pixel integral (the image ``spp``
        converges to): the interior derivative, each ray's face and each shadow ray's answer held, plus the
        boundary term of the edges the named parameters move: those camera rays see (silhouettes, occlusion
        edges and flat creases moving with objects.<name>.vertices, poses and the camera: image/grad_edges.py)
        and with shadows traced hard shadows' edges (moving with the occluders, the receivers, a light's
        position or direction, an area light's shape and the camera: image/grad_shadow_edges.py), both seen
        directly and in planar mirrors (render.max_depth > 1: through each chain of mirror planes a camera ray
        may follow, moving with the mirrors' vertices too: image/grad_mirror_edges.py), and what glass's ray tree
        and curved (smooth) mirrors show (image/grad_glass_edges.py: moving with other objects, the lights, the
        camera, their own vertices and pose and a glass's ior), a checker texture's squares, a hard spot's cone and
        an area light's soft shadows among them. Where the named parameters move an edge not covered yet (more
        chains of mirrors than grad_mirror_edges.MAX_CHAINS; with glass or a curved mirror, more ray levels than
        grad_glass_edges.MAX_GLASS_DEPTH, 12) it is refused in one line naming ``edges``; ``edges=False`` gives
        the interior derivative alone, as before (docs/gradients.md)."""
        if self._first_hits is None:
            raise ArgumentError("backward", "render", "no frame was rendered with grad=True since the last change")
        scene, geom, hits = self._first_hits
        if scene is not self._scene:
            raise ArgumentError("backward", "render", "the scene changed since render(grad=True): render it again")
        out = grad_backward(scene, geom, hits, d_image, wrt, self.options.device, object_poses(scene, self.poses),
                            edges, self._edge_frame)
        if arrays:  # computed on the device, read back per parameter (its slices and the texture's flip)
            out = {name: wp.array(np.asarray(g, np.float32).reshape(np.shape(g) or (1,)), dtype=float,
                                  device=self.options.device) for name, g in out.items()}
        return out

    # ---- Phases -------------------------------------------------------------------------------------

    def _frame_geometry(self, scene, build_bvh: bool = True) -> tuple[Geometry, dict]:
        """The Geometry for a frame of ``scene`` and how it came: given, reused (the same objects, and an
        eye that keeps its frame origin, so the image is a fresh build's to the bit), refit (only vertices
        moved: Geometry.move_vertices) or built; the caches go with a Geometry that is replaced or refit."""
        eye = scene.camera.eye
        if self._given is not None:
            return self._given, given_geometry(self._given, eye)
        keys, geom = _object_keys(drawn_objects(scene)), self._geometry
        if geom is not None and (geom.mesh is not None or not build_bvh):
            if objects_match(self._built_from, keys):
                if np.array_equal(geom.origin_for(eye), geom.planned_origin) and geom.covers(eye):
                    return geom, {"bvh": "reused", "reason": geometry_reason(geom, eye)}
                reason = f"the eye left the region the kept BVH covers ({geometry_reason(geom, eye)})"
            elif objects_match(self._built_from, keys, but_vertices=True) and geom.move_vertices(scene):
                self._built_from = keys
                self.caches.clear()
                return geom, {"bvh": "refit", "reason": "the objects' vertices moved"}
            elif objects_match(self._built_from, keys, but_colors=True) and \
                    np.array_equal(geom.origin_for(eye), geom.planned_origin) and geom.covers(eye):
                geom.recolor(scene)  # only vertex colours changed: written over the kept ones
                self._built_from = keys
                self.caches.clear()
                return geom, {"bvh": "reused", "reason": "only the objects' vertex colours changed"}
            else:
                reason = "the objects changed"
        else:
            reason = "no geometry was built for these objects"
        self._geometry = Geometry(scene, device=self.options.device, build_bvh=build_bvh)
        self._built_from = keys
        self.caches.clear()
        return self._geometry, {"bvh": "built", "reason": reason}

    def _shadow_grid(self, geom: Geometry, shortcuts: Shortcuts, times: dict) -> ShadowGridBuild | None:
        """The light-space grid the shortcuts chose, built or kept (None: traced shadow rays). Its .grid is
        None where the build fell back (over the memory budget, every light with geometry at it)."""
        if not shortcuts.shadow_grid:
            return None
        with timed(times, "shadow_grid"):
            return shadow_grid(geom, shortcuts.lights, memo=self.caches.shadow_grids, keep=SHADOW_GRIDS_KEPT)

    def _virtual_cameras(self, scene, plan: FramePlan, geom: Geometry, data, shortcuts: Shortcuts, times: dict,
                         pool):
        """The planar mirrors' virtual cameras the shortcuts chose, built or kept (None: reflection rays
        traced); a MirrorFrame with no chain worth a raster is reported in the stats and not used. ``data``:
        the frame's tables (the probes read the triangles and materials alone; the tracer's own tables, so
        that the Geometry's one kept set is not rebuilt twice a frame, with and without the grid)."""
        if not shortcuts.mirrors:
            return None
        o = self.options
        with timed(times, "mirrors"):
            frame, _ = mirror_frame(scene, geom, data, plan.fx, shortcuts.view, plan.threads, plan.bands, o.device,
                                    self.caches, pool)
        return frame

    def _render_zbuffer(self, progress) -> RenderResult:
        """A frame by rasterization with the tracer's local shading (no shadows, no reflections)."""
        o = self.options
        result, _ = _zbuffer_frame(self._scene, o, lambda scene: self._frame_geometry(scene, False)[0], progress,
                                   self._bands_pool(launch_plan(o.threads, o.bands, o.device)[0]))
        return result


def render(scene, options: RenderOptions | None = None, *, geometry: Geometry | None = None, progress=None,
           **kwargs) -> RenderResult:
    """One frame of ``scene``: Renderer(scene, options, geometry=geometry, **kwargs).render(progress=...),
    as ``options`` (a RenderOptions) and keyword arguments (its fields) say. ``effects`` (names) limits
    the effect set, ``disable`` removes effects; neither can add one the scene has nothing for.
    ``primary_query``, ``shadow_query`` and ``reflection_query`` say what answers the camera, shadow and
    reflection rays' queries (RenderOptions' help; "auto" by default, each the cheaper exact choice);
    the image never depends on them. With ``report_truncated``, stats.truncated is the weight per pixel
    (H, W, 3) of the reflected and refracted rays max_depth cut off. ``aovs`` (names from options.AOVS)
    come back as the result's ``.aovs``, from the camera rays' first hits; the image is the same with
    or without them. ``geometry``: a Geometry built for this scene, used as it is; ``progress``: a
    progress.Progress told of each band done. Nothing is kept for a later call: frames of one scene
    that should share a BVH and caches go through one Renderer."""
    with Renderer(scene, options, geometry=geometry, **kwargs) as r:
        return r.render(progress=progress)


def _without_geometry(estimate: dict, geometry) -> dict:
    """The estimate less the geometry when the caller hands over a Geometry already built."""
    if geometry is None:
        return estimate
    return {**estimate, "geometry": 0, "total": estimate["total"] - estimate["geometry"]}


def given_geometry(geom: Geometry, eye) -> dict:
    """How a Geometry handed to a Renderer came, if its BVH covers the eye (else a ValueError)."""
    if not geom.covers(eye):
        raise ValueError(f"the Geometry passed to render() does not cover the eye {list(eye)}: "
                         f"{geometry_reason(geom, eye)}; build one for this eye")
    return {"bvh": "given", "reason": geometry_reason(geom, eye)}


def _grad_frame_checked(scene, o: RenderOptions, plan: FramePlan, named: list) -> tuple:
    """(switched, mirrored) of a grad=True frame (the effects switched on; the materials whose mirror rays it
    records whatever their reflectivity), refused in one ArgumentError where it cannot be differentiated or its
    record would not fit in memory."""
    switched = switched_on(scene, o.effects, o.disable)
    mirrored = mirrored_materials(scene, named_parameters(scene, named), switched)
    why = grad_refusal(scene, plan.fx, mirrored)
    if why is not None:
        raise ArgumentError("render", "grad", why)
    check_record_memory(scene, plan.fx, o.device, mirrored)
    return switched, mirrored


def _trace(scene, o: RenderOptions, plan: FramePlan, geom: Geometry, data, kernel, zb, mirror_frame,
           progress, pool, rec=None) -> TracedFrame:
    """Launch the kernel over the image: the image, the truncated weights after it (report_truncated),
    each pixel's ray counts and the AOV buffers; with ``rec`` (grad_record.Record), the gradient's record too."""
    cam, device = scene.camera, o.device
    # With report_truncated the kernel writes the truncated weights after the image.
    image = wp.empty(plan.n_pixels * (2 if o.report_truncated else 1), dtype=wp.vec3, device=device)
    counts = wp.empty(plan.n_pixels, dtype=wp.vec4i if plan.fx.refraction else wp.vec3i, device=device)
    buffers = aov_buffers(o.aovs, geom, plan.n_pixels, plan.grid.side, device) if o.aovs else empty_aov_buffers(device)
    c = camera_data(camera_basis(cam), geom.eye_offset(cam.eye))
    frags = zb.fragments if zb is not None else empty_fragments(device)
    mirrors = mirror_frame.mirrors if mirror_frame is not None else empty_mirrors(device)
    tile_w, tile_h = o.pixel_tile or PIXEL_TILE
    inputs = lambda first: [data, c, plan.max_depth, plan.grid.k, first, tile_w, tile_h, frags, mirrors,  # noqa: E731
                            buffers, rec.for_band(first) if rec is not None else empty_record(device), image, counts]
    _launch_with_progress(kernel, inputs, plan.n_pixels, plan.threads, plan.bands, device, counts, progress, pool)
    pixels = image.numpy().reshape(-1, cam.height, cam.width, 3)
    return TracedFrame(image=pixels[0].copy(), truncated=pixels[1].copy() if o.report_truncated else None,
                       per_kind=counts.numpy().sum(0, dtype=np.int64),  # no int64 copy of every pixel's counts
                       buffers=buffers,
                       mirrors_decided=_total(mirrors.decided, device) if mirror_frame is not None else 0,
                       nbytes=image.capacity + counts.capacity)


def _total(values, device: str) -> int:
    """The sum of an int32 array, taken on its device: 8 bytes come back."""
    total = wp.zeros(1, dtype=wp.int64, device=device)
    wp.launch(total_kernel, dim=values.shape[0], inputs=[values, total], device=device)
    return int(total.numpy()[0])


def _finish(scene, o: RenderOptions, plan: FramePlan, geom: Geometry, frame: TracedFrame) -> tuple:
    """The image, checked, and the AOV arrays (material slots as indices in scene.materials)."""
    cam = scene.camera
    check_finite(frame.image)
    aov_arrays = {}
    if o.aovs:
        aov_arrays = finish_aovs(o.aovs, aov_sums(frame.buffers, o.aovs), plan.grid.per_pixel, geom.origin,
                                 cam.height, cam.width)
        if "material" in aov_arrays:  # the kernel's material slots, as indices in scene.materials
            slots = aov_arrays["material"]
            aov_arrays["material"] = np.where(slots >= 0, geom.material_indices(scene)[np.maximum(slots, 0)], -1).astype(np.int32)
    return frame.image, aov_arrays


def _frame_stats(scene, o: RenderOptions, plan: FramePlan, shortcuts: Shortcuts, variant: TraceVariant,
                 geom: Geometry, geometry_info: dict, grid: ShadowGridBuild | None, mirrors: MirrorFrame | None,
                 zb, frame: TracedFrame, times: dict) -> RenderStats:
    """The stats of a traced frame, from its plan and what each phase returned."""
    stats = RenderStats.begin(scene, plan.fx, threads=plan.threads, bands=plan.bands, device=o.device,
                              algorithm="raytrace", variant=variant.name, max_depth=plan.max_depth)
    stats.times.update(times)
    stats.triangles, stats.geometry = geom.triangle_count, geometry_info
    stats.primary_query = "zbuffer" if shortcuts.raster else "raytrace"
    stats.shortcuts = dict(shortcuts.reasons)
    if grid is not None:
        stats.shadow_grid = {"grid": "reused" if shortcuts.grid_kept else "built", **grid.stats}
    stats.shadow_query = "grid" if grid is not None and grid.grid is not None else "bvh"
    if mirrors is not None:
        stats.mirrors = {"rasters": "reused" if shortcuts.mirrors_kept else "built", **mirrors.stats}
    used_mirrors = mirrors is not None and mirrors.mirrors is not None
    stats.reflection_query = "mirrors" if used_mirrors else "bvh"
    k = frame.per_kind
    stats.rays = {"primary": int(k[0]), "shadow": int(k[1]), "reflection": int(k[2]),
                  "refraction": int(k[3]) if plan.fx.refraction else 0}
    stats.rays["total"] = sum(stats.rays.values())
    if used_mirrors:
        stats.mirrors.update(decided=frame.mirrors_decided, share=frame.mirrors_decided / max(stats.rays["reflection"], 1))
    stats.rays_per_second = stats.rays["total"] / max(stats.times["trace"], 1e-9)
    stats.truncated = frame.truncated
    stats.memory = frame_memory(geom, frame.nbytes, zb.nbytes if zb is not None else 0,
                                aov_bytes=aov_bytes(frame.buffers),
                                shadow_grid_bytes=stats.shadow_grid.get("bytes", 0) if stats.shadow_query == "grid" else 0,
                                mirrors_bytes=mirrors.nbytes if used_mirrors else 0)
    return stats


def _launch_with_progress(kernel, inputs, n_pixels, threads, bands, device, counts, progress, pool=None):
    """launch_bands, telling ``progress`` (a progress.Progress) of each band done and its exact ray count
    (``counts``: each pixel's, or None where there are no rays to count)."""
    on_band = None
    if progress is not None:
        # On the CPU the counts live in host memory and a finished band's counts are final; on a GPU (one
        # band: the whole image) they are read back once the band is done, which the frame does anyway.
        counts_host = counts.numpy() if counts is not None and device == "cpu" else None

        def report(first, count):
            if counts is None:
                rays = 0
            elif counts_host is not None:
                rays = int(counts_host[first:first + count].sum(dtype=np.int64))
            else:
                rays = int(counts[first:first + count].numpy().sum(dtype=np.int64))
            progress.band_done(count, rays)

        on_band = report

    try:
        if progress is not None:
            # Inside the try: a Ctrl-C landing while begin() waits for its thread to start must still
            # clear the line the thread may already have drawn.
            progress.begin(len(bands_of(n_pixels, bands)), n_pixels)
        launch_bands(kernel, inputs, n_pixels, threads, bands, device, on_band, pool)
    finally:
        if progress is not None:
            progress.end()


def render_zbuffer(scene, options: RenderOptions | None = None, *, geometry: Geometry | None = None,
                   return_faces: bool = False, progress=None, **kwargs):
    """Render ``scene`` by rasterization with the tracer's local shading (no shadows, no reflections), as
    ``options`` and keyword arguments say (RenderOptions' threads, device, effects, disable, bands and
    raster_tile, the raster tiles' side in pixels). Returns a RenderResult, and with return_faces also the
    visible face per sample (H, W, samples)."""
    if "tile" in kwargs:  # render_zbuffer's own first spelling: the raster tile (render()'s was the pixel tile)
        import warnings

        warnings.warn("render_zbuffer(): 'tile' is now 'raster_tile' ('tile' goes in the next release)",
                      DeprecationWarning, stacklevel=2)
        kwargs["raster_tile"] = kwargs.pop("tile")
    o = RenderOptions.of(options, kwargs, "render_zbuffer")
    o = o if o.algorithm == "zbuffer" else replace(o, algorithm="zbuffer")
    validate_camera(scene.camera, scene.source)
    result, zb = _zbuffer_frame(scene, o, lambda s: geometry or Geometry(s, device=o.device, build_bvh=False),
                                progress)
    return (result, zb.faces()) if return_faces else result


def _zbuffer_frame(scene, o: RenderOptions, geometry_for, progress, pool=None) -> tuple[RenderResult, ZBuffer]:
    """The Z-buffer algorithm's frame on the Geometry ``geometry_for(scene)`` gives, and its ZBuffer;
    ``pool``: the threads its bands run on (launch_bands)."""
    init_warp()
    times: dict = {}
    with timed(times, "total"):
        threads, bands = launch_plan(o.threads, o.bands, o.device)
        fx = zbuffer_effects(scene, o.effects, o.disable)
        estimate = frame_estimate(scene, sample_grid(scene, fx).per_pixel, True, algorithm="zbuffer")
        check_frame_memory(scene, estimate, o.device)
        stats = RenderStats.begin(scene, fx, threads=threads, bands=bands, device=o.device, algorithm="zbuffer",
                                  variant=f"zbuffer_{fx.variant}", max_depth=1)
        stats.rays = {"primary": 0, "shadow": 0, "reflection": 0, "refraction": 0, "total": 0}  # visibility is rasterized
        with stats.phase("geometry"):
            geom = geometry_for(scene)
            data = geom.scene_data(scene, strata=light_strata(scene, fx))
        stats.triangles = geom.triangle_count
        with stats.phase("compile"):
            kernel = make_shade_kernel(fx)
            for m in (kernel.module, raster_kernel.module):
                wp.load_module(m, device=o.device)
        with stats.phase("render"):  # project + bin + raster + shade
            zb = ZBuffer(scene, geom, fx, device=o.device, tile=o.raster_tile, track_uncertain=False)
            zb.rasterize(threads, bands, skip=culled_faces(scene, geom, zb.eye) if fx.culling else None, pool=pool)
            stats.times.update(zb.times)
            with stats.phase("shade"):
                cam = scene.camera
                image = wp.empty(cam.width * cam.height, dtype=wp.vec3, device=o.device)
                c, k, frags = camera_data(zb.basis, zb.eye), zb.k, zb.fragments
                _launch_with_progress(kernel, lambda first: [data, c, k, first, frags, image], cam.width * cam.height,
                                      threads, bands, o.device, None, progress, pool)
                out = image.numpy().reshape(cam.height, cam.width, 3).copy()
        check_finite(out, "zbuffer")
    stats.times["total"] = times["total"]
    stats.memory["estimate"] = estimate
    return RenderResult(out, stats), zb
