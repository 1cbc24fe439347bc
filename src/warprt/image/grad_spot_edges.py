"""The boundary term of a spot light's hard cone seen by camera rays (beam_width >= cutoff_angle: its falloff a
step; backward(edges=True), docs/gradients.md "A spot's hard cone"): where the cone meets each receiver
triangle in view, a conic, cut into short chords whose ends lie on it (found exactly in the cone's angle
about its axis; where it leaves a triangle by bisection), cut at the pixels with the other segments
(grad_edge_points), each Gauss point moved onto the true curve by Newton steps in the image and weighted by
the curve's own arc length; the jump the spot's own light either side (its shadow ray included), the speed
the curve's (kernels.spot_edge_distances)."""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .._warp import wp
from ..kernels import SOURCE_LIGHT, spot_edge_distances
from ..scene import camera_basis
from .grad_edge_launch import host_array, launch_points
from .grad_edge_points import (BoundaryTerm, EdgePoints, add_at, boundary_term, by_column, camera_adjoints,
                               camera_copies, project_points)
from .grad_shadow_edges import Receivers, source_sides

COARSE = 512  # the cone's angle about its axis, sampled this finely to find the arcs on each triangle
CHORD_PX = 0.5  # each arc cut into chords about this long in the image, at most
FINE = 4096  # chords an arc between two coarse samples is cut into, at most
BISECT = 48  # bisection steps to where an arc leaves its triangle
NEWTON = 3  # steps taking a Gauss point on a chord onto the curve
FACES_AT_ONCE = 1024  # receivers sampled in one NumPy array


def hard_spots(scene) -> list:
    """(l, i): per spot light whose cone is hard (beam >= cutoff), its Whitted index and its scene index."""
    whitted = [i for i, light in enumerate(scene.lights) if not light.area]
    return [(l, i) for l, i in enumerate(whitted)
            if scene.lights[i].type == "spot" and scene.lights[i].beam >= scene.lights[i].cutoff_angle]


@dataclass
class Cones:
    """The hard spots' cones as the forward holds them (float32 read as float64, relative to the frame
    origin): per spot its Whitted index ``l``, scene index ``i``, position ``at``, unit ``axis`` and cos(cutoff)."""

    l: np.ndarray
    i: np.ndarray
    at: np.ndarray
    axis: np.ndarray
    cos: np.ndarray


def cones(scene, geom) -> Cones:
    """The Cones of a frame's hard spots (hard_spots)."""
    spots = hard_spots(scene)
    l, i = (np.asarray([s[k] for s in spots], np.int64) for k in (0, 1))
    at = geom.light_positions(scene).astype(np.float64).reshape(-1, 3)[l]
    axis = np.asarray([scene.lights[k].direction for k in i], np.float32).astype(np.float64).reshape(-1, 3)
    cos = np.asarray([np.cos(np.radians(scene.lights[k].cutoff_angle)) for k in i], np.float32).astype(np.float64)
    return Cones(l, i, at, axis, cos)


@dataclass
class SpotSegments:
    """The chords of the cones' curves on their receivers, by spot then face: per chord its spot (a row of
    Cones), its face, its ends (relative to the frame origin) and ``plane``, the normal of the plane through
    the eye and it, signed so that the cone's inside is where its edge function is positive."""

    spot: np.ndarray
    face: np.ndarray
    q0: np.ndarray
    q1: np.ndarray
    plane: np.ndarray


def _curve(c: Cones, s: int, corner: np.ndarray, phi: np.ndarray) -> tuple:
    """(y, inside): the points of spot s's cone at angles ``phi`` about its axis (rows: one per triangle of
    ``corner``, (F, 3, 3)) on each triangle's plane, and whether each lies in its triangle (beyond the apex
    or at infinity: not)."""
    axis = c.axis[s]
    a = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(axis, a)
    sin = np.sqrt(max(1.0 - c.cos[s] ** 2, 0.0))
    r = c.cos[s] * axis + sin * (np.cos(phi)[..., None] * a + np.sin(phi)[..., None] * b)
    n_r = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.einsum("fx,fx->f", n_r, corner[:, 0] - c.at[s])[:, None] / np.einsum("fmx,fx->fm", r, n_r)
    ok = np.isfinite(t) & (t > 0.0)
    y = c.at[s] + np.where(ok, t, 0.0)[..., None] * r
    inside = ok
    for i, j in ((0, 1), (1, 2), (2, 0)):
        edge = np.cross(corner[:, j] - corner[:, i], n_r)  # pointing out of the triangle
        inside = inside & (np.einsum("fmx,fx->fm", y - corner[:, i, None], edge) <= 0.0)
    return y, inside


def spot_segments(scene, geom, r: Receivers, c: Cones, basis=None) -> SpotSegments:
    """The SpotSegments of every hard spot on the faces it may light in view (Receivers.lit, a flat face on the
    side the eye sees), all chords at most about CHORD_PX long in the image seen from r.eye along ``basis`` (the
    camera's, or a virtual camera's: grad_mirror_edges.MirrorChain.basis): a coarse ring of COARSE angles finds
    the arcs on each face (_arcs)."""
    b = camera_basis(scene.camera) if basis is None else basis
    parts = []
    for s in range(len(c.l)):
        toward = np.sign(np.einsum("ij,ij->i", r.normal, c.at[s] - r.p[r.faces[:, 0]]))
        eye_side = np.sign(np.einsum("ij,ij->i", r.normal, r.eye - r.p[r.faces[:, 0]]))
        faces = np.flatnonzero(r.lit & (~r.flat | (toward == eye_side)))
        for lo in range(0, len(faces), FACES_AT_ONCE):
            parts.append(_arcs(c, s, faces[lo:lo + FACES_AT_ONCE], r, b))
    if not parts:
        return SpotSegments(*(np.zeros(0, np.int64),) * 2, *(np.zeros((0, 3)),) * 3)
    spot, face, q0, q1 = (np.concatenate([p[k] for p in parts]) for k in range(4))
    mid = 0.5 * (q0 + q1)
    to = mid - c.at[spot]
    length = np.linalg.norm(to, axis=1, keepdims=True)
    u = to / length
    inward = (c.axis[spot] - np.einsum("ij,ij->i", u, c.axis[spot])[:, None] * u) / length  # grad_y of cos(theta)
    plane = np.cross(q0 - r.eye, q1 - r.eye)
    side = np.sign(np.einsum("ij,ij->i", plane, inward))  # the plane's normal towards the cone's inside
    return SpotSegments(spot, face, q0, q1, plane * np.where(side == 0.0, 1.0, side)[:, None])


def _arcs(c: Cones, s: int, faces: np.ndarray, r: Receivers, b) -> tuple:
    """(spot, face, q0, q1) of spot s's curve on ``faces``: the coarse ring's intervals with an end inside a
    face, each cut into chords of about CHORD_PX in the image (at most FINE), a chord kept where both its ends
    lie in the face and cut at the face's side by bisection where one does."""
    corner = r.p[r.faces[faces]]
    step = 2.0 * np.pi / COARSE
    y, inside = _curve(c, s, corner, np.arange(COARSE + 1)[None] * step * np.ones((len(faces), 1)))
    f, k = np.nonzero(inside[:, :-1] | inside[:, 1:])
    z = -((y[f, k] - r.eye) @ b.z_e), -((y[f, k + 1] - r.eye) @ b.z_e)
    seen = inside[f, k] & inside[f, k + 1] & (z[0] > 0.0) & (z[1] > 0.0)
    size = np.linalg.norm(project_points(y[f, k] - r.eye, b) - project_points(y[f, k + 1] - r.eye, b), axis=1)
    count = np.where(seen, np.clip(np.ceil(size / CHORD_PX), 1, FINE), 64).astype(np.int64)
    row = np.repeat(np.arange(len(f)), count)
    j = np.arange(len(row)) - np.repeat(np.cumsum(count) - count, count)
    phi0 = (k[row] + j / count[row]) * step
    phi1 = (k[row] + (j + 1) / count[row]) * step
    y, inside = _curve(c, s, corner[f[row]], np.stack([phi0, phi1], axis=1))
    y0, y1, in0, in1 = y[:, 0], y[:, 1], inside[:, 0], inside[:, 1]
    one = in0 != in1
    lo, hi = np.where(in0, phi0, phi1)[one], np.where(in0, phi1, phi0)[one]
    cut_corner = corner[f[row][one]]
    for _ in range(BISECT):
        mid = 0.5 * (lo + hi)
        _, in_mid = _curve(c, s, cut_corner, mid[:, None])
        lo, hi = np.where(in_mid[:, 0], mid, lo), np.where(in_mid[:, 0], hi, mid)
    cut = _curve(c, s, cut_corner, lo[:, None])[0][:, 0]
    y0, y1 = y0.copy(), y1.copy()
    y0[np.flatnonzero(one)[~in0[one]]] = cut[~in0[one]]
    y1[np.flatnonzero(one)[~in1[one]]] = cut[~in1[one]]
    keep = in0 | in1
    return np.full(keep.sum(), s), faces[f[row]][keep], y0[keep], y1[keep]


def _cone_values(c: Cones, spot: np.ndarray, corner: np.ndarray, at: np.ndarray, eye: np.ndarray, b) -> np.ndarray:
    """Per image point ``at`` (pixels from the lower-left corner) kernels.cone_distance's g in float64: the
    cosine of the angle off spot ``spot``'s axis of the point where its camera ray meets the receiver's plane
    (``corner``), less cos(cutoff)."""
    d = (-b.d_f * b.z_e + (b.h * (at[:, 1:2] / b.height - 0.5)) * b.y_e
         + (b.w * (at[:, 0:1] / b.width - 0.5)) * b.x_e)
    n_r = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
    t = np.einsum("ij,ij->i", n_r, corner[:, 0] - eye) / np.einsum("ij,ij->i", n_r, d)
    to = eye + t[:, None] * d - c.at[spot]
    return np.einsum("ij,ij->i", to, c.axis[spot]) / np.linalg.norm(to, axis=1) - c.cos[spot]


def on_cones(scene, geom, c: Cones, segments: SpotSegments, pts: EdgePoints, eye: np.ndarray,
             basis=None) -> EdgePoints:
    """``pts`` (the Gauss points of the chords' pieces) moved onto the true curves: NEWTON steps along the
    image gradient of g (_cone_values; central differences of 1e-4 pixel), each weight times |grad g| / |grad g .
    n| (n: its chord's image normal), the curve's length per length of its chord there. The rays from ``eye``
    along ``basis``: the camera's, or a virtual camera's, whose straight rays are the camera rays' last leg
    through a chain of mirrors (grad_mirror_edges.MirrorChain.basis)."""
    b = camera_basis(scene.camera) if basis is None else basis
    spot, corner = segments.spot[pts.edge], geom.points_np.astype(np.float64)[
        geom.indices_np.reshape(-1, 3)[segments.face[pts.edge]]]
    at, h = pts.at.astype(np.float64), 1e-4
    shift = np.eye(2) * h

    def value_and_gradient(x):
        grad = np.stack([(_cone_values(c, spot, corner, x + e, eye, b) - _cone_values(c, spot, corner, x - e, eye, b))
                         / (2.0 * h) for e in shift], axis=1)
        return _cone_values(c, spot, corner, x, eye, b), grad

    for _ in range(NEWTON):
        g, grad = value_and_gradient(at)
        size = np.einsum("ij,ij->i", grad, grad)
        at = at - np.where(size > 0.0, g / np.where(size > 0.0, size, 1.0), 0.0)[:, None] * grad
    _, grad = value_and_gradient(at)
    across = np.abs(np.einsum("ij,ij->i", grad, pts.normal[pts.edge]))
    ratio = np.where(across > 0.0, np.linalg.norm(grad, axis=1) / np.where(across > 0.0, across, 1.0), 1.0)
    return replace(pts, at=at, weight=pts.weight * ratio)


SPOT_KEYS = ("light", "axis", "p0", "p1", "p2")  # spot_edge_distances' rows, as the speeds name them


def spot_speeds(scene, geom, c: Cones, segments: SpotSegments, pts: EdgePoints, device: str,
                threads: int = 1) -> dict:
    """Per point, the derivative of its signed distance from its cone's curve's image
    (kernels.spot_edge_distances, its adjoint; float64 rows): ``light`` (the spot's position), ``axis`` (its
    direction), ``p0``, ``p1``, ``p2`` (the receiver's corners; SPOT_KEYS), ``eye``, ``center``, ``up`` and
    ``fovy``. The adjoint launch alone, in bands on ``threads`` (grad_edge_launch.launch_points)."""
    cam, n, seg = scene.camera, len(pts.edge), pts.edge
    corners = geom.indices_np.reshape(-1, 3)[segments.face[seg]]
    rows = np.empty((n, 5, 3), np.float32)
    rows[:, 0], rows[:, 1] = c.at[segments.spot[seg]], c.axis[segments.spot[seg]]
    rows[:, 2:] = geom.points_np[corners]
    geometry = host_array(rows.reshape(-1, 3), wp.vec3, device, True)
    cos = host_array(c.cos[segments.spot[seg]].astype(np.float32), float, device)
    camera, fovy = camera_copies(scene, geom, n, device)
    distance = wp.zeros(n, dtype=float, device=device)
    at = host_array(pts.at.astype(np.float32), wp.vec2, device)
    launch_points(spot_edge_distances, n, [geometry, cos, camera, fovy, float(cam.near), cam.width, cam.height, at,
                                           distance], [5, 1, 3, 1, 0, 0, 0, 1, 1], threads, device,
                  [geometry.grad, None, camera.grad, fovy.grad, None, None, None, None,
                   host_array(np.ones(n, np.float32), float, device)])
    g = by_column(geometry.grad.numpy().reshape(n, 5, 3))
    return {**{key: g[k] for k, key in enumerate(SPOT_KEYS)}, **camera_adjoints(camera, fovy, n)}


def spot_term(scene, geom, fx, c: Cones, segments: SpotSegments, pts: EdgePoints, d: np.ndarray, device: str,
              threads: int = 1, keep=None) -> tuple[BoundaryTerm, dict]:
    """The cones' BoundaryTerm (boundary_term of the spot's own light either side, grad_shadow_edges.source_sides,
    and spot_speeds): to the receivers' corners and the camera; and per spot its position's and direction's
    sums ({lights.<i>.position | direction: (3,)}, the direction's projected as Light keeps it unit). ``keep``:
    grad_edges.kept_part's."""
    keep = keep or (lambda name, make: make())
    source = np.stack([np.full(len(pts.edge), SOURCE_LIGHT), c.l[segments.spot[pts.edge]],
                       np.full(len(pts.edge), -1)], axis=1).astype(np.int32)
    jump = keep("spot sides", lambda: source_sides(scene, geom, fx, source, pts, device, threads))
    speed = keep("spot speeds", lambda: spot_speeds(scene, geom, c, segments, pts, device, threads))
    corners = geom.indices_np.reshape(-1, 3).astype(np.int64)[segments.face[pts.edge]]
    term = boundary_term(pts, jump, d, speed, {"p0": corners[:, 0], "p1": corners[:, 1], "p2": corners[:, 2]},
                         len(geom.points_np))
    w = pts.weight * np.einsum("ij,ij->i", d[pts.pixel], jump)
    return term, spot_sums(c, segments.spot[pts.edge], w, speed["light"], speed["axis"])


def spot_sums(c: Cones, spot: np.ndarray, w: np.ndarray, position: np.ndarray, axis: np.ndarray) -> dict:
    """{lights.<i>.position | direction: (3,)}: per spot the sum over its points (``spot``: per point its row of
    ``c``) of their weights ``w`` times their speeds in its position and axis, in their order; the direction's
    projected as Light keeps it unit ((I - u u^T))."""
    sums = [add_at(len(c.l), [spot], w, [v]) for v in (position, axis)]
    lights = {}
    for s, i in enumerate(c.i):
        lights[f"lights.{i}.position"] = sums[0][s]
        lights[f"lights.{i}.direction"] = sums[1][s] - c.axis[s] * (c.axis[s] @ sums[1][s])
    return lights
