"""Where the boundary term's segments lie in the image (backward(edges=True); docs/gradients.md): any 3D
segments (a mesh's edges seen from the eye, a shadow's edges on its receivers) clipped in front of the eye,
projected, clipped to the frame and cut at the pixels' borders and at each other's images, each piece
integrated at fixed Gauss-Legendre points."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._warp import wp
from ..scene import camera_basis

GAUSS_POINTS = 1  # per piece of an edge inside a pixel: the midpoint, exact for a linear integrand; within 9.3e-5
# of 8 a piece on gradient_cost's soft shadow (2: 2.5e-5), as much as the jump's own reading 1e-3 px off the edge
# moves it (8.6e-5 at 5e-4 px), for half the points (2 a piece: that backward 46.4 against 36.3 ms, alternated, loaded)
FINE_POINTS = 8  # a piece of a fine segment's (segment_points): a curved mirror's rim, whose jump turns within a
# pixel (grad_mesh_edges.rims); the mirror ball's camera.eye z -51.18 at 1 a piece, -52.41 at 8, -52.62 at 32
END_SLACK = 1e-9  # a segment ending on another (a checker line or a cone on a face's side) cuts it, its end rounded either way
PAIR_TABLE = 1 << 24  # segments' pairs that _neighbours finds in a table (bytes), more by a sort
EDGE_OFFSET_PX = 1e-3  # the two rays either side of an edge, this far from it in the image: at any depth, that
# share of a pixel's footprint; above float32's resolution of a ray's direction (about 1e-4 of a pixel at 512 wide)


@dataclass
class EdgePoints:
    """The Gauss-Legendre points of segments' pieces inside pixels, in the segments' order and along each
    one: per point its segment (a row of ``edges``, what the segments stand for: a camera edge's two vertex
    indices), where it lies in the image (pixels from the lower-left corner), its weight (the Gauss weight
    times the piece's length, in pixels) and its pixel (row major, row 0 at the top); per segment the unit
    normal of its image, towards the side where its edge function g > 0 (0 where it is seen end on)."""

    edges: np.ndarray | None
    edge: np.ndarray
    at: np.ndarray
    weight: np.ndarray
    pixel: np.ndarray
    normal: np.ndarray

    def part(self, lo: int, hi: int, edges=None) -> "EdgePoints":
        """The points of segments lo to hi - 1, renumbered from 0, ``edges`` what those stand for."""
        keep = (self.edge >= lo) & (self.edge < hi)
        return EdgePoints(edges, self.edge[keep] - lo, self.at[keep], self.weight[keep], self.pixel[keep],
                          self.normal[lo:hi])


def _clip(q0: np.ndarray, q1: np.ndarray, z_e: np.ndarray) -> tuple:
    """Per segment q0 q1 (rows, relative to the eye) its part in front of the eye, depth -q . z_e at least a
    millionth of its distance (the image of a point at the eye's depth lies at infinity), and whether it has
    one."""
    z0, z1 = -(q0 @ z_e), -(q1 @ z_e)
    z_min = 1e-6 * np.maximum(np.linalg.norm(q0, axis=1), np.linalg.norm(q1, axis=1))
    front = (z0 >= z_min) | (z1 >= z_min)
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = np.where(z0 < z_min, (z_min - z0) / (z1 - z0), 0.0)
        t1 = np.where(z1 < z_min, (z_min - z1) / (z0 - z1), 0.0)
    t0, t1 = np.where(front, t0, 0.0), np.where(front, t1, 0.0)
    return q0 + (q1 - q0) * t0[:, None], q1 + (q0 - q1) * t1[:, None], front


def project_points(q: np.ndarray, b) -> np.ndarray:
    """Where the points q (rows, relative to the eye, in front of it) lie in the image, in pixels from its
    lower-left corner: camera.camera_ray's d = -d_f z_e + h (y / H - 1/2) y_e + w (x / W - 1/2) x_e solved for
    (x, y)."""
    z = -(q @ b.z_e)
    return np.stack([b.width * (0.5 + b.d_f * (q @ b.x_e) / (z * b.w)),
                     b.height * (0.5 + b.d_f * (q @ b.y_e) / (z * b.h))], axis=1)


def _frame_clip(a: np.ndarray, c: np.ndarray, width: int, height: int) -> tuple:
    """Per segment a + t (c - a) (rows) the parameters (t0, t1) of its part inside the frame [0, W] x [0, H]
    (Liang-Barsky), and whether it has one."""
    t0, t1, d = np.zeros(len(a)), np.ones(len(a)), c - a
    inside = np.ones(len(a), bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        for p, q in ((-d[:, 0], a[:, 0]), (d[:, 0], width - a[:, 0]), (-d[:, 1], a[:, 1]), (d[:, 1], height - a[:, 1])):
            inside &= (p != 0.0) | (q >= 0.0)
            t = q / p
            t0 = np.where(p < 0.0, np.maximum(t0, t), t0)
            t1 = np.where(p > 0.0, np.minimum(t1, t), t1)
    return t0, t1, inside & (t0 < t1)


def _pieces(a: np.ndarray, c: np.ndarray, spans: np.ndarray) -> tuple:
    """(segment, t), by segment then t, no pair twice: the parameters cutting each a + t (c - a) (rows),
    t0 <= t <= t1 (``spans``' rows), where it crosses the pixels' borders, and its ends t0 and t1."""
    seg, ts = [np.arange(len(a))] * 2, [spans[:, 0], spans[:, 1]]
    for axis in (0, 1):
        moves = np.flatnonzero(c[:, axis] != a[:, axis])
        d = c[moves, axis] - a[moves, axis]
        x = a[moves, axis][:, None] + spans[moves] * d[:, None]  # where t0 and t1 lie along the axis
        start = np.floor(x.min(axis=1)) + 1.0  # the borders strictly between them: np.arange(start, ceil(x1))
        count = np.maximum(np.ceil(x.max(axis=1)) - start, 0.0).astype(np.int64)
        which = np.repeat(np.arange(len(moves)), count)
        lines = start[which] + (np.arange(len(which)) - np.repeat(np.cumsum(count) - count, count))
        seg.append(moves[which])
        ts.append((lines - a[moves[which], axis]) / d[which])
    seg, ts = np.concatenate(seg), np.concatenate(ts)
    return _unique(seg, np.clip(ts, spans[seg, 0], spans[seg, 1]))


def _unique(seg: np.ndarray, ts: np.ndarray) -> tuple:
    """(segment, t) sorted by segment then t, each pair once: per segment np.unique of its ts."""
    order = np.lexsort((ts, seg))
    seg, ts = seg[order], ts[order]
    keep = np.ones(len(seg), bool)
    keep[1:] = (seg[1:] != seg[:-1]) | (ts[1:] != ts[:-1])
    return seg[keep], ts[keep]


def _merged(seg: np.ndarray, ts: np.ndarray, more_seg: np.ndarray, more_ts: np.ndarray) -> tuple:
    """_unique of (seg, ts), sorted and each pair once, with the few pairs (more_seg, more_ts) added: each put
    in its place by a binary search within its segment's run, the new pairs among themselves by a sort, so
    that the whole is in the same order without sorting it all again."""
    o = np.lexsort((more_ts, more_seg))
    more_seg, more_ts = more_seg[o], more_ts[o]
    lo, hi = np.searchsorted(seg, more_seg, "left"), np.searchsorted(seg, more_seg, "right")
    while np.any(lo < hi):  # the first of the run above more_ts: after its equals, which _unique keeps
        mid = (lo + hi) // 2
        below = (lo < hi) & (ts[np.minimum(mid, len(ts) - 1)] <= more_ts)
        lo, hi = np.where(below, mid + 1, lo), np.where((lo < hi) & ~below, mid, hi)
    s, t = np.insert(seg, lo, more_seg), np.insert(ts, lo, more_ts)
    keep = np.ones(len(s), bool)
    keep[1:] = (s[1:] != s[:-1]) | (t[1:] != t[:-1])
    return s[keep], t[keep]


def _length(v: np.ndarray) -> np.ndarray:
    """Per row its norm, as np.linalg.norm of the row alone computes it (sqrt of its dot product: to the bit,
    which the axis=1 sum of squares is not)."""
    return np.sqrt(np.vecdot(v, v))


def _segments(q0: np.ndarray, q1: np.ndarray, n: np.ndarray, b) -> tuple:
    """Per segment q0 q1 (relative to the eye), whose image is the line n . d(x) = 0 (n: the normal of the
    plane through the eye and the segment, its sign the edge function's), its image's unit normal (towards
    g > 0), and for the segments in view their rows, their images' end points (a, c: the parts in front of
    the eye, projected) and the span (t0, t1) of a + t (c - a) in the frame."""
    grad = np.stack([(n @ b.x_e) * b.w / b.width, (n @ b.y_e) * b.h / b.height], axis=1)  # grad_x g
    size = np.linalg.norm(grad, axis=1)
    seen = size > 1e-12 * np.linalg.norm(q0, axis=1) * np.linalg.norm(q1, axis=1)  # not seen end on
    normal = np.where(seen[:, None], grad / np.where(seen, size, 1.0)[:, None], 0.0)
    c0, c1, front = _clip(q0, q1, b.z_e)
    keep = seen & front
    a, c = project_points(c0[keep], b), project_points(c1[keep], b)
    t0, t1, inside = _frame_clip(a, c, b.width, b.height)
    rows = np.flatnonzero(keep)[inside]
    return normal, rows, np.stack([a[inside], c[inside]], axis=1), np.stack([t0[inside], t1[inside]], axis=1)


def _crossings(ends: np.ndarray, spans: np.ndarray, j: np.ndarray, k: np.ndarray) -> tuple:
    """(segment, t): where segment j's image crosses segment k's (its parameter t), per pair j k: where what
    lies in front of it or behind it may change, so that the Gauss points integrate a smooth integrand
    between them."""
    a, d, a_f, d_f = ends[j, 0], ends[j, 1] - ends[j, 0], ends[k, 0], ends[k, 1] - ends[k, 0]
    det = d[:, 0] * (-d_f[:, 1]) + d_f[:, 0] * d[:, 1]  # a + t d = a_f + s d_f, by Cramer's rule
    r = a_f - a
    ok = np.abs(det) > 1e-12 * (_length(d) * np.linalg.norm(d_f, axis=1) + 1e-300)
    safe = np.where(ok, det, 1.0)
    t = (r[:, 0] * (-d_f[:, 1]) + d_f[:, 0] * r[:, 1]) / safe
    s = (d[:, 0] * r[:, 1] - d[:, 1] * r[:, 0]) / safe
    ok &= (s >= spans[k, 0] - END_SLACK) & (s <= spans[k, 1] + END_SLACK) & (t > spans[j, 0]) & (t < spans[j, 1])
    return j[ok], t[ok]


def _pixels_of(a: np.ndarray, c: np.ndarray, seg: np.ndarray, ts: np.ndarray, b) -> tuple:
    """(piece, pixel): the pieces between consecutive cuts ``ts`` of the same segment a + t (c - a) (``seg``;
    piece i from ts[i] to ts[i + 1]) and each one's pixel (row major, row 0 at the top)."""
    piece = np.flatnonzero(seg[1:] == seg[:-1])
    e = seg[piece]
    mid = a[e] + 0.5 * (ts[piece] + ts[piece + 1])[:, None] * (c[e] - a[e])
    x = np.minimum(mid[:, 0].astype(np.int64), b.width - 1)
    y = np.minimum(mid[:, 1].astype(np.int64), b.height - 1)
    return piece, (b.height - 1 - y) * b.width + x


def _neighbours(seg: np.ndarray, pixel: np.ndarray, n: int, family: np.ndarray | None = None) -> tuple:
    """(j, k): the pairs of two of the ``n`` segments whose pieces (``seg``, ``pixel``) share a pixel, each
    pair once, both ways; with ``family`` (per segment), less those of two different families both at least 0
    (segment_points'): such pairs are never made (a soft shadow's pixels hold many sources' edges)."""
    code = _distinct(pixel * n + seg)  # (pixel, segment), by pixel
    pix, seg = code // n, code % n
    if family is None:
        j, k = _pairs_within(pix, seg, np.ones(len(seg), bool))
    else:
        fam = family[seg]
        loose = fam < 0  # cut by, and cutting, every segment in their pixels
        j0, k0 = _pairs_within(pix, seg, loose)
        kin = np.flatnonzero(~loose)  # the rest by (pixel, family): each family's own
        kin = kin[np.lexsort((fam[kin], pix[kin]))]
        j1, k1 = _pairs_within(pix[kin] * (int(fam.max(initial=0)) + 1) + fam[kin], seg[kin],
                               np.ones(len(kin), bool))
        j, k = np.concatenate([j0, k0, j1]), np.concatenate([k0, j0, k1])
    if n * n <= PAIR_TABLE:  # a table of every pair, faster than sorting them
        table = np.zeros((n, n), bool)
        table[j, k] = True
        table[np.arange(n), np.arange(n)] = False
        return np.nonzero(table)
    pairs = _distinct(j[j != k] * n + k[j != k])
    return pairs // n, pairs % n


def _pairs_within(group: np.ndarray, seg: np.ndarray, first: np.ndarray) -> tuple:
    """(j, k): per entry of ``seg`` with ``first`` set, it against every entry of its run of equal ``group``
    (sorted), itself included."""
    starts = np.flatnonzero(np.concatenate([[True], group[1:] != group[:-1]]))
    size = np.diff(np.append(starts, len(group)))
    run = np.repeat(np.arange(len(starts)), size)[first]  # per first entry its run
    count = size[run]
    mine = np.repeat(np.flatnonzero(first), count)
    other = np.repeat(starts[run], count) + np.arange(len(mine)) - np.repeat(np.cumsum(count) - count, count)
    return seg[mine], seg[other]


def _distinct(x: np.ndarray) -> np.ndarray:
    """np.unique of integers, by a sort (np.unique's hash table is slower here)."""
    x = np.sort(x)
    return x[np.concatenate([[True], x[1:] != x[:-1]])] if len(x) else x


def segment_points(q0: np.ndarray, q1: np.ndarray, n: np.ndarray, cam, edges=None,
                   family: np.ndarray | None = None, fine: np.ndarray | None = None) -> EdgePoints:
    """The EdgePoints of the segments q0 q1 (rows, relative to the eye; ``n``: per segment the normal of the
    plane through the eye and it, whose sign says which side is g > 0; ``edges``: what they stand for): each
    segment's image cut where it crosses the pixels' borders and the images of the other segments in those
    pixels (but two of different ``family``, both at least 0: a hard shadow's segment is of its source's
    family, its jump that source's light alone, smooth across another source's edge), GAUSS_POINTS a piece,
    FINE_POINTS on the segments ``fine`` marks (per segment; none: no segment)."""
    b = camera_basis(cam)
    normal, rows, ends, spans = _segments(q0, q1, n, b)
    a, c = ends[:, 0], ends[:, 1]
    seg, ts = _pieces(a, c, spans)
    piece, pixel = _pixels_of(a, c, seg, ts, b)
    j, k = _neighbours(seg[piece], pixel, len(rows), None if family is None else np.asarray(family)[rows])
    crossing, t_crossing = _crossings(ends, spans, j, k)
    seg, ts = _merged(seg, ts, crossing, t_crossing)
    piece, pixel = _pixels_of(a, c, seg, ts, b)  # ts increases along a segment (_unique): no piece is empty
    e, s0, s1 = seg[piece], ts[piece], ts[piece + 1]
    gauss, gauss_w, count = _nodes(e, None if fine is None else np.asarray(fine, bool)[rows])
    on = np.repeat(np.arange(len(e)), count)  # per point its piece
    e, s0, s1 = e[on], s0[on], s1[on]
    t = s0 + (s1 - s0) * 0.5 * (gauss + 1.0)
    at = a[e] + t[:, None] * (c - a)[e]
    weight = gauss_w * 0.5 * (s1 - s0) * _length(c - a)[e]
    return EdgePoints(edges, rows[e].astype(np.int64), at, weight, pixel[on].astype(np.int64), normal)


def _nodes(e: np.ndarray, fine: np.ndarray | None) -> tuple:
    """(nodes, weights, count): per piece (of the segment ``e``) its count of Gauss-Legendre points, GAUSS_POINTS or
    FINE_POINTS where its segment is ``fine``, and per point its node and weight on [-1, 1], piece by piece."""
    count = np.full(len(e), GAUSS_POINTS, np.int64) if fine is None else np.where(fine[e], FINE_POINTS, GAUSS_POINTS)
    k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)  # per point its place in its piece
    nodes, weights = np.zeros((FINE_POINTS + 1, FINE_POINTS)), np.zeros((FINE_POINTS + 1, FINE_POINTS))
    for size in {GAUSS_POINTS, FINE_POINTS}:
        nodes[size, :size], weights[size, :size] = np.polynomial.legendre.leggauss(size)
    size = np.repeat(count, count)
    return nodes[size, k], weights[size, k], count


def edge_points(edges: np.ndarray, points: np.ndarray, eye: np.ndarray, cam) -> EdgePoints:
    """The EdgePoints of mesh edges (``edges``: vertex indices into ``points``, relative to the frame origin,
    as ``eye``), seen from the eye: segment_points with the edge function det(v0 - eye, v1 - eye, d(x))."""
    q0, q1 = points[edges[:, 0]] - eye, points[edges[:, 1]] - eye
    return segment_points(q0, q1, np.cross(q0, q1), cam, edges)


def ray_directions(at: np.ndarray, b) -> np.ndarray:
    """Unit camera-ray directions (float32) through image points (pixels from the lower-left corner): -d_f z_e
    + h (y / H - 1/2) y_e + w (x / W - 1/2) x_e over its norm, a component at a time (the same sums, in the same
    order, as the rows', in a third of the time)."""
    y, x = b.h * (at[:, 1] / b.height - 0.5), b.w * (at[:, 0] / b.width - 0.5)
    d = [-b.d_f * b.z_e[k] + y * b.y_e[k] + x * b.x_e[k] for k in range(3)]
    norm = np.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    out = np.empty((len(at), 3), np.float32)
    for k in range(3):
        out[:, k] = d[k] / norm
    return out


def side_directions(pts: EdgePoints, cam) -> np.ndarray:
    """(2 N, 3) float32: per point the camera rays EDGE_OFFSET_PX either side of its segment's image, first
    every point's towards the normal (g > 0), then every point's away from it."""
    offset = EDGE_OFFSET_PX * pts.normal[pts.edge]
    return ray_directions(np.concatenate([pts.at + offset, pts.at - offset]), camera_basis(cam))


def camera_copies(scene, geom, n: int, device: str) -> tuple:
    """(camera, fovy): the camera as a speed kernel reads it, one copy per point (its eye, center and up,
    the eye and center relative to the frame origin, rows 3 j to 3 j + 2; fovy[j]), differentiable, so that
    each point's adjoint is its own and the host sums them in a fixed order."""
    cam = scene.camera
    rows = np.tile(np.stack([geom.eye_offset(cam.eye), geom.eye_offset(cam.center), np.asarray(cam.up, np.float32)]),
                   (n, 1))
    camera = wp.array(rows.astype(np.float32), dtype=wp.vec3, device=device, requires_grad=True,
                      copy=not wp.get_device(device).is_cpu)  # on the CPU, rows' own memory
    return camera, wp.array(np.full(n, cam.fovy, np.float32), dtype=float, device=device, requires_grad=True,
                            copy=not wp.get_device(device).is_cpu)


def camera_adjoints(camera: wp.array, fovy: wp.array, n: int) -> dict:
    """Per point the adjoints camera_copies' arrays hold after a tape's backward: ``eye``, ``center``,
    ``up`` (n, 3) and ``fovy`` (n,), float64."""
    rows = by_column(camera.grad.numpy().reshape(n, 3, 3))
    return {"eye": rows[0], "center": rows[1], "up": rows[2], "fovy": fovy.grad.numpy().astype(np.float64)}


def by_column(rows: np.ndarray) -> np.ndarray:
    """(K, n, 3) float64 views of per point rows (n, K, 3) stored a column at a time: what boundary_term reads
    a column at a time, so that each column is contiguous. Copied a block of points at a time (a whole-array
    transposing copy runs 4 times slower, measured)."""
    out = np.empty((rows.shape[1], 3, len(rows)))
    for lo in range(0, len(rows), 1024):
        out[:, :, lo:lo + 1024] = rows[lo:lo + 1024].transpose(1, 2, 0)
    return out.transpose(0, 2, 1)


def tape_speeds(scene, geom, pts: EdgePoints, kernel, rows: list, extras: list, device: str) -> tuple[list, dict]:
    """Per point of ``pts``, the derivative of the signed distance a distance kernel gives (edge_distances,
    shadow_edge_distances, a mirrored distances kernel: its inputs the differentiable ``rows``, then ``extras``,
    then the camera, fovy, near, width, height and the points) in each of ``rows`` (float32 copies per point,
    (n, ...) x 3 each) and in the camera (camera_copies), on a wp.Tape: (per row array its adjoints, float64,
    shaped as given; camera_adjoints). Each point reads copies of its own, so that no two adjoints share a sum:
    the host reduces them in a fixed order."""
    cam, n = scene.camera, len(pts.edge)
    arrays = [wp.array(np.asarray(r, np.float32).reshape(-1, 3), dtype=wp.vec3, device=device, requires_grad=True)
              for r in rows]
    camera, fovy = camera_copies(scene, geom, n, device)
    distance = wp.zeros(n, dtype=float, device=device, requires_grad=True)
    tape = wp.Tape()
    with tape:
        wp.launch(kernel, dim=n, inputs=[*arrays, *extras, camera, fovy, float(cam.near), cam.width, cam.height,
                                         wp.array(pts.at.astype(np.float32), dtype=wp.vec2, device=device)],
                  outputs=[distance], device=device)
    tape.backward(grads={distance: wp.array(np.ones(n, np.float32), dtype=float, device=device)})
    out = [a.grad.numpy().astype(np.float64).reshape(np.shape(r)) for a, r in zip(arrays, rows)], \
        camera_adjoints(camera, fovy, n)
    tape.zero()
    return out


@dataclass
class BoundaryTerm:
    """A boundary term's sums, each in a fixed order: per geometry point (``points``), per camera parameter
    (``camera``: eye, center, up, fovy) and per shadow source (``sources``: ShadowSources' rows; None
    without shadows)."""

    points: np.ndarray
    camera: dict
    sources: np.ndarray | None = None


def boundary_term(pts: EdgePoints, jump: np.ndarray, d: np.ndarray, speed: dict, vertices: dict, n_points: int,
                  sources: tuple | None = None) -> BoundaryTerm:
    """The term of the points ``pts``: per point d at its pixel (``d``: (pixels, 3), float64) dotted with its
    jump f_+ - f_-, times its weight and its segment's speed (``speed``: per point and parameter), summed
    in the points' order (np.add.at: in order, one at a time); ``vertices``: {speed key: per point the
    geometry point it moves}; ``sources``: (per point its source, how many there are), whose speed is
    ``speed["light"]``."""
    w = pts.weight * np.einsum("ij,ij->i", d[pts.pixel], jump)
    points = add_at(n_points, list(vertices.values()), w, [speed[key] for key in vertices])
    camera = {k: _sum(w, speed[k]) for k in ("eye", "center", "up")}
    camera["fovy"] = np.add.reduce(w[:, None] * speed["fovy"].reshape(len(w), -1), axis=0)
    term = BoundaryTerm(points, camera)
    if sources is not None:
        term.sources = add_at(sources[1], [sources[0]], w, [speed["light"]])
    return term


def _sum(w: np.ndarray, v: np.ndarray) -> np.ndarray:
    """np.add.reduce(w[:, None] * v, axis=0) of per point rows ``v`` (n, 3) as C-ordered rows sum it, to the bit
    whatever v's order: one at a time, in order (np.bincount, a column at a time)."""
    first = np.zeros(len(w), np.intp)
    return np.array([np.bincount(first, w * v[:, k], minlength=1)[0] for k in range(3)])


def add_at(n: int, rows: list, w: np.ndarray, values: list) -> np.ndarray:
    """(n, 3): w times each list's ``values`` (rows) added at its ``rows``, the lists in order and each in its
    rows' order, one at a time: np.add.at's sums, to the bit (np.bincount adds its weights in their order
    too), a column at a time over the lists joined, ten times faster."""
    at = np.concatenate(rows)
    return np.stack([np.bincount(at, np.concatenate([w * v[:, k] for v in values]), minlength=n) for k in range(3)],
                    axis=1)


def add_terms(terms: list, n_points: int) -> BoundaryTerm:
    """The sum of BoundaryTerms, in their order (sources: those of the terms that have them; None if none)."""
    out = BoundaryTerm(np.zeros((n_points, 3)), {k: 0.0 for k in ("eye", "center", "up", "fovy")})
    for t in terms:
        out.points = out.points + t.points
        out.camera = {k: out.camera[k] + t.camera[k] for k in out.camera}
        if t.sources is not None:
            out.sources = t.sources if out.sources is None else out.sources + t.sources
    return out
