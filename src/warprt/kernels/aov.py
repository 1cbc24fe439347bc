"""Arbitrary output variables: what a camera ray's first hit records besides colour (depth, normal,
albedo, position, uv, object, material, face, coverage), one @wp.func the trace kernel calls there.

Per pixel, one thread walks all of the pixel's samples, so the buffers are plain sums over the samples
that hit (the host divides by the hit count) and the ID AOVs of one chosen sample: the one nearest the
pixel centre, never averaged. Only the AOVs asked for are compiled in (wp.static) and allocated.
"""

from __future__ import annotations

import functools

from .._warp import wp
from ..geometry import SceneData
from ..geometry.bvh import face_vertices
from .interaction import Surface
from .shading import make_coefficients

GEOMETRIC = ("depth", "normal", "albedo", "position", "uv")
IDS = ("object", "material", "face")


@wp.struct
class AovBuffers:
    """Per pixel: the number of samples that hit, the sums of the geometric AOVs over them, and the
    ID AOVs of sample ``id_sample``; with the object and texture-coordinate tables the IDs and uv are
    read from. An AOV not asked for has an empty array (its code is not compiled)."""

    hits: wp.array(dtype=wp.int32)
    depth: wp.array(dtype=float)  # distance from the eye along the ray
    normal: wp.array(dtype=wp.vec3)  # shading normal, facing the camera
    albedo: wp.array(dtype=wp.vec3)  # kd as shading reads it: times its texture and the vertex colour
    position: wp.array(dtype=wp.vec3d)  # hit point relative to the geometry's origin, summed in float64
    uv: wp.array(dtype=wp.vec2)  # the object's texture coordinates, or barycentrics (b1, b2) on the face
    object: wp.array(dtype=wp.int32)  # -1: the chosen sample missed
    material: wp.array(dtype=wp.int32)
    face: wp.array(dtype=wp.int32)  # within its object
    tri_object: wp.array(dtype=wp.int32)  # per triangle: its object's index in the scene
    object_first_face: wp.array(dtype=wp.int32)  # per object: its first triangle in the scene's set
    vertex_uv: wp.array(dtype=wp.vec2)  # per vertex: texture coordinates, (0, 0) on objects without
    object_has_uv: wp.array(dtype=wp.int32)  # per object
    id_sample: int


def id_sample(k: int) -> int:
    """Of k x k stratified samples (sample j k + i at ((i + 1/2)/k, (j + 1/2)/k)), the one nearest the
    pixel centre: the middle one for odd k; for even k four are equally near, and the first of them in
    sample order, the lower left, is taken."""
    c = (k - 1) // 2
    return c * k + c


@functools.cache
def make_record_first_hit(names: tuple, texture: bool = False, vertex_color: bool = False):
    """record_first_hit(a, s, pixel, sample, f, u, v, hit, o) for the AOVs ``names``: adds a camera
    ray's first hit (face f at Warp's barycentrics u, v; hit record ``hit``; ray origin o) to the pixel's
    sums, and sets the pixel's IDs when ``sample`` is a.id_sample. ``texture`` and ``vertex_color``: the
    effect set's, so that the albedo is the kd the shading reads."""
    DEPTH, NORMAL, ALBEDO, POSITION, UV = (n in names for n in GEOMETRIC)
    OBJECT, MATERIAL, FACE = (n in names for n in IDS)
    coefficients = make_coefficients(texture, vertex_color)

    @wp.func
    def record_first_hit(a: AovBuffers, s: SceneData, pixel: int, sample: int, f: int, u: float, v: float,
                         hit: Surface, o: wp.vec3):
        a.hits[pixel] = a.hits[pixel] + 1
        if wp.static(DEPTH):
            a.depth[pixel] = a.depth[pixel] + wp.length(hit.p - o)
        if wp.static(NORMAL):
            a.normal[pixel] = a.normal[pixel] + hit.n
        if wp.static(ALBEDO):
            a.albedo[pixel] = a.albedo[pixel] + coefficients(s, hit).kd
        if wp.static(POSITION):
            a.position[pixel] = a.position[pixel] + wp.vec3d(hit.p)
        if wp.static(UV):
            # Warp's u, v weigh the face's first and second vertex (p = u p0 + v p1 + (1 - u - v) p2).
            # As Mitsuba's uv: the object's texture coordinates, interpolated so; without, (b1, b2).
            w = 1.0 - u - v
            uv = wp.vec2(v, w)
            if a.object_has_uv[a.tri_object[f]] != 0:
                j0, j1, j2 = face_vertices(s.indices, f)
                uv = a.vertex_uv[j0] * u + a.vertex_uv[j1] * v + a.vertex_uv[j2] * w
            a.uv[pixel] = a.uv[pixel] + uv
        if wp.static(OBJECT or MATERIAL or FACE):
            if sample == a.id_sample:
                obj = a.tri_object[f]
                if wp.static(OBJECT):
                    a.object[pixel] = obj
                if wp.static(MATERIAL):
                    a.material[pixel] = hit.material
                if wp.static(FACE):
                    a.face[pixel] = f - a.object_first_face[obj]

    return record_first_hit


_DTYPES = {"depth": float, "normal": wp.vec3, "albedo": wp.vec3, "position": wp.vec3d, "uv": wp.vec2,
           "object": wp.int32, "material": wp.int32, "face": wp.int32}


def aov_buffers(names, geometry, n_pixels: int, k: int, device) -> AovBuffers:
    """Zeroed sums and hit counts, IDs at -1, for the AOVs ``names`` of an image of n_pixels with
    k x k samples per pixel; the object and uv tables from ``geometry`` only when IDs or uv are asked for."""
    a = empty_aov_buffers(device)
    a.hits = wp.zeros(n_pixels, dtype=wp.int32, device=device)
    for name in names:
        if name in GEOMETRIC:
            setattr(a, name, wp.zeros(n_pixels, dtype=_DTYPES[name], device=device))
        elif name in IDS:
            setattr(a, name, wp.full(n_pixels, -1, dtype=wp.int32, device=device))
    if any(n in IDS or n == "uv" for n in names):
        a.tri_object, a.object_first_face = geometry.object_tables()
    if "uv" in names:
        a.vertex_uv, a.object_has_uv = geometry.uv_tables()
    a.id_sample = id_sample(k)
    return a


def empty_aov_buffers(device) -> AovBuffers:
    """Buffers of no pixels: what the trace kernel gets when no AOV is asked for."""
    a = AovBuffers()
    for name in ("hits", *_DTYPES, "tri_object", "object_first_face", "vertex_uv", "object_has_uv"):
        setattr(a, name, wp.empty(0, dtype=wp.vec2 if name == "vertex_uv" else _DTYPES.get(name, wp.int32), device=device))
    a.id_sample = 0
    return a


def aov_sums(a: AovBuffers, names) -> dict:
    """The buffers on the host: "hits" and each AOV's per-pixel sum or ID, flat NumPy arrays."""
    return {name: getattr(a, name).numpy() for name in ("hits", *(n for n in names if n in _DTYPES))}


def aov_bytes(a: AovBuffers) -> int:
    return int(sum(getattr(a, name).capacity for name in ("hits", *_DTYPES)))
