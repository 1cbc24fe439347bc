"""What a grad=True frame writes as it traces (the trace kernel's record variant): per camera ray and ray
level the hit, and which lights and area-light sample points it sees; image/grad.py's FirstHits holds it.

The forward records as it goes, as it writes the AOVs: the record is the forward's own hits, shadow answers
and mirror rays (whichever query gave them, the shortcuts being exact), so the two cannot disagree and no ray
is traced twice. Without the record (the plain frame) its code is absent from the kernel (wp.static).
"""

from __future__ import annotations

import functools

from .._warp import wp

NO_RAY = -2  # a level the camera ray's chain did not reach (its face); -1 is a ray that met nothing


@wp.struct
class GradRecord:
    """Per camera ray (pixel * samples + sample, the tracer's strata) and ray level (``levels`` a ray: the
    camera ray, then its mirror rays): the face hit (-1: none, NO_RAY: no ray at that level), Warp's
    barycentrics, the ray's direction, and per Whitted light (``lights`` a level) whether the hit sees it;
    with area lights (``words`` > 0), the area light whose emitting side the ray met (-1: none) and a bit per
    sample point the hit sees (``words`` int32s a level). ``mirrored``: per material slot, 1 where the mirror
    rays are followed whatever its k_r (a named reflectivity of 0: their weight is 0, the image the same)."""

    face: wp.array(dtype=int)
    bary: wp.array(dtype=wp.vec2)
    dirs: wp.array(dtype=wp.vec3)
    visible: wp.array(dtype=int)
    emit: wp.array(dtype=int)
    area_bits: wp.array(dtype=int)
    mirrored: wp.array(dtype=int)
    levels: int
    lights: int
    words: int


@wp.func(inline=True)
def record_hit(rec: GradRecord, camera_ray: int, depth: int, face: int, u: float, v: float, d: wp.vec3) -> int:
    """Write a ray's nearest hit (face, Warp's barycentrics) and direction at its level of camera ray
    ``camera_ray``; its entry j, where shade() then writes what the hit sees."""
    j = camera_ray * rec.levels + depth
    rec.face[j] = face
    rec.dirs[j] = d
    rec.bary[j] = wp.vec2(u, v)
    return j


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


@functools.cache
def empty_record(device: str) -> GradRecord:
    """The stand-in a frame without the record passes (its kernel never reads it), made once a device."""
    r = GradRecord()
    r.face, r.visible, r.emit, r.area_bits, r.mirrored = (wp.zeros(1, dtype=int, device=device) for _ in range(5))
    r.bary = wp.zeros(1, dtype=wp.vec2, device=device)
    r.dirs = wp.zeros(1, dtype=wp.vec3, device=device)
    r.levels, r.lights, r.words = 1, 0, 0
    return r
