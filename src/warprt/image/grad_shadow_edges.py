"""The boundary term of hard shadows' edges seen by camera rays (backward(edges=True) with render.shadows;
docs/gradients.md, "Shadow edges"): per point source of light (a point or spot light, a directional light,
each area light's sample point), the meshes' silhouettes from it, the segment each one's wedge cuts on each
receiver triangle (vectorised, culled), and per Gauss point of those (grad_edge_points) the source's own
term either side and the edge's speed in the occluder, the receiver, the light and the camera
(kernels/shadow_edges.py)."""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from .._warp import wp
from ..kernels import SOURCE_LIGHT, SOURCE_SAMPLE, make_light_sides_kernel, shadow_edge_distances
from ..scene import camera_basis, emitter_of_triangles
from .grad_edge_launch import host_array, launch_points
from .grad_edge_points import (BoundaryTerm, EdgePoints, boundary_term, by_column, camera_adjoints, camera_copies,
                               side_directions)
from .grad_mesh_edges import MeshEdges, face_normals, facing
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
    lit = ~dark[geom.tri_material_np] & in_view(p[faces] - eye, camera_basis(scene.camera) if basis is None else basis)
    reach = max(float(np.abs(p).max(initial=0.0)), float(np.abs(eye).max()), 1e-30)
    return Receivers(p, faces, face_normals(p, faces), emitter_of_triangles(scene), lit, geom.tri_smooth_np == 0,
                     eye, reach)


def in_view(tri: np.ndarray, b) -> np.ndarray:
    """Per triangle (its corners relative to the eye) whether it may show in the frame: not wholly behind the
    eye nor beyond one side of the view's pyramid."""
    z = -(tri @ b.z_e)
    u, v = tri @ b.x_e, tri @ b.y_e
    sx, sy = 0.5 * b.w / b.d_f, 0.5 * b.h / b.d_f
    outside = [z <= 0.0, u > sx * z, -u > sx * z, v > sy * z, -v > sy * z]
    return ~np.any([np.all(o, axis=1) for o in outside], axis=0)


def shadow_segments(scene, geom, m: MeshEdges, sources: ShadowSources, eye: np.ndarray, basis=None) -> ShadowSegments:
    """The ShadowSegments of every source, in the sources' order, seen from ``eye`` along ``basis`` (receivers):
    each one's occluder edges and receivers (source_edges), the segments their wedges cut (_wedge_segments), all
    sources at once."""
    r = receivers(scene, geom, eye, basis)
    step = max(1, PAIRS_AT_ONCE // max(len(r.faces), 1))  # sources at once: (sources, faces) arrays this big
    parts = [source_edges(r, m, sources, np.arange(lo, min(lo + step, len(sources.at))))
             for lo in range(0, len(sources.at), step)]
    source, edges, shows = (np.concatenate([p[k] for p in parts]) if parts else None for k in range(3))
    if source is None:
        return ShadowSegments.concatenate([])
    return _wedge_segments(r, sources, source, edges.reshape(-1, 2), shows.reshape(-1, len(r.faces)))


def source_edges(r: Receivers, m: MeshEdges, sources: ShadowSources, which: np.ndarray) -> tuple:
    """(source, edges, shows) of the sources ``which``: their occluder edges by source, each its source and
    two vertex indices (the silhouettes from it: open edges, shared by more than two faces, or joining a face
    that faces it and one that does not; not its own emitter's), and per source (rows of ``which``) the faces
    whose shadows it may show (Receivers.lit; a flat face only where the eye sees the side the source
    lights; not its own emitter's)."""
    at, directional, emitter = sources.at[which], sources.directional[which], sources.emitter[which]
    corner = r.p[r.faces[:, 0]]
    own = (r.emitter[None] == emitter[:, None]) & (emitter[:, None] >= 0)
    toward = np.where(directional[:, None, None], -at[:, None], at[:, None] - corner[None])
    lit_side = np.sign(_dots(r.normal, toward))
    front = _dots(r.normal, corner[None] - at[:, None]) < 0.0  # grad_mesh_edges.facing's, a point's
    for s in np.flatnonzero(directional):  # a light travelling along at: facing's product
        front[s] = facing(r.normal, corner, at[s], True)
    eye_side = np.sign(np.einsum("ij,ij->i", r.normal, r.eye - corner))
    shows = r.lit & (~r.flat | (lit_side == eye_side)) & ~own
    silhouette = ~m.pair | (front[:, m.f1] != front[:, m.f2])  # grad_mesh_edges.silhouettes', every source's
    second = m.pair & ~front[:, m.f1] & front[:, m.f2]
    s, e = np.nonzero(silhouette & ~own[:, m.f1])
    return which[s], np.where(second[s, e][:, None], m.v2[e], m.v[e]), shows


def _dots(normal: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(S, F): per source and face, its normal dotted with v[s, f] (the rows' einsum of the faces' alone, so
    each value to the bit)."""
    rows = v.reshape(-1, 3)
    return np.einsum("ij,ij->i", np.tile(normal, (len(rows) // max(len(normal), 1), 1)), rows).reshape(v.shape[:2])


def _wedge_segments(r: Receivers, sources: ShadowSources, source: np.ndarray, edges: np.ndarray,
                    shows: np.ndarray) -> ShadowSegments:
    """The segments the wedges of ``edges`` (vertex pairs, by ``source``) cut on the triangles each source
    shows (``shows``: (sources, faces)), by source, edge then face: the crossing pairs (_crossing_pairs),
    each triangle's chord on the wedge's plane (_chords) clipped to the wedge (_wedge_span), less those
    shorter than ON_PLANE. A wedge's normal N: (v0 - at) x (v1 - v0), or for a light travelling along
    ``at``, at x (v1 - v0) (kernels.shadow_plane's)."""
    tol = ON_PLANE * r.reach
    at, directional = sources.at[source], sources.directional[source]
    v0, v1 = r.p[edges[:, 0]], r.p[edges[:, 1]]
    n = np.cross(np.where(directional[:, None], at, v0 - at), v1 - v0)
    size = np.linalg.norm(n, axis=1)
    lever = np.where(directional, 1.0, np.linalg.norm(v0 - at, axis=1))
    ok = size > 1e-12 * np.linalg.norm(v1 - v0, axis=1) * lever  # not seen end on from the source
    source, edges, v0, v1, n, size, at, directional = (x[ok] for x in (source, edges, v0, v1, n, size, at,
                                                                       directional))
    e, f, phi = _crossing_pairs(r, source, v0, v1, n / size[:, None], shows, tol)
    a, b = _chords(r.p[r.faces[f]], phi, tol)
    t0, t1 = _wedge_span(a, b, v0[e], v1[e], at[e], directional[e])
    keep = (t1 - t0) * np.linalg.norm(b - a, axis=1) > tol
    e, f, a, b, t0, t1 = e[keep], f[keep], a[keep], b[keep], t0[keep], t1[keep]
    corner = r.p[r.faces[f]]
    n_r = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
    plane = (np.einsum("ij,ij->i", n[e], r.eye - v0[e])[:, None] * n_r
             + np.einsum("ij,ij->i", n_r, corner[:, 0] - r.eye)[:, None] * n[e])  # kernels.shadow_plane's M
    return ShadowSegments(source[e].astype(np.int64), edges[e], f, a + t0[:, None] * (b - a),
                          a + t1[:, None] * (b - a), plane)


def _crossing_pairs(r: Receivers, source: np.ndarray, v0: np.ndarray, v1: np.ndarray, unit: np.ndarray,
                    shows: np.ndarray, tol: float) -> tuple:
    """(edge, face, phi): the pairs of an edge and a triangle its source shows whose corners lie strictly
    either side of the edge's wedge plane (unit normal ``unit``), by edge then face, with phi the corners'
    signed distances from it; less those whose triangle's plane holds the edge (its shadow would lie along
    the edge itself: where the occluder touches the receiver, a camera edge). The sources that show the same
    faces at once (a rectangle light's sample points mostly do: one source at a time was most of the shadows'
    segments' time), a few edges at a time, so that the NumPy arrays stay within PAIRS_AT_ONCE pairs."""
    corner = r.p[r.faces]
    offset = np.einsum("ij,ij->i", r.normal, corner[:, 0])
    corner_t = [np.ascontiguousarray(corner[:, k].T) for k in range(3)]  # (3, faces): BLAS's fast layout
    n_r_t = np.ascontiguousarray(r.normal.T)
    used, of_used = np.unique(source, return_inverse=True)
    _, kind = np.unique(shows[used], axis=0, return_inverse=True)  # the sources alike: their faces shown
    group = kind.reshape(-1)[of_used.reshape(-1)]  # per edge its source's kind
    by_group = np.argsort(group, kind="stable")
    bounds = np.flatnonzero(np.diff(group[by_group], prepend=-1, append=-1))  # each kind's run of edges
    out_e, out_f, out_phi = [], [], []
    for first, end in itertools.pairwise(bounds):
        edges = by_group[first:end]
        faces = np.flatnonzero(shows[source[edges[0]]])
        c_t, n_t, off = [c[:, faces] for c in corner_t], n_r_t[:, faces], offset[faces]
        step = max(1, PAIRS_AT_ONCE // max(len(faces), 1))
        for lo in range(0, len(edges), step):
            rows = edges[lo:lo + step]
            plane = np.einsum("ec,ec->e", unit[rows], v0[rows])[:, None]
            phi = [unit[rows] @ c - plane for c in c_t]  # (edges, faces) a corner: matrix products
            low, high = np.minimum(np.minimum(phi[0], phi[1]), phi[2]), np.maximum(np.maximum(phi[0], phi[1]), phi[2])
            holds = (np.abs(v0[rows] @ n_t - off) <= tol) & (np.abs(v1[rows] @ n_t - off) <= tol)
            e, f = np.nonzero((low < -tol) & (high > tol) & ~holds)
            out_e.append(rows[e])
            out_f.append(faces[f])
            out_phi.append(np.stack([x[e, f] for x in phi], axis=1))
    if not out_e:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 3))
    e = np.concatenate(out_e)
    order = np.argsort(e, kind="stable")  # by edge (then face, as each edge's row gave them)
    return e[order], np.concatenate(out_f)[order], np.concatenate(out_phi)[order]


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
                directional: np.ndarray) -> tuple:
    """(t0, t1): per chord a + t (b - a) on a wedge's plane, the part inside the wedge (t1 <= t0: none).
    With coordinates y - at = alpha (v0 - at) + beta (v1 - at) in the plane, the wedge of a point source is
    alpha >= 0, beta >= 0, alpha + beta >= 1; with y - v0 = alpha (v1 - v0) + beta D, that of a light
    travelling along D (``directional``, per chord) is 0 <= alpha <= 1, beta >= 0. Each is linear in y, so in
    t (Liang-Barsky)."""
    along = directional[:, None]
    u, w, origin = np.where(along, v1 - v0, v0 - at), np.where(along, at, v1 - at), np.where(along, v0, at)
    n = np.cross(u, w)
    nn = np.einsum("ij,ij->i", n, n)

    def coordinates(y):  # (alpha, beta): y - origin = alpha u + beta w
        rel = y - origin
        return (np.einsum("ij,ij->i", np.cross(rel, w), n) / nn, np.einsum("ij,ij->i", np.cross(u, rel), n) / nn)

    (alpha_a, beta_a), (alpha_b, beta_b) = coordinates(a), coordinates(b)
    bounds = ((alpha_a, alpha_b), (np.where(directional, 1.0 - alpha_a, beta_a), np.where(directional, 1.0 - alpha_b,
                                                                                            beta_b)),
              (np.where(directional, beta_a, alpha_a + beta_a - 1.0), np.where(directional, beta_b,
                                                                                alpha_b + beta_b - 1.0)))
    t0, t1 = np.zeros(len(a)), np.ones(len(a))
    for c_a, c_b in bounds:  # c_a + t (c_b - c_a) >= 0, in any order: the largest t0, the smallest t1
        rise = c_b - c_a
        with np.errstate(divide="ignore", invalid="ignore"):
            t = -c_a / rise
        t0 = np.where(rise > 0.0, np.maximum(t0, t), t0)
        t1 = np.where(rise < 0.0, np.minimum(t1, t), t1)
        t1 = np.where((rise == 0.0) & (c_a < 0.0), -1.0, t1)
    return t0, t1


def light_sides(scene, geom, fx, sources: ShadowSources, segments: ShadowSegments, pts: EdgePoints,
                device: str, threads: int = 1, level: np.ndarray | None = None) -> np.ndarray:
    """(N, 3) float64: per point f_+ - f_-, the light of its segment's source alone at the nearest hits of
    camera rays EDGE_OFFSET_PX either side of it (towards its normal, then away), or with ``level`` (per
    point) at their rays' of that level through the mirrors, times its k_r, shadow ray included
    (kernels.make_light_sides_kernel): that source's jump, whatever other sources' shadows edge there too
    (a row of a rectangle light's sample points casts one line through an edge parallel to it). In bands on
    ``threads`` (grad_edge_launch.launch_points)."""
    return source_sides(scene, geom, fx, sources.source[segments.source[pts.edge]], pts, device, threads, level)


def source_sides(scene, geom, fx, source: np.ndarray, pts: EdgePoints, device: str, threads: int = 1,
                 level: np.ndarray | None = None) -> np.ndarray:
    """light_sides of the sources ``source`` (per point its light sides kernel's row: ShadowSources.source's):
    (N, 3) float64, per point f_+ - f_- of that source alone (with the frame's shadow rays, fx.shadows)."""
    n = len(pts.edge)
    dirs = side_directions(pts, scene.camera)
    source = np.tile(source, (2, 1))
    level = np.tile(np.zeros(n, np.int32) if level is None else np.asarray(level, np.int32), 2)
    color = wp.zeros(2 * n, dtype=wp.vec3, device=device)
    launch_points(make_light_sides_kernel(fx), 2 * n,
                  [geom.scene_data(scene), wp.vec3(*geom.eye_offset(scene.camera.eye)), empty_fragments(device),
                   empty_mirrors(device), host_array(dirs, wp.vec3, device), host_array(source, wp.vec3i, device),
                   host_array(level, int, device), color], [0, 0, 0, 0, 1, 1, 1, 1], threads, device)
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
                  device: str, threads: int = 1) -> dict:
    """Per point, the derivative of its signed distance from its shadow edge's image
    (kernels.shadow_edge_distances, its adjoint; float64 rows): ``v0``, ``v1`` for the occluder edge's
    vertices, ``light`` for the source (a point's position, a light's direction of travel), ``p0``, ``p1``,
    ``p2`` for the receiver's corners (SHADOW_KEYS: shadow_rows' rows), ``eye``, ``center``, ``up`` and ``fovy``
    for the camera. The adjoint launch alone, in bands on ``threads`` (grad_edge_launch.launch_points)."""
    cam, n = scene.camera, len(pts.edge)
    p = geom.points_np
    seg = pts.edge
    corners = geom.indices_np.reshape(-1, 3)[segments.face]
    rows = np.empty((len(segments.face), 6, 3), np.float32)  # per segment, then per point: one gather
    rows[:, 0], rows[:, 1], rows[:, 2] = p[segments.edge[:, 0]], p[segments.edge[:, 1]], sources.at[segments.source]
    rows[:, 3], rows[:, 4], rows[:, 5] = p[corners[:, 0]], p[corners[:, 1]], p[corners[:, 2]]
    geometry = host_array(rows[seg].reshape(-1, 3), wp.vec3, device, True)
    directional = host_array(sources.directional[segments.source[seg]].astype(np.int32), int, device)
    camera, fovy = camera_copies(scene, geom, n, device)
    distance = wp.zeros(n, dtype=float, device=device)
    at = host_array(pts.at.astype(np.float32), wp.vec2, device)
    launch_points(shadow_edge_distances, n,
                  [geometry, directional, camera, fovy, float(cam.near), cam.width, cam.height, at, distance],
                  [6, 1, 3, 1, 0, 0, 0, 1, 1], threads, device,
                  [geometry.grad, None, camera.grad, fovy.grad, None, None, None, None,
                   host_array(np.ones(n, np.float32), float, device)])
    g = by_column(geometry.grad.numpy().reshape(n, 6, 3))
    out = {key: g[k] for k, key in enumerate(SHADOW_KEYS)}
    out.update(camera_adjoints(camera, fovy, n))
    return out


def shadow_term(scene, geom, fx, sources: ShadowSources, segments: ShadowSegments, pts: EdgePoints, d: np.ndarray,
                device: str, threads: int = 1, keep=None) -> BoundaryTerm:
    """The shadow edges' BoundaryTerm (boundary_term of light_sides and shadow_speeds): to the occluder
    edges' vertices, the receivers' corners, the camera and each source. ``keep(name, make)``: make() or what
    the frame kept of it (grad_edges.kept_part)."""
    keep = keep or (lambda name, make: make())
    jump = keep("shadow sides", lambda: light_sides(scene, geom, fx, sources, segments, pts, device, threads))
    speed = keep("shadow speeds", lambda: shadow_speeds(scene, geom, sources, segments, pts, device, threads))
    return boundary_term(pts, jump, d, speed, shadow_vertices(geom, segments, pts), len(geom.points_np),
                         (segments.source[pts.edge], len(sources.at)))
