"""The exact light-space structure for point-light shadow rays, built on the host side (float64): per
light a cube map of cells, each listing, nearest the light first, every triangle whose projection may cover it.

A shadow ray from o to light l is blocked iff wp.mesh_query_ray_anyhit(o, d, max_t) says so: iff Woop's
test (intersect_ray_tri_woop, the query's leaf test) reports some triangle at 0 <= t < max_t, the BVH's
padded boxes guaranteeing that the query reaches every such triangle (bvh.py). kernels/shadow.py runs
that very test on the triangles listed in the cell of o's direction from the light, nearer the light
than o, and so gives the same answer, provided each list holds every triangle Woop could report:

- A triangle Woop reports lies within delta of the exact segment o -> light: delta <= 3 eps dist (the
  rounding of the direction) + 6 eps max |vertex - o| (Woop's shear of the vertices, its rounding
  before the edge functions) <= 9 eps D, D the diameter of the vertices and lights. Seen from the
  light, from at least dmin (the triangle's distance to the light), that is an angle <= 1.1 delta /
  dmin, and on a cube face an angle maps to at most 3 times that in (u, v). We use delta = DELTA_EPS D
  (64 eps D) and widen each triangle's projection by 8 delta / dmin + UV_ABS (the float32 cell lookup):
  at least 7 times the bound. tests/shadows counts mismatches against the BVH on every shadow ray of
  every scene and on rays through every vertex and edge midpoint, and the structure built without
  this margin misses rays (the negative control).
- It can block only if it comes nearer the light than o (dmin <= |o - light| + delta): lists are sorted
  by dmin, so the query stops at the first entry beyond that.
- A triangle within NEAR_LIGHT D of a light (where the margin stops making sense) sends every shadow
  ray of that light to the BVH; so does a structure beyond MAX_BYTES (the caller falls back).
- A spot light's shadow rays are a point light's (o to its position): its cube map is the same. A
  directional light has no position (NaN in ``lights``): its rays, to infinity, go to the BVH.

The lists are built on the geometry's device by one launch per light: a count pass and a fill pass whose
threads claim their slots with atomics (on a GPU many threads write one cell at once), then one thread per
cell sorts its list back into the triangles' nearest-first rank, so the structure is the same on every
device whatever order the threads ran in (on the CPU, one thread in order, the sort finds the lists sorted).
The ranks (an argsort of the distances) and the lists' prefix sum are computed on the host: a build runs
once per light placement, not per frame.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np

from .._warp import wp
from ..floats import EPS32
from ..timing import timed
from .bvh import face_vertices

DELTA_EPS = 64.0 * EPS32  # delta = DELTA_EPS * D: the depth margin, ~7x the bound above
UV_ABS = 1.0e-5  # covers the float32 cell lookup's rounding of (u, v), ~1e-7
NEAR_LIGHT = 1.0e-3  # a triangle this close to a light (times D) sends the light's rays to the BVH
MAX_BYTES = 256 * 2**20  # beyond this the shadow rays are traced: memory is bounded


@wp.struct
class GridEntry:
    dmin: float  # a lower bound on the triangle's distance from the light (rounded down to float32)
    tri: int


@wp.struct
class ShadowGrid:
    """What the kernels read: n x n cells per cube face per light, as CSR lists of GridEntry."""

    n: int
    start: wp.array(dtype=wp.int32)  # cell (light * 6 + face) * n * n + row * n + col: entries start[c]..start[c + 1]
    entries: wp.array(dtype=GridEntry)
    light_ok: wp.array(dtype=wp.int32)  # 0: this light's shadow rays go to the BVH
    delta: float


def empty_grid(device="cpu") -> ShadowGrid:
    """A structure of no lights: what the kernels get when shadow rays are traced."""
    g = ShadowGrid()
    g.n = 1
    g.start = wp.zeros(1, dtype=wp.int32, device=device)
    g.entries = wp.zeros(1, dtype=GridEntry, device=device)
    g.light_ok = wp.zeros(1, dtype=wp.int32, device=device)
    g.delta = 0.0
    return g


@wp.func
def closest_distance(p: wp.vec3d, a: wp.vec3d, b: wp.vec3d, c: wp.vec3d) -> wp.float64:
    """Distance from p to the triangle abc (Ericson, Real-Time Collision Detection 5.1.5), float64."""
    ab = b - a
    ac = c - a
    ap = p - a
    d1 = wp.dot(ab, ap)
    d2 = wp.dot(ac, ap)
    zero = wp.float64(0.0)
    if d1 <= zero and d2 <= zero:
        return wp.length(ap)
    bp = p - b
    d3 = wp.dot(ab, bp)
    d4 = wp.dot(ac, bp)
    if d3 >= zero and d4 <= d3:
        return wp.length(bp)
    vc = d1 * d4 - d3 * d2
    if vc <= zero and d1 >= zero and d3 <= zero:
        return wp.length(p - (a + (d1 / (d1 - d3)) * ab))
    cp = p - c
    d5 = wp.dot(ab, cp)
    d6 = wp.dot(ac, cp)
    if d6 >= zero and d5 <= d6:
        return wp.length(cp)
    vb = d5 * d2 - d1 * d6
    if vb <= zero and d2 >= zero and d6 <= zero:
        return wp.length(p - (a + (d2 / (d2 - d6)) * ac))
    va = d3 * d6 - d5 * d4
    if va <= zero and (d4 - d3) >= zero and (d5 - d6) >= zero:
        return wp.length(p - (b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)))
    den = wp.float64(1.0) / (va + vb + vc)
    return wp.length(p - (a + ab * (vb * den) + ac * (vc * den)))


@wp.func
def to_f64(p: wp.vec3) -> wp.vec3d:
    return wp.vec3d(wp.float64(p[0]), wp.float64(p[1]), wp.float64(p[2]))


@wp.func
def corners(points: wp.array(dtype=wp.vec3), indices: wp.array(dtype=wp.int32), f: int):
    """Face f's vertices, in float64."""
    i0, i1, i2 = face_vertices(indices, f)
    return to_f64(points[i0]), to_f64(points[i1]), to_f64(points[i2])


@wp.kernel(enable_backward=False)
def distance_kernel(points: wp.array(dtype=wp.vec3), indices: wp.array(dtype=wp.int32), light: wp.vec3d,
                    out: wp.array(dtype=wp.float64)):
    f = wp.tid()
    a, b, c = corners(points, indices, f)
    out[f] = closest_distance(light, a, b, c)


@wp.func
def polygon_overlaps_box(px: wp.vec4d, py: wp.vec4d, m: int, u0: wp.float64, u1: wp.float64, v0: wp.float64,
                         v1: wp.float64) -> bool:
    """Whether the convex polygon (px, py)[0:m] meets the box [u0, u1] x [v0, v1] (separating axes: the
    box's own axes are covered by the caller's bounding-box test, so the polygon's edges remain)."""
    for k in range(m):
        k2 = (k + 1) % m
        nx = -(py[k2] - py[k])
        ny = px[k2] - px[k]
        lo = wp.float64(1.0e300)
        hi = wp.float64(-1.0e300)
        for j in range(m):
            t = nx * px[j] + ny * py[j]
            lo = wp.min(lo, t)
            hi = wp.max(hi, t)
        b0 = nx * u0 + ny * v0
        b1 = nx * u1 + ny * v0
        b2 = nx * u0 + ny * v1
        b3 = nx * u1 + ny * v1
        if wp.max(wp.max(b0, b1), wp.max(b2, b3)) < lo or wp.min(wp.min(b0, b1), wp.min(b2, b3)) > hi:
            return False
    return True


@wp.func
def face_projection(verts: wp.mat33d, a: int, sign: wp.float64, z_clip: wp.float64):
    """The triangle ``verts`` (relative to the light) on the cube face of axis ``a`` and ``sign``:
    Sutherland-Hodgman against depth >= z_clip, then the projection (u, v) = (x_b, x_c) / depth. Returns
    the polygon's u and v (up to 4 corners) and its corner count m (0: wholly behind the face)."""
    b = (a + 1) % 3
    c = (a + 2) % 3
    px = wp.vec4d()
    py = wp.vec4d()
    m = int(0)
    for k in range(3):
        P = verts[k]
        Q = verts[(k + 1) % 3]
        zp = sign * P[a]
        zq = sign * Q[a]
        if zp >= z_clip:
            px[m] = P[b] / zp
            py[m] = P[c] / zp
            m += 1
        if (zp >= z_clip) != (zq >= z_clip):
            t = (z_clip - zp) / (zq - zp)
            px[m] = (P[b] + t * (Q[b] - P[b])) / z_clip
            py[m] = (P[c] + t * (Q[c] - P[c])) / z_clip
            m += 1
    return px, py, m


@wp.func
def polygon_bounds(px: wp.vec4d, py: wp.vec4d, m: int, margin: wp.float64) -> wp.vec4d:
    """The polygon's (u_lo, u_hi, v_lo, v_hi), widened by ``margin``."""
    u_lo = px[0]
    u_hi = px[0]
    v_lo = py[0]
    v_hi = py[0]
    for k in range(1, m):
        u_lo = wp.min(u_lo, px[k])
        u_hi = wp.max(u_hi, px[k])
        v_lo = wp.min(v_lo, py[k])
        v_hi = wp.max(v_hi, py[k])
    return wp.vec4d(u_lo - margin, u_hi + margin, v_lo - margin, v_hi + margin)


@wp.kernel(enable_backward=False)
def bin_kernel(points: wp.array(dtype=wp.vec3), indices: wp.array(dtype=wp.int32), light: wp.vec3d, l: int, n: int,
               delta: wp.float64, uv_abs: wp.float64, sequence: wp.array(dtype=wp.int32), rank: wp.array(dtype=wp.int32),
               dmin: wp.array(dtype=wp.float64), fill: int, cursor: wp.array(dtype=wp.int32),
               entries: wp.array(dtype=GridEntry), entry_rank: wp.array(dtype=wp.int32)):
    """Triangle sequence[tid]: count it (fill = 0: cursor[cell] += 1) or append it with its rank nearest the
    light (fill = 1: at the slot cursor[cell]++ it claims) in every cell of light l its widened projection
    may cover. Atomics: any number of threads may write one cell at once."""
    f = sequence[wp.tid()]
    dm = dmin[f]
    q0, q1, q2 = corners(points, indices, f)
    verts = wp.mat33d()
    verts[0] = q0 - light
    verts[1] = q1 - light
    verts[2] = q2 - light
    margin = wp.float64(8.0) * delta / dm + uv_abs
    # Points of the triangle that a face's frustum holds lie at depth >= dm / sqrt(3) along its axis:
    # clipping at dm / 2 keeps them all and keeps the projection finite.
    z_clip = dm * wp.float64(0.5)
    nn = wp.float64(n)
    one = wp.float64(1.0)
    entry = GridEntry()
    entry.dmin = wp.float32(dm * wp.float64(0.999999))  # float32, rounded down
    entry.tri = f
    for face in range(6):
        sign = one
        if face % 2 == 1:
            sign = -one
        px, py, m = face_projection(verts, face / 2, sign, z_clip)
        if m == 0:
            continue
        box = polygon_bounds(px, py, m, margin)
        u_lo, u_hi, v_lo, v_hi = box[0], box[1], box[2], box[3]
        if u_lo > one or v_lo > one or u_hi < -one or v_hi < -one:
            continue
        i0 = wp.clamp(int(wp.floor((wp.max(u_lo, -one) + one) * wp.float64(0.5) * nn)), 0, n - 1)
        i1 = wp.clamp(int(wp.floor((wp.min(u_hi, one) + one) * wp.float64(0.5) * nn)), 0, n - 1)
        j0 = wp.clamp(int(wp.floor((wp.max(v_lo, -one) + one) * wp.float64(0.5) * nn)), 0, n - 1)
        j1 = wp.clamp(int(wp.floor((wp.min(v_hi, one) + one) * wp.float64(0.5) * nn)), 0, n - 1)
        small = (i1 - i0) <= 1 and (j1 - j0) <= 1  # its box's cells: the polygon test would keep (nearly) all
        base = (l * 6 + face) * n * n
        for j in range(j0, j1 + 1):
            cv0 = wp.float64(j) * wp.float64(2.0) / nn - one - margin
            cv1 = wp.float64(j + 1) * wp.float64(2.0) / nn - one + margin
            for i in range(i0, i1 + 1):
                if not small:
                    cu0 = wp.float64(i) * wp.float64(2.0) / nn - one - margin
                    cu1 = wp.float64(i + 1) * wp.float64(2.0) / nn - one + margin
                    if not polygon_overlaps_box(px, py, m, cu0, cu1, cv0, cv1):
                        continue
                cell = base + j * n + i
                e = wp.atomic_add(cursor, cell, 1)
                if fill != 0:
                    entries[e] = entry
                    entry_rank[e] = rank[f]


@wp.kernel(enable_backward=False)
def sort_cells_kernel(start: wp.array(dtype=wp.int32), first_cell: int, entries: wp.array(dtype=GridEntry),
                      entry_rank: wp.array(dtype=wp.int32)):
    """Cell first_cell + tid's list sorted by rank, nearest the light first (insertion sort: linear on a
    list already in order, as one CPU thread leaves it)."""
    c = first_cell + wp.tid()
    lo = start[c]
    hi = start[c + 1]
    for k in range(lo + 1, hi):
        e = entries[k]
        r = entry_rank[k]
        j = k - 1
        while j >= lo and entry_rank[j] > r:
            entries[j + 1] = entries[j]
            entry_rank[j + 1] = entry_rank[j]
            j -= 1
        entries[j + 1] = e
        entry_rank[j + 1] = r


class ShadowGridBuild:
    """A ShadowGrid for one Geometry and its lights, with what it cost: ``grid`` (None where the
    structure would exceed max_bytes: then every shadow ray is traced), ``nbytes``, ``seconds``,
    ``entries``, ``light_ok`` and ``reason``."""

    def __init__(self, points: np.ndarray, indices: np.ndarray, lights: np.ndarray, n: int, device="cpu",
                 max_bytes: int = MAX_BYTES, delta_eps: float = DELTA_EPS, uv_abs: float = UV_ABS,
                 thread_order: str = "nearest", sort_cells: bool = True):
        """``points`` (V, 3) and ``indices`` (3T,) as the kernels read them (float32, relative to the
        frame origin), ``lights`` (L, 3): the kernels' float32 light positions; built on ``device``.
        delta_eps = uv_abs = 0 builds the structure without its margin, sort_cells=False without its sort
        (the tests' negative controls); thread_order "farthest" launches the triangles farthest the light
        first, the worst order a GPU's threads may take them in (the tests': the same structure must come
        out)."""
        times: dict = {}
        with timed(times, "build"):
            self._build(points, indices, lights, n, device, max_bytes, delta_eps, uv_abs, thread_order, sort_cells)
        self.seconds = times["build"]

    def _build(self, points, indices, lights, n, device, max_bytes, delta_eps, uv_abs, thread_order, sort_cells):
        self.n = n
        points = np.ascontiguousarray(points, np.float32)
        indices = np.ascontiguousarray(indices, np.int32)
        lights = np.asarray(lights, np.float64).reshape(-1, 3)
        tris, n_lights = len(indices) // 3, len(lights)
        placed = np.all(np.isfinite(lights), axis=1)  # directional lights have no position
        every = np.concatenate([points.astype(np.float64), lights[placed]])
        D = float(np.linalg.norm(every.max(axis=0) - every.min(axis=0))) * 1.01 + 1e-30
        delta = delta_eps * D
        self.delta = delta
        cells = n_lights * 6 * n * n
        p_wp = wp.array(points, dtype=wp.vec3, device=device)
        i_wp = wp.array(indices, dtype=wp.int32, device=device)
        ok = np.zeros(max(n_lights, 1), np.int32)
        dmins, sequences, ranks = {}, {}, {}
        for l in range(n_lights):
            if not placed[l]:
                continue
            dm = wp.zeros(max(tris, 1), dtype=wp.float64, device=device)
            wp.launch(distance_kernel, dim=tris, inputs=[p_wp, i_wp, wp.vec3d(*lights[l]), dm], device=device)
            near = dm.numpy()[:tris]
            ok[l] = int(tris > 0 and near.min() >= NEAR_LIGHT * D)
            order = np.argsort(near, kind="stable").astype(np.int32)
            rank = np.empty(max(tris, 1), np.int32)
            rank[order] = np.arange(tris, dtype=np.int32)
            dmins[l] = dm
            sequences[l] = wp.array(order if thread_order == "nearest" else order[::-1].copy(), dtype=wp.int32,
                                    device=device)
            ranks[l] = wp.array(rank, dtype=wp.int32, device=device)
        self.light_ok = ok[:n_lights]
        counts = wp.zeros(max(cells, 1), dtype=wp.int32, device=device)
        on_grid = [l for l in range(n_lights) if ok[l]]

        def bin_light(l, fill, cursor, entries, entry_rank):
            wp.launch(bin_kernel, dim=tris, inputs=[p_wp, i_wp, wp.vec3d(*lights[l]), l, n, wp.float64(delta),
                                                    wp.float64(uv_abs), sequences[l], ranks[l], dmins[l], fill, cursor,
                                                    entries, entry_rank], device=device)

        # On the CPU one launch per light, the lights in parallel (a launch runs on one thread); on a GPU, in turn.
        workers = max(1, len(on_grid)) if wp.get_device(device).is_cpu else 1
        with ThreadPoolExecutor(max_workers=workers) as pool:
            none = wp.zeros(1, dtype=GridEntry, device=device), wp.zeros(1, dtype=wp.int32, device=device)
            list(pool.map(lambda l: bin_light(l, 0, counts, *none), on_grid))
            start = np.zeros(cells + 1, np.int64)
            start[1:] = np.cumsum(counts.numpy()[:cells])
            self.entries = int(start[-1])
            self.nbytes = int((cells + 1) * 4 + self.entries * 8 + ok.nbytes)
            self.grid, self.reason = None, ""
            if not on_grid:
                self.reason = ("every light is directional or has geometry within NEAR_LIGHT of it" if n_lights
                               else "no lights")
            elif self.nbytes > max_bytes or self.entries >= 2**31:
                self.reason = f"{self.nbytes / 2**20:.0f} MiB would exceed the {max_bytes / 2**20:.0f} MiB budget"
            else:
                entries = wp.zeros(max(self.entries, 1), dtype=GridEntry, device=device)
                entry_rank = wp.zeros(max(self.entries, 1), dtype=wp.int32, device=device)
                start_wp = wp.array(start.astype(np.int32), dtype=wp.int32, device=device)
                cursor = wp.clone(start_wp[:cells])
                list(pool.map(lambda l: bin_light(l, 1, cursor, entries, entry_rank), on_grid))
                if sort_cells:
                    per_light = 6 * n * n
                    list(pool.map(lambda l: wp.launch(sort_cells_kernel, dim=per_light,
                                                      inputs=[start_wp, l * per_light, entries, entry_rank],
                                                      device=device), on_grid))
                g = ShadowGrid()
                g.n = n
                g.start = start_wp
                g.entries = entries
                g.light_ok = wp.array(ok, dtype=wp.int32, device=device)
                g.delta = float(delta)
                self.grid = g

    @property
    def stats(self) -> dict:
        return {"cells": self.n, "lights_on_grid": int(self.light_ok.sum()), "lights": len(self.light_ok),
                "entries": self.entries, "bytes": self.nbytes if self.grid is not None else 0,
                "build_seconds": self.seconds, **({"fallback": self.reason} if self.reason else {})}


def cells_for(triangles: int) -> int:
    """Cells per cube face side: 256 keeps lists short up to some 50,000 triangles; 512 beyond."""
    return 256 if triangles <= 50_000 else 512


def kept_shadow_grid(memo: dict, lights: np.ndarray, max_bytes: int = MAX_BYTES) -> ShadowGridBuild | None:
    """The structure shadow_grid() built for these lights and kept in ``memo``, or None."""
    return memo.get((np.asarray(lights, np.float32).tobytes(), max_bytes))


def shadow_grid(geom, lights: np.ndarray, max_bytes: int = MAX_BYTES, memo: dict | None = None,
                keep: int = 2) -> ShadowGridBuild:
    """The structure for ``geom``'s triangles and these float32 light positions, built once and kept in
    ``memo`` (a Renderer's FrameCaches.shadow_grids, for the next frames of these triangles with the
    same lights); at most ``keep`` structures, the oldest dropped first (moving lights)."""
    key = (np.asarray(lights, np.float32).tobytes(), max_bytes)
    memo = {} if memo is None else memo
    if key not in memo:
        if len(memo) >= keep:
            memo.pop(next(iter(memo)))
        memo[key] = ShadowGridBuild(geom.points_np, geom.indices_np, lights, cells_for(geom.triangle_count),
                                    geom.device, max_bytes)
    return memo[key]
