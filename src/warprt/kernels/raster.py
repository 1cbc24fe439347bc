"""The Z-buffer's depth test, in Warp kernels: per triangle, the pixels whose samples its clipped
projection may cover (project_kernel); binning into tiles (count_kernel, fill_kernel); per tile, one
thread owning the tile's samples and depth-testing every triangle binned to it (raster_kernel), so no
two threads write one sample on any device; on a GPU, one thread per pixel over its tile's list
(raster_pixel_kernel: the same tests per sample, far more threads). The result is a Fragments per sample.
"""

from __future__ import annotations

from .._warp import wp
from ..geometry import SceneData
from .camera import RasterCamera, sample_position
from .clip import ScreenVertex, clip_triangle, project
from .triangle import triangle


@wp.struct
class Fragments:
    """What the rasterizer hands on per sample (pixel * samples + sample, rows from the top): the
    visible face (-1: none), its inverse depth 1/z (0: nothing yet), its barycentrics (u, v) as Warp
    defines them, and the inverse depth of the nearest uncertain rival (hybrid.uncertain; only
    filled, and only allocated, when the rasterizer tracks uncertainty for the hybrid)."""

    face: wp.array(dtype=wp.int32)
    inv_depth: wp.array(dtype=wp.float64)
    uv: wp.array(dtype=wp.vec2)
    rival_inv_depth: wp.array(dtype=wp.float64)


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
                    y_lo: int, y_hi: int, c: RasterCamera, k: int, samples: int, out: Fragments):
    """Depth-test one screen triangle at every sample in the pixel rectangle [x_lo, x_hi] x [y_lo, y_hi]
    (y up). Depth is 1/z, which is linear in screen space; (u, v) are interpolated perspective-correctly.
    out.rival_inv_depth[n] keeps the nearest 1/z of every surface that could be the tracer's answer at
    sample n but need not be the rasterizer's: one within MARGIN_PX of an edge, inside or out, and one
    that lost the depth test (see hybrid.uncertain()); only where c.margin > 0, for hybrid rendering: a
    plain Z-buffer image needs none of it, and it costs that 10-20 %."""
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
        # every sample of its box is uncertain (a rival at the largest 1/z: nearer than anything).
        for y in range(y0, y1 + 1):
            for x in range(x0, x1 + 1):
                for i in range(samples):
                    out.rival_inv_depth[((c.height - 1 - y) * c.width + x) * samples + i] = wp.float64(1.0e300)
        return
    orientation = one
    if area < wp.float64(0.0):
        orientation = -one  # two-sided: either winding is drawn
    e0 = make_edge(s1, s2, orientation, c.margin)
    e1 = make_edge(s2, s0, orientation, c.margin)
    e2 = make_edge(s0, s1, orientation, c.margin)
    step = one / wp.float64(k)
    for y in range(y0, y1 + 1):
        row = c.height - 1 - y
        for j in range(k):  # sample rows: sample index j k + i sits at (x + (i + 1/2)/k, y + (j + 1/2)/k)
            py = sample_position(y, j, step)
            r0 = e0.dx * (py - e0.ay)
            r1 = e1.dx * (py - e1.ay)
            r2 = e2.dx * (py - e2.ay)
            for x in range(x0, x1 + 1):
                for i in range(k):
                    px = sample_position(x, i, step)
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
                        out.rival_inv_depth[n] = wp.max(out.rival_inv_depth[n], iz)
                    if inside:
                        # Equal depth goes to the lower face index, so the image does not depend on
                        # the order of a tile's list (which atomics make arbitrary on a GPU).
                        if iz > out.inv_depth[n] or (iz == out.inv_depth[n] and f < out.face[n]):
                            if track:  # the surface it hides, for the tie test
                                out.rival_inv_depth[n] = wp.max(out.rival_inv_depth[n], out.inv_depth[n])
                            out.inv_depth[n] = iz
                            out.face[n] = f
                            out.uv[n] = (s0.uv * float(w0 / wsum) + s1.uv * float(w1 / wsum)) + s2.uv * float(w2 / wsum)
                        elif track:
                            out.rival_inv_depth[n] = wp.max(out.rival_inv_depth[n], iz)


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
    p0, p1, p2 = triangle(s, f)
    poly = clip_triangle(c, p0, p1, p2)
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


@wp.func
def raster_list(s: SceneData, c: RasterCamera, tile_start: wp.array(dtype=wp.int32), tile_faces: wp.array(dtype=wp.int32),
                t: int, x_lo: int, x_hi: int, y_lo: int, y_hi: int, k: int, samples: int, out: Fragments):
    """Every triangle binned to tile t, in the list's order, clipped, projected and depth-tested at the
    samples of the pixel rectangle [x_lo, x_hi] x [y_lo, y_hi] (the tile's, or one pixel of it)."""
    for j in range(tile_start[t], tile_start[t + 1]):
        f = tile_faces[j]
        p0, p1, p2 = triangle(s, f)
        poly = clip_triangle(c, p0, p1, p2)
        a = project(c, poly.v0)
        b = project(c, poly.v1)
        d = project(c, poly.v2)
        raster_triangle(a, b, d, f, x_lo, x_hi, y_lo, y_hi, c, k, samples, out)
        if poly.n == 4:
            # The quad as the fan (v0, v1, v2), (v0, v2, v3): the diagonal is shared exactly.
            e = project(c, poly.v3)
            raster_triangle(a, d, e, f, x_lo, x_hi, y_lo, y_hi, c, k, samples, out)


@wp.kernel(enable_backward=False)
def raster_kernel(s: SceneData, c: RasterCamera, tile_start: wp.array(dtype=wp.int32),
                  tile_faces: wp.array(dtype=wp.int32), tiles_x: int, tile: int, k: int, samples: int, first: int,
                  out: Fragments):
    """One thread per tile: every triangle binned to it clipped, projected and depth-tested at the
    tile's samples. Only this thread writes the tile's samples."""
    t = first + wp.tid()
    x_lo = (t % tiles_x) * tile
    y_lo = (t / tiles_x) * tile
    x_hi = wp.min(x_lo + tile, c.width) - 1
    y_hi = wp.min(y_lo + tile, c.height) - 1
    raster_list(s, c, tile_start, tile_faces, t, x_lo, x_hi, y_lo, y_hi, k, samples, out)


@wp.kernel(enable_backward=False)
def raster_pixel_kernel(s: SceneData, c: RasterCamera, tile_start: wp.array(dtype=wp.int32),
                        tile_faces: wp.array(dtype=wp.int32), tiles_x: int, tile: int, k: int, samples: int,
                        first: int, out: Fragments):
    """One thread per pixel (row-major from the bottom, y up), for a GPU's many threads: every triangle
    binned to the pixel's tile, in the list's order, depth-tested at the pixel's samples alone. Each
    sample sees the very tests raster_kernel makes there, in the same order: the same Fragments, bit for
    bit (tests/zbuffer), with the clipping and projection done per pixel instead of per tile."""
    pixel = first + wp.tid()
    x = pixel % c.width
    y = pixel / c.width
    t = (y / tile) * tiles_x + x / tile
    raster_list(s, c, tile_start, tile_faces, t, x, x, y, y, k, samples, out)


@wp.func
def wanted(mask: wp.array(dtype=wp.int32), t: int) -> bool:
    """Whether tile t is rasterized: every tile with an empty mask (a scissor for the virtual cameras)."""
    return mask.shape[0] == 0 or mask[t] != 0


@wp.kernel(enable_backward=False)
def count_kernel(bounds: wp.array(dtype=wp.vec4i), tile: int, tiles_x: int, mask: wp.array(dtype=wp.int32),
                 tile_count: wp.array(dtype=wp.int32)):
    """Per triangle: +1 for every wanted tile its pixel rectangle touches."""
    b = bounds[wp.tid()]
    if b[0] > b[1]:
        return  # culled
    for ty in range(b[2] / tile, b[3] / tile + 1):
        for tx in range(b[0] / tile, b[1] / tile + 1):
            if wanted(mask, ty * tiles_x + tx):
                wp.atomic_add(tile_count, ty * tiles_x + tx, 1)


@wp.kernel(enable_backward=False)
def fill_kernel(bounds: wp.array(dtype=wp.vec4i), tile: int, tiles_x: int, mask: wp.array(dtype=wp.int32),
                cursor: wp.array(dtype=wp.int32), tile_faces: wp.array(dtype=wp.int32)):
    """Per triangle: its index into the list of every wanted tile it touches."""
    f = wp.tid()
    b = bounds[f]
    if b[0] > b[1]:
        return
    for ty in range(b[2] / tile, b[3] / tile + 1):
        for tx in range(b[0] / tile, b[1] / tile + 1):
            if wanted(mask, ty * tiles_x + tx):
                tile_faces[wp.atomic_add(cursor, ty * tiles_x + tx, 1)] = f
