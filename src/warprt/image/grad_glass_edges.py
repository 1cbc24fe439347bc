"""The boundary term of the edges seen through glass and in curved mirrors (backward(edges=True); docs/gradients.md,
"Edges seen through glass"): a refracted edge, or one a curved mirror reflects, is no straight segment of any scene,
so instead of enumerating edges the image is crossed by fixed lines (LINES a pixel each way), each walked with the
forward's ray tree (kernels/glass_edges.py make_tree_kernel) at STEPS points a pixel; where neighbours' tree
signatures part below a dielectric's split or a curved mirror's bounce (crossed_surfaces), the
crossing is found by bisection, the radiance traced either side, and its speed along the line taken from the
parting node's boundary function by implicit differentiation (make_tree_distances, on Warp's adjoint). Each line's
Leibniz rule, horizontal and vertical lines weighted by the crossing's image normal, gives the term."""
from __future__ import annotations

import numpy as np

from .._warp import wp
from ..kernels import (CHECKER_LINE, DIRECTIONAL_WEDGE, FACE_EDGE, MIRRORED, NO_RAY, POINT_WEDGE, REFLECTED,
                       SPOT_CONE, TRANSMITTED, empty_aov_buffers, empty_record, make_edge_sides_kernel,
                       make_tree_distances, make_tree_kernel)
from ..scene import camera_basis
from .grad_checker_edges import checker_rows, has_checker
from .grad_edge_launch import host_array, launch_points
from .grad_edge_points import EDGE_OFFSET_PX, EdgePoints, add_at, boundary_term, camera_adjoints, camera_copies, \
    ray_directions
from .grad_mirror_edges import mirror_planes
from .grad_normals import normals_to_points
from .grad_shadow_edges import shadow_sources
from .grad_spot_edges import cones, hard_spots, spot_sums
from .mirrors import empty_mirrors
from .zbuffer import empty_fragments

LINES = 16  # sample lines a pixel, each way
STEPS = 8  # points a pixel along a line, where neighbours' signatures are compared
STRIP = 8  # points along the boundary's piece a crossing stands for, where the image adjoint is read
BISECTIONS = 14
MAX_CROSSINGS = 8  # signature changes found between two neighbouring points  # a crossing found within 2^-14 of a step (8e-6 of a pixel)
MAX_GLASS_DEPTH = 12  # ray levels: 4095 tree nodes a point, each walked and compared: a walk's work grows as 2^levels
NODES_A_WALK = 1 << 24  # points x tree nodes a signature walk takes at once (8 bytes a node: 2^18 points at 6 levels)
NODES_A_PART = 1 << 22  # crossings x tree nodes a part's detailed walks hold at most, at one light (48 bytes a
# node + 12 a light; with area lights 24 a light or sample point: detail_columns, _axis_crossings)
SIGNATURE = ("face", "blocked", "cone", "square", "hidden")  # a tree's signature: per node its face, blocked
# lights, hard cones holding it, checker squares holding it, its area lights' blocked sample points' key


def crossed_surfaces(scene, geom, fx) -> dict:
    """Per kind of surface below whose rays the crossings follow the edges ("glass": a dielectric's split,
    "curved mirror": a bounce off a reflective triangle in no planar group, grad_mirror_edges.mirror_planes;
    a planar mirror's are unfolded), per triangle whether it is one, where the frame traces those rays."""
    n = geom.triangle_count
    glass = np.zeros(n, bool)
    curved = np.zeros(n, bool)
    if scene.render.max_depth > 1 and fx.refraction:
        glass = np.array([m.ior is not None for m in geom.slot_materials(scene)])[geom.tri_material_np[:n]]
    if scene.render.max_depth > 1 and fx.reflection:
        curved = mirror_planes(scene, geom)[2]
    return {"glass": glass, "curved mirror": curved}


def crossing_refusal(scene, surfaces: dict) -> str | None:
    """Why the crossings would miss an edge seen through glass or in a curved mirror (None: they cover them all,
    or there are none; ``surfaces``: crossed_surfaces'): "the edges seen through glass" (or "in curved mirrors")
    and why: more ray levels than MAX_GLASS_DEPTH. Every parameter's edges there are covered otherwise: a glass or
    curved mirror object's own vertices and pose too (its faces on the speeds' path, a smooth one's normals taken
    back to its vertices: glass_terms; its rims read at FINE_POINTS: grad_mesh_edges.rims), an area light's sample
    points' shadows (each point a point light's wedge: _parting) and its own outline."""
    kinds = [kind for kind, on in surfaces.items() if on.any()]
    if not kinds or scene.render.max_depth <= MAX_GLASS_DEPTH:
        return None
    seen = " and ".join({"glass": "through glass", "curved mirror": "in curved mirrors"}[k] for k in kinds)
    return f"the edges seen {seen} at more than {MAX_GLASS_DEPTH} ray levels (render.max_depth)"


def traced_colours(scene, geom, frame, at: np.ndarray, device: str) -> np.ndarray:
    """(N, 3) float64: the colours of camera rays through the image points ``at`` (pixels from the lower-left
    corner), traced with the frame's walk (kernels.edges.make_edge_sides_kernel: full Whitted shading)."""
    dirs = ray_directions(at, camera_basis(scene.camera))
    color = wp.zeros(len(at), dtype=wp.vec3, device=device)
    launch_points(make_edge_sides_kernel(frame.fx, frame.stack), len(at),
                  [geom.scene_data(scene), wp.vec3(*geom.eye_offset(scene.camera.eye)), frame.max_depth,
                   empty_fragments(device), empty_mirrors(device), empty_aov_buffers(device), empty_record(device),
                   host_array(dirs, wp.vec3, device), color], [0] * 7 + [1, 1], frame.threads, device)
    return color.numpy().astype(np.float64)


def tree_walk(scene, geom, frame, at: np.ndarray, device: str, detail: bool = False) -> dict:
    """The tree signatures of camera rays through ``at`` (make_tree_kernel): ``face``, ``blocked`` and, where the
    frame has a hard spot (and EdgeFrame.cone_bits), ``cone`` (N, nodes; its bits the hard spots whose cone holds
    each hit: absent, the walk is the one without), where it has a checker (and EdgeFrame.square_bits)
    ``square`` (N, nodes: the checker squares holding each hit, kernels.glass_edges.checker_squares), where it
    has area lights and shadows (and EdgeFrame.hidden_bits) ``hidden`` (N, nodes: the key of the sample points its
    shadow rays find blocked, kernels.glass_edges.hidden_points); with ``detail`` also ``below``, ``ray`` (N,
    nodes, 2, 3), ``hit`` (N, nodes, 3: u, v, distance), ``blocker`` (N, nodes, columns: a Whitted light's, then an
    area light sample point's, detail_columns), ``blocker_at`` (N, nodes, columns, 2) and ``share`` (N, nodes,
    columns, 3: a sample point's share of the colour were it seen, kernels.glass_edges.hidden_points; 0 in a
    Whitted light's column; only with ``hidden``)."""
    nodes, n = 2 ** frame.max_depth - 1, len(at)
    data = geom.scene_data(scene)
    lights = detail_columns(data)
    k = nodes if detail else 0
    spots = bool(frame.fx.light_model and hard_spots(scene) and frame.cone_bits)
    squares = bool(frame.fx.texture and has_checker(scene, geom) and frame.square_bits)
    hidden = holds_points(frame)
    out = {"face": np.full(n * nodes, NO_RAY, np.int32), "blocked": np.zeros(n * nodes, np.int32),
           "below": np.zeros(max(n * k, 1), np.int32), "ray": np.zeros((max(n * k, 1) * 2, 3), np.float32),
           "hit": np.zeros((max(n * k, 1), 3), np.float32), "blocker": np.full(max(n * k * lights, 1), -1, np.int32),
           "blocker_at": np.zeros((max(n * k * lights, 1), 2), np.float32),
           "cone": np.zeros(n * nodes if spots else 1, np.int32),
           "square": np.zeros(n * nodes if squares else 1, np.int32),
           "hidden": np.zeros(n * nodes if hidden else 1, np.int32),
           "share": np.zeros((max(n * k * lights * hidden, 1), 3), np.float32)}
    types = {"face": int, "blocked": int, "below": int, "ray": wp.vec3, "hit": wp.vec3, "blocker": int,
             "blocker_at": wp.vec2, "cone": int, "square": int, "hidden": int, "share": wp.vec3}
    arrays = {name: host_array(v, types[name], device) for name, v in out.items()}
    dirs = host_array(ray_directions(at, camera_basis(scene.camera)), wp.vec3, device)
    launch_points(make_tree_kernel(frame.fx, frame.stack, nodes, detail, spots, squares, hidden), n,
                  [data, wp.vec3(*geom.eye_offset(scene.camera.eye)), frame.max_depth, empty_fragments(device),
                   empty_mirrors(device), dirs, *arrays.values()],
                  [0] * 5 + [1, nodes, nodes, k, 2 * k, k, k * lights, k * lights, nodes * spots, nodes * squares,
                             nodes * hidden, k * lights * hidden], frame.threads, device)
    got = {name: a.numpy() for name, a in arrays.items()}
    shapes = {"face": (n, nodes), "blocked": (n, nodes), "below": (n, nodes), "ray": (n, nodes, 2, 3),
              "hit": (n, nodes, 3), "blocker": (n, nodes, lights), "blocker_at": (n, nodes, lights, 2),
              "cone": (n, nodes), "square": (n, nodes), "hidden": (n, nodes), "share": (n, nodes, lights, 3)}
    held = {"cone": spots, "square": squares, "hidden": hidden, "share": hidden}
    return {name: v.reshape(shapes[name]) for name, v in got.items()
            if (detail or name in SIGNATURE) and held.get(name, True)}


def holds_points(frame) -> bool:
    """Whether the frame's tree walks hold its area lights' blocked sample points (``hidden``, and with detail their
    shares: tree_walk): with area lights lighting through shadow rays, and EdgeFrame.hidden_bits."""
    fx = frame.fx
    return bool(fx.shadows and fx.area_lights and (fx.diffuse or fx.specular) and frame.hidden_bits)


def detail_columns(data) -> int:
    """A detailed walk's blocker columns a node (kernels.glass_edges.detail_columns; 1 at least): one per Whitted
    light, then one per area light sample point, in shadow_sources' order of rows."""
    return max(int(data.num_lights) + int(data.area.first.numpy()[data.area.num]), 1)


def line_points(cam, axis: int) -> np.ndarray:
    """(lines, points, 2): the sample lines along ``axis`` (0: horizontal, x varying), LINES a pixel across it at
    the strata's centres, each at STEPS points a pixel from one side of the frame to the other."""
    size = (cam.width, cam.height)
    across = (np.arange(size[1 - axis] * LINES) + 0.5) / LINES
    along = np.arange(size[axis] * STEPS + 1) / STEPS
    at = np.empty((len(across), len(along), 2))
    at[:, :, axis] = along[None, :]
    at[:, :, 1 - axis] = across[:, None]
    return at


def _same(a: dict, b: dict) -> np.ndarray:
    """Per point whether two signatures agree in every node."""
    return np.all(a["face"] == b["face"], axis=1) & _lit_alike(a, b)


def _lit_alike(a: dict, b: dict) -> np.ndarray:
    """Per point whether two signatures' lights agree in every node: the blocked ones (Whitted lights and area
    lights' sample points) and the hard cones, and so do their checker squares (where the signatures hold them:
    tree_walk)."""
    alike = np.all(a["blocked"] == b["blocked"], axis=1)
    for name in ("cone", "square", "hidden"):
        alike = alike & np.all(a[name] == b[name], axis=1) if name in a else alike
    return alike


def _smoothly(geom, fx, a: np.ndarray, b: np.ndarray, lit: np.ndarray) -> np.ndarray:
    """Per row of two signatures' faces (a, b: (N, nodes)) and whether their lights agree (_lit_alike), whether
    every node where they differ passes between two smooth faces of one object that share a corner (_smooth_pass):
    no crossing need be looked for; a tessellated glass ball's inner edges, seen at every level of its tree, would
    otherwise be most of the crossings."""
    return lit & np.all((a == b) | _smooth_pass(geom, fx, a, b), axis=1)


def _smooth_pass(geom, fx, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per node of two signatures' faces (a, b: (N, nodes)) whether it passes between two smooth faces of one
    object that share a corner: the radiance is continuous there (the interpolated normals are)."""
    if not fx.smooth:
        return np.zeros(a.shape, bool)
    corners = geom.indices_np.reshape(-1, 3)
    fa, fb = np.maximum(a, 0), np.maximum(b, 0)
    near = np.any(corners[fa][..., :, None] == corners[fb][..., None, :], axis=(-1, -2))
    smooth = (geom.tri_smooth_np[fa] != 0) & (geom.tri_smooth_np[fb] != 0) & (a >= 0) & (b >= 0)
    return smooth & (geom.tri_object_np[fa] == geom.tri_object_np[fb]) & near


def points_a_walk(frame, nodes: int = NODES_A_WALK) -> int:
    """How many points a tree walk takes at once: ``nodes`` tree nodes (2^max_depth - 1 a point), so that a
    walk's memory is the same at any depth."""
    return max(2, nodes // (2 ** frame.max_depth - 1))


def _pairs(scene, geom, frame, at: np.ndarray, device: str) -> tuple:
    """(lo, hi): neighbouring points of the lines ``at`` whose signatures differ, in the lines' order, walked
    points_a_walk at a time (the lines' points one run, each walk's last point the next one's first)."""
    points = at.shape[1]
    flat = at.reshape(-1, 2)
    per = points_a_walk(frame)
    lo, hi = [], []
    for first in range(0, len(flat) - 1, per - 1):
        part = flat[first:first + per]
        sig = tree_walk(scene, geom, frame, part, device)
        differ = (first + np.arange(len(part) - 1)) % points != points - 1  # not from a line's end to the next
        differ &= np.any([np.any(v[1:] != v[:-1], axis=1) for v in sig.values()], axis=0)
        i = np.nonzero(differ)[0]
        a, b = ({k: v[i + j] for k, v in sig.items()} for j in (0, 1))
        i = i[~_smoothly(geom, frame.fx, a["face"], b["face"], _lit_alike(a, b))]
        lo.append(part[i])
        hi.append(part[i + 1])
    return np.concatenate(lo), np.concatenate(hi)


def _crossings(scene, geom, frame, a: np.ndarray, b: np.ndarray, device: str) -> tuple:
    """(lo, hi): every place between the pairs a b where the signature changes, as _bisect finds one, then
    again past it while the signature there is not b's (an interval may hold several: a triangle's inner edge
    at one level of the tree and an object's silhouette at another), MAX_CROSSINGS an interval at most."""
    end = tree_walk(scene, geom, frame, b, device)
    los, his = [], []
    for _ in range(MAX_CROSSINGS):
        if not len(a):
            break
        lo, hi = _bisect(scene, geom, frame, a, b, device)
        los.append(lo)
        his.append(hi)
        past = tree_walk(scene, geom, frame, hi, device)
        more = ~_same(past, end) & ~_smoothly(geom, frame.fx, past["face"], end["face"], _lit_alike(past, end))
        a, b, end = hi[more], b[more], {k: v[more] for k, v in end.items()}
    return np.concatenate(los), np.concatenate(his)


def _bisect(scene, geom, frame, lo: np.ndarray, hi: np.ndarray, device: str) -> tuple:
    """(lo, hi) BISECTIONS halvings closer, each lo keeping its start's signature (or one it passes to
    smoothly: _smoothly) and each hi another."""
    start = tree_walk(scene, geom, frame, lo, device)
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        sig = tree_walk(scene, geom, frame, mid, device)
        same = (_same(sig, start) | _smoothly(geom, frame.fx, sig["face"], start["face"],
                                               _lit_alike(sig, start)))[:, None]
        lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
    return lo, hi


def _edge_of(geom, face: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(C, 2) point indices: the edge of each face nearest its hit at Warp's barycentrics (u, v) (weights on its
    first and second corner): the one opposite its smallest weight's corner."""
    corners = geom.indices_np.reshape(-1, 3).astype(np.int64)[np.maximum(face, 0)]
    weights = np.stack([uv[:, 0], uv[:, 1], 1.0 - uv[:, 0] - uv[:, 1]], axis=1)
    c = np.argmin(weights, axis=1)
    rows = np.arange(len(face))
    return np.stack([corners[rows, (c + 1) % 3], corners[rows, (c + 2) % 3]], axis=1)


def _parting(scene, geom, frame, lo: np.ndarray, hi: np.ndarray, curved: np.ndarray | None, device: str) -> dict:
    """Per crossing (lo, hi its two sides) the first tree node (in the tree's level order) where the two
    signatures part (faces both traced and different, the hard cones holding the hit, the lights or area light
    sample points its shadow rays find blocked, or the checker squares holding it), what parts them (``kind``:
    FACE_EDGE, SPOT_CONE of the spot ``light``, a wedge of light or sample point ``light`` (a row of shadow_sources:
    _each_point), or CHECKER_LINE; a cone's before a wedge's: outside a cone no shadow
    ray is traced, so its edge in a shadow parts both; a wedge's before a line's) and its edge (``edge``: the nearer
    face's edge nearest its hit, or the blocker's nearest its shadow ray's hit; a cone's and a line's unread), a
    checker line's values at the lo side's face's corners (``line``: _checker_lines; 0 elsewhere), the lo side's
    faces (``faces``), ``keep``: a parting found, and unless ``curved`` is None below a dielectric's split or a
    bounce off a curved mirror (``curved``: per triangle; _through), and ``own``: a sample point's wedge, whose
    jump f_- - f_+ is its share alone (``jump``: the share on its lit side, hidden_points'); a crossing parted by
    several sample points is a row each, ``row`` the crossing each row is (_each_point)."""
    a, b = tree_walk(scene, geom, frame, lo, device, True), tree_walk(scene, geom, frame, hi, device, True)
    node, keep, faces_part = _first_parting(geom, frame.fx, a, b)
    row, column, points, a, b, node, keep = _each_point(a, b, node, keep, faces_part, len(scene.whitted_lights))
    faces_part, rows = faces_part[row], np.arange(len(row))
    cone_a, cone_b = _cones(a, b)
    if curved is not None:
        keep &= _through(a, node, curved)
    fa, fb = a["face"][rows, node], b["face"][rows, node]
    use_a = (fb < 0) | ((fa >= 0) & (a["hit"][rows, node, 2] <= b["hit"][rows, node, 2]))
    face = np.where(use_a, fa, fb)
    uv = np.where(use_a[:, None], a["hit"][rows, node, :2], b["hit"][rows, node, :2])
    parted = (cone_a[rows, node] ^ cone_b[rows, node]).astype(np.int64)
    cone = ~faces_part[rows, node] & (parted != 0)
    bits = np.where(cone, parted, a["blocked"][rows, node] ^ b["blocked"][rows, node]).astype(np.int64)
    light = np.where(faces_part[rows, node], 0, np.log2(np.maximum(bits & -bits, 1)).astype(np.int64))
    squares = ~faces_part[rows, node] & (bits == 0) & ~points & (_squares(a)[rows, node] != _squares(b)[rows, node])
    shadow = ~faces_part[rows, node] & ~cone & ~squares
    blocked_a = ((a["blocked"][rows, node] >> light) & 1) != 0  # a's side the blocked one (a wedge's)
    light[points] = column[points]
    blocked_a[points] = a["blocker"][rows, node, light][points] != -1
    jump = np.zeros((len(rows), 3))
    if points.any():
        r, n, q = rows[points], node[points], light[points]
        jump[points] = np.where(blocked_a[points, None], -b["share"][r, n, q], a["share"][r, n, q])
    line = np.zeros((len(rows), 3))
    if squares.any():
        line[squares], on = _checker_lines(scene, geom, a, b, rows[squares], node[squares])
        keep[squares] &= on
    if shadow.any():
        blocker = np.where(blocked_a, a["blocker"][rows, node, light], b["blocker"][rows, node, light])
        at = np.where(blocked_a[:, None], a["blocker_at"][rows, node, light], b["blocker_at"][rows, node, light])
        face, uv = np.where(shadow, blocker, face), np.where(shadow[:, None], at, uv)
    keep &= face >= 0
    kind = np.select([shadow, cone, squares], [POINT_WEDGE, SPOT_CONE, CHECKER_LINE], FACE_EDGE)
    return {"node": node, "kind": kind, "light": light, "edge": _edge_of(geom, face, uv), "line": line,
            "faces": a["face"], "keep": keep, "row": row, "own": points, "jump": jump}


def _each_point(a: dict, b: dict, node: np.ndarray, keep: np.ndarray, faces_part: np.ndarray, whitted: int) -> tuple:
    """(row, column, points, a, b, node, keep): the crossings of two detailed signatures (a, b: tree_walk's;
    ``node``, ``keep`` and ``faces_part``: _first_parting's) one row each, but those parted by the area lights'
    blocked sample points alone (their faces, hard cones and Whitted lights alike there: ``points``, per row) a row
    per point whose shadow ray's answer differs (``column``: its blocker column, past the ``whitted`` lights': a row
    of shadow_sources; 0 elsewhere; a key parted with no column, their chance collision, no row), the rows of the
    crossing they come from (``row``, in order) and a, b, node and keep taken to them. Several points' shadow edges
    at one crossing are the rule, not the exception, where a rectangle light's row of points lies in one plane with
    an occluder's edge (an axis-aligned box under an axis-aligned light): one jump, each point's share of it its
    own (hidden_points)."""
    c = np.arange(len(node))
    cone_a, cone_b = _cones(a, b)
    alike = (cone_a[c, node] == cone_b[c, node]) & (a["blocked"][c, node] == b["blocked"][c, node])
    points = ~faces_part[c, node] & alike & (_hidden(a)[c, node] != _hidden(b)[c, node])
    differ = (a["blocker"][c, node, whitted:] != -1) != (b["blocker"][c, node, whitted:] != -1)
    differ &= points[:, None]
    count = np.where(points, differ.sum(axis=1), 1)
    row = np.repeat(c, count)
    column, on = np.zeros(len(row), np.int64), np.repeat(points, count)
    column[on] = whitted + np.nonzero(differ)[1]  # row-major: each crossing's points in order, as row repeats it
    return row, column, on, {k: v[row] for k, v in a.items()}, {k: v[row] for k, v in b.items()}, node[row], keep[row]


def _checker_lines(scene, geom, a: dict, b: dict, rows: np.ndarray, node: np.ndarray) -> tuple:
    """(values (S, 3), found (S,)): per crossing where the checker squares part (``rows`` of the detailed
    signatures a and b, at ``node``) the line between them: of its face's material's checker rows (checker_rows:
    a u + b v + c) the one whose coordinate lies nearest an integer k midway between the two sides' hits (the
    bisection leaves them 2^-14 of a step apart), as its value a u + b v + c - k at the lo side's face's three
    corners (make_tree_distances' CHECKER_LINE), and whether that face has a checker at all."""
    corners = geom.indices_np.reshape(-1, 3).astype(np.int64)
    uv = np.c_[geom.uv_array().numpy().astype(np.float64), np.ones(len(geom.points_np))]
    maps = [checker_rows(m) for m in geom.slot_materials(scene)]
    table = np.full((len(maps), max(map(len, maps)), 3), np.nan)
    for slot, m in enumerate(maps):
        table[slot, :len(m)] = np.reshape(m, (-1, 3))
    fa, fb = a["face"][rows, node], b["face"][rows, node]

    def at(x: dict, f: np.ndarray) -> np.ndarray:  # (u, v, 1) at a side's hit, from its barycentrics
        w = x["hit"][rows, node, :2].astype(np.float64)
        return np.einsum("sc,scx->sx", np.c_[w, 1.0 - w.sum(axis=1)], uv[corners[f]])

    lines = table[geom.tri_material_np[fa]]  # (S, R, 3)
    q = np.einsum("srx,sx->sr", lines, 0.5 * (at(a, fa) + at(b, fb)))
    off = np.where(np.isnan(q), np.inf, np.abs(q - np.round(q)))
    r = np.argmin(off, axis=1)
    s = np.arange(len(rows))
    line = np.nan_to_num(lines[s, r]) - np.c_[np.zeros((len(s), 2)), np.round(np.nan_to_num(q[s, r]))]
    return np.einsum("scx,sx->sc", uv[corners[fa]], line), np.isfinite(off[s, r])


def _first_parting(geom, fx, a: dict, b: dict) -> tuple:
    """(node, found, faces_part): per row of two signatures (tree_walk's, (N, nodes) each) the first node in the
    tree's level order where they part (faces both traced and different, not passing smoothly: _smooth_pass; the
    hard cones holding the hit; the lights and area light sample points its shadow rays find blocked; or the
    checker squares holding it), whether they part at all, and per node whether their faces do."""
    both = (a["face"] != NO_RAY) & (b["face"] != NO_RAY)
    faces_part = both & (a["face"] != b["face"]) & ~_smooth_pass(geom, fx, a["face"], b["face"])
    cone_a, cone_b = _cones(a, b)
    squares, hidden = (x(a) != x(b) for x in (_squares, _hidden))
    differ = faces_part | (both & ((a["blocked"] != b["blocked"]) | (cone_a != cone_b) | squares | hidden))
    return np.argmax(differ, axis=1), differ.any(axis=1), faces_part


def _cones(a: dict, b: dict) -> tuple:
    """Two signatures' hard-cone bits (zeros where the walk holds none: tree_walk)."""
    return tuple(x.get("cone", np.zeros_like(x["face"])) for x in (a, b))


def _squares(a: dict) -> np.ndarray:
    """A signature's checker squares (zeros where the walk holds none: tree_walk)."""
    return a.get("square", np.zeros_like(a["face"]))


def _hidden(a: dict) -> np.ndarray:
    """A signature's blocked sample points' keys (zeros where the walk holds none: tree_walk)."""
    return a.get("hidden", np.zeros_like(a["face"]))


def _through(a: dict, node: np.ndarray, curved: np.ndarray) -> np.ndarray:
    """Per row whether the node ``node`` of the signature ``a`` (a detailed tree_walk) lies below a dielectric's
    split or a bounce off a face ``curved`` marks (_bounced): the crossings' own; a camera ray's own node, or one
    only planar mirrors lead to, is the camera's, shadows' and mirrors' terms'."""
    return (node > 0) & ((a["below"][np.arange(len(node)), node] != 0) | _bounced(a["face"], node, curved))


def _theirs_near(scene, geom, frame, lo: np.ndarray, hi: np.ndarray, axis: int, curved: np.ndarray,
                 device: str) -> np.ndarray:
    """Per crossing (lo, hi: its sides along a line along ``axis``) whether a boundary of the other terms (not
    _through) lies within EDGE_OFFSET_PX of it along its line: their jump, read that far either side of their
    edge, spans this crossing's, which is theirs then. The case: a glass's outline seen directly and, just inside
    it, the band where the transmitted rays, spawned past the next face's plane by the ray offset, leave the glass
    without meeting that face; counted by both terms, the slab's outline moved by the camera was counted twice."""
    step = np.zeros(2)
    step[axis] = EDGE_OFFSET_PX
    at = 0.5 * (lo + hi)
    near = np.zeros(len(lo), bool)
    for side, reach in ((lo, at - step), (hi, at + step)):
        a, b = (tree_walk(scene, geom, frame, p, device, True) for p in (side, reach))
        node, found, _ = _first_parting(geom, frame.fx, a, b)
        near |= found & ~_through(a, node, curved)
        del a, b  # two detailed walks held at once, not four
    return near


def _bounced(faces: np.ndarray, node: np.ndarray, curved: np.ndarray) -> np.ndarray:
    """Per row whether its tree's node ``node`` (faces: (N, nodes), the tree's) lies below a bounce off a face
    ``curved`` marks: one of its ancestors' faces is (a reflective face's child is its mirror ray)."""
    rows = np.arange(len(node))
    out = np.zeros(len(node), bool)
    node = node.copy()
    while np.any(node > 0):
        up = node > 0
        node = np.where(up, (node - 1) // 2, 0)
        f = faces[rows, node]
        out |= up & (f >= 0) & curved[np.maximum(f, 0)]
    return out


def _path(scene, geom, frame, x: dict) -> tuple:
    """Per crossing the faces its parting node's ray came through (C, LEVELS: the root's first, then at its own
    level the node's face, a shadow's receiver), how it left each (REFLECTED, TRANSMITTED, MIRRORED), each one's
    ior (0: none) and the node's level."""
    levels, c = frame.max_depth, len(x["node"])
    rows = np.arange(c)
    level = np.array([int(n + 1).bit_length() - 1 for n in x["node"]], np.int64)
    faces = np.zeros((c, levels), np.int64)
    faces[rows, level] = np.maximum(x["faces"][rows, x["node"]], 0)
    branch, eta = np.zeros((c, levels), np.int32), np.zeros((c, levels), np.float32)
    mats = geom.slot_materials(scene)
    mirror = np.array([max(m.reflectivity) > 0.0 and frame.fx.reflection for m in mats], bool)
    ior = np.array([m.ior or 0.0 for m in mats], np.float32)
    node = x["node"].copy()
    for step in range(levels - 1):
        up = node > 0
        parent = np.where(up, (node - 1) // 2, 0)
        at = np.maximum(level - 1 - step, 0)
        f = np.maximum(x["faces"][rows, parent], 0)
        slot = geom.tri_material_np[f]
        how = np.where(mirror[slot], MIRRORED, np.where((node - 1) % 2 == 0, REFLECTED, TRANSMITTED))
        faces[up, at[up]], branch[up, at[up]], eta[up, at[up]] = f[up], how[up], ior[slot][up]
        node = parent
    return faces, branch, eta, level


def _speeds(scene, geom, frame, x: dict, sources, spots, at: np.ndarray, device: str) -> dict:
    """Per crossing the adjoint of its boundary function g (make_tree_distances) in each of its inputs: ``p<k><i>``
    corner i of the path's face at level k, ``n<k><i>`` its vertex normal (where a smooth face is at level k: the
    ray turns about them), ``v0`` and ``v1`` the edge, ``light`` (a shadow's source), a hard cone's ``position``
    and ``axis`` (0 where the crossing is no cone's), ``ior`` (C, slots) each material slot's ior (the eta of the
    refractions above the node: _by_slot), the camera's (camera_adjoints) and ``at`` (the image point: g's
    gradient in x and y); ``points``: the geometry points the inputs are; ``normals``: the vertices whose normals
    the ``n<k><i>`` are (grad_normals.normals_to_points takes them to the points); ``spot``: per crossing its row
    of ``spots`` (grad_spot_edges.Cones; -1: no cone's)."""
    levels, c = frame.max_depth, len(at)
    faces, branch, eta, level = _path(scene, geom, frame, x)
    corners = geom.indices_np.reshape(-1, 3).astype(np.int64)[faces]  # (C, levels, 3)
    p = geom.points_np.astype(np.float32)
    smooth = (geom.tri_smooth_np[faces] != 0) & bool(frame.fx.smooth)
    normals = geom.normals.numpy()[corners] * smooth[:, :, None, None]
    light, edge, cos_cutoff = np.zeros((c, 3), np.float32), p[x["edge"]], np.zeros(c, np.float32)
    kind = x["kind"].astype(np.int32)
    if sources is not None:
        light = sources.at[x["light"]].astype(np.float32)
        kind = np.where(kind == POINT_WEDGE, np.where(sources.directional[x["light"]], DIRECTIONAL_WEDGE, POINT_WEDGE),
                        kind).astype(np.int32)
    cone, check = kind == SPOT_CONE, kind == CHECKER_LINE
    spot = np.where(cone, np.searchsorted(spots.l, x["light"]) if cone.any() else -1, -1)
    if cone.any():  # the cone's axis in the edge's first row (make_tree_distances)
        row = spot[cone]
        light[cone], edge[cone, 0], cos_cutoff[cone] = spots.at[row], spots.axis[row], spots.cos[row]
    edge[check, 0] = x["line"][check]  # a checker line's values at its face's corners (make_tree_distances)
    grad = lambda v: host_array(np.asarray(v, np.float32).reshape(-1, 3), wp.vec3, device, True)  # noqa: E731
    path, edge, light_a, turn = grad(p[corners]), grad(edge), grad(light), grad(normals)
    eta_a = host_array(eta.reshape(-1), float, device, True)
    camera, fovy = camera_copies(scene, geom, c, device)
    point = host_array(at.astype(np.float32), wp.vec2, device, True)
    ints = lambda v: host_array(np.asarray(v, np.int32).reshape(-1), int, device)  # noqa: E731
    cam = scene.camera
    launch_points(make_tree_distances(levels), c,
                  [path, edge, light_a, turn, ints(branch), eta_a, ints(level), ints(kind),
                   host_array(cos_cutoff, float, device), camera, fovy, float(cam.near), cam.width, cam.height, point,
                   wp.zeros(c, dtype=float, device=device)],
                  [3 * levels, 2, 1, 3 * levels, levels, levels, 1, 1, 1, 3, 1, 0, 0, 0, 1, 1], frame.threads, device,
                  [path.grad, edge.grad, light_a.grad, turn.grad, None, eta_a.grad, None, None, None, camera.grad,
                   fovy.grad, None, None, None, point.grad, host_array(np.ones(c, np.float32), float, device)])
    rows = path.grad.numpy().astype(np.float64).reshape(c, levels, 3, 3)
    e = edge.grad.numpy().astype(np.float64).reshape(c, 2, 3)
    turned = np.where(smooth[:, :, None, None], turn.grad.numpy().astype(np.float64).reshape(c, levels, 3, 3), 0.0)
    speed = {f"p{k}{i}": rows[:, k, i] for k in range(levels) for i in range(3)}
    speed.update({f"n{k}{i}": turned[:, k, i] for k in range(levels) for i in range(3) if smooth[:, k].any()})
    points = {f"p{k}{i}": corners[:, k, i] for k in range(levels) for i in range(3)}
    turning = {key: corners[:, int(key[1]), int(key[2])] for key in speed if key[0] == "n"}
    at_light, apart = light_a.grad.numpy().astype(np.float64), ~(cone | check)[:, None]
    speed.update(v0=e[:, 0] * apart, v1=e[:, 1] * apart, light=at_light * apart, position=at_light * cone[:, None],
                 axis=e[:, 0] * cone[:, None], at=point.grad.numpy().astype(np.float64),
                 ior=_by_slot(geom, faces, level, eta_a.grad.numpy().reshape(c, levels)),
                 **camera_adjoints(camera, fovy, c))
    points.update(v0=x["edge"][:, 0], v1=x["edge"][:, 1])
    return {"speed": speed, "points": points, "normals": turning, "spot": spot}


def _by_slot(geom, faces: np.ndarray, level: np.ndarray, d_eta: np.ndarray) -> np.ndarray:
    """(C, slots) float64: per crossing its boundary function's adjoint in each material slot's ior, from its
    adjoints in the eta of each level of its path (``d_eta``: (C, LEVELS), _path's ``faces`` and ``level``), the
    levels above its node added in order (a slot's glass entered and left is two levels of one ior)."""
    slots, (c, levels) = len(geom.material_names), d_eta.shape
    out, rows, slot = np.zeros((c, slots)), np.arange(c), geom.tri_material_np[faces]
    for k in range(levels - 1):
        above = k < level
        out[rows[above], slot[above, k]] += d_eta[above, k]
    return out


def _axis_crossings(scene, geom, frame, sources, spots, axis: int, curved: np.ndarray | None, device: str) -> list:
    """The parts (_part_crossings) of the crossings of the lines along ``axis``, a part per points_a_walk of
    their pairs (_pairs): each part's detailed walks (per node its ray, hit and blockers) hold the trees of as
    many points as its pairs hold crossings, MAX_CROSSINGS a pair at most, so NODES_A_PART nodes at most, fewer
    where a node holds more than one light's blockers (48 bytes a node, 12 a light; with area lights a column per
    sample point, detail_columns, and 24 a column: their shares)
    (scenes/glass_slab.toml: 1.8 crossings a pair at 32 x 16 pixels, 5.2 at 8 x 4, its stripes finer than a pixel)."""
    lo, hi = _pairs(scene, geom, frame, line_points(scene.camera, axis), device)
    column = 24 if holds_points(frame) else 12  # bytes: a blocker and its (u, v), and a share where held
    per = points_a_walk(frame, NODES_A_PART * 60 // (48 + column * detail_columns(geom.scene_data(scene)))
                        // MAX_CROSSINGS)
    parts = [_part_crossings(scene, geom, frame, sources, spots, axis, curved, lo[i:i + per], hi[i:i + per], device)
             for i in range(0, len(lo), per)]
    return [p for p in parts if p is not None]


def _part_crossings(scene, geom, frame, sources, spots, axis: int, curved: np.ndarray | None, lo: np.ndarray,
                    hi: np.ndarray, device: str) -> tuple | None:
    """(EdgePoints, jump, speed, points, light rows, spot rows) of the crossings between the pairs lo hi of the
    lines along ``axis`` (_speeds' rows: ``sources``'s, ``spots``'s; ``points`` its points and normals, n<k><i>
    naming a vertex whose normal that speed is): per crossing
    its place, its pixel, its weight -sign(g_axis) / (LINES (|g_x| + |g_y|)) (the line's Leibniz term
    dx_c/dtheta = -g_theta / g_axis, times the line's share |g_axis| / (|g_x| + |g_y|), over the lines' spacing)
    and f_- - f_+ (the colours at its sides, the bisection's last lo and hi: two crossings nearer than a fixed
    offset each read its own jump; an area light sample point's shadow edge its point's share alone, _each_point:
    several points' edges may lie at one crossing); with ``curved`` those below a split or a curved bounce
    (_through) and not within reach of the other terms' boundaries (_theirs_near)."""
    if len(lo):
        lo, hi = _crossings(scene, geom, frame, lo, hi, device)
        x = _parting(scene, geom, frame, lo, hi, curved, device)
        lo, hi = lo[x["row"]], hi[x["row"]]
        keep = x.pop("keep")
        x, lo, hi = {k: v[keep] for k, v in x.items()}, lo[keep], hi[keep]
        if curved is not None and len(lo):
            mine = ~_theirs_near(scene, geom, frame, lo, hi, axis, curved, device)
            x, lo, hi = {k: v[mine] for k, v in x.items()}, lo[mine], hi[mine]
    if not len(lo):
        return None
    at = 0.5 * (lo + hi)
    colours = traced_colours(scene, geom, frame, np.concatenate([lo, hi]), device)
    jump = _jumps(x, colours[:len(at)] - colours[len(at):])
    s = _speeds(scene, geom, frame, x, sources, spots, at, device)
    g = s["speed"].pop("at")
    size = np.abs(g[:, 0]) + np.abs(g[:, 1])
    weight = np.where(size > 0.0, -np.sign(g[:, axis]) / (LINES * np.where(size > 0.0, size, 1.0)), 0.0)
    pixel = _strip_pixels(scene.camera, at, g, axis)
    spread = lambda v: np.repeat(v, STRIP, axis=0)  # noqa: E731
    pts = EdgePoints(None, np.arange(len(at) * STRIP), spread(at), spread(weight) / STRIP, pixel.reshape(-1),
                     np.zeros((len(at) * STRIP, 2)))
    jump, speed = spread(jump), {k: spread(v) for k, v in s["speed"].items()}
    points = {k: spread(v) for k, v in {**s["points"], **s["normals"]}.items()}
    return pts, jump, speed, points, spread(x["light"]), spread(s["spot"])


def _jumps(x: dict, traced: np.ndarray) -> np.ndarray:
    """(C, 3) float64: per crossing row (_parting's ``x``) f_- - f_+: the ``traced`` colours' (its sides'), or a
    sample point's wedge its share alone (``own``), the first row of its crossing also the rest of the traced jump
    (a crossing parted by one point alone: the traced jump; by several in one plane, each its own share: the rest
    0; by points whose shares are 0, as on a dielectric's face, where what parts the tree below moves with them:
    the node's hit on a crease, its children spawned past the next face's plane within the ray offset of it, the
    traced jump, as a Whitted light's wedge takes it)."""
    own, crossing = x["own"], x["row"]
    if not own.any():
        return traced
    first = np.r_[True, crossing[1:] != crossing[:-1]]
    shares = np.zeros((crossing.max() + 1, 3))
    np.add.at(shares, crossing[own], x["jump"][own])
    return np.where(own[:, None], x["jump"] + first[:, None] * (traced - shares[crossing]), traced)


def _strip_pixels(cam, at: np.ndarray, g: np.ndarray, axis: int) -> np.ndarray:
    """(C, STRIP) the pixels of STRIP points along the boundary's piece each crossing stands for (the strip of
    1 / LINES across its line, which pixels' rows or columns never cut), its tangent from g's gradient: the image
    adjoint averaged over them, not read at the crossing alone, so that a pixel border the piece crosses costs
    the sum a 1 / (LINES STRIP) share of a line's error, not 1 / LINES."""
    across = ((np.arange(STRIP) + 0.5) / STRIP - 0.5) / LINES
    g_along = g[:, axis]
    slope = np.where(g_along != 0.0, -g[:, 1 - axis] / np.where(g_along != 0.0, g_along, 1.0), 0.0)
    p = np.repeat(at[:, None, :], STRIP, axis=1)
    p[:, :, 1 - axis] += across[None, :]
    p[:, :, axis] += slope[:, None] * across[None, :]
    col = np.clip(np.floor(p[:, :, 0]).astype(np.int64), 0, cam.width - 1)
    row = cam.height - 1 - np.clip(np.floor(p[:, :, 1]).astype(np.int64), 0, cam.height - 1)
    return row * cam.width + col


def glass_crossings(scene, geom, frame, device: str, through: bool = True) -> list:
    """The crossings of both sets of lines (_axis_crossings; with ``through`` only those below a dielectric's
    split or a curved mirror's bounce: crossed_surfaces), with what takes their normals' adjoint to the points
    (grad_normals.normals_to_points; None without smooth faces): what the frame alone decides of the term, kept
    for its next backward."""
    sources = shadow_sources(scene, geom) if frame.fx.shadows else None
    spots = cones(scene, geom) if frame.fx.light_model and hard_spots(scene) else None
    curved = crossed_surfaces(scene, geom, frame.fx)["curved mirror"] if through else None
    parts = [p for axis in (0, 1) for p in _axis_crossings(scene, geom, frame, sources, spots, axis, curved, device)]
    turns = normals_to_points(scene, geom, device) if frame.fx.smooth else None
    return [(p, sources, spots, turns) for p in parts]


def glass_terms(crossings: list, d: np.ndarray, n_points: int) -> list:
    """The BoundaryTerms of ``crossings`` (glass_crossings) for the image adjoint ``d`` ((pixels, 3), float64),
    summed in the crossings' order (boundary_term); the smooth faces' vertex normals' share (the n<k><i>
    speeds: a smooth glass's normals turn its rays as its vertices move) summed per vertex the same way and
    taken to the points through the normals (the crossings' normals_to_points)."""
    out = []
    for (pts, jump, speed, points, light, _), sources, _, turns in crossings:
        rows = None if sources is None else (light, len(sources.at))
        normals = {k: v for k, v in points.items() if k[0] == "n"}
        term = boundary_term(pts, jump, d, speed, {k: v for k, v in points.items() if k[0] != "n"}, n_points, rows)
        if normals and turns is not None:
            w = pts.weight * np.einsum("ij,ij->i", d[pts.pixel], jump)
            term.points = term.points + turns(add_at(n_points, list(normals.values()), w,
                                                     [speed[k] for k in normals]))
        out.append(term)
    return out


def glass_cone_lights(crossings: list, d: np.ndarray) -> dict:
    """{lights.<i>.position | direction: (3,)}: the hard spots' sums of ``crossings``' cone crossings
    (grad_spot_edges.spot_sums, in the crossings' order) for the image adjoint ``d``."""
    lights = {}
    for (pts, jump, speed, _, _, spot), _, spots, _ in crossings:
        if spots is not None and np.any(spot >= 0):
            w = pts.weight * np.einsum("ij,ij->i", d[pts.pixel], jump)
            for name, g in spot_sums(spots, np.maximum(spot, 0), w, speed["position"], speed["axis"]).items():
                lights[name] = lights[name] + g if name in lights else g
    return lights


def glass_iors(crossings: list, d: np.ndarray, slot_names: list) -> dict:
    """{materials.<name>.ior: ()}: the crossings' term in each dielectric's ior (the refractions above each
    crossing's node bend the ray that meets its edge: _speeds' ``ior``) for the image adjoint ``d``, summed in the
    crossings' order; ``slot_names``: the material slots' names (geom.material_names). The edges camera rays see
    directly, the shadows' (a shadow ray's answer is the glass's faces', whatever its ior) and the unfolded planar
    mirrors' do not move with an ior: this is all of its boundary term."""
    total = np.zeros(len(slot_names))
    for (pts, jump, speed, _, _, _), *_ in crossings:
        w = pts.weight * np.einsum("ij,ij->i", d[pts.pixel], jump)
        first = np.zeros(len(w), np.intp)
        total += [np.bincount(first, w * speed["ior"][:, k], minlength=1)[0] for k in range(len(slot_names))]
    return {f"materials.{name}.ior": np.float64(total[k]) for k, name in enumerate(slot_names)}
