"""A shape light's own parameters in the gradient (lights.<i>.center, normal, size, radius, u, v: a rectangle's,
disk's or sphere's, as its light has them): the tables kernels/area_shape.py moves its sample points and its drawn
triangles' vertices with (ShapeTable), the replay's moving samples (moving_samples), and the edges' term of
those points taken back to the parameters (shape_edge_gradients)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._warp import wp
from ..kernels import ShapeLights, shape_points, shape_samples
from ..scene import SHAPE_KINDS, local_coordinates

SHAPE_KEYS = ("center", "normal", "size", "radius", "u", "v")


def shape_keys(light) -> tuple:
    """The shape parameters an area light has, in SHAPE_KEYS' order: a rectangle's center and normal and size, or
    its center and half-edges u and v; a disk's center, normal and radius; a sphere's center and radius; none
    for an object light (its triangles are an object's) or a shape light without a center."""
    if not light.area or light.shape is None or light.center is None:
        return ()
    if light.shape == "rectangle":
        return ("center", "u", "v") if light.u is not None else ("center", "normal", "size")
    return ("center", "normal", "radius") if light.shape == "disk" else ("center", "radius")


@dataclass
class ShapeTable:
    """The shape lights (those with shape_keys) as the kernels read them: ``lights`` their parameters,
    differentiable, ``frame`` the same values without adjoints (what the forward drew); ``rows`` each one's
    index among scene.area_lights, ``names`` its lights.<i> prefix."""

    lights: ShapeLights
    frame: ShapeLights
    rows: list
    names: list


def shape_table(scene, geom, device: str) -> ShapeTable:
    """The ShapeTable of a frame of ``scene`` on ``geom`` (centers relative to its origin)."""
    index = {id(light): i for i, light in enumerate(scene.lights)}
    rows = [e for e, light in enumerate(scene.area_lights) if shape_keys(light)]
    lights = [scene.area_lights[e] for e in rows]

    def table(grad: bool) -> ShapeLights:
        vec = lambda values: wp.array(np.asarray(values, np.float32).reshape(-1, 3), dtype=wp.vec3,  # noqa: E731
                                      device=device, requires_grad=grad)
        t = ShapeLights()
        t.kind = wp.array([SHAPE_KINDS[l.shape] for l in lights] or [0], dtype=int, device=device)
        t.by_edges = wp.array([int(l.u is not None) for l in lights] or [0], dtype=int, device=device)
        t.center = vec([np.asarray(l.center, np.float64) - geom.origin for l in lights] or [[0, 0, 0]])
        t.normal = vec([l.normal if l.normal is not None else (0, 0, 1) for l in lights] or [[0, 0, 1]])
        t.size = wp.array(np.asarray([l.size if l.size is not None else (0, 0) for l in lights] or [[0, 0]],
                                     np.float32), dtype=wp.vec2, device=device, requires_grad=grad)
        t.radius = wp.array(np.asarray([l.radius or 0.0 for l in lights] or [0.0], np.float32), dtype=float,
                            device=device, requires_grad=grad)
        t.u, t.v = (vec([getattr(l, k) if getattr(l, k) is not None else (0, 0, 0) for l in lights] or [[0, 0, 0]])
                    for k in ("u", "v"))
        return t

    return ShapeTable(table(True), table(False), rows, [f"lights.{index[id(l)]}" for l in lights])


def _ints(values, device: str) -> wp.array:
    return wp.array(np.asarray(values, np.int32).reshape(-1) if len(values) else np.full(1, -1, np.int32),
                    dtype=int, device=device)


def _vec3(values, device: str) -> wp.array:
    return wp.array(np.asarray(values, np.float32).reshape(-1, 3) if len(values) else np.zeros((1, 3), np.float32),
                    dtype=wp.vec3, device=device)


def sample_places(scene, table: ShapeTable, k: int, device: str) -> tuple:
    """(light, local, count): per sample point of the area lights (the AreaLights table's order) its shape
    light's row (-1: an object light's) and its place in that light's frame; per row its points' count."""
    light, local = [], []
    for e, l in enumerate(scene.area_lights):
        row = table.rows.index(e) if e in table.rows else -1
        light += [row] * (k * k)
        local.append(local_coordinates(l, k)[0] if row >= 0 else np.zeros((k * k, 3)))
    count = wp.array(np.full(max(len(table.rows), 1), k * k, np.float32), dtype=float, device=device)
    return _ints(light, device), _vec3(np.concatenate(local), device), count


def moving_samples(scene, area, table: ShapeTable, k: int, device: str) -> tuple:
    """(points, normals, dA, launch): the area lights' sample points, normals and areas (``area``, the frame's
    AreaLights) moving with their shape lights (kernels.shape_samples), and the launch that makes them."""
    light, local, count = sample_places(scene, table, k, device)
    n = int(area.points.shape[0])
    points, normals = (wp.zeros(n, dtype=wp.vec3, device=device, requires_grad=True) for _ in range(2))
    dA = wp.zeros(n, dtype=float, device=device, requires_grad=True)
    launch = (shape_samples, n, [table.lights, table.frame, light, local, count, area.points, area.normals, area.dA],
              [points, normals, dA])
    return points, normals, dA, launch


def shape_vertex_places(scene, geom, table: ShapeTable) -> tuple[np.ndarray, np.ndarray, int]:
    """(light, local, first): per vertex of the shape lights' drawn triangles (drawn_objects after the scene's
    objects, in the geometry's points from ``first``) its shape light's row and its place in that light's frame."""
    first = sum(len(o.vertices) for o in scene.objects)
    light, local = [], []
    for e, l in enumerate(scene.area_lights):
        if l.shape is None:
            continue
        vertices = local_coordinates(l, 1)[1]
        light += [table.rows.index(e) if e in table.rows else -1] * len(vertices)
        local.append(vertices)
    return np.asarray(light, np.int32), np.concatenate(local) if local else np.zeros((0, 3)), first


def shape_edge_gradients(scene, geom, table: ShapeTable, d_samples: np.ndarray | None, d_vertices: np.ndarray,
                         k: int, device: str) -> dict:
    """{lights.<i>.<key>: gradient} of the edges' term of the shape lights' points taken back to their
    parameters (kernels.shape_points on a wp.Tape, its adjoint the points' term): ``d_samples`` per area-light
    sample point (its shadows' edges; None: none), ``d_vertices`` per point of the geometry (the lights' own
    outlines are their drawn vertices')."""
    light, local, first = shape_vertex_places(scene, geom, table)
    s_light, s_local, _ = sample_places(scene, table, k, device)
    n_s = int(s_light.shape[0])
    forward = np.concatenate([np.zeros((n_s, 3)), geom.points_np[first:first + len(light)]])
    adjoint = np.concatenate([np.zeros((n_s, 3)) if d_samples is None else d_samples,
                              d_vertices[first:first + len(light)]]).astype(np.float32)
    places = _vec3(np.concatenate([s_local.numpy()[:n_s], local]), device)
    owner = _ints(np.concatenate([s_light.numpy()[:n_s], light]), device)
    points = wp.zeros(len(adjoint), dtype=wp.vec3, device=device, requires_grad=True)
    tape = wp.Tape()
    with tape:
        wp.launch(shape_points, dim=len(adjoint), inputs=[table.lights, table.frame, owner, places,
                                                          _vec3(forward, device)], outputs=[points], device=device)
    tape.backward(grads={points: wp.array(adjoint, dtype=wp.vec3, device=device)})
    out = gradients_of(scene, table)
    tape.zero()
    return out


def gradients_of(scene, table: ShapeTable) -> dict:
    """{lights.<i>.<key>: gradient} read from the adjoints of ``table.lights`` (float64, shaped as the
    parameter), for each shape light and each of its shape_keys."""
    out = {}
    for row, (e, prefix) in enumerate(zip(table.rows, table.names)):
        for key in shape_keys(scene.area_lights[e]):
            g = getattr(table.lights, key).grad.numpy()[row]
            out[f"{prefix}.{key}"] = np.asarray(g, np.float64).reshape(np.shape(getattr(scene.area_lights[e], key)))
    return out
