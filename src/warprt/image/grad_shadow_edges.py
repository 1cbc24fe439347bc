"""The boundary term of hard shadows' edges seen by camera rays (backward(edges=True) with render.shadows;
docs/gradients.md, "Shadow edges"): per point source of light (a point or spot light, a directional light,
each area light's sample point), the meshes' silhouettes from it, the segment each one's wedge cuts on each
receiver triangle (vectorised, culled), and per Gauss point of those (grad_edge_points) the source's own
term either side and the edge's speed in the occluder, the receiver, the light and the camera
(kernels/shadow_edges.py)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._warp import wp
from ..kernels import SOURCE_LIGHT, SOURCE_SAMPLE, make_light_sides_kernel, shadow_edge_distances
from ..scene import camera_basis, emitter_of_triangles
from .grad_edge_points import BoundaryTerm, EdgePoints, boundary_term, side_directions, tape_speeds
from .grad_mesh_edges import MeshEdges, face_normals, facing, silhouettes
from .grad_params import area_sources, parameter_names
from .mirrors import empty_mirrors
from .zbuffer import empty_fragments

ON_PLANE = 1e-9  # a vertex this close to a plane (times the scene's reach) lies on it
PAIRS_AT_ONCE = 1 << 20  # (receiver, edge) pairs tested in one NumPy array


@dataclass
class ShadowSources:
    """The points hard shadows are cast from, as the forward's tables hold them (float32 read as float64,
    relative to the frame origin): per Whitted light its position, or a directional light's direction of
    travel (``directional``); per area light sample point (scene/area.py: each a point light) its point.
    ``source``: the light sides kernel's row ((SOURCE_LIGHT, l, -1) or (SOURCE_SAMPLE, q, e)); ``name``: the
    parameter that moves it (lights.<i>.position | direction | center; "" where none does); ``emitter``: the
    area light it belongs to (-1: none), whose own triangles cast it no shadow."""

    at: np.ndarray
    directional: np.ndarray
    source: np.ndarray
    name: list
    emitter: np.ndarray


def shadow_sources(scene, geom) -> ShadowSources:
    """The ShadowSources of a frame of ``scene`` on ``geom``."""
    whitted = [i for i, light in enumerate(scene.lights) if not light.area]
    at = [np.asarray(light.direction if light.type == "directional" else p, np.float32).astype(np.float64)
          for light, p in zip(scene.whitted_lights, geom.light_positions(scene))]
    directional = [light.type == "directional" for light in scene.whitted_lights]
    source = [(SOURCE_LIGHT, l, -1) for l in range(len(whitted))]
    name = [f"lights.{i}.{'direction' if scene.lights[i].type == 'directional' else 'position'}" for i in whitted]
    emitter = [-1] * len(whitted)
    if scene.area_lights:
        area = geom.scene_data(scene).area
        first, points = area.first.numpy(), area.points.numpy().astype(np.float64)
        known = set(parameter_names(scene))
        for e, radiance in enumerate(area_sources(scene)):
            centre = radiance.replace(".radiance", ".center")
            for q in range(first[e], first[e + 1]):
                at.append(points[q])
                directional.append(False)
                source.append((SOURCE_SAMPLE, q, e))
                name.append(centre if centre in known else "")
                emitter.append(e)
    return ShadowSources(np.asarray(at, np.float64).reshape(-1, 3), np.asarray(directional, bool),
                         np.asarray(source, np.int32).reshape(-1, 3), name, np.asarray(emitter, np.int64))


@dataclass
class ShadowSegments:
    """The edges of hard shadows on their receivers, in the order (source, occluder edge, receiver face): per
    segment its source (a row of ShadowSources), its occluder edge's two vertex indices, its receiver face,
    its ends (relative to the frame origin) and ``plane``, the normal of the plane through the eye and it
    (kernels.shadow_plane's M, float64: its sign says which side of the image line is g > 0)."""

    source: np.ndarray
    edge: np.ndarray
    face: np.ndarray
    q0: np.ndarray
    q1: np.ndarray
    plane: np.ndarray

    @staticmethod
    def concatenate(parts: list) -> "ShadowSegments":
        shapes = ((0,), (0, 2), (0,), (0, 3), (0, 3), (0, 3))
        fields = ("source", "edge", "face", "q0", "q1", "plane")
        return ShadowSegments(*(np.concatenate([getattr(p, f) for p in parts]) if parts else
                                np.zeros(s, np.float64 if f in ("q0", "q1", "plane") else np.int64)
                                for f, s in zip(fields, shapes)))


@dataclass
class Receivers:
    """What every source's enumeration reads of the frame: the points and faces (float64, int), the faces'
    unit normals and emitters, which faces may show a shadow (``lit``: a material that reflects light, not
    wholly outside the view) and which are flat, the eye and the scene's reach (for ON_PLANE)."""

    p: np.ndarray
    faces: np.ndarray
    normal: np.ndarray
    emitter: np.ndarray
    lit: np.ndarray
    flat: np.ndarray
    eye: np.ndarray
    reach: float


def receivers(scene, geom, eye: np.ndarray, basis=None) -> Receivers:
    """The Receivers of a frame seen from ``eye`` (relative to the frame origin) along ``basis`` (the
    camera's, or a virtual camera's: grad_mirror_edges.MirrorChain.basis)."""
    p = geom.points_np.astype(np.float64)
    faces = geom.indices_np.reshape(-1, 3).astype(np.int64)
    mats = geom.slot_materials(scene)
    dark = np.asarray([max(m.kd) <= 0.0 and max(m.ks) <= 0.0 for m in mats] or [True])
    lit = ~dark[geom.tri_material_np] & _in_view(p[faces] - eye, camera_basis(scene.camera) if basis is None else basis)
    reach = max(float(np.abs(p).max(initial=0.0)), float(np.abs(eye).max()), 1e-30)
    return Receivers(p, faces, face_normals(p, faces), emitter_of_triangles(scene), lit, geom.tri_smooth_np == 0,
                     eye, reach)


def _in_view(tri: np.ndarray, b) -> np.ndarray:
    """Per triangle (its corners relative to the eye) whether it may show in the frame: not wholly behind the
    eye nor beyond one side of the view's pyramid."""
    z = -(tri @ b.z_e)
    u, v = tri @ b.x_e, tri @ b.y_e
    sx, sy = 0.5 * b.w / b.d_f, 0.5 * b.h / b.d_f
    outside = [z <= 0.0, u > sx * z, -u > sx * z, v > sy * z, -v > sy * z]
    return ~np.any([np.all(o, axis=1) for o in outside], axis=0)


def shadow_segments(scene, geom, m: MeshEdges, sources: ShadowSources, eye: np.ndarray, basis=None) -> ShadowSegments:
    """The ShadowSegments of every source, in the sources' order (source_segments), seen from ``eye`` along
    ``basis`` (receivers)."""
    r = receivers(scene, geom, eye, basis)
    parts = []
    for s in range(len(sources.at)):
        part = source_segments(r, m, sources.at[s], bool(sources.directional[s]), int(sources.emitter[s]))
        part.source = np.full(len(part.face), s)
        parts.append(part)
    return ShadowSegments.concatenate(parts)


def source_segments(r: Receivers, m: MeshEdges, at: np.ndarray, directional: bool, emitter: int) -> ShadowSegments:
    """The edges of the shadows one source casts (its ``source`` rows left 0): of the silhouettes from it
    (open edges, shared by more than two faces, or joining a face that faces it and one that does not; not
    its own emitter's), each one's wedge (the part of the plane through the source and the edge beyond the
    edge) cut by each receiver triangle it crosses, those that can show its light (Receivers.lit; a flat
    face only where the eye sees the side the source lights; not its own emitter's)."""
    own = (r.emitter == emitter) & (emitter >= 0)
    which, edges = silhouettes(m, facing(r.normal, r.p[r.faces[:, 0]], at, directional))
    toward = np.broadcast_to(-at, r.normal.shape) if directional else at - r.p[r.faces[:, 0]]
    lit_side = np.sign(np.einsum("ij,ij->i", r.normal, toward))
    eye_side = np.sign(np.einsum("ij,ij->i", r.normal, r.eye - r.p[r.faces[:, 0]]))
    shown = ~r.flat | (lit_side == eye_side)
    return _wedge_segments(r, edges[which & ~own[m.f1]], np.flatnonzero(r.lit & shown & ~own), at, directional)


def _wedge_normals(v0: np.ndarray, v1: np.ndarray, at: np.ndarray, directional: bool) -> np.ndarray:
    """Per edge v0 v1 the normal N of the plane through it and the source: (v0 - at) x (v1 - v0), or for a
    light travelling along ``at``, at x (v1 - v0) (kernels.shadow_plane's)."""
    w = np.broadcast_to(at, v0.shape) if directional else v0 - at
    return np.cross(w, v1 - v0)


def _wedge_segments(r: Receivers, edges: np.ndarray, faces: np.ndarray, at: np.ndarray,
                    directional: bool) -> ShadowSegments:
    """The segments the wedges of ``edges`` (vertex pairs) cut on the triangles ``faces`` (indices), by edge
    then face: the crossing pairs (_crossing_pairs), each triangle's chord on the wedge's plane (_chords)
    clipped to the wedge (_wedge_span), less those shorter than ON_PLANE."""
    tol = ON_PLANE * r.reach
    v0, v1 = r.p[edges[:, 0]], r.p[edges[:, 1]]
    n = _wedge_normals(v0, v1, at, directional)
    size = np.linalg.norm(n, axis=1)
    lever = np.ones(len(v0)) if directional else np.linalg.norm(v0 - at, axis=1)
    ok = size > 1e-12 * np.linalg.norm(v1 - v0, axis=1) * lever  # not seen end on from the source
    edges, v0, v1, n, size = edges[ok], v0[ok], v1[ok], n[ok], size[ok]
    e, f, phi = _crossing_pairs(r, v0, v1, n / size[:, None], faces, tol)
    a, b = _chords(r.p[r.faces[f]], phi, tol)
    t0, t1 = _wedge_span(a, b, v0[e], v1[e], at, directional)
    keep = (t1 - t0) * np.linalg.norm(b - a, axis=1) > tol
    e, f, a, b, t0, t1 = e[keep], f[keep], a[keep], b[keep], t0[keep], t1[keep]
    corner = r.p[r.faces[f]]
    n_r = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
    plane = (np.einsum("ij,ij->i", n[e], r.eye - v0[e])[:, None] * n_r
             + np.einsum("ij,ij->i", n_r, corner[:, 0] - r.eye)[:, None] * n[e])  # kernels.shadow_plane's M
    return ShadowSegments(np.zeros(len(e), np.int64), edges[e], f, a + t0[:, None] * (b - a),
                          a + t1[:, None] * (b - a), plane)


def _crossing_pairs(r: Receivers, v0: np.ndarray, v1: np.ndarray, unit: np.ndarray, faces: np.ndarray,
                    tol: float) -> tuple:
    """(edge, face, phi): the pairs of an edge and a triangle of ``faces`` whose corners lie strictly either
    side of the edge's wedge plane (unit normal ``unit``), by edge then face, with phi the corners' signed
    distances from it; less those whose triangle's plane holds the edge (its shadow would lie along the
    edge itself: where the occluder touches the receiver, a camera edge). A few edges at a time, so that the
    NumPy arrays stay within PAIRS_AT_ONCE pairs."""
    corner = r.p[r.faces[faces]]
    n_r = r.normal[faces]
    offset = np.einsum("ij,ij->i", n_r, corner[:, 0])
    corner_t = [np.ascontiguousarray(corner[:, k].T) for k in range(3)]  # (3, faces): BLAS's fast layout
    n_r_t = np.ascontiguousarray(n_r.T)
    step = max(1, PAIRS_AT_ONCE // max(len(faces), 1))
    out_e, out_f, out_phi = [], [], []
    for lo in range(0, len(v0), step):
        hi = min(lo + step, len(v0))
        plane = np.einsum("ec,ec->e", unit[lo:hi], v0[lo:hi])[:, None]
        phi = [unit[lo:hi] @ c - plane for c in corner_t]  # (edges, faces) a corner: matrix products
        low, high = np.minimum(np.minimum(phi[0], phi[1]), phi[2]), np.maximum(np.maximum(phi[0], phi[1]), phi[2])
        holds = (np.abs(v0[lo:hi] @ n_r_t - offset) <= tol) & (np.abs(v1[lo:hi] @ n_r_t - offset) <= tol)
        e, f = np.nonzero((low < -tol) & (high > tol) & ~holds)
        out_e.append(e + lo)
        out_f.append(faces[f])
        out_phi.append(np.stack([x[e, f] for x in phi], axis=1))
    if not out_e:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 3))
    return np.concatenate(out_e), np.concatenate(out_f), np.concatenate(out_phi)


def _chords(corner: np.ndarray, phi: np.ndarray, tol: float) -> tuple:
    """Per triangle (``corner``: (K, 3, 3)) crossed by a plane (``phi``: its corners' signed distances, some
    below -tol and some above tol) the two ends of its chord on the plane: its corners on the plane and the
    points where its sides cross it, the first two in that order."""
    zero = np.abs(phi) <= tol
    sign = np.where(zero, 0.0, np.sign(phi))
    ends, valid = [corner[:, 0], corner[:, 1], corner[:, 2]], [zero[:, 0], zero[:, 1], zero[:, 2]]
    for i, j in ((0, 1), (1, 2), (2, 0)):
        crosses = sign[:, i] * sign[:, j] < 0.0
        t = phi[:, i] / np.where(crosses, phi[:, i] - phi[:, j], 1.0)
        ends.append(corner[:, i] + t[:, None] * (corner[:, j] - corner[:, i]))
        valid.append(crosses)
    ends, valid = np.stack(ends, axis=1), np.stack(valid, axis=1)
    first = np.argsort(~valid, axis=1, kind="stable")[:, :2]
    rows = np.arange(len(corner))
    return ends[rows, first[:, 0]], ends[rows, first[:, 1]]


def _wedge_span(a: np.ndarray, b: np.ndarray, v0: np.ndarray, v1: np.ndarray, at: np.ndarray,
                directional: bool) -> tuple:
    """(t0, t1): per chord a + t (b - a) on a wedge's plane, the part inside the wedge (t1 <= t0: none).
    With coordinates y - at = alpha (v0 - at) + beta (v1 - at) in the plane, the wedge of a point source is
    alpha >= 0, beta >= 0, alpha + beta >= 1; with y - v0 = alpha (v1 - v0) + beta D, that of a light
    travelling along D is 0 <= alpha <= 1, beta >= 0. Each is linear in y, so in t (Liang-Barsky)."""
    if directional:
        u, w, origin = v1 - v0, np.broadcast_to(at, v0.shape), v0
    else:
        u, w, origin = v0 - at, v1 - at, np.broadcast_to(at, v0.shape)
    n = np.cross(u, w)
    nn = np.einsum("ij,ij->i", n, n)

    def coordinates(y):  # (alpha, beta): y - origin = alpha u + beta w
        rel = y - origin
        return (np.einsum("ij,ij->i", np.cross(rel, w), n) / nn, np.einsum("ij,ij->i", np.cross(u, rel), n) / nn)

    (alpha_a, beta_a), (alpha_b, beta_b) = coordinates(a), coordinates(b)
    if directional:
        bounds = ((alpha_a, alpha_b), (1.0 - alpha_a, 1.0 - alpha_b), (beta_a, beta_b))
    else:
        bounds = ((alpha_a, alpha_b), (beta_a, beta_b), (alpha_a + beta_a - 1.0, alpha_b + beta_b - 1.0))
    t0, t1 = np.zeros(len(a)), np.ones(len(a))
    for c_a, c_b in bounds:  # c_a + t (c_b - c_a) >= 0
        rise = c_b - c_a
        with np.errstate(divide="ignore", invalid="ignore"):
            t = -c_a / rise
        t0 = np.where(rise > 0.0, np.maximum(t0, t), t0)
        t1 = np.where(rise < 0.0, np.minimum(t1, t), t1)
        t1 = np.where((rise == 0.0) & (c_a < 0.0), -1.0, t1)
    return t0, t1


def light_sides(scene, geom, fx, sources: ShadowSources, segments: ShadowSegments, pts: EdgePoints,
                device: str, level: np.ndarray | None = None) -> np.ndarray:
    """(N, 3) float64: per point f_+ - f_-, the light of its segment's source alone at the nearest hits of
    camera rays EDGE_OFFSET_PX either side of it (towards its normal, then away), or with ``level`` (per
    point) at their rays' of that level through the mirrors, times its k_r, shadow ray included
    (kernels.make_light_sides_kernel): that source's jump, whatever other sources' shadows edge there too
    (a row of a rectangle light's sample points casts one line through an edge parallel to it)."""
    n = len(pts.edge)
    dirs = side_directions(pts, scene.camera)
    source = np.tile(sources.source[segments.source[pts.edge]], (2, 1))
    level = np.tile(np.zeros(n, np.int32) if level is None else np.asarray(level, np.int32), 2)
    color = wp.zeros(2 * n, dtype=wp.vec3, device=device)
    wp.launch(make_light_sides_kernel(fx), dim=2 * n,
              inputs=[geom.scene_data(scene), wp.vec3(*geom.eye_offset(scene.camera.eye)), empty_fragments(device),
                      empty_mirrors(device), wp.array(dirs, dtype=wp.vec3, device=device),
                      wp.array(source, dtype=wp.vec3i, device=device), wp.array(level, dtype=int, device=device)],
              outputs=[color], device=device)
    c = color.numpy().astype(np.float64)
    return c[:n] - c[n:]


def shadow_rows(geom, sources: ShadowSources, segments: ShadowSegments, pts: EdgePoints) -> np.ndarray:
    """(N, 6, 3) float64: per point what its shadow edge's distance reads of the geometry: the occluder edge's
    v0 and v1, the source (a point's position, a light's direction of travel), the receiver's p0, p1, p2."""
    p, seg = geom.points_np.astype(np.float64), pts.edge
    corners = geom.indices_np.reshape(-1, 3)[segments.face[seg]]
    return np.stack([p[segments.edge[seg, 0]], p[segments.edge[seg, 1]], sources.at[segments.source[seg]],
                     p[corners[:, 0]], p[corners[:, 1]], p[corners[:, 2]]], axis=1)


def shadow_vertices(geom, segments: ShadowSegments, pts: EdgePoints) -> dict:
    """Per point the geometry points shadow_rows' rows are (boundary_term's ``vertices``)."""
    seg = pts.edge
    corners = geom.indices_np.reshape(-1, 3).astype(np.int64)[segments.face[seg]]
    return {"v0": segments.edge[seg, 0], "v1": segments.edge[seg, 1], "p0": corners[:, 0], "p1": corners[:, 1],
            "p2": corners[:, 2]}


SHADOW_KEYS = ("v0", "v1", "light", "p0", "p1", "p2")  # shadow_rows' rows, as the speeds name them


def shadow_speeds(scene, geom, sources: ShadowSources, segments: ShadowSegments, pts: EdgePoints,
                  device: str) -> dict:
    """Per point, the derivative of its signed distance from its shadow edge's image
    (kernels.shadow_edge_distances, on a wp.Tape: grad_edge_points.tape_speeds; float64 rows): ``v0``, ``v1``
    for the occluder edge's vertices, ``light`` for the source (a point's position, a light's direction of
    travel), ``p0``, ``p1``, ``p2`` for the receiver's corners, ``eye``, ``center``, ``up`` and ``fovy`` for the
    camera."""
    directional = sources.directional[segments.source[pts.edge]].astype(np.int32)
    (g,), camera = tape_speeds(scene, geom, pts, shadow_edge_distances, [shadow_rows(geom, sources, segments, pts)],
                               [wp.array(directional, dtype=int, device=device)], device)
    return {**{key: g[:, k] for k, key in enumerate(SHADOW_KEYS)}, **camera}


def shadow_term(scene, geom, fx, sources: ShadowSources, segments: ShadowSegments, pts: EdgePoints, d: np.ndarray,
                device: str) -> BoundaryTerm:
    """The shadow edges' BoundaryTerm (boundary_term of light_sides and shadow_speeds): to the occluder
    edges' vertices, the receivers' corners, the camera and each source."""
    jump = light_sides(scene, geom, fx, sources, segments, pts, device)
    speed = shadow_speeds(scene, geom, sources, segments, pts, device)
    return boundary_term(pts, jump, d, speed, shadow_vertices(geom, segments, pts), len(geom.points_np),
                         (segments.source[pts.edge], len(sources.at)))
