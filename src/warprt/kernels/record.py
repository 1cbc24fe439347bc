"""What a grad=True frame writes as it traces (the trace kernel's record variant): per ray of the frame's ray
tree, the hit, which lights and area-light sample points it sees, and where the ray came from; image/grad_record.py
lays the arrays out and reads them back, kernels/replay.py differentiates the frame over them.

The forward records as it goes, as it writes the AOVs: the record is the forward's own hits, shadow answers
and spawned rays (whichever query gave them, the shortcuts being exact), so the two cannot disagree and no ray
is traced twice. Without the record (the plain frame) its code is absent from the kernel (wp.static).

The record is a list of entries, one a ray, level by level (entry j of ray level k lies in [level_start[k],
level_start[k + 1])). The camera rays are level 0, entry level_start[0] + camera ray. A chain of mirror rays has
at most one ray a level per camera ray, at the same place in each level. Glass's ray tree has up to two
children a ray, and a level's rays are counted as they come: each band of pixels (one launch) takes entries
from a region of its own per level (``region``, ``capacity``), ``used`` counting what it took, past the
capacity too (the host then makes the regions larger and traces the frame again: image/grad_record.py).
A tree's entry names its parent (2 parent + branch: 0 the reflected or a mirror's ray, 1 the transmitted one), its
camera ray and its medium, so the replay runs one launch a level with no host pass between; a chain's follow from
its place (make_entry). No direction is kept: the replay makes each ray again, the camera's from the camera and
a child from its parent's hit, with the very functions and values the forward used.
"""

from __future__ import annotations

import functools

from .._warp import wp
from ..geometry import SceneData
from .interaction import Surface

NO_RAY = -2  # the face of an entry no ray reached (a chain that ended, a region's unused tail); -1 met nothing
NO_PARENT = -1  # a camera ray's parent


@wp.struct
class GradRecord:
    """The record's entries (see the module docstring): per entry the face hit (-1: none, NO_RAY: no ray),
    Warp's barycentrics, a bit per Whitted light (``lights`` of them, 16 at most: the replay's limit) the hit
    sees, the area light whose emitting side the ray met (-1: none) and a bit per area-light sample point the
    hit sees (``words`` int32s an entry); with glass its parent (2 entry + branch, NO_PARENT for a camera ray),
    its camera ray and the medium it travels in (-1: air). ``level_start``: where each of the ``levels``
    levels begins (levels + 1 values). With glass, per (band, level) the band's region in its level, its capacity and the
    entries it used; ``band``: the band a launch traces (a copy of the record per band). ``scratch``: the entry
    written where a region is full, never read. ``mirrored``: per material slot, 1 where the mirror rays are
    followed whatever its k_r (a named reflectivity of 0: their weight is 0, the image the same)."""

    face: wp.array(dtype=int)
    bary: wp.array(dtype=wp.vec2)
    visible: wp.array(dtype=int)
    emit: wp.array(dtype=int)
    area_bits: wp.array(dtype=int)
    parent: wp.array(dtype=int)
    ray_of: wp.array(dtype=int)
    medium: wp.array(dtype=int)
    level_start: wp.array(dtype=int)
    region: wp.array(dtype=int)
    capacity: wp.array(dtype=int)
    used: wp.array(dtype=int)
    mirrored: wp.array(dtype=int)
    band: int
    scratch: int
    levels: int
    lights: int
    words: int


@functools.cache
def make_record_hit(TREE: bool):
    """record_hit(rec, depth, camera_ray, parent, medium, face, u, v) -> j: the entry of a ray at ray level
    ``depth`` of camera ray ``camera_ray``, with its nearest hit (face, Warp's barycentrics) written; shade()
    then writes what the hit sees at j. A camera ray's entry, and without TREE (a chain) every ray's, is its
    camera ray's place in its level; with TREE a deeper ray takes the next entry of its band's region
    (rec.scratch where that is full, ``used`` counting it all the same), and its parent and medium are written
    too (a chain's follow from its place: make_entry)."""

    @wp.func(inline=True)
    def record_hit(rec: GradRecord, depth: int, camera_ray: int, parent: int, medium: int, face: int, u: float,
                   v: float) -> int:
        j = rec.level_start[depth] + camera_ray
        if wp.static(TREE):
            if depth > 0:
                cell = rec.band * rec.levels + depth
                slot = wp.atomic_add(rec.used, cell, 1)
                j = rec.scratch
                if slot < rec.capacity[cell]:
                    j = rec.level_start[depth] + rec.region[cell] + slot
            rec.parent[j] = parent
            rec.ray_of[j] = camera_ray
            rec.medium[j] = medium
        rec.face[j] = face
        rec.bary[j] = wp.vec2(u, v)
        return j

    return record_hit


@functools.cache
def make_entry(TREE: bool):
    """(entry_parent, entry_ray, entry_medium): of a record's entry j (not a camera ray's, for its parent), its
    parent's code (2 entry + branch), its camera ray and its medium: with TREE as written; a chain's from its
    place (level k holds camera ray r at level_start[k] + r, every level the camera rays' count; its parent the
    same camera ray's entry a level up, branch 0; every ray in the eye's medium: a mirror's ray stays in its)."""

    @wp.func
    def entry_parent(rec: GradRecord, j: int) -> int:
        if wp.static(TREE):
            return rec.parent[j]
        return 2 * (j - rec.level_start[1])

    @wp.func
    def entry_ray(rec: GradRecord, j: int) -> int:
        if wp.static(TREE):
            return rec.ray_of[j]
        return j % rec.level_start[1]

    @wp.func
    def entry_medium(rec: GradRecord, s: SceneData, j: int) -> int:
        if wp.static(TREE):
            return rec.medium[j]
        return s.eye_medium

    return entry_parent, entry_ray, entry_medium


@wp.func(inline=True)
def record_area_point(rec: GradRecord, j: int, q: int):
    """Mark area-light sample point q seen from the hit of entry j: bit q % 32 of its word q / 32."""
    word = j * rec.words + q / 32
    rec.area_bits[word] = rec.area_bits[word] | (1 << (q % 32))


@functools.cache
def make_follows_mirror(RECORD: bool):
    """follows_mirror(kr, rec, m): whether a hit of material slot m with reflectivity kr spawns a mirror ray:
    where some k_r > 0, and with RECORD also where ``rec.mirrored`` flags m (a named reflectivity of 0:
    its mirror rays followed with weight 0, for its derivative)."""

    @wp.func(inline=True)
    def follows_mirror(kr: wp.vec3, rec: GradRecord, m: int) -> bool:
        if wp.static(RECORD):
            return wp.max(kr) > 0.0 or rec.mirrored[m] != 0
        return wp.max(kr) > 0.0

    return follows_mirror


@wp.func
def mirror_reach(reach: wp.vec3, kr: wp.vec3) -> wp.vec3:
    """A mirror ray's reach (what the record follows it by): its parent's times k_r, or its parent's where
    every k_r is 0 (a named reflectivity of 0: its rays followed for its derivative)."""
    if wp.max(kr) <= 0.0:
        return reach
    return wp.cw_mul(reach, kr)


@functools.cache
def make_record_stack(size: int):
    """(ParentRows, ReachRows): what the record keeps of the rays waiting on the ray tree's stack (trace.py's
    make_ray_stack, ``size`` of them), each written in place: their parents' codes, and their reaches."""
    return wp.types.vector(length=size, dtype=int), wp.types.matrix(shape=(size, 3), dtype=float)


@functools.cache
def empty_record(device: str) -> GradRecord:
    """The stand-in a frame without the record passes (its kernel never reads it), made once a device."""
    r = GradRecord()
    ints = ("face", "visible", "emit", "area_bits", "parent", "ray_of", "medium", "level_start", "region",
            "capacity", "used", "mirrored")
    for name in ints:
        setattr(r, name, wp.zeros(1, dtype=int, device=device))
    r.bary = wp.zeros(1, dtype=wp.vec2, device=device)
    r.band, r.scratch, r.levels, r.lights, r.words = 0, 0, 1, 0, 0
    return r



@wp.struct
class Reaches:
    """The reaches of a dielectric hit's two children (dielectric_reaches)."""

    r: wp.vec3
    t: wp.vec3


@wp.func
def dielectric_reaches(s: SceneData, hit: Surface, reach: wp.vec3, F: float) -> Reaches:
    """The reaches of a dielectric hit's reflected and transmitted rays: the Fresnel split (F, the hit's
    dielectric_children's) of the ray's ``reach`` with a transmittance of 0 (every channel) taken as 1, so that a
    refracted ray the forward leaves out because it carries nothing is followed for the derivative in that
    transmittance (its radiance); 0 past the critical angle."""
    kt = s.transmittance[hit.material]
    if wp.max(kt) <= 0.0:
        kt = wp.vec3(1.0)
    out = Reaches()
    out.r = reach * F
    out.t = wp.vec3(0.0)
    if F < 1.0:
        out.t = wp.cw_mul(reach, kt) * (1.0 - F)
    return out
