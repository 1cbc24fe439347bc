"""The gradient's boundary term for the edges camera rays see (backward(edges=True); docs/gradients.md): the
silhouettes and creases of the meshes, enumerated from the eye, projected and cut at the pixels, each piece
integrated at fixed Gauss-Legendre points with the radiance traced either side (kernels/edges.py)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._warp import wp
from ..errors import ArgumentError
from ..kernels import edge_distances, empty_aov_buffers, empty_record, make_edge_sides_kernel
from ..scene import camera_basis, drawn_objects, position_ids
from .mirrors import empty_mirrors
from .params import object_names
from .zbuffer import empty_fragments

GAUSS_POINTS = 4  # per piece of an edge inside a pixel
EDGE_OFFSET_PX = 1e-3  # the two rays either side of an edge, this far from it in the image: at any depth, that
# share of a pixel's footprint; above float32's resolution of a ray's direction (about 1e-4 of a pixel at 512 wide)
COPLANAR = 1e-6  # |n1 x n2| of two flat faces' unit normals below which their shared edge shows no crease


@dataclass(frozen=True)
class EdgeFrame:
    """What the edges' rays need of the frame: its effect set, ray stack and ray levels (FramePlan's)."""

    fx: object
    stack: int
    max_depth: int


def moves_edges(name: str) -> bool:
    """Whether a parameter moves an edge of the image: the objects' vertices (their poses too) and the camera move the edges
    camera rays see; a light's position, direction or centre moves its shadows, a spot's hard cone, a shape
    light's own outline; a dielectric's ior what is seen through it."""
    parts = name.split(".")
    return (parts[0] == "camera" or (parts[0] == "objects" and parts[-1] in ("vertices", "translation", "rotation"))
            or (parts[0] == "lights" and parts[-1] in ("position", "direction", "center"))
            or (parts[0] == "materials" and parts[-1] == "ior"))


def edge_refusal(scene, geom, fx, hits, wrt) -> str | None:
    """Why backward(edges=True) would leave out an edge that the parameters ``wrt`` move (None: the camera
    rays' edges are all of them): shadows, mirror or glass rays, a checker's squares, a spot's hard cone, an
    area light's outline."""
    moving = [n for n in wrt if moves_edges(n)]
    if not moving:
        return None
    if fx.shadows:
        return (f"{moving[0]} moves shadows' edges, not differentiated yet: only the edges camera rays see "
                f"(render.shadows off)")
    if scene.render.max_depth > 1 and (fx.reflection or fx.refraction or hits.mirrored):
        return (f"{moving[0]} moves the edges seen in mirrors or through glass, not differentiated yet: only the "
                f"edges camera rays see (render.max_depth 1)")
    for m in geom.slot_materials(scene):
        if any(getattr(m, k) is not None and getattr(m, k).checker is not None for k in
               ("ka_texture", "kd_texture", "ks_texture")):
            return f"{moving[0]} moves a checker texture's squares' edges, not differentiated yet"
    for light in scene.whitted_lights:
        if light.type == "spot" and light.beam >= light.cutoff_angle:
            return f"{moving[0]} moves a spot light's hard cone edge, not differentiated yet"
    lit = [n for n in moving if n.startswith("lights.") and n.endswith(".center")]
    if lit:
        return f"{lit[0]} moves the area light's own outline, not differentiated yet"
    return None


def _facing(p: np.ndarray, faces: np.ndarray, eye: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per face its unit normal (by its winding; 0 where degenerate) and whether it faces the eye."""
    tri = p[faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
    return n, np.einsum("ij,ij->i", n, tri[:, 0] - eye) < 0.0


def _same(a: np.ndarray, i: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Whether a per-vertex attribute is equal at vertices i and k (rows)."""
    return np.all(a[i] == a[k], axis=-1)


def camera_edges(scene, geom, fx, eye) -> np.ndarray:
    """(E, 2) vertex indices of the edges whose image can jump, sorted by (object, position): of each mesh's
    edges, welded by vertex position per object as the vertex normals are (scene.position_ids), those that
    are open (one face), silhouettes from ``eye`` (two faces facing opposite ways from it), shared by more
    than two faces, or creases where the shading jumps (two faces of other materials, a flat pair not coplanar,
    a smooth pair whose normals, uvs or colours differ at the edge); each by its face facing the eye (the
    edge the visible side shows), else its first."""
    objects = drawn_objects(scene)
    if geom.triangle_count == 0:
        return np.zeros((0, 2), np.int64)
    p = geom.points_np.astype(np.float64)
    faces = geom.indices_np.reshape(-1, 3).astype(np.int64)
    pos, base, unique = [], 0, 0
    for obj in objects:  # one id per position and object
        ids = position_ids(obj.vertices) if len(obj.vertices) else np.zeros(0, np.int64)
        pos.append(ids + unique)
        unique += int(ids.max()) + 1 if len(ids) else 0
    pos = np.concatenate(pos)
    normal, front = _facing(p, faces, np.asarray(eye, np.float64))
    ev = faces[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2)
    ef = np.repeat(np.arange(len(faces)), 3)
    lo, hi = np.minimum(pos[ev[:, 0]], pos[ev[:, 1]]), np.maximum(pos[ev[:, 0]], pos[ev[:, 1]])
    order = np.lexsort((ef, hi, lo))
    lo, hi, ev, ef = lo[order], hi[order], ev[order], ef[order]
    start = np.flatnonzero(np.r_[True, (lo[1:] != lo[:-1]) | (hi[1:] != hi[:-1])])
    count = np.diff(np.r_[start, len(lo)])
    keep = (count != 2) & (lo[start] != hi[start])
    i, k = start, np.minimum(start + 1, len(lo) - 1)  # a pair's two faces
    f1, f2 = ef[i], ef[k]
    # face 2's copies of face 1's two vertices, matched by position
    a2 = np.where(pos[ev[k, 0]] == pos[ev[i, 0]], ev[k, 0], ev[k, 1])
    b2 = np.where(pos[ev[k, 0]] == pos[ev[i, 0]], ev[k, 1], ev[k, 0])
    jump = (front[f1] != front[f2]) | (geom.tri_material_np[f1] != geom.tri_material_np[f2])
    smooth = (geom.tri_smooth_np[f1] != 0) & (geom.tri_smooth_np[f2] != 0)
    flat = (geom.tri_smooth_np[f1] == 0) & (geom.tri_smooth_np[f2] == 0)
    crease = np.linalg.norm(np.cross(normal[f1], normal[f2]), axis=1) > COPLANAR
    normals = geom.normals.numpy()
    smooth_jump = ~(_same(normals, ev[i, 0], a2) & _same(normals, ev[i, 1], b2))
    jump |= ~(smooth | flat) | (flat & crease) | (smooth & smooth_jump)
    for table in ([geom.uv_array().numpy()] if fx.texture else []) + ([geom.colors.numpy()] if fx.vertex_color else []):
        jump |= ~(_same(table, ev[i, 0], a2) & _same(table, ev[i, 1], b2))
    keep |= (count == 2) & jump & (lo[start] != hi[start])
    use_second = (count == 2) & ~front[f1] & front[f2]
    edges = np.where(use_second[:, None], np.stack([a2, b2], 1), ev[i])
    return edges[keep]


@dataclass
class EdgePoints:
    """The Gauss-Legendre points of the edges' pieces inside pixels, in the edges' order (camera_edges) and
    along each edge: per point its edge (a row of ``edges``), where it lies in the image (pixels from the
    lower-left corner), its weight (the Gauss weight times the piece's length, in pixels) and its pixel (row
    major, row 0 at the top); per edge the unit normal of its image, towards the side where g > 0."""

    edges: np.ndarray
    edge: np.ndarray
    at: np.ndarray
    weight: np.ndarray
    pixel: np.ndarray
    normal: np.ndarray


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


def _segments(edges: np.ndarray, points: np.ndarray, eye: np.ndarray, b) -> tuple:
    """Per edge its image's unit normal (towards g > 0), and for the edges in view their rows, their images'
    end points (a, c: the parts in front of the eye, projected) and the span (t0, t1) of a + t (c - a) in the
    frame."""
    q0, q1 = points[edges[:, 0]] - eye, points[edges[:, 1]] - eye
    n = np.cross(q0, q1)
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


def edge_points(edges: np.ndarray, points: np.ndarray, eye: np.ndarray, cam) -> EdgePoints:
    """The EdgePoints of ``edges`` (vertex indices into ``points``, relative to the frame origin, as ``eye``):
    each edge's image cut where it crosses the pixels' borders and the images of the other edges in those
    pixels, GAUSS_POINTS a piece."""
    b = camera_basis(cam)
    gauss, gauss_w = np.polynomial.legendre.leggauss(GAUSS_POINTS)
    normal, rows, ends, spans = _segments(edges, points, eye, b)
    cuts = [_pieces(a, c, *span) for (a, c), span in zip(ends, spans)]
    by_pixel: dict = {}  # the edges in view whose image passes through each pixel, in their order
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


def _directions(at: np.ndarray, b) -> np.ndarray:
    """Unit camera-ray directions (float32) through image points (pixels from the lower-left corner)."""
    d = (-b.d_f * b.z_e[None] + b.h * (at[:, 1:2] / b.height - 0.5) * b.y_e[None]
         + b.w * (at[:, 0:1] / b.width - 0.5) * b.x_e[None])
    return (d / np.linalg.norm(d, axis=1, keepdims=True)).astype(np.float32)


def edge_sides(scene, geom, frame: EdgeFrame, pts: EdgePoints, device: str) -> np.ndarray:
    """(N, 3) float64: per point f_+ - f_-, the colours of camera rays EDGE_OFFSET_PX either side of the edge
    (towards its normal, then away), traced with the frame's walk (kernels.edges.make_edge_sides_kernel)."""
    b = camera_basis(scene.camera)
    offset = EDGE_OFFSET_PX * pts.normal[pts.edge]
    dirs = np.concatenate([_directions(pts.at + offset, b), _directions(pts.at - offset, b)])
    n = len(pts.edge)
    color = wp.zeros(2 * n, dtype=wp.vec3, device=device)
    kernel = make_edge_sides_kernel(frame.fx, frame.stack)
    wp.launch(kernel, dim=2 * n, inputs=[geom.scene_data(scene), wp.vec3(*geom.eye_offset(scene.camera.eye)),
                                         frame.max_depth, empty_fragments(device), empty_mirrors(device),
                                         empty_aov_buffers(device), empty_record(device),
                                         wp.array(dirs, dtype=wp.vec3, device=device)], outputs=[color], device=device)
    c = color.numpy().astype(np.float64)
    return c[:n] - c[n:]


def edge_speeds(scene, geom, pts: EdgePoints, device: str) -> dict:
    """Per point, the derivative of its signed distance from its edge (kernels.edges.edge_distances, on a
    wp.Tape; float64 rows): the edge's speed along its normal, in pixels per unit of each parameter, ``v0`` and
    ``v1`` for its two vertices, ``eye``, ``center``, ``up`` and ``fovy`` for the camera. Each point reads
    copies of its own, so that no two adjoints share a sum: the host reduces them in a fixed order."""
    cam, n = scene.camera, len(pts.edge)
    p = geom.points_np
    vec = lambda rows: wp.array(np.asarray(rows, np.float32).reshape(-1, 3), dtype=wp.vec3, device=device,  # noqa: E731
                                requires_grad=True)
    v0, v1 = vec(p[pts.edges[pts.edge, 0]]), vec(p[pts.edges[pts.edge, 1]])
    camera = vec(np.tile(np.stack([geom.eye_offset(cam.eye), geom.eye_offset(cam.center),
                                   np.asarray(cam.up, np.float32)]), (n, 1)))
    fovy = wp.array(np.full(n, cam.fovy, np.float32), dtype=float, device=device, requires_grad=True)
    distance = wp.zeros(n, dtype=float, device=device, requires_grad=True)
    tape = wp.Tape()
    with tape:
        wp.launch(edge_distances, dim=n, inputs=[v0, v1, camera, fovy, float(cam.near), cam.width, cam.height,
                                                 wp.array(pts.at.astype(np.float32), dtype=wp.vec2, device=device)],
                  outputs=[distance], device=device)
    tape.backward(grads={distance: wp.array(np.ones(n, np.float32), dtype=float, device=device)})
    rows = camera.grad.numpy().astype(np.float64).reshape(n, 3, 3)
    out = {"v0": v0.grad.numpy().astype(np.float64), "v1": v1.grad.numpy().astype(np.float64), "eye": rows[:, 0],
           "center": rows[:, 1], "up": rows[:, 2], "fovy": fovy.grad.numpy().astype(np.float64)}
    tape.zero()
    return out


def edge_gradients(scene, geom, frame: EdgeFrame, d: np.ndarray, wrt, device: str) -> dict:
    """The boundary term of d(sum(d * image)) / d(param) for each name in ``wrt`` the camera rays' edges move
    (objects' vertices, the camera), float64, shaped as the parameter: per edge point, d at its pixel dotted with
    f_+ - f_- (edge_sides), times its weight and its edge's speed (edge_speeds), summed in the points' order
    (np.add.at: in order, one at a time), so the sum is the same on every run and thread count."""
    wrt = [n for n in wrt if n.startswith("camera.") or (n.startswith("objects.") and n.endswith(".vertices"))]
    if not wrt:
        return {}
    eye = geom.eye_offset(scene.camera.eye).astype(np.float64)
    edges = camera_edges(scene, geom, frame.fx, eye)
    pts = edge_points(edges, geom.points_np.astype(np.float64), eye, scene.camera)
    if len(pts.edge) == 0:
        return {name: np.zeros_like(np.asarray(_value(scene, name), np.float64)) for name in wrt}
    jump = edge_sides(scene, geom, frame, pts, device)
    w = pts.weight * np.einsum("ij,ij->i", d.reshape(-1, 3).astype(np.float64)[pts.pixel], jump)
    speed = edge_speeds(scene, geom, pts, device)
    points = np.zeros((len(geom.points_np), 3))
    np.add.at(points, pts.edges[pts.edge, 0], w[:, None] * speed["v0"])
    np.add.at(points, pts.edges[pts.edge, 1], w[:, None] * speed["v1"])
    starts = np.cumsum([0] + [len(o.vertices) for o in scene.objects])
    out = {}
    for name in wrt:
        section, owner = name.split(".")[:2]
        if section == "camera":
            out[name] = np.add.reduce(w[:, None] * speed[owner].reshape(len(w), -1), axis=0).reshape(
                np.shape(_value(scene, name)))
        else:
            i = object_names(scene)[owner]
            out[name] = points[starts[i]:starts[i + 1]]
    return out


def _value(scene, name: str):
    """A camera or vertex parameter's value, for its shape."""
    section, owner = name.split(".")[:2]
    if section == "camera":
        return getattr(scene.camera, owner)
    return scene.objects[object_names(scene)[owner]].vertices


def check_edges(scene, geom, frame: EdgeFrame | None, hits, wrt):
    """backward(edges=True)'s refusal (edge_refusal) as one ArgumentError naming ``edges``."""
    if frame is None:
        raise ArgumentError("backward", "edges", "no frame's plan was kept: render(grad=True) first")
    why = edge_refusal(scene, geom, frame.fx, hits, wrt)
    if why is not None:
        raise ArgumentError("backward", "edges", why)
