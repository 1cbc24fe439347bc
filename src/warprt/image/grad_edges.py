"""The gradient's boundary term (backward(edges=True); docs/gradients.md): the edges camera rays see (the
meshes' silhouettes and creases; with shadows, where a smooth mesh's shading is cut by its own shadow), with
shadows the hard shadows' edges (grad_shadow_edges.py), a checker's squares (grad_checker_edges.py) and a
spot's hard cone (grad_spot_edges.py), all cut at the pixels together (grad_edge_points.py),
each piece integrated at fixed Gauss-Legendre points with the radiance traced either side (kernels/edges.py)."""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import partial

import numpy as np

from .._warp import wp
from ..errors import ArgumentError
from ..kernels import edge_distances
from ..scene import drawn_objects
from .grad_area_shape import SHAPE_KEYS, shape_edge_gradients, shape_table
from .grad_checker_edges import CheckerSegments, checker_segments, checker_speeds, checker_term, has_checker
from .grad_edge_launch import host_array, launch_points
from .grad_edge_points import (EDGE_OFFSET_PX, BoundaryTerm, EdgePoints, add_terms, boundary_term, camera_adjoints, camera_copies,
                               segment_points)
from .grad_glass_edges import (crossed_surfaces, crossing_refusal, glass_cone_lights, glass_crossings, glass_iors,
                               glass_terms, traced_colours)
from .grad_mesh_edges import MeshEdges, camera_edges, face_normals, facing, mesh_edges, rims
from .grad_mirror_edges import (BLOCKS, MirroredSegments, frame_mirrors, mirror_terms, mirrored_segments,
                                on_mirrored_cones)
from .grad_shadow_edges import ShadowSources, receivers, shadow_segments, shadow_sources, shadow_term
from .grad_spot_edges import Cones, SpotSegments, cones, hard_spots, on_cones, spot_segments, spot_term
from .mirrors import empty_mirrors
from .params import object_names


@dataclass(frozen=True)
class EdgeFrame:
    """What the edges' rays need of the frame: its effect set, ray stack and ray levels (FramePlan's), the
    CPU threads its per-point launches run on (grad_edge_launch.launch_points), what its backward calls
    keep for the next (``kept``: kept_part's), and whether the crossings' tree signatures hold the hard cones
    (``cone_bits``), the checker squares (``square_bits``) and the area lights' blocked sample points
    (``hidden_bits``; each False only as a check's control: grad_glass_edges.tree_walk)."""

    fx: object
    stack: int
    max_depth: int
    threads: int = 1
    cone_bits: bool = True
    square_bits: bool = True
    hidden_bits: bool = True
    kept: dict = field(default_factory=dict, compare=False, repr=False)


def kept_part(frame: EdgeFrame, scene, geom, name: str, make):
    """``make()``, kept in ``frame`` for its next backward(edges=True): a part of the boundary term that is the
    frame's alone (its segments and points, the colours either side of them, their speeds), not the image
    adjoint's or the parameters named; made again for another scene or geometry than the one kept (backward
    refuses a scene changed since its frame anyway)."""
    of = frame.kept.get("of")
    if of is None or of[0] is not scene or of[1] is not geom:
        frame.kept.clear()
        frame.kept["of"] = (scene, geom)
    if name not in frame.kept:
        frame.kept[name] = make()
    return frame.kept[name]


def moves_edges(name: str) -> bool:
    """Whether a parameter moves an edge of the image: the objects' vertices (their poses too) and the camera move the edges
    camera rays see; a light's position or direction, or a shape light's own shape (its center, normal, size,
    radius), moves its shadows, a spot's hard cone, a shape light's own outline; a dielectric's ior what is seen
    through it."""
    parts = name.split(".")
    return (parts[0] == "camera" or (parts[0] == "objects" and parts[-1] in ("vertices", "translation", "rotation"))
            or (parts[0] == "lights" and parts[-1] in ("position", "direction") + SHAPE_KEYS)
            or (parts[0] == "materials" and parts[-1] == "ior"))


def edge_refusal(scene, geom, fx, wrt, mirrors=None, crossed=None) -> str | None:
    """Why backward(edges=True) would leave out an edge that the parameters ``wrt`` move (None: the camera
    rays' edges, the hard shadows', a checker's squares', a spot's hard cone, and those seen in mirrors and
    through glass are all of them): glass's and curved mirrors' that the crossings do not cover
    (grad_glass_edges.crossing_refusal; a checker's squares seen through them they do), too many planar mirrors'
    (frame_mirrors, or ``mirrors()``: its answer kept; ``crossed()`` crossed_surfaces' kept). (A reflectivity of 0
    whose mirror rays a frame records for its derivative reflects nothing: no edge is seen in it.)"""
    moving = [n for n in wrt if moves_edges(n)]
    if not moving:
        return None
    why = crossing_refusal(scene, (crossed or partial(crossed_surfaces, scene, geom, fx))())
    if why is not None:
        return f"{moving[0]} moves {why}, not differentiated yet"
    reflects = scene.render.max_depth > 1 and fx.reflection
    chains, why = (mirrors or partial(frame_mirrors, scene, geom))()[2:] if reflects else ((), None)
    if why is not None:
        return f"{moving[0]} moves the edges seen in {why}, not differentiated yet"
    return None


def edge_sides(scene, geom, frame: EdgeFrame, pts: EdgePoints, device: str) -> np.ndarray:
    """(N, 3) float64: per point f_+ - f_-, the colours of camera rays EDGE_OFFSET_PX either side of the edge
    (towards its normal, then away), traced with the frame's walk (grad_glass_edges.traced_colours)."""
    offset = EDGE_OFFSET_PX * pts.normal[pts.edge]
    c = traced_colours(scene, geom, frame, np.concatenate([pts.at + offset, pts.at - offset]), device)
    n = len(pts.edge)
    return c[:n] - c[n:]


def edge_speeds(scene, geom, pts: EdgePoints, device: str, threads: int = 1) -> dict:
    """Per point, the derivative of its signed distance from its edge (kernels.edges.edge_distances, its
    adjoint; float64 rows): the edge's speed along its normal, in pixels per unit of each parameter, ``v0`` and
    ``v1`` for its two vertices, ``eye``, ``center``, ``up`` and ``fovy`` for the camera. Each point reads
    copies of its own, so that no two adjoints share a sum: the host reduces them in a fixed order (the adjoint
    launch alone, in bands on ``threads``: grad_edge_launch.launch_points)."""
    cam, n = scene.camera, len(pts.edge)
    p = geom.points_np
    vec = lambda rows: host_array(np.asarray(rows, np.float32).reshape(-1, 3), wp.vec3, device, True)  # noqa: E731
    v0, v1 = vec(p[pts.edges[pts.edge, 0]]), vec(p[pts.edges[pts.edge, 1]])
    camera, fovy = camera_copies(scene, geom, n, device)
    distance = wp.zeros(n, dtype=float, device=device)
    at = host_array(pts.at.astype(np.float32), wp.vec2, device)
    launch_points(edge_distances, n, [v0, v1, camera, fovy, float(cam.near), cam.width, cam.height, at, distance],
                  [1, 1, 3, 1, 0, 0, 0, 1, 1], threads, device,
                  [v0.grad, v1.grad, camera.grad, fovy.grad, None, None, None, None,
                   host_array(np.ones(n, np.float32), float, device)])
    return {"v0": v0.grad.numpy().astype(np.float64), "v1": v1.grad.numpy().astype(np.float64),
            **camera_adjoints(camera, fovy, n)}


def covered(name: str) -> bool:
    """Whether edge_gradients gives ``name`` a term: the camera, objects' vertices (their poses through them:
    grad.pose_edge_gradients), a Whitted light's position or direction, a shape light's own shape (its sample
    points' and outline's term taken back to it: grad_area_shape.shape_edge_gradients), a dielectric's ior (the
    crossings' alone: grad_glass_edges.glass_iors)."""
    parts = name.split(".")
    return (parts[0] == "camera" or (parts[0] == "objects" and parts[-1] == "vertices")
            or (parts[0] == "lights" and parts[-1] in ("position", "direction") + SHAPE_KEYS)
            or (parts[0] == "materials" and parts[-1] == "ior"))


@dataclass
class Boundary:
    """A frame's boundary segments, cut at the pixels together (grad_edge_points.segment_points): the
    camera's edges (``edges``, their points ``camera``), with shadows the shadows' (``segments`` from
    ``sources``, their points ``shadows``), with mirror rays those seen in planar mirrors (``mirrored``,
    their points within), with a checker its lines (``checkers``, their points ``checker``) and with a hard spot
    its cone's chords (``spots`` of ``cones``, their points ``spot``, moved onto the curves)."""

    edges: np.ndarray
    camera: EdgePoints
    sources: ShadowSources | None = None
    segments: object = None
    shadows: EdgePoints | None = None
    mirrored: MirroredSegments | None = None
    checkers: CheckerSegments | None = None
    checker: EdgePoints | None = None
    cones: Cones | None = None
    spots: SpotSegments | None = None
    spot: EdgePoints | None = None


def boundary(scene, geom, fx, eye: np.ndarray, mirrors=None, crossed=None) -> Boundary:
    """The Boundary of a frame seen from ``eye`` (relative to the frame origin): with shadows (fx.shadows),
    the sources (shadow_sources), the camera's edges and the shadows' (shadow_segments), with mirror rays
    (fx.reflection, render.max_depth > 1) those seen through each chain of planar mirrors (mirrored_segments),
    with a checker its lines (checker_segments), with a hard spot its cone's chords (spot_segments, on_cones),
    each one's image cut where it crosses the others'. ``mirrors()``: the frame's frame_mirrors, kept (else
    made here; ``eye`` is then the frame's own); ``crossed()`` its crossed_surfaces, kept (else made here: a
    curved mirror's rims get FINE_POINTS, grad_mesh_edges.rims)."""
    m = mesh_edges(scene, geom) if geom.triangle_count else None
    sources = shadow_sources(scene, geom) if fx.shadows and m is not None else None
    edges, rows, front = camera_edges(scene, geom, fx, eye, sources, m, rows=True)
    fine = [rims(geom, m, rows, front, (crossed or partial(crossed_surfaces, scene, geom, fx))()["curved mirror"])]
    p = geom.points_np.astype(np.float64)
    q0, q1 = p[edges[:, 0]] - eye, p[edges[:, 1]] - eye
    blocks, segments, mirrored = [(q0, q1, np.cross(q0, q1))], None, None
    if sources is not None:
        segments = shadow_segments(scene, geom, m, sources, eye)
        blocks.append((segments.q0 - eye, segments.q1 - eye, segments.plane))
    checkers = checker_segments(scene, geom, m, edges, eye) if m is not None and has_checker(scene, geom) else None
    if checkers is not None:
        blocks.append((checkers.q0 - eye, checkers.q1 - eye, checkers.plane))
    spots = None
    if m is not None and fx.light_model and hard_spots(scene):
        spots = (c := cones(scene, geom), spot_segments(scene, geom, receivers(scene, geom, eye), c))
        blocks.append((spots[1].q0 - eye, spots[1].q1 - eye, spots[1].plane))
    if m is not None and fx.reflection and scene.render.max_depth > 1:
        group, planes, chains, _ = (mirrors or partial(frame_mirrors, scene, geom))()
        if chains:
            mirrored = mirrored_segments(scene, geom, fx, m, sources, eye, group, chains, checkers is not None,
                                         spots[0] if spots is not None else None)
            blocks += mirrored.blocks(eye)
    start = np.cumsum([0] + [len(q) for q, _, _ in blocks])
    family = np.full(start[-1], -1, np.int64)  # the shadows' by source (and chain): not cut by each other's
    if segments is not None:
        family[start[1]:start[2]] = segments.source
    if mirrored is not None and sources is not None:
        at = len(blocks) - len(BLOCKS) + BLOCKS.index("shadows")
        family[start[at]:start[at + 1]] = len(sources.at) * (1 + mirrored.shadow_chain) + mirrored.shadows.source
    fine = np.concatenate(fine + [np.zeros(start[-1] - start[1], bool)])
    pts = segment_points(*(np.concatenate([block[k] for block in blocks]) for k in range(3)), scene.camera,
                         family=family, fine=fine)
    part = lambda i, what=None: pts.part(start[i], start[i + 1], what)  # noqa: E731
    if mirrored is not None:  # its blocks the last (BLOCKS)
        mirrored.take([part(i) for i in range(len(blocks) - len(BLOCKS), len(blocks))])
        if mirrored.spot_points is not None:
            mirrored.spot_points = on_mirrored_cones(scene, geom, mirrored, mirrored.spot_points)
    out = Boundary(edges, part(0, edges), sources, segments, part(1) if segments is not None else None, mirrored)
    at = 1 + (segments is not None)
    if checkers is not None:
        out.checkers, out.checker, at = checkers, part(at), at + 1
    if spots is not None:
        out.cones, out.spots = spots
        out.spot = on_cones(scene, geom, *spots, part(at), eye)
    return out


def edge_gradients(scene, geom, frame: EdgeFrame, d: np.ndarray, wrt, device: str) -> dict:
    """The boundary term of d(sum(d * image)) / d(param) for each name in ``wrt`` the frame's edges move
    (covered: objects' vertices, the camera, lights' positions, directions and centres, dielectrics' iors),
    float64, shaped as the parameter: per edge point, d at its pixel dotted with f_+ - f_- (edge_sides; a
    shadow's: its source's light alone, grad_shadow_edges.light_sides), times its weight and its edge's speed
    (edge_speeds, shadow_speeds), summed in the points' order (np.add.at: in order, one at a time), so the sum
    is the same on every run and thread count. What is the frame's alone is kept in it for its next backward
    (kept_part)."""
    wrt = [n for n in wrt if covered(n)]
    if not wrt:
        return {}
    eye = geom.eye_offset(scene.camera.eye).astype(np.float64)
    keep = partial(kept_part, frame, scene, geom)
    mirrors = partial(keep, "mirrors", partial(frame_mirrors, scene, geom))  # check_edges' too
    crossed = partial(keep, "crossed", partial(crossed_surfaces, scene, geom, frame.fx))
    b = keep("boundary", lambda: boundary(scene, geom, frame.fx, eye, mirrors, crossed))
    d3 = d.reshape(-1, 3).astype(np.float64)
    terms = []
    if len(b.camera.edge):
        terms.append(boundary_term(b.camera, keep("sides", lambda: edge_sides(scene, geom, frame, b.camera, device)),
                                   d3, keep("speeds", lambda: edge_speeds(scene, geom, b.camera, device, frame.threads)),
                                   {"v0": b.edges[b.camera.edge, 0], "v1": b.edges[b.camera.edge, 1]},
                                   len(geom.points_np)))
    if b.shadows is not None and len(b.shadows.edge):
        terms.append(shadow_term(scene, geom, frame.fx, b.sources, b.segments, b.shadows, d3, device, frame.threads,
                                 keep))
    if b.checker is not None and len(b.checker.edge):
        terms.append(checker_term(geom, b.checkers, b.checker,
                                  keep("checker sides", lambda: edge_sides(scene, geom, frame, b.checker, device)),
                                  keep("checker speeds", lambda: checker_speeds(scene, geom, b.checkers, b.checker,
                                                                                device, frame.threads)), d3))
    named = {}  # the hard spots' lights and the iors: sums of their own, not BoundaryTerm rows
    if b.spot is not None and len(b.spot.edge):
        term, named = spot_term(scene, geom, frame.fx, b.cones, b.spots, b.spot, d3, device, frame.threads, keep)
        terms.append(term)
    if b.mirrored is not None:
        mirrored, seen = mirror_terms(scene, geom, frame.fx, b.mirrored, b.sources,
                                      partial(edge_sides, scene, geom, frame, device=device), d3, device, keep)
        terms += mirrored
        for name, g in seen.items():
            named[name] = named[name] + g if name in named else g
    if any(on.any() for on in crossed().values()):
        crossings = keep("glass", lambda: glass_crossings(scene, geom, frame, device))
        terms += glass_terms(crossings, d3, len(geom.points_np))
        for name, g in glass_cone_lights(crossings, d3).items():
            named[name] = named[name] + g if name in named else g
        if any(n.startswith("materials.") for n in wrt):
            named.update(glass_iors(crossings, d3, geom.material_names))
    term = add_terms(terms, len(geom.points_np))
    shapes = {}
    if any(n.startswith("lights.") and n.endswith(tuple(f".{k}" for k in SHAPE_KEYS)) for n in wrt):
        samples = None if term.sources is None else term.sources[len(scene.whitted_lights):]
        shapes = shape_edge_gradients(scene, geom, shape_table(scene, geom, device), samples, term.points,
                                      int(round(np.sqrt(scene.render.light_samples))), device)
    out = {name: g for name in wrt if (g := shapes.get(name, _by_name(scene, b.sources, term, name))) is not None}
    for name in wrt:
        if name in named:
            out[name] = out[name] + named[name] if name in out else named[name]
    return out


def _by_name(scene, sources: ShadowSources | None, term: BoundaryTerm, name: str):
    """``name``'s share of ``term`` (None: the term has none): a camera parameter's sum, an object's
    vertices' rows, a light's sources' sum (a direction's projected as Light keeps it unit: (I - u u^T)). A
    shape light's own shape's is its sample points' and its own triangles' points' taken back through the
    shape (edge_gradients: grad_area_shape.shape_edge_gradients)."""
    section, owner, key = (name.split(".") + [""])[:3]
    if section == "materials":  # an ior's: the crossings' alone (edge_gradients)
        return None
    if section == "camera":
        return np.asarray(term.camera[owner], np.float64).reshape(np.shape(getattr(scene.camera, owner)))
    starts = np.cumsum([0] + [len(o.vertices) for o in drawn_objects(scene)])
    if section == "objects":
        i = object_names(scene)[owner]
        return term.points[starts[i]:starts[i + 1]]
    g = None
    if sources is not None and term.sources is not None:
        rows = [s for s, n in enumerate(sources.name) if n == name]
        g = np.add.reduce(term.sources[rows], axis=0) if rows else np.zeros(3)
    if key == "direction" and g is not None:
        unit = np.asarray(scene.lights[int(owner)].direction, np.float64)
        g = g - unit * (unit @ g)
    return g


def check_edges(scene, geom, frame: EdgeFrame | None, wrt):
    """backward(edges=True)'s refusal (edge_refusal) as one ArgumentError naming ``edges``."""
    if frame is None:
        raise ArgumentError("backward", "edges", "no frame's plan was kept: render(grad=True) first")
    keep = partial(kept_part, frame, scene, geom)
    why = edge_refusal(scene, geom, frame.fx, wrt, partial(keep, "mirrors", partial(frame_mirrors, scene, geom)),
                       partial(keep, "crossed", partial(crossed_surfaces, scene, geom, frame.fx)))
    if why is not None:
        raise ArgumentError("backward", "edges", f"{why} (edges=False: the derivative with each ray's face and "
                                                 f"each shadow ray's answer held)")
