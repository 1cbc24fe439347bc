"""Where the boundary term's segments lie in the image (backward(edges=True); docs/gradients.md): any 3D
segments (a mesh's edges seen from the eye, a shadow's edges on its receivers) clipped in front of the eye,
projected, clipped to the frame and cut at the pixels' borders and at each other's images, each piece
integrated at fixed Gauss-Legendre points."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._warp import wp
from ..scene import camera_basis

GAUSS_POINTS = 4  # per piece of an edge inside a pixel
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


def _project(q: np.ndarray, b) -> np.ndarray:
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


def _pieces(a: np.ndarray, c: np.ndarray, t0: float, t1: float) -> np.ndarray:
    """The parameters cutting a + t (c - a), t0 <= t <= t1, where it crosses the pixels' borders, in order."""
    ts = [np.array([t0, t1])]
    for axis in (0, 1):
        if c[axis] != a[axis]:
            x0, x1 = sorted((a[axis] + t0 * (c[axis] - a[axis]), a[axis] + t1 * (c[axis] - a[axis])))
            lines = np.arange(np.floor(x0) + 1, np.ceil(x1))
            ts.append((lines - a[axis]) / (c[axis] - a[axis]))
    return np.unique(np.clip(np.concatenate(ts), t0, t1))


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
    a, c = _project(c0[keep], b), _project(c1[keep], b)
    t0, t1, inside = _frame_clip(a, c, b.width, b.height)
    rows = np.flatnonzero(keep)[inside]
    return normal, rows, np.stack([a[inside], c[inside]], axis=1), np.stack([t0[inside], t1[inside]], axis=1)


def _crossings(ends: np.ndarray, spans: np.ndarray, e: int) -> np.ndarray:
    """Where segment e's image crosses the others' (its parameters t): where what lies in front of it or
    behind it may change, so that the Gauss points integrate a smooth integrand between them."""
    a, c = ends[e]
    d, a_f, d_f = c - a, ends[:, 0], ends[:, 1] - ends[:, 0]
    det = d[0] * (-d_f[:, 1]) + d_f[:, 0] * d[1]  # a + t d = a_f + s d_f, by Cramer's rule
    r = a_f - a
    ok = np.abs(det) > 1e-12 * (np.linalg.norm(d) * np.linalg.norm(d_f, axis=1) + 1e-300)
    safe = np.where(ok, det, 1.0)
    t = (r[:, 0] * (-d_f[:, 1]) + d_f[:, 0] * r[:, 1]) / safe
    s = (d[0] * r[:, 1] - d[1] * r[:, 0]) / safe
    ok &= (s >= spans[:, 0]) & (s <= spans[:, 1]) & (t > spans[e, 0]) & (t < spans[e, 1])
    return t[ok]


def _pixels_of(a: np.ndarray, c: np.ndarray, ts: np.ndarray, b) -> np.ndarray:
    """The pixel (row major, row 0 at the top) of each piece between consecutive cuts ``ts`` of a + t (c - a)."""
    mid = a[None] + 0.5 * (ts[:-1] + ts[1:])[:, None] * (c - a)[None]
    x = np.minimum(mid[:, 0].astype(np.int64), b.width - 1)
    y = np.minimum(mid[:, 1].astype(np.int64), b.height - 1)
    return (b.height - 1 - y) * b.width + x


def segment_points(q0: np.ndarray, q1: np.ndarray, n: np.ndarray, cam, edges=None) -> EdgePoints:
    """The EdgePoints of the segments q0 q1 (rows, relative to the eye; ``n``: per segment the normal of the
    plane through the eye and it, whose sign says which side is g > 0; ``edges``: what they stand for): each
    segment's image cut where it crosses the pixels' borders and the images of the other segments in those
    pixels, GAUSS_POINTS a piece."""
    b = camera_basis(cam)
    gauss, gauss_w = np.polynomial.legendre.leggauss(GAUSS_POINTS)
    normal, rows, ends, spans = _segments(q0, q1, n, b)
    cuts = [_pieces(a, c, *span) for (a, c), span in zip(ends, spans)]
    by_pixel: dict = {}  # the segments in view whose image passes through each pixel, in their order
    for j, ts in enumerate(cuts):
        for p in np.unique(_pixels_of(*ends[j], ts, b)):
            by_pixel.setdefault(int(p), []).append(j)
    edge, at, weight, pixel = [], [], [], []
    for j, e in enumerate(rows):
        a, c = ends[j]
        near = sorted({k for p in np.unique(_pixels_of(a, c, cuts[j], b)) for k in by_pixel[int(p)] if k != j})
        ts = cuts[j]
        if near:
            near = np.asarray([j] + near)
            ts = np.unique(np.concatenate([ts, _crossings(ends[near], spans[near], 0)]))
        s0, s1 = ts[:-1], ts[1:]  # ts is increasing (np.unique): no piece is empty
        t = s0[:, None] + (s1 - s0)[:, None] * 0.5 * (gauss + 1.0)[None]  # (pieces, GAUSS_POINTS)
        at.append(a[None] + t.reshape(-1, 1) * (c - a)[None])
        weight.append((gauss_w[None] * 0.5 * (s1 - s0)[:, None] * np.linalg.norm(c - a)).reshape(-1))
        edge.append(np.full(t.size, e))
        pixel.append(np.repeat(_pixels_of(a, c, ts, b), GAUSS_POINTS))
    cat = lambda parts, shape: np.concatenate(parts) if parts else np.zeros(shape)  # noqa: E731
    return EdgePoints(edges, cat(edge, (0,)).astype(np.int64), cat(at, (0, 2)), cat(weight, (0,)),
                      cat(pixel, (0,)).astype(np.int64), normal)


def edge_points(edges: np.ndarray, points: np.ndarray, eye: np.ndarray, cam) -> EdgePoints:
    """The EdgePoints of mesh edges (``edges``: vertex indices into ``points``, relative to the frame origin,
    as ``eye``), seen from the eye: segment_points with the edge function det(v0 - eye, v1 - eye, d(x))."""
    q0, q1 = points[edges[:, 0]] - eye, points[edges[:, 1]] - eye
    return segment_points(q0, q1, np.cross(q0, q1), cam, edges)


def ray_directions(at: np.ndarray, b) -> np.ndarray:
    """Unit camera-ray directions (float32) through image points (pixels from the lower-left corner)."""
    d = (-b.d_f * b.z_e[None] + b.h * (at[:, 1:2] / b.height - 0.5) * b.y_e[None]
         + b.w * (at[:, 0:1] / b.width - 0.5) * b.x_e[None])
    return (d / np.linalg.norm(d, axis=1, keepdims=True)).astype(np.float32)


def side_directions(pts: EdgePoints, cam) -> np.ndarray:
    """(2 N, 3) float32: per point the camera rays EDGE_OFFSET_PX either side of its segment's image, first
    every point's towards the normal (g > 0), then every point's away from it."""
    b = camera_basis(cam)
    offset = EDGE_OFFSET_PX * pts.normal[pts.edge]
    return np.concatenate([ray_directions(pts.at + offset, b), ray_directions(pts.at - offset, b)])


def camera_copies(scene, geom, n: int, device: str) -> tuple:
    """(camera, fovy): the camera as a speed kernel reads it, one copy per point (its eye, center and up,
    the eye and center relative to the frame origin, rows 3 j to 3 j + 2; fovy[j]), differentiable, so that
    each point's adjoint is its own and the host sums them in a fixed order."""
    cam = scene.camera
    rows = np.tile(np.stack([geom.eye_offset(cam.eye), geom.eye_offset(cam.center), np.asarray(cam.up, np.float32)]),
                   (n, 1))
    camera = wp.array(rows.astype(np.float32), dtype=wp.vec3, device=device, requires_grad=True)
    return camera, wp.array(np.full(n, cam.fovy, np.float32), dtype=float, device=device, requires_grad=True)


def camera_adjoints(camera: wp.array, fovy: wp.array, n: int) -> dict:
    """Per point the adjoints camera_copies' arrays hold after a tape's backward: ``eye``, ``center``,
    ``up`` (n, 3) and ``fovy`` (n,), float64."""
    rows = camera.grad.numpy().astype(np.float64).reshape(n, 3, 3)
    return {"eye": rows[:, 0], "center": rows[:, 1], "up": rows[:, 2], "fovy": fovy.grad.numpy().astype(np.float64)}


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
    points = np.zeros((n_points, 3))
    for key, rows in vertices.items():
        np.add.at(points, rows, w[:, None] * speed[key])
    camera = {k: np.add.reduce(w[:, None] * speed[k].reshape(len(w), -1), axis=0) for k in
              ("eye", "center", "up", "fovy")}
    term = BoundaryTerm(points, camera)
    if sources is not None:
        term.sources = np.zeros((sources[1], 3))
        np.add.at(term.sources, sources[0], w[:, None] * speed["light"])
    return term


def add_terms(terms: list, n_points: int) -> BoundaryTerm:
    """The sum of BoundaryTerms, in their order (sources: those of the terms that have them; None if none)."""
    out = BoundaryTerm(np.zeros((n_points, 3)), {k: 0.0 for k in ("eye", "center", "up", "fovy")})
    for t in terms:
        out.points = out.points + t.points
        out.camera = {k: out.camera[k] + t.camera[k] for k in out.camera}
        if t.sources is not None:
            out.sources = t.sources if out.sources is None else out.sources + t.sources
    return out
