"""The Z-buffer renderer, the seed's point of comparison, in Warp kernels: triangles clipped at the eye,
projected with the tracer's camera, depth-tested at the tracer's samples, shaded by the tracer's Phong.

Stages, one kernel each: project (per triangle: clip, project, the pixels whose samples it may cover)
-> bin (count per tile, scan, fill) -> raster (per tile: one thread owns the tile's samples and walks
its triangles, so no two threads write one sample on any device) -> shade (per pixel: make_surface
and make_shade with shadows off, the very functions the tracer calls at its primary hit).

Near plane: the tracer's primary rays start at the eye and report every hit with t >= 0, so it draws
geometry between the eye and the image plane at d_f = near. Clipping at z = -near, as OpenGL does,
would cut exactly that away; the rasterizer clips at z = -CLIP_SCALE R instead (R bounds the distance
of every vertex from the eye), which loses only what lies within about 1e-6 R of the eye. Screen
coordinates are float64, so vertices clipped that close to the eye still rasterize exactly.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
from ._warp import wp

from .camera import camera_basis
from .effects import EffectSet, resolve_effects
from .geometry import Geometry, SceneData
from .shading import make_shade
from .tracer import CameraData, camera_data, camera_ray, make_surface

CLIP_SCALE = 1.0e-6
TILE = 16  # pixels per tile side: each raster thread owns one tile

# Where the rasterizer's float64 answer may not be the tracer's float32 one (hybrid rendering takes a
# sample's first hit from here only where it is the same): a sample within MARGIN_PX pixels of a
# triangle's edge, or two surfaces within TIE_REL of each other in depth. Float32 rounding moves the
# tracer's rays by about 1e-4 pixel at 1024 pixels across (a few ulp of the direction, 1e-7 rad,
# against 7.7e-4 rad per pixel at fovy 45) and its hit distances by about 1e-6 relative; both margins
# are a hundred times that. Such samples are marked in `near`, and the hybrid traces them.
MARGIN_PX = 1.0e-2
TIE_REL = 1.0e-4


def clip_distance(geometry: Geometry) -> float:
    """z_clip = CLIP_SCALE R, R = sqrt(3) max |coordinate| bounding every vertex's distance from the eye."""
    reach = float(np.abs(geometry.points_np).max(initial=0.0)) * math.sqrt(3.0)
    return CLIP_SCALE * max(reach, 1e-30)


def eye_on_surface(geometry: Geometry, basis) -> bool:
    """Whether some triangle comes within reach of the eye that the rasterizer clips: its plane that
    close, and the eye inside its box grown by as much. The clip plane z = z_clip cuts away points
    that camera rays (at most the corner ray's angle theta off the axis) reach within
    z_clip / cos(theta); twice that is the reach. The tracer's rays, which start at the eye and keep
    hits from t = 0, hit such a triangle there, as they do one the eye lies on. Hybrid rendering
    traces the first hits of such a view: a camera placed on (or a hair from) a surface."""
    cos_corner = basis.d_f / math.sqrt(basis.d_f ** 2 + (basis.h / 2.0) ** 2 + (basis.w / 2.0) ** 2)
    tol = 2.0 * clip_distance(geometry) / cos_corner
    cache = geometry.__dict__.setdefault("_eye_on_surface", {})  # a Geometry is reused across frames
    if tol not in cache:
        cache[tol] = _eye_on_surface(geometry, tol)
    return cache[tol]


def _eye_on_surface(geometry: Geometry, tol: float) -> bool:
    if geometry.triangle_count == 0:
        return False
    tri = geometry.points_np.astype(np.float64)[geometry.indices_np.reshape(-1, 3)]  # eye at the origin
    in_box = np.all((tri.min(axis=1) <= tol) & (tri.max(axis=1) >= -tol), axis=1)
    if not in_box.any():
        return False
    t = tri[in_box]
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    length = np.linalg.norm(n, axis=1)
    plane = np.abs(np.einsum("ij,ij->i", n, t[:, 0]))  # |n . p0|: |n| times the eye's distance to the plane
    return bool(np.any(plane <= tol * length))


@wp.struct
class RasterCamera:
    """The camera basis in float64 and the projection onto continuous pixel coordinates
    (X, Y) = (c_x + f_x x/z, c_y + f_y y/z), y counted up from the bottom edge like the tracer."""

    x_e: wp.vec3d
    y_e: wp.vec3d
    z_e: wp.vec3d
    f_x: wp.float64  # d_f * width / w: pixels per unit of x/z
    f_y: wp.float64
    c_x: wp.float64  # width / 2
    c_y: wp.float64
    z_clip: wp.float64  # clip distance in front of the eye
    margin: wp.float64  # MARGIN_PX when the rasterizer tracks uncertain samples for the hybrid, else 0
    width: int
    height: int


def raster_camera(basis, z_clip: float, margin: float = 0.0) -> RasterCamera:
    c = RasterCamera()
    c.x_e, c.y_e, c.z_e = (wp.vec3d(*map(float, v)) for v in (basis.x_e, basis.y_e, basis.z_e))
    c.f_x = wp.float64(basis.d_f * basis.width / basis.w)
    c.f_y = wp.float64(basis.d_f * basis.height / basis.h)
    c.c_x = wp.float64(basis.width / 2.0)
    c.c_y = wp.float64(basis.height / 2.0)
    c.z_clip = wp.float64(z_clip)
    c.margin = wp.float64(margin)
    c.width, c.height = int(basis.width), int(basis.height)
    return c


@wp.struct
class ClipVertex:
    c: wp.vec3d  # camera coordinates (p.x_e, p.y_e, -p.z_e): the last is the depth in front of the eye
    uv: wp.vec2  # Warp's barycentrics of the original triangle: p = p0 u + p1 v + p2 (1 - u - v)


@wp.struct
class Polygon:
    """A triangle after clipping against the plane z = z_clip: n = 0, 3 or 4 vertices, in order."""

    n: int
    v0: ClipVertex
    v1: ClipVertex
    v2: ClipVertex
    v3: ClipVertex


@wp.struct
class ScreenVertex:
    x: wp.float64  # continuous pixel coordinates, y up
    y: wp.float64
    iz: wp.float64  # 1 / depth: linear in screen space, so it interpolates exactly
    uv: wp.vec2


@wp.func
def lex_less(a: wp.vec3d, b: wp.vec3d) -> bool:
    if a[0] != b[0]:
        return a[0] < b[0]
    if a[1] != b[1]:
        return a[1] < b[1]
    return a[2] < b[2]


@wp.func
def clip_vertex(c: RasterCamera, p: wp.vec3, uv: wp.vec2) -> ClipVertex:
    """Camera coordinates of a camera-relative point: (p.x_e, p.y_e, -p.z_e)."""
    q = wp.vec3d(wp.float64(p[0]), wp.float64(p[1]), wp.float64(p[2]))
    out = ClipVertex()
    out.c = wp.vec3d(wp.dot(q, c.x_e), wp.dot(q, c.y_e), -wp.dot(q, c.z_e))
    out.uv = uv
    return out


@wp.func
def clip_edge(a: ClipVertex, b: ClipVertex, z_clip: wp.float64) -> ClipVertex:
    """Where the edge a-b crosses z = z_clip. Computed from the lexicographically smaller endpoint,
    so two triangles sharing the edge get the same point and the clipped mesh stays watertight."""
    p = a
    q = b
    if lex_less(b.c, a.c):
        p = b
        q = a
    t = (z_clip - p.c[2]) / (q.c[2] - p.c[2])
    out = ClipVertex()
    out.c = wp.vec3d(p.c[0] + t * (q.c[0] - p.c[0]), p.c[1] + t * (q.c[1] - p.c[1]), z_clip)
    out.uv = p.uv + float(t) * (q.uv - p.uv)
    return out


@wp.func
def clip_triangle(c: RasterCamera, points: wp.array(dtype=wp.vec3), indices: wp.array(dtype=wp.int32), f: int) -> Polygon:
    """Sutherland-Hodgman against the one plane z = z_clip, in camera space (before the divide)."""
    a = clip_vertex(c, points[indices[f * 3 + 0]], wp.vec2(1.0, 0.0))
    b = clip_vertex(c, points[indices[f * 3 + 1]], wp.vec2(0.0, 1.0))
    d = clip_vertex(c, points[indices[f * 3 + 2]], wp.vec2(0.0, 0.0))
    in_a = a.c[2] >= c.z_clip
    in_b = b.c[2] >= c.z_clip
    in_d = d.c[2] >= c.z_clip
    inside = int(in_a) + int(in_b) + int(in_d)
    out = Polygon()
    out.n = 0
    if inside == 3:
        out.n = 3
        out.v0 = a
        out.v1 = b
        out.v2 = d
    elif inside == 1:
        # Rotate (keeping the winding) so the inside vertex comes first: (first, first-next, prev-first).
        p0 = a
        p1 = b
        p2 = d
        if in_b:
            p0 = b
            p1 = d
            p2 = a
        elif in_d:
            p0 = d
            p1 = a
            p2 = b
        out.n = 3
        out.v0 = p0
        out.v1 = clip_edge(p0, p1, c.z_clip)
        out.v2 = clip_edge(p2, p0, c.z_clip)
    elif inside == 2:
        # Rotate so the outside vertex comes last: a quad (p0, p1, p1-p2, p2-p0).
        p0 = a
        p1 = b
        p2 = d
        if not in_a:
            p0 = b
            p1 = d
            p2 = a
        elif not in_b:
            p0 = d
            p1 = a
            p2 = b
        out.n = 4
        out.v0 = p0
        out.v1 = p1
        out.v2 = clip_edge(p1, p2, c.z_clip)
        out.v3 = clip_edge(p2, p0, c.z_clip)
    return out


@wp.func
def project(c: RasterCamera, v: ClipVertex) -> ScreenVertex:
    """(X, Y) = (c_x + f_x x/z, c_y + f_y y/z): the inverse of the tracer's camera_ray."""
    out = ScreenVertex()
    out.iz = wp.float64(1.0) / v.c[2]
    out.x = c.c_x + c.f_x * v.c[0] * out.iz
    out.y = c.c_y + c.f_y * v.c[1] * out.iz
    out.uv = v.uv
    return out


@wp.struct
class Edge:
    """The edge function of a->b, (b - a) x (P - a), set up from the lexicographically smaller endpoint:
    two triangles sharing an edge evaluate the very same expression, so their values are exactly
    opposite and no sample falls in both or in neither."""

    ax: wp.float64  # the smaller endpoint
    ay: wp.float64
    dx: wp.float64  # larger - smaller
    dy: wp.float64
    sign: wp.float64  # +1 where the triangle's interior is on the positive side of the canonical function
    m: wp.float64  # the margin times the edge's length: the edge function's value that many pixels off the edge


@wp.func
def make_edge(a: ScreenVertex, b: ScreenVertex, orientation: wp.float64, margin: wp.float64) -> Edge:
    e = Edge()
    if b.x < a.x or (b.x == a.x and b.y < a.y):
        e.ax = b.x
        e.ay = b.y
        e.dx = a.x - b.x
        e.dy = a.y - b.y
        e.sign = -orientation
    else:
        e.ax = a.x
        e.ay = a.y
        e.dx = b.x - a.x
        e.dy = b.y - a.y
        e.sign = orientation
    e.m = margin * wp.sqrt(e.dx * e.dx + e.dy * e.dy)
    return e


@wp.func
def edge_at(e: Edge, row_term: wp.float64, px: wp.float64) -> wp.float64:
    """sign ((b - a) x (P - a)), with row_term = dx (P.y - a.y) computed once per sample row."""
    return e.sign * (row_term - e.dy * (px - e.ax))


@wp.func
def covers(e: Edge, value: wp.float64) -> bool:
    """Inside, or exactly on the edge and on its owning side: the top-left rule, since the canonical
    function is positive below a rightward edge and right of an upward one; of two triangles sharing
    the edge exactly one owns such a sample."""
    return value > wp.float64(0.0) or (value == wp.float64(0.0) and e.sign > wp.float64(0.0))


@wp.func
def raster_triangle(s0: ScreenVertex, s1: ScreenVertex, s2: ScreenVertex, f: int, x_lo: int, x_hi: int,
                    y_lo: int, y_hi: int, c: RasterCamera, k: int, samples: int,
                    depth: wp.array(dtype=wp.float64), face: wp.array(dtype=wp.int32), uv: wp.array(dtype=wp.vec2),
                    near: wp.array(dtype=wp.float64)):
    """Depth-test one screen triangle at every sample in the pixel rectangle [x_lo, x_hi] x [y_lo, y_hi]
    (y up). Depth is 1/z, which is linear in screen space; (u, v) are interpolated perspective-correctly.
    near[n] keeps the nearest 1/z of every surface that could be the tracer's answer at sample n but
    need not be the rasterizer's: one within MARGIN_PX of an edge, inside or out, and one that lost
    the depth test (see uncertain()); only where c.margin > 0, for hybrid rendering: a plain Z-buffer
    image needs none of it, and it costs that 10-20 %."""
    track = c.margin > wp.float64(0.0)
    one = wp.float64(1.0)
    # The sample (x + sx, y + sy) lies in the triangle, or within the margin of it, only if
    # floor(min X - margin) <= x <= floor(max X + margin).
    big = wp.float64(1.0e9)
    pad = c.margin
    x0 = wp.max(x_lo, int(wp.floor(wp.clamp(wp.min(wp.min(s0.x, s1.x), s2.x) - pad, -big, big))))
    x1 = wp.min(x_hi, int(wp.floor(wp.clamp(wp.max(wp.max(s0.x, s1.x), s2.x) + pad, -big, big))))
    y0 = wp.max(y_lo, int(wp.floor(wp.clamp(wp.min(wp.min(s0.y, s1.y), s2.y) - pad, -big, big))))
    y1 = wp.min(y_hi, int(wp.floor(wp.clamp(wp.max(wp.max(s0.y, s1.y), s2.y) + pad, -big, big))))
    probe = make_edge(s1, s2, one, c.margin)
    area = edge_at(probe, probe.dx * (s0.y - probe.ay), s0.x)  # twice the signed area, as the edges see it
    if area == wp.float64(0.0):
        if not track:
            return
        # Seen edge-on: no sample lies strictly inside, but float32 rays near its line may hit it, so
        # every sample of its box is uncertain (near = the largest 1/z: nearer than anything).
        for y in range(y0, y1 + 1):
            for x in range(x0, x1 + 1):
                for i in range(samples):
                    near[((c.height - 1 - y) * c.width + x) * samples + i] = wp.float64(1.0e300)
        return
    orientation = one
    if area < wp.float64(0.0):
        orientation = -one  # two-sided: either winding is drawn
    e0 = make_edge(s1, s2, orientation, c.margin)
    e1 = make_edge(s2, s0, orientation, c.margin)
    e2 = make_edge(s0, s1, orientation, c.margin)
    step = one / wp.float64(k)
    half = wp.float64(0.5) * step
    for y in range(y0, y1 + 1):
        row = c.height - 1 - y
        for j in range(k):  # sample rows: sample index j k + i sits at (x + (i + 1/2)/k, y + (j + 1/2)/k)
            py = wp.float64(y) + (wp.float64(j) * step + half)
            r0 = e0.dx * (py - e0.ay)
            r1 = e1.dx * (py - e1.ay)
            r2 = e2.dx * (py - e2.ay)
            for x in range(x0, x1 + 1):
                for i in range(k):
                    px = wp.float64(x) + (wp.float64(i) * step + half)
                    v0 = edge_at(e0, r0, px)
                    v1 = edge_at(e1, r1, px)
                    v2 = edge_at(e2, r2, px)
                    inside = covers(e0, v0) and covers(e1, v1) and covers(e2, v2)
                    edgy = False
                    if track:  # within the margin band around the triangle, and close to one of its edges?
                        if not (v0 >= -e0.m and v1 >= -e1.m and v2 >= -e2.m):
                            continue
                        edgy = v0 <= e0.m or v1 <= e1.m or v2 <= e2.m
                    elif not inside:
                        continue
                    w0 = v0 * s0.iz
                    w1 = v1 * s1.iz
                    w2 = v2 * s2.iz
                    wsum = w0 + w1 + w2
                    iz = wsum / (v0 + v1 + v2)  # 1/z is linear in screen space, off the triangle too
                    n = (row * c.width + x) * samples + j * k + i
                    if edgy:
                        near[n] = wp.max(near[n], iz)
                    if inside:
                        # Equal depth goes to the lower face index, so the image does not depend on
                        # the order of a tile's list (which atomics make arbitrary on a GPU).
                        if iz > depth[n] or (iz == depth[n] and f < face[n]):
                            if track:
                                near[n] = wp.max(near[n], depth[n])  # the surface it hides, for the tie test
                            depth[n] = iz
                            face[n] = f
                            uv[n] = (s0.uv * float(w0 / wsum) + s1.uv * float(w1 / wsum)) + s2.uv * float(w2 / wsum)
                        elif track:
                            near[n] = wp.max(near[n], iz)


@wp.func
def uncertain(depth: wp.float64, near: wp.float64) -> bool:
    """Whether the tracer may see another surface than the rasterizer at a sample: some surface near
    an edge there, or hidden by less than TIE_REL in depth, is about as near as the visible one
    (1/z at least (1 - TIE_REL) times the visible one's; depth 0 where nothing is visible)."""
    return near > wp.float64(0.0) and near >= depth * wp.float64(1.0 - TIE_REL)


@wp.func
def sample_span(lo: wp.float64, hi: wp.float64, k: int, n: int, margin: wp.float64) -> wp.vec2i:
    """The pixels (first, last) whose samples x + (j + 1/2)/k, j < k, fall in [lo, hi] on one axis of n
    pixels; first > last when none does. Widened by the margin, so samples near the triangle are seen
    too, and by a hair more so that rounding can only add a pixel."""
    kf = wp.float64(k)
    pad = margin + wp.float64(1.0e-9) * (wp.float64(1.0) + wp.abs(lo) + wp.abs(hi))
    big = wp.float64(4.0e9)  # keeps int() in range for vertices projected from just in front of the eye
    m_lo = wp.max(wp.ceil(wp.clamp(kf * (lo - pad) - wp.float64(0.5), -big, big)), wp.float64(0.0))
    m_hi = wp.min(wp.floor(wp.clamp(kf * (hi + pad) - wp.float64(0.5), -big, big)), wp.float64(n * k - 1))
    if m_lo > m_hi:
        return wp.vec2i(1, 0)
    return wp.vec2i(int(m_lo) / k, int(m_hi) / k)


@wp.kernel(enable_backward=False)
def project_kernel(s: SceneData, c: RasterCamera, k: int, first: int, bounds: wp.array(dtype=wp.vec4i)):
    """Per triangle: the pixel rectangle (x0, x1, y0, y1), y up, whose samples its clipped projection
    may cover; x0 > x1 when it can cover none (behind the eye, off the image, or so small that it
    falls between samples, the fate of most triangles of a mesh finer than the pixels)."""
    f = first + wp.tid()
    poly = clip_triangle(c, s.points, s.indices, f)
    out = wp.vec4i(1, 0, 1, 0)
    if poly.n > 0:
        a = project(c, poly.v0)
        b = project(c, poly.v1)
        d = project(c, poly.v2)
        lo_x = wp.min(wp.min(a.x, b.x), d.x)
        hi_x = wp.max(wp.max(a.x, b.x), d.x)
        lo_y = wp.min(wp.min(a.y, b.y), d.y)
        hi_y = wp.max(wp.max(a.y, b.y), d.y)
        if poly.n == 4:
            e = project(c, poly.v3)
            lo_x = wp.min(lo_x, e.x)
            hi_x = wp.max(hi_x, e.x)
            lo_y = wp.min(lo_y, e.y)
            hi_y = wp.max(hi_y, e.y)
        span_x = sample_span(lo_x, hi_x, k, c.width, c.margin)
        span_y = sample_span(lo_y, hi_y, k, c.height, c.margin)
        if span_x[0] <= span_x[1] and span_y[0] <= span_y[1]:
            out = wp.vec4i(span_x[0], span_x[1], span_y[0], span_y[1])
    bounds[f] = out


@wp.kernel(enable_backward=False)
def raster_kernel(s: SceneData, c: RasterCamera, tile_start: wp.array(dtype=wp.int32),
                  tile_faces: wp.array(dtype=wp.int32), tiles_x: int, tile: int, k: int, samples: int, first: int,
                  depth: wp.array(dtype=wp.float64), face: wp.array(dtype=wp.int32), uv: wp.array(dtype=wp.vec2),
                  near: wp.array(dtype=wp.float64)):
    """One thread per tile: every triangle binned to it clipped, projected and depth-tested at the
    tile's samples. Only this thread writes the tile's samples."""
    t = first + wp.tid()
    x_lo = (t % tiles_x) * tile
    y_lo = (t / tiles_x) * tile
    x_hi = wp.min(x_lo + tile, c.width) - 1
    y_hi = wp.min(y_lo + tile, c.height) - 1
    for j in range(tile_start[t], tile_start[t + 1]):
        f = tile_faces[j]
        poly = clip_triangle(c, s.points, s.indices, f)
        a = project(c, poly.v0)
        b = project(c, poly.v1)
        d = project(c, poly.v2)
        raster_triangle(a, b, d, f, x_lo, x_hi, y_lo, y_hi, c, k, samples, depth, face, uv, near)
        if poly.n == 4:
            # The quad as the fan (v0, v1, v2), (v0, v2, v3): the diagonal is shared exactly.
            e = project(c, poly.v3)
            raster_triangle(a, d, e, f, x_lo, x_hi, y_lo, y_hi, c, k, samples, depth, face, uv, near)


_shade_kernels: dict = {}


def make_shade_kernel(fx: EffectSet):
    """Per pixel: the tracer's surface and local shading at each sample's visible point, box-filtered."""
    if fx in _shade_kernels:
        return _shade_kernels[fx]
    shade = make_shade(fx)
    surface = make_surface(fx.smooth)
    SUPERSAMPLING = fx.supersampling

    @wp.kernel(module="unique", enable_backward=False)
    def shade_zbuffer(s: SceneData, c: CameraData, k: int, first_pixel: int, face: wp.array(dtype=wp.int32),
                      uv: wp.array(dtype=wp.vec2), image: wp.array(dtype=wp.vec3)):
        pixel = first_pixel + wp.tid()
        x = pixel % c.width
        row = pixel / c.width
        samples = int(1)
        if wp.static(SUPERSAMPLING):
            samples = k * k
        total = wp.vec3(0.0)
        for sample in range(samples):
            i = pixel * samples + sample
            f = face[i]
            if f < 0:
                total = total + s.background
                continue
            sx = float(0.5)
            sy = float(0.5)
            if wp.static(SUPERSAMPLING):
                sx = (float(sample % k) + 0.5) / float(k)
                sy = (float(sample / k) + 0.5) / float(k)
            d = camera_ray(c, x, row, sx, sy)
            p0 = s.points[s.indices[f * 3 + 0]]
            p1 = s.points[s.indices[f * 3 + 1]]
            p2 = s.points[s.indices[f * 3 + 2]]
            # The same normal Warp's ray query reports, cross(p1 - p0, p2 - p0), so make_surface
            # turns smooth normals to the same side as in the tracer.
            hit = surface(s, f, uv[i][0], uv[i][1], wp.normalize(wp.cross(p1 - p0, p2 - p0)), d)
            r = shade(s, hit.material, hit.p, hit.err, hit.ng, hit.n, -d)
            total = total + r.color
        image[pixel] = total / float(samples)

    _shade_kernels[fx] = shade_zbuffer
    return shade_zbuffer


@wp.kernel(enable_backward=False)
def count_kernel(bounds: wp.array(dtype=wp.vec4i), tile: int, tiles_x: int, tile_count: wp.array(dtype=wp.int32)):
    """Per triangle: +1 for every tile its pixel rectangle touches."""
    b = bounds[wp.tid()]
    if b[0] > b[1]:
        return  # culled
    for ty in range(b[2] / tile, b[3] / tile + 1):
        for tx in range(b[0] / tile, b[1] / tile + 1):
            wp.atomic_add(tile_count, ty * tiles_x + tx, 1)


@wp.kernel(enable_backward=False)
def fill_kernel(bounds: wp.array(dtype=wp.vec4i), tile: int, tiles_x: int, cursor: wp.array(dtype=wp.int32),
                tile_faces: wp.array(dtype=wp.int32)):
    """Per triangle: its index into the list of every tile it touches."""
    f = wp.tid()
    b = bounds[f]
    if b[0] > b[1]:
        return
    for ty in range(b[2] / tile, b[3] / tile + 1):
        for tx in range(b[0] / tile, b[1] / tile + 1):
            tile_faces[wp.atomic_add(cursor, ty * tiles_x + tx, 1)] = f


class ZBuffer:
    """Owns the per-sample buffers of one scene's rasterization: 1/depth, visible face, (u, v)."""

    def __init__(self, scene, geometry: Geometry, fx: EffectSet, device: str = "cpu", tile: int = TILE,
                 track_uncertain: bool = True):
        cam = scene.camera
        self.geometry, self.device, self.tile = geometry, device, int(tile)
        self.track_uncertain = track_uncertain
        self.basis = camera_basis(cam)
        self.k = math.isqrt(scene.render.spp)
        self.samples = self.k * self.k if fx.supersampling else 1
        # track_uncertain: fill `near` for hybrid rendering (uncertain()); a plain Z-buffer image skips it.
        self.camera = raster_camera(self.basis, clip_distance(geometry), MARGIN_PX if track_uncertain else 0.0)
        n = cam.width * cam.height * self.samples
        self.depth = wp.zeros(n, dtype=wp.float64, device=device)  # 1/z; 0 is "nothing yet"
        self.face = wp.full(n, -1, dtype=wp.int32, device=device)
        self.uv = wp.zeros(n, dtype=wp.vec2, device=device)
        # 1/z of the nearest uncertain rival, 0 where none; only allocated when tracked
        self.near = wp.zeros(n if track_uncertain else 0, dtype=wp.float64, device=device)
        self.times: dict = {}
        self.pairs = 0

    def rasterize(self, threads: int, bands: int):
        from .renderer import launch_bands

        g, c, dev = self.geometry, self.camera, self.device
        data = g.data
        k = self.k if self.samples > 1 else 1
        t = time.perf_counter()
        bounds = wp.empty(max(g.triangle_count, 1), dtype=wp.vec4i, device=dev)
        if g.triangle_count:
            # A few thousand triangles per launch: below that, launching costs more than projecting.
            launch_bands(project_kernel, lambda first: [data, c, k, first, bounds], g.triangle_count, threads,
                         max(1, min(bands, g.triangle_count // 4096)), dev)
        self.times["project"] = time.perf_counter() - t

        # Binning: count per tile, scan, fill. One launch each: Warp's atomics are plain
        # read-modify-writes on the CPU, safe within a launch (one thread) but not across launches.
        t = time.perf_counter()
        tile = self.tile
        tiles_x, tiles_y = -(-c.width // tile), -(-c.height // tile)
        tile_count = wp.zeros(tiles_x * tiles_y, dtype=wp.int32, device=dev)
        wp.launch(count_kernel, dim=g.triangle_count, inputs=[bounds, tile, tiles_x, tile_count], device=dev)
        tile_start = np.zeros(tiles_x * tiles_y + 1, np.int32)
        tile_start[1:] = np.cumsum(tile_count.numpy())
        self.pairs = int(tile_start[-1])
        starts = wp.array(tile_start, dtype=wp.int32, device=dev)
        cursor = wp.array(tile_start[:-1], dtype=wp.int32, device=dev)
        faces = wp.empty(max(self.pairs, 1), dtype=wp.int32, device=dev)
        wp.launch(fill_kernel, dim=g.triangle_count, inputs=[bounds, tile, tiles_x, cursor, faces], device=dev)
        wp.synchronize_device(dev)
        self.times["bin"] = time.perf_counter() - t

        t = time.perf_counter()
        samples = self.samples
        launch_bands(raster_kernel, lambda first: [data, c, starts, faces, tiles_x, tile, k, samples, first,
                                                   self.depth, self.face, self.uv, self.near],
                     tiles_x * tiles_y, threads, max(bands, 4 * threads), dev)
        self.times["raster"] = time.perf_counter() - t

    def uncertain(self) -> np.ndarray:
        """Where the rasterizer's visible triangle may not be the tracer's, (height, width, samples):
        uncertain() of every sample, in NumPy."""
        if not self.track_uncertain:
            raise ValueError("this ZBuffer was made with track_uncertain=False: it has no uncertain samples to report")
        depth, near = self.depth.numpy(), self.near.numpy()
        shape = (self.basis.height, self.basis.width, self.samples)
        return ((near > 0.0) & (near >= depth * (1.0 - TIE_REL))).reshape(shape)

    def faces(self) -> np.ndarray:
        """The visible triangle of every sample, (height, width, samples), -1 where none."""
        return self.face.numpy().reshape(self.basis.height, self.basis.width, self.samples)


def _zbuffer_effects(scene, effects, disable) -> EffectSet:
    """The scene's effect set without what a Z-buffer cannot simulate: shadows and reflections."""
    return dataclasses.replace(resolve_effects(scene, effects, disable), shadows=False, reflection=False)


def render_zbuffer(scene, *, threads: int | None = None, device: str = "cpu", effects=None, disable=(),
                   bands: int | None = None, geometry: Geometry | None = None, tile: int = TILE,
                   return_faces: bool = False):
    """Render ``scene`` by rasterization with the tracer's local shading (no shadows, no reflections).
    Returns a RenderResult, and with return_faces also the visible face per sample (H, W, samples)."""
    from .renderer import RenderResult, RenderStats, check_finite, init_warp, launch_bands, launch_plan
    from .scene import validate_camera

    init_warp()
    validate_camera(scene.camera, scene.source)
    t_start = time.perf_counter()
    threads, bands = launch_plan(threads, bands, device)
    cam = scene.camera
    n_pixels = cam.width * cam.height
    fx = _zbuffer_effects(scene, effects, disable)
    stats = RenderStats(width=cam.width, height=cam.height, spp=scene.render.spp, max_depth=1,
                        lights=len(scene.lights), device=str(device), threads=threads, bands=bands,
                        algorithm="zbuffer", effects=str(fx), variant=f"zbuffer_{fx.variant}")
    stats.rays = {"primary": 0, "shadow": 0, "reflection": 0, "total": 0}  # none: visibility is rasterized
    if getattr(scene, "load_seconds", None) is not None:
        stats.times["load"] = scene.load_seconds

    t = time.perf_counter()
    geom = geometry or Geometry(scene, device=device, build_bvh=False)
    stats.triangles = geom.triangle_count
    stats.times["geometry"] = time.perf_counter() - t

    t = time.perf_counter()
    kernel = make_shade_kernel(fx)
    for m in (kernel.module, raster_kernel.module):
        wp.load_module(m, device=device)
    stats.times["compile"] = time.perf_counter() - t

    t = time.perf_counter()
    zb = ZBuffer(scene, geom, fx, device=device, tile=tile, track_uncertain=False)
    zb.rasterize(threads, bands)
    stats.times.update(zb.times)
    t_shade = time.perf_counter()
    image = wp.empty(n_pixels, dtype=wp.vec3, device=device)
    c = camera_data(zb.basis)
    data, k = geom.data, zb.k
    launch_bands(kernel, lambda first: [data, c, k, first, zb.face, zb.uv, image], n_pixels, threads, bands, device)
    out = image.numpy().reshape(cam.height, cam.width, 3).copy()
    stats.times["shade"] = time.perf_counter() - t_shade
    stats.times["render"] = time.perf_counter() - t  # project + bin + raster + shade
    check_finite(out, "zbuffer")
    stats.times["total"] = time.perf_counter() - t_start
    result = RenderResult(out, stats)
    return (result, zb.faces()) if return_faces else result


# The tracer's primary visibility, for comparison: the very query the trace kernel makes first
# (same camera_ray, origin at the eye, same max_t), without shading, so the hot path is untouched.


@wp.kernel(enable_backward=False)
def primary_faces_kernel(s: SceneData, c: CameraData, k: int, samples: int, first_pixel: int,
                         face: wp.array(dtype=wp.int32)):
    pixel = first_pixel + wp.tid()
    x = pixel % c.width
    row = pixel / c.width
    for sample in range(samples):
        sx = float(0.5)
        sy = float(0.5)
        if samples > 1:
            sx = (float(sample % k) + 0.5) / float(k)
            sy = (float(sample / k) + 0.5) / float(k)
        q = wp.mesh_query_ray(s.mesh, wp.vec3(0.0), camera_ray(c, x, row, sx, sy), 1.0e30)
        f = int(-1)
        if q.result:
            f = q.face
        face[pixel * samples + sample] = f


def traced_faces(scene, *, geometry: Geometry | None = None, effects=None, disable=(), threads: int | None = None,
                 device: str = "cpu") -> np.ndarray:
    """The face the ray tracer's primary ray hits at every sample, (height, width, samples), -1 for a miss;
    samples as the tracer takes them for this effect set (k*k with supersampling, else the centre)."""
    from .renderer import default_threads, init_warp, launch_bands

    init_warp()
    cam = scene.camera
    fx = resolve_effects(scene, effects, disable)
    k = math.isqrt(scene.render.spp)
    samples = k * k if fx.supersampling else 1
    geom = geometry or Geometry(scene, device=device)
    if geom.mesh is None:
        raise ValueError("traced_faces needs a Geometry with its BVH (build_bvh=True)")
    threads = threads or default_threads()
    face = wp.empty(cam.width * cam.height * samples, dtype=wp.int32, device=device)
    c = camera_data(camera_basis(cam))
    launch_bands(primary_faces_kernel, lambda first: [geom.data, c, k, samples, first, face],
                 cam.width * cam.height, threads, max(16, 8 * threads), device)
    return face.numpy().reshape(cam.height, cam.width, samples)
