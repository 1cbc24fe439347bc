"""A grad=True frame's record made by its own trace (kernels/record.py): the plan the recording frame
follows, and the record's arrays, handed to the trace kernel and then to backward() as FirstHits."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .._warp import wp
from ..kernels import NO_RAY, GradRecord, camera_data, empty_aov_buffers, empty_record, make_trace_kernel
from ..scene import camera_basis, scene_effects
from .grad import FirstHits, _words, area_samples, ray_levels, record_tree
from .launch import launch_bands
from .mirrors import empty_mirrors
from .zbuffer import empty_fragments


def records_in_trace(fx) -> bool:
    """Whether a grad=True frame's record is its trace's: a chain of rays (no glass: the ray tree is
    recorded level by level, image/grad.py's record_tree)."""
    return not fx.refraction


def recording_effects(scene, fx, switched=None, mirrored=()):
    """The effects of a grad=True frame that records as it traces: ``fx`` with those the record needs though
    the scene's values leave them out, each adding exactly 0 to the image (so it is the plain frame's to the
    bit): shadow rays where the scene asks for shadows but no light or colour would dim (a light of colour
    0: its derivative is the shadowed one's), the light loop where there are lights (a kd and ks of 0
    everywhere: their derivative is not 0), and the mirror code where a reflectivity of 0 is named
    (``mirrored``: its rays followed with weight 0). Effects switched off (``switched``, the caller's
    options' effects.switched_on) stay off."""
    called = scene_effects(scene)
    wanted = switched is None or "shadows" in switched
    unlit = bool(scene.lights) and not (fx.diffuse or fx.specular)  # no light loop to record its tests in
    return replace(fx, shadows=fx.shadows or (scene.render.shadows and wanted and not called.shadows),
                   diffuse=fx.diffuse or unlit, reflection=fx.reflection or bool(mirrored))


def recording_plan(scene, plan, switched=None, mirrored=()):
    """The FramePlan of a grad=True frame that records as it traces: ``plan`` with recording_effects' effect
    set, over the ray levels the record holds (render.max_depth where mirror rays are followed)."""
    fx = recording_effects(scene, plan.fx, switched, mirrored)
    return replace(plan, fx=fx, max_depth=ray_levels(scene, fx, mirrored))


def record_arrays(scene, geom, data, fx, levels: int, device: str, mirrored=(), switched=None) -> tuple[GradRecord,
                                                                                                     FirstHits]:
    """The record's arrays for a recording frame (``plan``: recording_plan's), as the trace kernel writes them
    (GradRecord) and as backward() reads them (FirstHits, the same arrays): per camera ray and level, the face
    (NO_RAY until a ray reaches that level), barycentrics, direction, each Whitted light's visibility, the
    emitter met (-1 until one is) and the area-light points seen; ``fx`` and ``levels``: the recording frame's
    effects (recording_effects) and ray levels."""
    cam = scene.camera
    k = math.isqrt(scene.render.spp) if fx.supersampling else 1
    n, L, D = cam.width * cam.height * k * k, len(scene.whitted_lights), levels
    words = _words(area_samples(scene)) if fx.area_lights else 0
    r = GradRecord()
    r.face = wp.full(n * D, NO_RAY, dtype=int, device=device)
    r.bary = wp.empty(n * D, dtype=wp.vec2, device=device)
    r.dirs = wp.empty(n * D, dtype=wp.vec3, device=device)
    r.visible = wp.zeros(max(n * D * L, 1), dtype=int, device=device)
    r.emit = wp.full(max(n * D, 1) if words else 1, -1, dtype=int, device=device)
    r.area_bits = wp.zeros(max(n * D * words, 1), dtype=int, device=device)
    r.mirrored = wp.array(np.asarray([int(m in mirrored) for m in geom.material_names] or [0], np.int32),
                          dtype=int, device=device)
    r.levels, r.lights, r.words = D, L, words
    reflects = scene.render.max_depth > 1 and (switched is None or "reflection" in switched)
    hits = FirstHits(r.face, r.bary, r.dirs, r.visible, cam.width, cam.height, L, D, fx.smooth, k * k,
                     fx.light_model, fx.texture, r.emit, r.area_bits, words, data.area if words else None,
                     tuple(mirrored), reflects, fx.vertex_color)
    return r, hits


def record_first_hits(scene, geom, data, fx, device: str, threads: int = 1, bands: int = 1, pool=None,
                      switched=None, mirrored=()):
    """The record of a frame of ``scene`` on ``geom`` (its tables ``data``) without its image: the trace
    kernel's recording variant over every camera ray (render.spp a pixel, the tracer's strata), every query
    the BVH's, in ``bands`` bands on ``threads`` threads (``pool``: the Renderer's); with glass, the ray tree
    level by level (record_tree). What Renderer.render(grad=True) records, for tests and tools that replay a
    frame by hand. ``switched``: the effects the caller's options leave on (None: every one); ``mirrored``:
    the materials whose mirror rays are recorded whatever their k_r (grad.mirrored_materials)."""
    if not records_in_trace(fx):
        return record_tree(scene, geom, data, fx, device, threads, bands, pool, switched, mirrored)
    fx = recording_effects(scene, fx, switched, mirrored)
    levels = ray_levels(scene, fx, mirrored)
    rec, hits = record_arrays(scene, geom, data, fx, levels, device, mirrored, switched)
    cam = scene.camera
    pixels = cam.width * cam.height
    image = wp.empty(pixels, dtype=wp.vec3, device=device)
    counts = wp.empty(pixels, dtype=wp.vec3i, device=device)
    kernel = make_trace_kernel(fx, record=True)
    c = camera_data(camera_basis(cam), geom.eye_offset(cam.eye))
    frags, mirrors, aovs = empty_fragments(device), empty_mirrors(device), empty_aov_buffers(device)
    launch_bands(kernel, lambda first: [data, c, levels, math.isqrt(hits.samples), first, cam.width, 1, frags,
                                        mirrors, aovs, rec, image, counts], pixels, threads, bands, device, pool=pool)
    return hits


__all__ = ["empty_record", "record_arrays", "record_first_hits", "recording_plan", "records_in_trace"]
