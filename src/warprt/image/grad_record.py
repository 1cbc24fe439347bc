"""The gradient's record of a grad=True frame (grad.py says what is differentiated): its layout (Record: the
entries level by level, kernels/record.py), its size and the memory check, and how the frame's own trace
makes it (recording_plan, record_arrays, regrown where glass's regions were too small; record_first_hits for
tools and tests)."""
from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field, replace

import numpy as np

from .._warp import wp
from ..errors import ArgumentError
from ..kernels import NO_RAY, GradRecord, camera_data, empty_aov_buffers, make_trace_kernel, stack_size
from ..scene import camera_basis, scene_effects
from .launch import bands_of, launch_bands
from .memory import available_memory, human
from .mirrors import empty_mirrors
from .zbuffer import empty_fragments

_BANDS_LOCK = threading.Lock()  # Record.for_band's: its copies made once

# Bytes of an entry of the record (face, barycentrics, the lights seen: 4 + 8 + 4; with glass its parent, camera ray
# and medium, 12); with area lights the emitter met (4) and a bit per sample point (in 4-byte words). And of the
# replay (kernels/replay.py), each with its adjoint: a child's weight and direction (2 x 24 a branch; its origin
# too where the hits move, 2 x 12), where it began (2 x 12); with area lights the hit, its colours, its weight and
# local colour (2 x 132).
RECORD_BYTES_PER_ENTRY, TREE_BYTES_PER_ENTRY, REPLAY_BYTES_PER_ENTRY = 16, 12, 48 + 24 + 24
AREA_RECORD_BYTES_PER_ENTRY, AREA_REPLAY_BYTES_PER_ENTRY = 4, 264
GROWTH = 1.25  # a glass frame's regions, made again from the rays a frame used: room for the next frame's
FIRST_CAPACITY = 2  # a glass frame's region in each deeper level, per camera ray, when no frame has said more


def area_samples(scene) -> int:
    """The area lights' sample points in all (render.light_samples each): the record's bits an entry."""
    return len(scene.area_lights) * scene.render.light_samples


def _words(samples: int) -> int:
    return max(1, -(-samples // 32))


def ray_levels(scene, fx, mirrored=()) -> int:
    """The ray levels a grad frame records: render.max_depth where the tracer spawns mirror or glass rays (some
    k_r > 0, a dielectric) or the caller named a reflectivity to differentiate (``mirrored``), else the camera
    ray's."""
    return scene.render.max_depth if fx.reflection or fx.refraction or mirrored else 1


def entry_bytes(scene, fx) -> int:
    """What an entry of a frame's record and its replay hold, in bytes."""
    per = RECORD_BYTES_PER_ENTRY + REPLAY_BYTES_PER_ENTRY + (TREE_BYTES_PER_ENTRY if fx.refraction else 0)
    if fx.area_lights:
        per += AREA_RECORD_BYTES_PER_ENTRY + 4 * _words(area_samples(scene)) + AREA_REPLAY_BYTES_PER_ENTRY
    return per


def record_bytes(scene, fx, mirrored=()) -> int:
    """What render(grad=True) and backward() hold for a frame's record and replay, in bytes, at the least: an
    entry per camera ray (width x height x spp) and ray level (glass's tree may take more: checked as the
    frame's regions grow, check_tree_memory)."""
    cam, r = scene.camera, scene.render
    rays = cam.width * cam.height * (r.spp if fx.supersampling else 1)
    return rays * ray_levels(scene, fx, mirrored) * entry_bytes(scene, fx)


def _too_big(need: int, device: str, fx, what: str):
    available, where = available_memory(device)
    if available is not None and need > available:
        samples = ", render.light_samples" if fx.area_lights else ""  # a bit per area-light sample and entry
        raise ArgumentError("render", "grad", f"the gradient's record of this frame{what} needs about {human(need)} "
                            f"(per ray and ray level), more than the {human(available)} {where}: lower render.spp, "
                            f"render.max_depth{samples} or camera.width and camera.height")


def check_record_memory(scene, fx, device: str, mirrored=()):
    """Refuse, in one line naming the budget and the settings that reduce it, a grad=True frame whose
    record would not fit in the memory this process can still take (before the frame allocates anything)."""
    _too_big(record_bytes(scene, fx, mirrored), device, fx, "")


@dataclass
class Record:
    """What a grad=True frame recorded, as backward() reads it: ``rec``, the entries (kernels/record.py's
    GradRecord: per ray of the frame's tree its hit, parent, camera ray and medium, the lights and area-light
    points it sees, level by level from ``level_start``), and how to read them: the camera rays (``samples``
    a pixel, ray pixel * samples + sample, the tracer's strata), the ray levels, the Whitted lights and the
    area-light words an entry, the frame's tables (``data``, its SceneData) and the effects the replay models
    (``fx``, the recording frame's: recording_effects; ``absorption``: whether the replay applies Beer's law,
    unless switched off also where every absorption is 0 in a frame with glass, its derivative not being 0).
    ``tree``: glass's, whose deeper levels are per-band regions (``bands``, launch_bands' ranges).
    ``mirrored``: the materials whose mirror rays were recorded whatever their k_r; ``reflects``: whether the
    frame could reflect at all."""

    rec: GradRecord
    level_start: np.ndarray
    width: int
    height: int
    samples: int
    levels: int
    lights: int
    words: int
    tree: bool
    fx: object
    data: object
    absorption: bool
    mirrored: tuple = ()
    reflects: bool = False
    bands: list = field(default_factory=list)
    capacity: np.ndarray | None = None  # glass: per (band, level) the region's size
    _bands: dict | None = field(default=None, repr=False)  # for_band's copies
    pool: dict = field(default_factory=dict, repr=False)  # the replay's arrays by name (grad.pooled_zeros)

    @property
    def camera_rays(self) -> int:
        return self.width * self.height * self.samples

    @property
    def entries(self) -> int:
        return int(self.level_start[-1])

    def level(self, k: int) -> tuple[int, int]:
        """(first entry, count) of ray level k."""
        return int(self.level_start[k]), int(self.level_start[k + 1] - self.level_start[k])

    def for_band(self, first: int) -> GradRecord:
        """The GradRecord a launch of the band starting at pixel ``first`` writes through (its regions' row)."""
        if not self.tree:
            return self.rec
        bands = self._bands
        if bands is None:  # made once a frame: the bands' copies, differing only in ``band``
            # Band threads ask at once: one makes them, and they are published whole. (Published as they were
            # made, a second thread found the dict while the first filled it: KeyError in a loaded full run.)
            with _BANDS_LOCK:
                if self._bands is None:
                    made = {}
                    for b, (f, _) in enumerate(self.bands):
                        made[f] = r = _copy(self.rec)
                        r.band = b
                    self._bands = made
                bands = self._bands
        return bands[first]

    def used(self) -> np.ndarray:
        """Glass: per (band, level) the entries the frame's rays took (past the capacity too)."""
        return self.rec.used.numpy().reshape(len(self.bands), self.levels)

    def overflowed(self) -> bool:
        """Whether some band's region was too small (glass): the frame must be traced again, regrown."""
        return self.tree and bool((self.used() > self.capacity).any())


def _copy(rec: GradRecord) -> GradRecord:
    out = GradRecord()
    for name in GradRecord.vars:
        setattr(out, name, getattr(rec, name))
    return out


def recording_effects(scene, fx, switched=None, mirrored=()):
    """The effects of a grad=True frame: ``fx`` with those the record needs though the scene's values leave
    them out, each adding exactly 0 to the image (so it is the plain frame's to the bit): shadow rays where the
    scene asks for shadows but no light or colour would dim (a light of colour 0: its derivative is the
    shadowed one's), the light loop where there are lights (a kd and ks of 0 everywhere: their derivative is
    not 0), and the mirror code where a reflectivity of 0 is named (``mirrored``: its rays followed with weight
    0). Effects switched off (``switched``, the caller's options' effects.switched_on) stay off."""
    called = scene_effects(scene)
    wanted = switched is None or "shadows" in switched
    unlit = bool(scene.lights) and not (fx.diffuse or fx.specular)  # no light loop to record its tests in
    return replace(fx, shadows=fx.shadows or (scene.render.shadows and wanted and not called.shadows),
                   diffuse=fx.diffuse or unlit, reflection=fx.reflection or bool(mirrored))


def recording_plan(scene, plan, switched=None, mirrored=()):
    """The FramePlan of a grad=True frame: ``plan`` with recording_effects' effect set, over the ray levels
    the record holds (render.max_depth where mirror or glass rays are followed)."""
    fx = recording_effects(scene, plan.fx, switched, mirrored)
    return replace(plan, fx=fx, max_depth=ray_levels(scene, fx, mirrored))


def _capacity(n_bands: int, levels: int, band_rays: np.ndarray, used: np.ndarray | None) -> np.ndarray:
    """Per (band, level) the size of glass's region: the camera rays at level 0 (not read: their entries are
    fixed), then FIRST_CAPACITY a camera ray, or GROWTH times what a frame used."""
    cap = np.repeat((FIRST_CAPACITY * band_rays)[:, None], levels, axis=1).astype(np.int64)
    if used is not None and used.shape == cap.shape:  # a frame of these bands and levels
        cap = np.ceil(used * GROWTH).astype(np.int64) + 16
    cap[:, 0] = band_rays
    return cap


def record_arrays(scene, geom, data, fx, levels: int, device: str, bands: list, mirrored=(), switched=None,
                  reuse: Record | None = None, used: np.ndarray | None = None) -> Record:
    """The Record of a grad frame about to be traced: its arrays as the trace kernel's recording variant writes
    them, every entry's face NO_RAY and every area-light bit 0 until a ray writes it (the rest is written at
    every ray and read only there: not filled). ``fx`` and ``levels``: the recording frame's effects
    (recording_effects) and ray levels; ``bands``: its bands (launch.bands_of), whose regions glass's deeper
    levels are; ``used``: with glass, what a frame used per (band, level) (the regions made from it, else a
    first guess). ``reuse``: the last grad frame's Record, whose arrays are taken again where their sizes are
    this frame's, and whose replay's arrays (``pool``) the next backward takes where theirs are."""
    cam = scene.camera
    k = math.isqrt(scene.render.spp) if fx.supersampling else 1
    n, L, D = cam.width * cam.height * k * k, len(scene.whitted_lights), levels
    words = _words(area_samples(scene)) if fx.area_lights else 0
    tree = bool(fx.refraction)
    capacity = None
    if tree:
        band_rays = np.asarray([count * k * k for _, count in bands], np.int64)
        capacity = _capacity(len(bands), D, band_rays, used)
        region = np.zeros_like(capacity)
        region[:, 1:] = np.cumsum(capacity[:, 1:], axis=0) - capacity[:, 1:]
        level_size = np.concatenate([[n], capacity[:, 1:].sum(0)])
        check_tree_memory(scene, fx, int(level_size.sum()), device)
    else:
        level_size = np.full(D, n, np.int64)
    level_start = np.concatenate([[0], np.cumsum(level_size)]).astype(np.int64)
    total = int(level_start[-1])
    sizes = (total + 1, (total + 1) if tree else 1, (total + 1) if words else 1, (total + 1) * words or 1)
    r = reuse.rec if reuse is not None and _fits(reuse, sizes, device) else None
    if r is None:
        r = GradRecord()
        r.face, r.visible = (wp.empty(sizes[0], dtype=int, device=device) for _ in range(2))
        r.bary = wp.empty(sizes[0], dtype=wp.vec2, device=device)
        r.parent, r.ray_of, r.medium = (wp.empty(sizes[1], dtype=int, device=device) for _ in range(3))
        r.emit = wp.empty(sizes[2], dtype=int, device=device)
        r.area_bits = wp.zeros(sizes[3], dtype=int, device=device)
    r.face.fill_(NO_RAY)
    if words:
        r.area_bits.zero_()
    ints = lambda a: wp.array(np.asarray(a, np.int32).ravel(), dtype=int, device=device)  # noqa: E731
    r.level_start = ints(level_start)
    r.region, r.capacity = (ints(region), ints(capacity)) if tree else (ints([0]), ints([0]))
    r.used = wp.zeros(len(bands) * D if tree else 1, dtype=int, device=device)
    r.mirrored = ints([int(m in mirrored) for m in geom.material_names] or [0])
    r.band, r.scratch, r.levels, r.lights, r.words = 0, total, D, L, words
    reflects = scene.render.max_depth > 1 and (switched is None or "reflection" in switched)
    absorb = fx.absorption or ((switched is None or "absorption" in switched) and not scene_effects(scene).absorption
                               and tree)
    return Record(r, level_start, cam.width, cam.height, k * k, D, L, words, tree, fx, data, absorb, tuple(mirrored),
                  reflects, list(bands), capacity, pool=reuse.pool if reuse is not None else {})


def _fits(old: Record, sizes: tuple, device: str) -> bool:
    r = old.rec
    return (r.face.shape[0], r.parent.shape[0], r.emit.shape[0], r.area_bits.shape[0]) == sizes and \
        r.face.device == wp.get_device(device)


def check_tree_memory(scene, fx, entries: int, device: str):
    """The one error for a glass frame whose record would not fit (its regions as laid out), naming the settings
    that make it smaller."""
    _too_big(entries * entry_bytes(scene, fx), device, fx, "'s ray tree (glass; each level may double the rays)")


def record_first_hits(scene, geom, data, fx, device: str, threads: int = 1, bands: int = 1, pool=None,
                      switched=None, mirrored=()) -> Record:
    """The record of a frame of ``scene`` on ``geom`` (its tables ``data``) without its image: the trace
    kernel's recording variant over every camera ray (render.spp a pixel, the tracer's strata), every query
    the BVH's, in ``bands`` bands on ``threads`` threads (``pool``: the Renderer's), traced again where glass's
    regions were too small. What Renderer.render(grad=True) records, for tests and tools that replay a frame by
    hand. ``switched``: the effects the caller's options leave on (None: every one); ``mirrored``: the
    materials whose mirror rays are recorded whatever their k_r (grad_params.mirrored_materials)."""
    fx = recording_effects(scene, fx, switched, mirrored)
    levels = ray_levels(scene, fx, mirrored)
    cam = scene.camera
    pixels = cam.width * cam.height
    ranges = bands_of(pixels, bands)
    kernel = make_trace_kernel(fx, stack=stack_size(scene.render.max_depth) if fx.refraction else 0, record=True)
    c = camera_data(camera_basis(cam), geom.eye_offset(cam.eye))
    frags, mirrors, aovs = empty_fragments(device), empty_mirrors(device), empty_aov_buffers(device)
    image = wp.empty(pixels, dtype=wp.vec3, device=device)
    counts = wp.empty(pixels, dtype=wp.vec4i if fx.refraction else wp.vec3i, device=device)
    used = None
    while True:
        hits = record_arrays(scene, geom, data, fx, levels, device, ranges, mirrored, switched, used=used)
        launch_bands(kernel, lambda first: [data, c, levels, math.isqrt(hits.samples), first, cam.width, 1, frags,
                                            mirrors, aovs, hits.for_band(first), image, counts],
                     pixels, threads, bands, device, pool=pool)
        if not hits.overflowed():
            return hits
        used = hits.used()
