"""Exact shortcut for area lights' shadow rays: a proof, per hit and light, that none of the rays it would trace to
the light's points can be stopped, so that they need not be traced (shadow_query "auto" or "grid"; "bvh" traces
every one). Each of those rays runs from spawn_ray's origin o (the hit p pushed along its geometric normal by d, the
error bound's offset) towards a point q of the light, and stops SHADOW_EPSILON of the way short of it. Every q lies
in the light's hull (AreaLights.hull: a planar quadrilateral, the light's rectangle, a disk's square, a flat mesh
light's bounding rectangle in its plane), so every ray lies in the pyramid from o over that hull, cut at
SHADOW_EPSILON h(o) from the light's plane. A triangle no ray can meet is one all of whose corners lie beyond one
plane of that pyramid, by a margin the float32 ray test cannot cross:

- the light's plane, shifted to where the rays stop (h < SHADOW_EPSILON h(p) - margin): the light's own triangles,
  the ceiling around it;
- the hit's own plane (n_g . (v - p) <= d / 2, the hull wholly above it): the receiver's own and coplanar
  triangles, as spawn_ray's offset keeps its own triangle off the rays;
- the four planes through p and each edge of the hull (beyond them by d + margin): everything to the side.

The candidates are the triangles whose boxes meet the pyramid's box (the BVH's AABB query); where every one is
beyond some plane the hit sees the whole light, and its image is the traced one to the bit (the same points, the
same terms, only the any-hit queries skipped: benchmarks/image_hashes.txt and tests/lighting). Where a triangle
is not, the rays are traced."""

from __future__ import annotations

from .._warp import wp
from ..geometry import SceneData
from .interaction import Surface
from .triangle import triangle

SHADOW_EPSILON = 1.0e-3  # the share of an area light's shadow ray left short of its sample point
CLEAR_MARGIN = 1.0e-5  # a plane's margin, relative to the distance from the hit to the light
RISE = 1.0e-3  # the least n_g . (c - p) / |c - p| of the hull's corners for the hit's own plane to part them
# The fewest points of a light a hit traces for the proof to be tried: it costs about two shadow rays (measured on
# scenes/cornell_box.xml, 240x240, one thread: with one point a hit, light_spread at 16 spp and 16 light samples,
# trying it took 307 ms against 221 ms; with four, at 64 light samples, 445 ms against 575 ms).
CLEAR_MIN_POINTS = 4


@wp.struct
class Pyramid:
    """The pyramid of a hit's shadow rays to one light: apex p, the light's plane (unit normal nl towards p,
    through c0, the rays' ends at h_end), the hit's plane (ng towards the light, ``own`` 1 where the whole hull
    lies above it by RISE), the side planes' unit normals (inwards) and the margins."""

    p: wp.vec3
    nl: wp.vec3
    c0: wp.vec3
    h_end: float
    ng: wp.vec3
    own: int
    d: float
    sides: wp.mat44
    margin: float


@wp.func
def side_plane(p: wp.vec3, a: wp.vec3, b: wp.vec3, inside: wp.vec3) -> wp.vec4:
    """The unit normal of the plane through p, a and b, turned towards ``inside`` (w 0), or w 1 where the three
    points are too near a line for a plane."""
    m = wp.cross(a - p, b - p)
    length = wp.length(m)
    if not (length > 1.0e-12 * wp.length(a - p) * wp.length(b - p)):
        return wp.vec4(0.0, 0.0, 0.0, 1.0)
    m = m / length
    if wp.dot(m, inside - p) < 0.0:
        m = -m
    return wp.vec4(m[0], m[1], m[2], 0.0)


@wp.func
def pyramid(s: SceneData, hit: Surface, e: int) -> Pyramid:
    """Light e's pyramid from the hit (Pyramid); margin < 0 where there is none to prove with (the hit too near
    the light's plane, or a side degenerate)."""
    out = Pyramid()
    c0 = s.area.hull[4 * e]
    c1 = s.area.hull[4 * e + 1]
    c2 = s.area.hull[4 * e + 2]
    c3 = s.area.hull[4 * e + 3]
    p = hit.p
    centre = (c0 + c1 + c2 + c3) * 0.25
    out.p = p
    out.c0 = c0
    out.margin = -1.0
    out.d = wp.abs(hit.ng[0]) * hit.err[0] + wp.abs(hit.ng[1]) * hit.err[1] + wp.abs(hit.ng[2]) * hit.err[2]
    nl = wp.normalize(wp.cross(c1 - c0, c3 - c0))
    h_p = wp.dot(nl, p - c0)
    if h_p < 0.0:
        nl = -nl
        h_p = -h_p
    out.nl = nl
    margin = wp.static(CLEAR_MARGIN) * wp.length(centre - p) + out.d
    out.h_end = wp.static(SHADOW_EPSILON) * h_p - margin
    ng = hit.ng
    if wp.dot(ng, centre - p) < 0.0:
        ng = -ng
    out.ng = ng
    rise = wp.min(wp.min(wp.dot(ng, c0 - p) / wp.length(c0 - p), wp.dot(ng, c1 - p) / wp.length(c1 - p)),
                  wp.min(wp.dot(ng, c2 - p) / wp.length(c2 - p), wp.dot(ng, c3 - p) / wp.length(c3 - p)))
    out.own = wp.where(rise > wp.static(RISE), 1, 0)
    s0 = side_plane(p, c0, c1, c2)
    s1 = side_plane(p, c1, c2, c3)
    s2 = side_plane(p, c2, c3, c0)
    s3 = side_plane(p, c3, c0, c1)
    out.sides = wp.matrix_from_rows(s0, s1, s2, s3)
    if out.h_end > margin and s0[3] + s1[3] + s2[3] + s3[3] == 0.0:
        out.margin = margin
    return out


@wp.func
def beyond(py: Pyramid, a: wp.vec3, b: wp.vec3, c: wp.vec3) -> bool:
    """Whether the triangle (a, b, c) lies wholly beyond one of the pyramid's planes (the module's three)."""
    nl, c0 = py.nl, py.c0
    if wp.max(wp.max(wp.dot(nl, a - c0), wp.dot(nl, b - c0)), wp.dot(nl, c - c0)) < py.h_end:
        return True
    p = py.p
    if py.own != 0:
        ng = py.ng
        if wp.max(wp.max(wp.dot(ng, a - p), wp.dot(ng, b - p)), wp.dot(ng, c - p)) <= 0.5 * py.d:
            return True
    for i in range(4):
        m = wp.vec3(py.sides[i, 0], py.sides[i, 1], py.sides[i, 2])
        if wp.max(wp.max(wp.dot(m, a - p), wp.dot(m, b - p)), wp.dot(m, c - p)) < -py.margin:
            return True
    return False


@wp.func
def light_clear(s: SceneData, hit: Surface, e: int, points: int) -> int:
    """1 where no triangle can stop a shadow ray from the hit to area light e's points (the module's proof), 0
    where one might (or the frame traces every ray, or the light has no hull: AreaLights.clear, hulled, or the
    hit takes fewer than CLEAR_MIN_POINTS ``points`` of it, too few to pay for the proof), and its rays are
    traced."""
    if points < wp.static(CLEAR_MIN_POINTS) or s.area.clear == 0 or s.area.hulled[e] == 0:
        return 0
    py = pyramid(s, hit, e)
    if py.margin < 0.0:
        return 0
    lower = py.p
    upper = py.p
    for i in range(4):
        c = s.area.hull[4 * e + i]
        lower = wp.min(lower, c)
        upper = wp.max(upper, c)
    pad = wp.vec3(py.margin + py.d)
    query = wp.mesh_query_aabb(s.mesh, lower - pad, upper + pad)
    f = int(0)
    clear = int(1)
    while wp.mesh_query_aabb_next(query, f):
        a, b, c = triangle(s, f)
        if not beyond(py, a, b, c):
            clear = 0
            break
    return clear
