"""The boundary term of checker textures' squares seen by camera rays (backward(edges=True); docs/gradients.md,
"A checker's squares"): the lines u' = k and v' = k of each checker's affine uv map, straight on each
triangle, as segments whose ends are fixed barycentric combinations of its corners (they move with the
triangle), their speed in the corners and the camera (kernels.checker_edge_distances)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._warp import wp
from ..kernels import checker_edge_distances
from ..scene import camera_basis
from .grad_edge_launch import host_array, launch_points
from .grad_edge_points import BoundaryTerm, EdgePoints, boundary_term, camera_adjoints, camera_copies
from .grad_mesh_edges import MeshEdges
from .grad_shadow_edges import in_view

ON_LINE = 1e-6  # a corner whose mapped coordinate is this close to an integer k (times 1 + |k|) lies on its line
TEXTURE_KEYS = ("ka_texture", "kd_texture", "ks_texture")


def checker_rows(material) -> list:
    """The distinct rows (a, b, c) of a material's checkers' uv maps: each draws the lines a u + b v + c = k."""
    rows = []
    for key in TEXTURE_KEYS:
        t = getattr(material, key, None)
        if t is not None and t.checker is not None:
            rows += [tuple(t.uv_transform[:3]), tuple(t.uv_transform[3:])]
    return list(dict.fromkeys(rows))


def has_checker(scene, geom) -> bool:
    """Whether any material slot of ``geom`` has a checker texture."""
    return any(checker_rows(m) for m in geom.slot_materials(scene))


@dataclass
class CheckerSegments:
    """The checkers' lines on their triangles, by face: per segment its face, its two ends' barycentric weights
    on the face's corners (``weights``: (K, 2, 3), as geom.indices orders them), its ends (relative to the
    frame origin) and ``plane``, the normal of the plane through the eye and it."""

    face: np.ndarray
    weights: np.ndarray
    q0: np.ndarray
    q1: np.ndarray
    plane: np.ndarray


def checker_segments(scene, geom, m: MeshEdges, edges: np.ndarray, eye: np.ndarray, basis=None) -> CheckerSegments:
    """The CheckerSegments of the faces in view whose material has a checker, seen from ``eye`` along ``basis``
    (the camera's, or a virtual camera's: grad_mirror_edges.MirrorChain.basis): each line
    crossing a face's inside (_lines), and each line lying along an inner mesh edge that is not a camera edge
    (``edges``: camera_edges'; _edge_lines), where no camera edge carries its jump. Where two checker maps draw
    the same line on a face it is taken once (its jump is the two checkers' at once)."""
    p = geom.points_np.astype(np.float64)
    faces = geom.indices_np.reshape(-1, 3).astype(np.int64)
    uv = np.concatenate([geom.uv_array().numpy().astype(np.float64), np.ones((len(p), 1))], axis=1)
    seen = in_view(p[faces] - eye, camera_basis(scene.camera) if basis is None else basis)
    face, weights, line = [np.zeros(0, np.int64)], [np.zeros((0, 2, 3))], [np.zeros((0, 3))]
    for slot, material in enumerate(geom.slot_materials(scene)):
        which = np.flatnonzero(seen & (geom.tri_material_np == slot))
        for row in checker_rows(material) if len(which) else ():
            row = np.asarray(row, np.float64)
            f, w, k = _lines(uv[faces[which]] @ row)
            g, v, j = _edge_lines(m, edges, faces, uv, row, geom.tri_material_np == slot, seen)
            face += [which[f], g]
            weights += [w, v]
            line += [row[None] - np.c_[np.zeros((len(k), 2)), k], row[None] - np.c_[np.zeros((len(j), 2)), j]]
    face, weights = _distinct(np.concatenate(face), np.concatenate(weights), np.concatenate(line))
    corner = p[faces[face]]
    q0, q1 = np.einsum("kc,kcx->kx", weights[:, 0], corner), np.einsum("kc,kcx->kx", weights[:, 1], corner)
    return CheckerSegments(face, weights, q0, q1, np.cross(q0 - eye, q1 - eye))


def _near(x: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Whether mapped coordinates x lie on the lines k (ON_LINE)."""
    return np.abs(x - k) <= ON_LINE * (1.0 + np.abs(k))


def _lines(f: np.ndarray) -> tuple:
    """(face, weights, k): per face (rows of ``f``, its corners' mapped coordinate) each integer k strictly
    between its corners' least and greatest (a line through its inside), with the barycentric weights of
    the line's two ends on its sides: its corners on the line, and where its sides cross it (as
    grad_shadow_edges._chords finds a plane's chord)."""
    lo, hi = np.floor(f.min(axis=1)), np.ceil(f.max(axis=1))
    count = (hi - lo + 1).astype(np.int64)
    face = np.repeat(np.arange(len(f)), count)
    k = np.repeat(lo, count) + (np.arange(len(face)) - np.repeat(np.cumsum(count) - count, count))
    phi = f[face] - k[:, None]
    zero = _near(f[face], k[:, None])
    inside = ~np.all(zero | (phi > 0.0), axis=1) & ~np.all(zero | (phi < 0.0), axis=1)
    face, k, phi, zero = face[inside], k[inside], phi[inside], zero[inside]
    sign = np.where(zero, 0.0, np.sign(phi))
    unit = np.eye(3)
    ends = [np.broadcast_to(unit[c], (len(k), 3)) for c in range(3)]
    valid = [zero[:, c] for c in range(3)]
    for i, j in ((0, 1), (1, 2), (2, 0)):
        crosses = sign[:, i] * sign[:, j] < 0.0
        s = phi[:, i] / np.where(crosses, phi[:, i] - phi[:, j], 1.0)
        ends.append((1.0 - s)[:, None] * unit[i] + s[:, None] * unit[j])
        valid.append(crosses)
    ends, valid = np.stack(ends, axis=1), np.stack(valid, axis=1)
    first = np.argsort(~valid, axis=1, kind="stable")[:, :2]
    rows = np.arange(len(k))
    return face, np.stack([ends[rows, first[:, 0]], ends[rows, first[:, 1]]], axis=1), k


def _edge_lines(m: MeshEdges, edges: np.ndarray, faces: np.ndarray, uv: np.ndarray, row: np.ndarray,
                material: np.ndarray, seen: np.ndarray) -> tuple:
    """(face, weights, k): the inner mesh edges (two faces, of this material, one in view) that lie along a line
    k of the map ``row`` and are not camera edges (``edges``: there the camera's term has the whole jump), each
    on its first face, its ends' weights that face's corners."""
    n = len(uv)
    code = lambda v: np.minimum(v[:, 0], v[:, 1]) * n + np.maximum(v[:, 0], v[:, 1])  # noqa: E731
    f = uv[m.v] @ row  # (E, 2)
    k = np.round(f[:, 0])
    ok = m.pair & material[m.f1] & (seen[m.f1] | seen[m.f2]) & _near(f[:, 0], k) & _near(f[:, 1], k)
    ok &= ~np.isin(code(m.v), code(edges)) & ~np.isin(code(m.v2), code(edges))
    e = np.flatnonzero(ok)
    corner = faces[m.f1[e]]
    weights = np.stack([(corner == m.v[e, 0][:, None]).astype(np.float64),
                        (corner == m.v[e, 1][:, None]).astype(np.float64)], axis=1)
    return m.f1[e], weights, k[e]


def _distinct(face: np.ndarray, weights: np.ndarray, line: np.ndarray) -> tuple:
    """(face, weights) with each line (a, b, c: a u + b v + c = 0) once per face, in their first order: the
    lines compared scaled to a unit (a, b) whose first non-zero is positive, to ON_LINE."""
    size = np.hypot(line[:, 0], line[:, 1])
    sign = np.where((line[:, 0] > 0.0) | ((line[:, 0] == 0.0) & (line[:, 1] > 0.0)), 1.0, -1.0)
    key = np.round(line * (sign / np.maximum(size, 1e-300))[:, None] / ON_LINE)
    _, first = np.unique(np.c_[face, key], axis=0, return_index=True)
    keep = np.sort(first)
    return face[keep], weights[keep]


def checker_speeds(scene, geom, segments: CheckerSegments, pts: EdgePoints, device: str, threads: int = 1) -> dict:
    """Per point, the derivative of its signed distance from its checker line's image
    (kernels.checker_edge_distances, its adjoint; float64 rows): ``p0``, ``p1``, ``p2`` for its face's corners,
    ``eye``, ``center``, ``up`` and ``fovy`` for the camera. The adjoint launch alone, in bands on
    ``threads`` (grad_edge_launch.launch_points)."""
    cam, n = scene.camera, len(pts.edge)
    faces = geom.indices_np.reshape(-1, 3)[segments.face[pts.edge]]
    corners = host_array(geom.points_np[faces].astype(np.float32).reshape(-1, 3), wp.vec3, device, True)
    weights = host_array(segments.weights[pts.edge].astype(np.float32).reshape(-1, 3), wp.vec3, device)
    camera, fovy = camera_copies(scene, geom, n, device)
    distance = np.zeros(n, np.float32)
    at = host_array(pts.at.astype(np.float32), wp.vec2, device)
    launch_points(checker_edge_distances, n,
                  [corners, weights, camera, fovy, float(cam.near), cam.width, cam.height, at,
                   host_array(distance, float, device)], [3, 2, 3, 1, 0, 0, 0, 1, 1], threads, device,
                  [corners.grad, None, camera.grad, fovy.grad, None, None, None, None,
                   host_array(np.ones(n, np.float32), float, device)])
    g = corners.grad.numpy().astype(np.float64).reshape(n, 3, 3)
    return {"p0": g[:, 0], "p1": g[:, 1], "p2": g[:, 2], **camera_adjoints(camera, fovy, n)}


def checker_term(geom, segments: CheckerSegments, pts: EdgePoints, jump: np.ndarray, speed: dict,
                 d: np.ndarray) -> BoundaryTerm:
    """The checkers' lines' BoundaryTerm (boundary_term of ``jump``, edge_sides', and checker_speeds): to their
    faces' corners and the camera."""
    corners = geom.indices_np.reshape(-1, 3).astype(np.int64)[segments.face[pts.edge]]
    return boundary_term(pts, jump, d, speed, {"p0": corners[:, 0], "p1": corners[:, 1], "p2": corners[:, 2]},
                         len(geom.points_np))
