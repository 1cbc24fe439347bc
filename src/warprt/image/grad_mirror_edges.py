"""The boundary term of the edges seen in planar mirrors (backward(edges=True) with render.max_depth > 1;
docs/gradients.md, "Edges seen in mirrors"): what the eye sees through a chain of planar mirrors is the scene
reflected across their planes (unfolded), so the edges the camera sees of that scene and its shadows' edges are
straight segments in the image, as are a checker's lines (grad_checker_edges) and a hard spot's cone's chords
(grad_spot_edges) found from the virtual eye, cut at the pixels with the rest (grad_edge_points), their jump
traced by the forward's walk through the mirrors, their speed on a wp.Tape through the reflections to the
vertices, the lights, the receivers, the mirrors' own vertices and the camera (kernels/mirror_edges.py)."""
from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from .._warp import wp
from ..geometry import planar_groups
from ..geometry.planar import clip_in_front, reflect_points
from ..kernels import (CONE, DIRECTIONAL_SHADOW, EDGE, POINT_SHADOW, SOURCE_LIGHT, make_mirror_faces_kernel,
                       make_mirrored_distances)
from ..scene import camera_basis
from .grad_checker_edges import CheckerSegments, checker_segments
from .grad_edge_points import BoundaryTerm, EdgePoints, boundary_term, ray_directions, tape_speeds
from .grad_mesh_edges import MeshEdges, camera_edges
from .grad_shadow_edges import (SHADOW_KEYS, ShadowSegments, ShadowSources, light_sides, receivers, shadow_rows,
                                shadow_segments, shadow_vertices, source_sides)
from .grad_spot_edges import Cones, SpotSegments, on_cones, spot_segments, spot_sums
from .mirrors import empty_mirrors, tiles_seen
from .zbuffer import empty_fragments

MAX_CHAINS = 64  # chains of mirrors a frame's edges are followed through; more is refused (edge_refusal)
WINDOW_TILE = 8  # pixels a side: the tiles by which the part of the image a chain may show in is bounded
ON_MIRROR = 1e-7  # relative to the scene's size, as geometry.planar.COPLANAR: what lies this close to a mirror's
# plane lies on it, and is the same seen directly as in that mirror (not counted twice)


@dataclass(frozen=True)
class MirrorChain:
    """A chain of planar mirror groups a camera ray may bounce off in turn (``groups``, its first first) and
    the scene as the eye sees it through them: ``unfold`` (4 x 4, affine) maps the real scene to the one seen
    (the reflections across the planes, the last first: M_1 ... M_k), ``eye`` is the virtual eye (the real one
    unfolded backwards, M_k ... M_1 eye: where the last mirror's rays seem to leave from), ``plane`` the last
    mirror's (n, offset), ``side`` the side of it those rays leave into (+1, -1: where what they see lies) and
    ``window`` the image tiles (WINDOW_TILE) where the chain may show: every plane's image, seen through the ones
    before, covers them (a bound, never less)."""

    groups: tuple
    unfold: np.ndarray
    eye: np.ndarray
    plane: np.ndarray | None
    side: float
    window: np.ndarray

    def apply(self, p: np.ndarray) -> np.ndarray:
        """The points p (..., 3) as the eye sees them through the chain."""
        return p @ self.unfold[:3, :3].T + self.unfold[:3, 3]

    def basis(self, b):
        """The camera basis ``b`` seen from the virtual eye: its axes mapped back through the chain (so that a
        point's coordinates along them from ``eye`` are its unfolded point's from the real eye)."""
        lin = self.unfold[:3, :3]
        return b._replace(eye=self.eye, z_e=lin.T @ b.z_e, x_e=lin.T @ b.x_e, y_e=lin.T @ b.y_e)


def reflection(plane: np.ndarray) -> np.ndarray:
    """The 4 x 4 affine reflection across the plane (n, offset): p - 2 (n . p - offset) n."""
    n = plane[:3]
    out = np.eye(4)
    out[:3, :3] -= 2.0 * np.outer(n, n)
    out[:3, 3] = 2.0 * plane[3] * n
    return out


def mirror_planes(scene, geom) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(group per triangle, planes, curved): the planar mirror groups of the frame's reflective triangles
    (geometry.planar_groups: k_r > 0 in float32, as the kernels read it), and per triangle whether it reflects
    in no group (a smooth, curved mirror, or past the planes planar_groups keeps): the edges seen in those cannot
    be followed through planes, and are the crossings' (grad_glass_edges: below a curved mirror's bounce)."""
    kr = np.asarray([m.reflectivity for m in geom.slot_materials(scene)] or [[0.0] * 3], np.float32).reshape(-1, 3)
    reflective = kr.max(axis=1) > 0.0
    group, planes = planar_groups(geom, reflective)
    n = geom.triangle_count
    return group, planes, reflective[geom.tri_material_np[:n]] & (group[:n] < 0)


def mirror_chains(scene, geom, eye: np.ndarray, group: np.ndarray, planes: np.ndarray) -> list[MirrorChain]:
    """The chains of mirror groups (``group``, ``planes``: mirror_planes') that camera rays from ``eye``
    (relative to the frame origin) may follow within render.max_depth ray levels, shortest first, each after
    the chain it extends (_extend; at most MAX_CHAINS + the last level's, for the refusal to count)."""
    basis = camera_basis(scene.camera)
    p = geom.points_np.astype(np.float64)
    faces = geom.indices_np.reshape(-1, 3)[: geom.triangle_count]
    tol = ON_MIRROR * float(np.ptp(p, axis=0).max(initial=0.0))
    tiles = -(-basis.width // WINDOW_TILE) * -(-basis.height // WINDOW_TILE)
    frontier = [MirrorChain((), np.eye(4), eye, None, 0.0, np.ones(tiles, bool))]
    chains: list[MirrorChain] = []
    for _ in range(1, scene.render.max_depth):
        frontier = [c for prefix in frontier for g in range(len(planes))
                    if (c := _extend(prefix, g, planes[g], p[faces[group[: len(faces)] == g]], basis, eye, tol))]
        chains += frontier
        if not frontier or len(chains) > MAX_CHAINS:
            break
    return chains


def frame_mirrors(scene, geom) -> tuple:
    """(group, planes, chains, why not) of a frame's mirrors, seen from its eye: mirror_planes' groups and
    planes, mirror_chains' chains of the planar ones (a curved mirror's reflections are the crossings'), and what
    backward(edges=True) cannot follow the edges seen in them through (None: nothing): more than MAX_CHAINS
    chains of mirrors. Made once a frame (grad_edges.kept_part): the refusal and the boundary read it."""
    group, planes, _ = mirror_planes(scene, geom)
    chains = mirror_chains(scene, geom, geom.eye_offset(scene.camera.eye).astype(np.float64), group, planes)
    why = None
    if len(chains) > MAX_CHAINS:
        why = f"more than {MAX_CHAINS} chains of mirrors within render.max_depth {scene.render.max_depth}"
    return group, planes, chains, why


def _extend(prefix: MirrorChain, g: int, plane: np.ndarray, tri: np.ndarray, basis, eye: np.ndarray,
            tol: float) -> MirrorChain | None:
    """``prefix`` followed by group ``g`` (its plane, its triangles ``tri``), or None where no ray can: the
    same group twice running, the virtual eye on its plane, its triangles wholly behind the last mirror, or
    their image through the prefix outside the prefix's window."""
    if prefix.groups and prefix.groups[-1] == g:
        return None
    if prefix.plane is not None:
        tri = clip_in_front(tri, prefix.plane, prefix.side, tol)[0]
    side = float(np.sign(plane[:3] @ prefix.eye - plane[3]))
    if side == 0.0 or not len(tri):
        return None
    window = prefix.window & tiles_seen(prefix.apply(tri), basis, eye, WINDOW_TILE)
    if not window.any():
        return None
    return MirrorChain(prefix.groups + (g,), prefix.unfold @ reflection(plane), reflect_points(prefix.eye, plane),
                       plane, side, window)


def _front_part(a: np.ndarray, b: np.ndarray, chain: MirrorChain, tol: float) -> tuple:
    """(t0, t1, keep): per segment a + t (b - a) (rows) its part on the side of the chain's last mirror that
    its rays see, and whether it has one not within ``tol`` of the plane (a segment on the mirror is seen
    there directly, not in it)."""
    n, offset = chain.plane[:3], chain.plane[3]
    da, db = chain.side * (a @ n - offset), chain.side * (b @ n - offset)
    with np.errstate(divide="ignore", invalid="ignore"):
        cut = da / (da - db)
    return np.where(da < 0.0, cut, 0.0), np.where(db < 0.0, cut, 1.0), np.maximum(da, db) > tol


@dataclass
class MirroredSegments:
    """The edges seen through the frame's mirror chains (``chains``; ``group``: per triangle its mirror group,
    mirror_planes'), unfolded (relative to the frame origin, as the eye sees them): the meshes' edges (``edges``:
    their vertex pairs, ``edge_chain``, ``edge_lines``: (q0, q1, plane), their parts seen and the normal of the
    plane through the eye and the unfolded edge) and the shadows' edges (``shadows``: ShadowSegments with their
    ends and planes unfolded, ``shadow_chain``); ``seams``: (q0, q1, plane) of the lines where a ray's mirror
    face changes within a group (mirror_seams, seen directly and through each chain), where the points are cut
    (their speed in a face's vertices changes there) but that add no term; ``camera`` and ``shadow_points``:
    the edges' and shadows' EdgePoints (grad_edges.boundary). With a checker, its lines (``checkers``:
    CheckerSegments, their ends unfolded; ``checker_chain``, ``checker_points``); with hard spots (``cones``),
    their cones' chords (``spots``: SpotSegments, their ends and planes unfolded; ``spot_chain``,
    ``spot_points``, moved onto the curves: on_mirrored_cones)."""

    chains: list
    group: np.ndarray
    edges: np.ndarray
    edge_chain: np.ndarray
    edge_lines: tuple
    shadows: ShadowSegments
    shadow_chain: np.ndarray
    seams: tuple
    camera: EdgePoints | None = None
    shadow_points: EdgePoints | None = None
    checkers: CheckerSegments | None = None
    checker_chain: np.ndarray | None = None
    checker_points: EdgePoints | None = None
    cones: Cones | None = None
    spots: SpotSegments | None = None
    spot_chain: np.ndarray | None = None
    spot_points: EdgePoints | None = None

    def blocks(self, eye: np.ndarray) -> list:
        """The (q0, q1, plane) of the edges, the shadows, the checkers' lines, the cones' chords and the seams
        (BLOCKS; a kind absent: no rows), relative to ``eye`` (segment_points')."""
        none = np.zeros((0, 3))
        lines = [(x.q0, x.q1, x.plane) if x is not None else (none, none, none)
                 for x in (self.shadows, self.checkers, self.spots)]
        return [(q0 - eye, q1 - eye, plane) for q0, q1, plane in (self.edge_lines, *lines, self.seams)]

    def take(self, parts: list):
        """Keep the points of blocks()' blocks (``parts``: theirs, in BLOCKS' order; the seams' only cut the
        others)."""
        self.camera, self.shadow_points = parts[:2]
        self.checker_points = parts[2] if self.checkers is not None else None
        self.spot_points = parts[3] if self.spots is not None else None


BLOCKS = ("edges", "shadows", "checkers", "spots", "seams")  # MirroredSegments.blocks', in order


def mirror_seams(m: MeshEdges, group: np.ndarray) -> np.ndarray:
    """(E, 2) vertex indices of the edges inside mirror groups (both faces in one group): no edge of the image
    (the faces are coplanar), but a point seen through a mirror meets one face or the other either side."""
    inner = m.pair & (group[m.f1] >= 0) & (group[m.f1] == group[m.f2])
    return m.v[inner]


def _through(chain: MirrorChain | None, a: np.ndarray, b: np.ndarray, eye: np.ndarray, tol: float) -> tuple:
    """(keep, q0, q1, plane): of the segments a b (rows, the real scene), those seen through ``chain`` (None:
    directly), their parts on the side of its last mirror its rays see, unfolded, and the normal of the plane
    through the eye and each unfolded segment."""
    if chain is None:
        return np.ones(len(a), bool), a, b, np.cross(a - eye, b - eye)
    t0, t1, keep = _front_part(a, b, chain, tol)
    ua, ub = chain.apply(a[keep]), chain.apply(b[keep])
    t0, t1 = t0[keep, None], t1[keep, None]
    return keep, ua + t0 * (ub - ua), ua + t1 * (ub - ua), np.cross(ua - eye, ub - eye)


def mirrored_segments(scene, geom, fx, m: MeshEdges, sources: ShadowSources | None, eye: np.ndarray,
                      group: np.ndarray, chains: list, checker: bool = False,
                      cones: Cones | None = None) -> MirroredSegments:
    """The MirroredSegments of ``chains`` seen from ``eye`` (relative to the frame origin): per chain, the
    edges camera_edges finds from its virtual eye and, with ``sources``, the shadows' edges shadow_segments
    finds from there (its receivers in the virtual camera's view), each cut to its part on the side of the last
    mirror its rays see, then unfolded (_through); and the mirrors' seams. With ``checker`` the checkers' lines,
    with ``cones`` the hard spots' chords, seen through each chain (_lines_through)."""
    p = geom.points_np.astype(np.float64)
    tol = ON_MIRROR * float(np.ptp(p, axis=0).max(initial=0.0))
    basis, seam = camera_basis(scene.camera), mirror_seams(m, group)
    edges, shadows, seams, pairs = [], [], [_through(None, p[seam[:, 0]], p[seam[:, 1]], eye, tol)[1:]], []
    for c, chain in enumerate(chains):
        pair = camera_edges(scene, geom, fx, chain.eye, sources, m)
        pairs.append(pair)
        keep, *line = _through(chain, p[pair[:, 0]], p[pair[:, 1]], eye, tol)
        edges.append((pair[keep], np.full(keep.sum(), c), *line))
        seams.append(_through(chain, p[seam[:, 0]], p[seam[:, 1]], eye, tol)[1:])
        if sources is not None:
            seg = shadow_segments(scene, geom, m, sources, chain.eye, chain.basis(basis))
            keep, q0, q1, _ = _through(chain, seg.q0, seg.q1, eye, tol)
            shadows.append((ShadowSegments(seg.source[keep], seg.edge[keep], seg.face[keep], q0, q1,
                                           seg.plane[keep] @ chain.unfold[:3, :3].T), np.full(keep.sum(), c)))
    stack = lambda parts: tuple(np.concatenate([x[k] for x in parts]) for k in range(len(parts[0])))  # noqa: E731
    pair, chain_of, *line = stack(edges)  # chains: one at least (grad_edges.boundary asks for none else)
    out = MirroredSegments(chains, group, pair, chain_of, tuple(line),
                           ShadowSegments.concatenate([x for x, _ in shadows]),
                           np.concatenate([c for _, c in shadows]) if shadows else np.zeros(0, np.int64),
                           stack(seams))
    if checker or cones is not None:
        _lines_through(scene, geom, m, out, eye, tol, checker, cones, pairs)
    return out


def _joined(parts: list, cls):
    """(segments, chain): the (``cls`` segments, chain index) pairs ``parts`` joined, field by field."""
    return (cls(*(np.concatenate([getattr(x, f.name) for x, _ in parts]) for f in fields(cls))),
            np.concatenate([np.full(len(x.face), c) for x, c in parts]).astype(np.int64))


def _lines_through(scene, geom, m: MeshEdges, mb: MirroredSegments, eye: np.ndarray, tol: float, checker: bool,
                   cones: Cones | None, pairs: list):
    """Into ``mb``: per chain, with ``checker`` the checkers' lines checker_segments finds from its virtual eye
    (``pairs``: per chain its camera edges there, where no line is taken), with ``cones`` the cones' chords spot_segments finds there (its
    receivers in the virtual camera's view), each cut to its part on the side of the last mirror its rays see,
    then unfolded (_through); a chord's plane is mapped as a normal (the cone's inside stays on its side)."""
    basis = camera_basis(scene.camera)
    lines, chords = [], []
    for c, chain in enumerate(mb.chains):
        seen = chain.basis(basis)
        if checker:
            seg = checker_segments(scene, geom, m, pairs[c], chain.eye, seen)
            keep, *line = _through(chain, seg.q0, seg.q1, eye, tol)
            lines.append((CheckerSegments(seg.face[keep], seg.weights[keep], *line), c))
        if cones is not None:
            seg = spot_segments(scene, geom, receivers(scene, geom, chain.eye, seen), cones, seen)
            keep, q0, q1, _ = _through(chain, seg.q0, seg.q1, eye, tol)
            chords.append((SpotSegments(seg.spot[keep], seg.face[keep], q0, q1,
                                        seg.plane[keep] @ chain.unfold[:3, :3].T), c))
    if checker:
        mb.checkers, mb.checker_chain = _joined(lines, CheckerSegments)
    if cones is not None:
        mb.cones, (mb.spots, mb.spot_chain) = cones, _joined(chords, SpotSegments)


def on_mirrored_cones(scene, geom, mb: MirroredSegments, pts: EdgePoints) -> EdgePoints:
    """The cones' chords' points ``pts`` moved onto the true curves as seen through their chains
    (grad_spot_edges.on_cones from each chain's virtual eye along its virtual camera's axes)."""
    at, weight, chain = pts.at.copy(), pts.weight.copy(), mb.spot_chain[pts.edge]
    basis = camera_basis(scene.camera)
    for c, ch in enumerate(mb.chains):
        sel = np.flatnonzero(chain == c)
        if len(sel):
            part = replace(pts, edge=pts.edge[sel], at=pts.at[sel], weight=pts.weight[sel], pixel=pts.pixel[sel])
            moved = on_cones(scene, geom, mb.cones, mb.spots, part, ch.eye, ch.basis(basis))
            at[sel], weight[sel] = moved.at, moved.weight
    return replace(pts, at=at, weight=weight)


@dataclass
class ChainFaces:
    """Per point of segments seen through mirror chains: its chain's length (``level``), the mirror face its
    ray meets at each bounce (``faces``, (N, L), L the longest chain's; where the ray leaves its chain a face of
    each of the chain's groups, and past the chain's end face 0: read by no term) and whether its ray follows its
    chain (``follows``: where it does not, the point shows nothing of that chain: its term is 0)."""

    level: np.ndarray
    faces: np.ndarray
    follows: np.ndarray


def chain_faces(scene, geom, fx, group: np.ndarray, chains: list, chain: np.ndarray, pts: EdgePoints,
                device: str) -> ChainFaces:
    """The ChainFaces of ``pts``, whose segments' chains are ``chain`` (per segment, rows of ``chains``): the
    faces the camera ray through each point meets at each level (kernels.make_mirror_faces_kernel: the
    forward's hits and bounces), checked against its chain's groups."""
    groups = [c.groups for c in chains]
    longest = max(len(g) for g in groups)
    wanted = np.asarray([list(g) + [-1] * (longest - len(g)) for g in groups], np.int64)[chain[pts.edge]]
    level = (wanted >= 0).sum(axis=1)
    n = len(pts.edge)
    found = wp.zeros((max(n, 1), longest), dtype=int, device=device)
    if n:
        dirs = ray_directions(pts.at, camera_basis(scene.camera))
        wp.launch(make_mirror_faces_kernel(fx), dim=(n, longest),
                  inputs=[geom.scene_data(scene), wp.vec3(*geom.eye_offset(scene.camera.eye)), empty_fragments(device),
                          empty_mirrors(device), wp.array(dirs, dtype=wp.vec3, device=device)], outputs=[found],
                  device=device)
    faces = found.numpy()[:n].astype(np.int64)
    seen = np.where(faces >= 0, group[np.maximum(faces, 0)], -1)
    follows = np.all((seen == wanted) | (wanted < 0), axis=1)
    first = np.asarray([np.flatnonzero(group == g)[0] for g in range(int(group.max(initial=-1)) + 1)] or [0])
    stand_in = np.where(wanted >= 0, first[np.maximum(wanted, 0)], 0)
    return ChainFaces(level, np.where(follows[:, None] & (wanted >= 0), faces, stand_in), follows)


def mirrored_speeds(scene, geom, rows: np.ndarray, kind: np.ndarray, cf: ChainFaces, pts: EdgePoints,
                    device: str, cos_cutoff: np.ndarray | None = None) -> dict:
    """Per point, the derivative of its signed distance from its edge's image through its mirrors
    (kernels.make_mirrored_distances, on a wp.Tape: tape_speeds; float64 rows): SHADOW_KEYS for what ``rows``
    (N, 6, 3) holds (the edge's v0 and v1; for a shadow's edge, ``kind``, also its source and receiver: shadow_rows;
    for a cone's, CONE, v0 its spot's axis, ``light`` its position, the receiver, and ``cos_cutoff`` per point),
    ``m<i><c>`` for corner c of the mirror face its ray meets at bounce i (``cf``), and the camera's."""
    corners = geom.points_np.astype(np.float64)[geom.indices_np.reshape(-1, 3)[cf.faces]]  # (N, L, 3, 3)
    extras = [wp.array(np.asarray(a, np.int32), dtype=int, device=device) for a in (kind, cf.level)]
    extras.append(wp.array(np.zeros(len(kind)) if cos_cutoff is None else cos_cutoff, dtype=float, device=device))
    (g, m), camera = tape_speeds(scene, geom, pts, make_mirrored_distances(cf.faces.shape[1]), [rows, corners],
                                 extras, device)
    mirrors = {f"m{i}{c}": m[:, i, c] for i in range(cf.faces.shape[1]) for c in range(3)}
    return {**{key: g[:, k] for k, key in enumerate(SHADOW_KEYS)}, **mirrors, **camera}


def mirror_vertices(geom, cf: ChainFaces) -> dict:
    """Per point the geometry points mirrored_speeds' ``m<i><c>`` are (boundary_term's ``vertices``)."""
    faces = geom.indices_np.reshape(-1, 3).astype(np.int64)[cf.faces]
    return {f"m{i}{c}": faces[:, i, c] for i in range(cf.faces.shape[1]) for c in range(3)}


def mirror_terms(scene, geom, fx, mb: MirroredSegments, sources: ShadowSources | None, sides, d: np.ndarray,
                 device: str, keep=None) -> tuple[list, dict]:
    """The BoundaryTerms of the edges seen in mirrors, and the hard spots' positions' and directions' sums
    (mirrored_spot_term's): per point d at its pixel · its jump (the mirrored mesh edges' and checkers' lines':
    ``sides(pts)``, the forward walk's either side, grad_edges.edge_sides; the shadows': light_sides, its
    source's light at its ray's hit through its chain, times the mirrors' k_r), 0 where its ray does not
    follow its chain (chain_faces), times its weight and its speed (mirrored_speeds), into the edges' and the
    receivers' vertices, the mirrors' (their faces the rays meet), the camera and the sources. ``keep(name,
    make)``: where what is the frame's alone (the chains' faces, jumps and speeds) is kept for its next backward
    (grad_edges.kept_part; None: made here)."""
    keep = keep or (lambda name, make: make())
    n_points, terms = len(geom.points_np), []
    p = geom.points_np.astype(np.float64)
    if mb.camera is not None and len(mb.camera.edge):
        pts = mb.camera

        def seen():
            cf = chain_faces(scene, geom, fx, mb.group, mb.chains, mb.edge_chain, pts, device)
            rows = np.zeros((len(pts.edge), 6, 3))
            rows[:, :2] = p[mb.edges[pts.edge]]
            return (cf, sides(pts) * cf.follows[:, None],
                    mirrored_speeds(scene, geom, rows, np.full(len(pts.edge), EDGE), cf, pts, device))
        cf, jump, speed = keep("mirrored edges", seen)
        vertices = {"v0": mb.edges[pts.edge, 0], "v1": mb.edges[pts.edge, 1], **mirror_vertices(geom, cf)}
        terms.append(boundary_term(pts, jump, d, speed, vertices, n_points))
    if mb.shadow_points is not None and len(mb.shadow_points.edge):
        pts, seg = mb.shadow_points, mb.shadows

        def shadows():
            cf = chain_faces(scene, geom, fx, mb.group, mb.chains, mb.shadow_chain, pts, device)
            jump = light_sides(scene, geom, fx, sources, seg, pts, device, level=cf.level) * cf.follows[:, None]
            kind = np.where(sources.directional[seg.source[pts.edge]], DIRECTIONAL_SHADOW, POINT_SHADOW)
            return cf, jump, mirrored_speeds(scene, geom, shadow_rows(geom, sources, seg, pts), kind, cf, pts, device)
        cf, jump, speed = keep("mirrored shadows", shadows)
        terms.append(boundary_term(pts, jump, d, speed, {**shadow_vertices(geom, seg, pts), **mirror_vertices(geom, cf)},
                                   n_points, (seg.source[pts.edge], len(sources.at))))
    if mb.checker_points is not None and len(mb.checker_points.edge):
        terms.append(mirrored_checker_term(scene, geom, fx, mb, sides, d, device, keep))
    lights = {}
    if mb.spot_points is not None and len(mb.spot_points.edge):
        term, lights = mirrored_spot_term(scene, geom, fx, mb, d, device, keep)
        terms.append(term)
    return terms, lights


def mirrored_checker_term(scene, geom, fx, mb: MirroredSegments, sides, d: np.ndarray, device: str,
                          keep) -> BoundaryTerm:
    """The checkers' lines seen in mirrors: their jump ``sides(pts)`` (the forward walk's) where the ray follows
    its chain, their speed that of the segment between the line's ends (EDGE: the ends fixed barycentric
    combinations of the face's corners, so a corner's speed is the ends' weighted by its weights), into the
    faces' corners, the mirrors' and the camera."""
    pts, seg = mb.checker_points, mb.checkers
    corners = geom.indices_np.reshape(-1, 3).astype(np.int64)[seg.face[pts.edge]]
    w = seg.weights[pts.edge]  # (N, 2, 3)

    def made():
        cf = chain_faces(scene, geom, fx, mb.group, mb.chains, mb.checker_chain, pts, device)
        rows = np.zeros((len(pts.edge), 6, 3))
        rows[:, :2] = np.einsum("nec,ncx->nex", w, geom.points_np.astype(np.float64)[corners])
        speed = mirrored_speeds(scene, geom, rows, np.full(len(pts.edge), EDGE), cf, pts, device)
        for c in range(3):
            speed[f"p{c}"] = w[:, 0, c, None] * speed["v0"] + w[:, 1, c, None] * speed["v1"]
        return cf, sides(pts) * cf.follows[:, None], speed
    cf, jump, speed = keep("mirrored checkers", made)
    vertices = {"p0": corners[:, 0], "p1": corners[:, 1], "p2": corners[:, 2], **mirror_vertices(geom, cf)}
    return boundary_term(pts, jump, d, speed, vertices, len(geom.points_np))


def mirrored_spot_term(scene, geom, fx, mb: MirroredSegments, d: np.ndarray, device: str,
                       keep) -> tuple[BoundaryTerm, dict]:
    """The hard cones' chords seen in mirrors: their jump the spot's own light either side at its ray's hit
    through its chain, times the mirrors' k_r (source_sides of that level), where the ray follows its chain;
    their speed the cone's curve's through the reflections (CONE), into the receivers' corners, the mirrors'
    and the camera; and per spot its position's and direction's sums (as grad_spot_edges.spot_term's)."""
    pts, seg, c = mb.spot_points, mb.spots, mb.cones
    spot = seg.spot[pts.edge]
    corners = geom.indices_np.reshape(-1, 3).astype(np.int64)[seg.face[pts.edge]]

    def made():
        cf = chain_faces(scene, geom, fx, mb.group, mb.chains, mb.spot_chain, pts, device)
        source = np.stack([np.full(len(spot), SOURCE_LIGHT), c.l[spot], np.full(len(spot), -1)], axis=1)
        jump = source_sides(scene, geom, fx, source.astype(np.int32), pts, device, level=cf.level)
        rows = np.zeros((len(spot), 6, 3))
        rows[:, 0], rows[:, 2], rows[:, 3:] = c.axis[spot], c.at[spot], geom.points_np.astype(np.float64)[corners]
        speed = mirrored_speeds(scene, geom, rows, np.full(len(spot), CONE), cf, pts, device, c.cos[spot])
        return cf, jump * cf.follows[:, None], speed
    cf, jump, speed = keep("mirrored spots", made)
    vertices = {"p0": corners[:, 0], "p1": corners[:, 1], "p2": corners[:, 2], **mirror_vertices(geom, cf)}
    term = boundary_term(pts, jump, d, speed, vertices, len(geom.points_np))
    return term, spot_sums(c, spot, pts.weight * np.einsum("ij,ij->i", d[pts.pixel], jump), speed["light"],
                           speed["v0"])
