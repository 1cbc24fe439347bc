"""The gradient's record of a grad=True frame (grad.py says what is differentiated): its layout (FirstHits,
TreeHits), its size and the memory check, and how it is made: by the frame's own trace (recording_plan,
record_arrays: kernels/record.py's GradRecord), and for glass's ray tree level by level (record_tree)."""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .._warp import wp
from ..errors import ArgumentError
from ..kernels import NO_RAY, GradRecord, camera_data, empty_aov_buffers, make_trace_kernel
from ..kernels.grad_tree import make_tree_record_kernel, tree_camera_rays
from ..scene import camera_basis, scene_effects
from .launch import launch_bands
from .memory import available_memory, human
from .mirrors import empty_mirrors
from .zbuffer import empty_fragments


# Bytes per camera ray and level of the record (face, barycentrics, direction: 4 + 8 + 12, then 4 a light),
# and per camera ray of the replay (its colour and adjoint, the adjoint handed to the tape, and for camera
# gradients its direction made again and that one's adjoint: 5 x 12). With area
# lights, per camera ray and level: the emitter met (4) and a bit per sample point (in 4-byte words), and the
# replay's state (hit point, normal, kd, ks, weight, local colour, each with its adjoint: 2 x 6 x 12).
RECORD_BYTES_PER_LEVEL, RECORD_BYTES_PER_LIGHT, REPLAY_BYTES_PER_RAY = 24, 4, 60
AREA_RECORD_BYTES_PER_LEVEL, AREA_REPLAY_BYTES_PER_LEVEL = 4, 144


def area_samples(scene) -> int:
    """The area lights' sample points in all (render.light_samples each): the record's bits per ray level."""
    return len(scene.area_lights) * scene.render.light_samples


def ray_levels(scene, fx, mirrored=()) -> int:
    """The ray levels a grad frame records: render.max_depth where the tracer spawns mirror rays (some
    k_r > 0) or the caller named a reflectivity to differentiate (``mirrored``), else the camera ray's."""
    return scene.render.max_depth if fx.reflection or fx.refraction or mirrored else 1


def record_bytes(scene, fx, mirrored=()) -> int:
    """What render(grad=True) and backward() hold for a frame's record and replay, in bytes: per camera
    ray (width x height x spp) and ray level."""
    cam, r = scene.camera, scene.render
    rays = cam.width * cam.height * (r.spp if fx.supersampling else 1)
    levels = ray_levels(scene, fx, mirrored)  # with glass, the least: a chain (record_tree checks the tree as
    # it grows)
    per_level = RECORD_BYTES_PER_LEVEL + RECORD_BYTES_PER_LIGHT * len(scene.whitted_lights)
    if fx.area_lights:
        per_level += AREA_RECORD_BYTES_PER_LEVEL + 4 * _words(area_samples(scene)) + AREA_REPLAY_BYTES_PER_LEVEL
    return rays * (levels * per_level + REPLAY_BYTES_PER_RAY)


def _words(samples: int) -> int:
    return max(1, -(-samples // 32))


def check_record_memory(scene, fx, device: str, mirrored=()):
    """Refuse, in one line naming the budget and the settings that reduce it, a grad=True frame whose
    record would not fit in the memory this process can still take (before the frame allocates anything)."""
    need = record_bytes(scene, fx, mirrored)
    available, what = available_memory(device)
    if available is not None and need > available:
        samples = ", render.light_samples" if fx.area_lights else ""  # a bit per area-light sample and level
        raise ArgumentError("render", "grad", f"the gradient's record of this frame needs about {human(need)} "
                            f"(per camera ray and ray level), more than the {human(available)} {what}: lower "
                            f"render.spp, render.max_depth{samples} or camera.width and camera.height")


@dataclass
class FirstHits:
    """What a grad=True frame recorded: per camera ray (``samples`` per pixel, ray pixel * samples +
    sample, the tracer's strata) and ray level (``levels``: the camera ray, then the mirror rays) the
    hit's face (-1: none, NO_RAY: no ray at that level), barycentrics and ray direction, and per light
    whether the hit saw it; with area lights (``words`` > 0), the area light whose emitting side the ray met
    (``emit``, -1: none) and a bit per area-light sample point the hit sees (``area_bits``, ``words`` int32s
    a level)."""

    face: wp.array
    bary: wp.array
    dirs: wp.array
    visible: wp.array
    width: int
    height: int
    lights: int
    levels: int
    smooth: bool
    samples: int = 1
    light_model: bool = False  # shading's general light model (spot, directional, falloff), as the frame's
    texture: bool = False  # textured colours, as the frame's
    emit: wp.array | None = None
    area_bits: wp.array | None = None
    words: int = 0  # 0: no area lights
    area: object = None  # the frame's AreaLights table (its sample points, normals and areas), as recorded
    mirrored: tuple = ()  # the materials whose mirror rays were recorded whatever their k_r (mirrored_materials)
    reflects: bool = False  # whether the frame could reflect (render.max_depth > 1, reflection not switched off)
    vertex_color: bool = False  # ka and kd times the vertex colours, as the frame's


def records_in_trace(fx) -> bool:
    """Whether a grad=True frame's record is its trace's: a chain of rays (no glass: the ray tree is
    recorded level by level, record_tree)."""
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


def record_arrays(scene, geom, data, fx, levels: int, device: str, mirrored=(), switched=None,
                  reuse: GradRecord | None = None) -> tuple[GradRecord, FirstHits]:
    """The record's arrays for a recording frame, as the trace kernel writes them (GradRecord) and as
    backward() reads them (FirstHits, the same arrays): per camera ray and level, the face (NO_RAY until a ray
    reaches that level), barycentrics, direction, each Whitted light's visibility, the emitter met and the
    area-light points seen (all but the faces and the points seen are written at every hit and read only
    there: not filled). ``fx`` and ``levels``: the recording frame's effects (recording_effects) and ray
    levels. ``reuse``: the last grad frame's record, whose arrays are taken again where their sizes are this
    frame's (its FirstHits is then stale: the Renderer drops it when a frame starts)."""
    cam = scene.camera
    k = math.isqrt(scene.render.spp) if fx.supersampling else 1
    n, L, D = cam.width * cam.height * k * k, len(scene.whitted_lights), levels
    words = _words(area_samples(scene)) if fx.area_lights else 0
    sizes = (n * D, max(n * D * L, 1), max(n * D, 1) if words else 1, max(n * D * words, 1))
    if reuse is not None and (reuse.face.shape[0], reuse.visible.shape[0], reuse.emit.shape[0],
                              reuse.area_bits.shape[0]) == sizes and reuse.face.device == wp.get_device(device):
        r = reuse
        r.face.fill_(NO_RAY)
        if words:
            r.area_bits.zero_()
    else:
        r = GradRecord()
        r.face = wp.full(sizes[0], NO_RAY, dtype=int, device=device)
        r.bary = wp.empty(sizes[0], dtype=wp.vec2, device=device)
        r.dirs = wp.empty(sizes[0], dtype=wp.vec3, device=device)
        r.visible = wp.empty(sizes[1], dtype=int, device=device)
        r.emit = wp.empty(sizes[2], dtype=int, device=device)
        r.area_bits = wp.zeros(sizes[3], dtype=int, device=device)
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


# --- Glass: Whitted's full ray tree (kernels/grad_tree.py) --------------------------------------------------

# Bytes per ray of the recorded tree (any level): the record's face, medium, camera ray, child kind and the
# children's places (4 + 4 + 4 + 4 + 8), 4 a light; the replay's origin, direction, weight and segment start,
# each with its adjoint (2 x 4 x 12); and while recording, the level's rays and children and their reaches
# (12 x 12 + 12 + 8).
# With area lights, per ray: the emitter met (4) and a bit per sample point (in 4-byte words), and the
# replay's state (hit point, normal, kd, ks, weight, local colour, direction, each with its adjoint: 2 x 7 x 12).
TREE_BYTES_PER_RAY, TREE_RECORD_BYTES_PER_RAY, TREE_AREA_BYTES_PER_RAY = 24 + 96, 164, 4 + 168


@dataclass
class TreeLevel:
    """One level of a recorded ray tree: per ray of its list (``count``), the hit's face (-1: none), which
    lights it sees (``lights`` ints a ray), its medium (-1: air), its camera ray, what it spawns
    (grad_tree.CHILD_*) and its children's places in the next level's list (reflected, transmitted; -1:
    none); the first level's directions too (the camera rays', as the forward traced them); with area
    lights, the emitter each ray met (-1: none) and a bit per sample point its hit sees (TreeHits.words
    int32s a ray)."""

    face: wp.array
    visible: wp.array
    medium: wp.array
    ray_of: wp.array
    kind: wp.array
    child: wp.array
    count: int
    dirs: wp.array | None = None
    emit: wp.array | None = None
    area_bits: wp.array | None = None


@dataclass
class TreeHits:
    """What a grad=True frame with glass recorded: the forward's ray tree per camera ray, level by level
    (``tree``, TreeLevels: the camera rays, then each level's children in their parents' order), the
    counterpart of FirstHits for replay() and backward(). ``absorption``: whether the replay applies
    Beer's law (unless switched off, also where every absorption is 0: its derivative is not)."""

    tree: list
    width: int
    height: int
    lights: int
    levels: int  # render.max_depth
    smooth: bool
    samples: int = 1
    light_model: bool = False
    texture: bool = False
    absorption: bool = True
    words: int = 0  # 0: no area lights
    area: object = None  # the frame's AreaLights table, as recorded
    mirrored: tuple = ()  # the opaque materials whose mirror rays were recorded whatever their k_r
    vertex_color: bool = False  # ka and kd times the vertex colours, as the frame's
    reflects: bool = True  # its levels could hold mirror rays

    @property
    def rays(self) -> int:
        """The rays the tree holds, all levels."""
        return sum(level.count for level in self.tree)


def _tree_too_big(scene, need: int, device: str):
    """The one error for a tree whose record would not fit, naming the settings that make it smaller."""
    available, what = available_memory(device)
    if available is not None and need > available:
        samples = ", render.light_samples" if scene.area_lights else ""
        raise ArgumentError("render", "grad", f"the gradient's record of this frame's ray tree (glass) needs about "
                            f"{human(need)} or more, more than the {human(available)} {what}: lower render.max_depth "
                            f"(each level may double the rays), render.spp{samples} or camera.width and camera.height")


def record_tree(scene, geom, data, fx, device: str, threads: int = 1, bands: int = 1, pool=None,
                switched=None, mirrored=()) -> TreeHits:
    """record_first_hits for a scene with glass: the forward's ray tree, one launch of grad_tree's record
    kernel a level (in ``bands`` bands on ``threads`` threads), the children of each level compacted on the
    host into the next level's list (the reflected before the transmitted, parents in order); the rays'
    origins, directions, weights and media are the forward's to the bit (the same functions make them). Where
    a dielectric's transmittance is 0 the tree also holds the refracted rays the forward leaves out (weight
    0: the image is the same), whose radiance is that transmittance's derivative.
    The memory the tree takes is checked as it grows (_tree_too_big)."""
    cam, L, D = scene.camera, len(scene.whitted_lights), scene.render.max_depth
    k = math.isqrt(scene.render.spp) if fx.supersampling else 1
    n = cam.width * cam.height * k * k
    wanted = switched is None or "shadows" in switched
    shadows = fx.shadows or (scene.render.shadows and wanted and not scene_effects(scene).shadows)
    absorb = fx.absorption or ((switched is None or "absorption" in switched) and not scene_effects(scene).absorption)
    c = camera_data(camera_basis(cam), geom.eye_offset(cam.eye))
    v3 = lambda m: wp.zeros(max(m, 1), dtype=wp.vec3, device=device)  # noqa: E731
    i1 = lambda m: wp.zeros(max(m, 1), dtype=int, device=device)  # noqa: E731
    orig, dirs, weight, start, medium = v3(n), v3(n), v3(n), v3(n), i1(n)
    launch_bands(tree_camera_rays, lambda first: [data, c, k, first, orig, dirs, weight, start, medium], n, threads,
                 bands, device, pool=pool)
    reach = wp.array(np.ones((max(n, 1), 3), np.float32), dtype=wp.vec3, device=device)  # the camera rays': 1
    words = _words(area_samples(scene)) if fx.area_lights else 0
    # The opaque materials named by render(grad=[...reflectivity]): their mirror rays recorded whatever their k_r
    # (a dielectric's k_r > 0 makes it a mirror: a jump, not a slope).
    mirrored = tuple(m for m in mirrored if not scene.materials[m].dielectric)
    anyway = wp.array(np.asarray([int(m in mirrored) for m in geom.material_names] or [0], np.int32), dtype=int,
                      device=device)
    kernel = make_tree_record_kernel(L, fx.smooth, shadows, fx.culling, fx.light_model, fx.reflection or bool(mirrored),
                                     fx.absorption, bool(words))
    per_ray = TREE_BYTES_PER_RAY + 4 * L + (TREE_AREA_BYTES_PER_RAY + 4 * words if words else 0)
    ray_of, levels, held = np.arange(n, dtype=np.int32), [], 0
    for level in range(D):
        m = len(ray_of)
        held += m
        _tree_too_big(scene, held * per_ray + m * TREE_RECORD_BYTES_PER_RAY, device)
        face, kind, visible = i1(m), i1(m), wp.zeros(max(m * L, 1), dtype=int, device=device)
        has = wp.zeros(max(m, 1), dtype=wp.vec2i, device=device)
        hit_p, o_r, d_r, w_r, o_t, d_t, w_t, x_r, x_t = (v3(m) for _ in range(9))
        med_r, med_t = i1(m), i1(m)
        emit = wp.full(max(m, 1) if words else 1, -1, dtype=int, device=device)
        area_bits = wp.zeros(max(m * words, 1), dtype=int, device=device)
        launch_bands(kernel, lambda first: [data, D, level, first, orig, dirs, weight, start, medium, face,
                                            visible, kind, has, hit_p, o_r, d_r, w_r, med_r, o_t, d_t, w_t, med_t,
                                            emit, area_bits, words, reach, x_r, x_t, anyway],
                     m, threads, bands, device, pool=pool)
        h = has.numpy()[:m]
        hr, ht = h[:, 0] != 0, h[:, 1] != 0
        per = hr.astype(np.int32) + ht
        base = np.cumsum(per, dtype=np.int64) - per
        child = np.stack([np.where(hr, base, -1), np.where(ht, base + hr, -1)], 1).astype(np.int32)
        levels.append(TreeLevel(face, visible, medium, wp.array(ray_of if m else np.zeros(1, np.int32), dtype=int,
                                                               device=device),
                                kind, wp.array(child if m else np.zeros((1, 2), np.int32), dtype=wp.vec2i,
                                               device=device), m, dirs if level == 0 else None, emit, area_bits))
        total = int(per.sum())
        if total == 0 or level + 1 == D:
            break

        def gather(a_r, a_t, dtype):  # the next level's list: each child at its place
            r, t = a_r.numpy()[:m], a_t.numpy()[:m]
            out = np.empty((total,) + r.shape[1:], r.dtype)
            out[child[hr, 0]] = r[hr]
            out[child[ht, 1]] = t[ht]
            return wp.array(out, dtype=dtype, device=device)

        orig, dirs, weight = gather(o_r, o_t, wp.vec3), gather(d_r, d_t, wp.vec3), gather(w_r, w_t, wp.vec3)
        reach = gather(x_r, x_t, wp.vec3)
        start, medium = gather(hit_p, hit_p, wp.vec3), gather(med_r, med_t, int)
        nxt = np.empty(total, np.int32)
        nxt[child[hr, 0]] = ray_of[hr]
        nxt[child[ht, 1]] = ray_of[ht]
        ray_of = nxt
    return TreeHits(levels, cam.width, cam.height, L, D, fx.smooth, k * k, fx.light_model, fx.texture, absorb, words,
                    data.area if words else None, mirrored=mirrored, vertex_color=fx.vertex_color)
