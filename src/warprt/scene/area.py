"""Area lights as geometry: the surface a ``type = "area"`` light emits from (its own rectangle or disk,
drawn as triangles, or the triangles of the objects it names) and its fixed stratified sample points.

The points are a pure function of the light and ``light_samples`` = N = k*k: N points (a, b) of the unit
square (sample_coordinates), mapped as Mitsuba's shapes map a sample in their ``sample_position``: a
rectangle's (2a - 1, 2b - 1) on its half-edges, a disk's concentric map (Shirley and Chiu), a sphere's
(z = 1 - 2b, phi = 2 pi a), a mesh's triangle chosen by area from b and the rest of b with a on that triangle
(Mitsuba's ``square_to_uniform_triangle``). Each map preserves area, so each point stands for A / N of the
surface. A shape light takes the centres of a k x k grid of cells; a mesh the Fibonacci lattice
((n + 1/2) / phi mod 1, (n + 1/2) / N): with a grid's k rows of b, only k of a mesh's triangles were sampled,
each along one line, which lit a floor under a 1,280-triangle sphere lamp at 17% of its closed form at 16
points and 48% at 4,096 (the lattice: within 0.4% from 1,024 points).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .model import Material, SceneObject

# The material slot of a shape light's own triangles: black, so that they show only their radiance.
EMITTER_MATERIAL_NAME = "<area light>"
EMITTER_MATERIAL = Material(kd=(0.0, 0.0, 0.0), ka=(0.0, 0.0, 0.0), ks=(0.0, 0.0, 0.0))
DISK_SEGMENTS = 64  # the drawn disk's polygon (its samples lie on the true disk)
SPHERE_SUBDIVISIONS = 4  # the drawn sphere's icosphere (5,120 triangles; its samples lie on the true sphere)


def coordinate_system(n) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors s, t with (s, t, n) right-handed and orthonormal: Mitsuba's coordinate_system
    (Duff et al. 2017), so that a rectangle given by its normal and size is oriented as Mitsuba would."""
    n = np.asarray(n, np.float64)
    sign = math.copysign(1.0, n[2])
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    s = np.array([1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]])
    t = np.array([b, sign + n[1] * n[1] * a, -n[1]])
    return s, t


def frame_corners(c, u, v) -> np.ndarray:
    """(4, 3): the corners c -+ u -+ v of the parallelogram a frame spans, in order around it (u x v up)."""
    return np.array([c - u - v, c + u - v, c + u + v, c - u + v])


def rectangle_axes(light) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(center, u, v) of a rectangle light: corners at center +- u +- v, emitting along u x v."""
    c = np.asarray(light.center if light.center is not None else (0.0, 0.0, 0.0), np.float64)
    if light.u is not None:
        return c, np.asarray(light.u, np.float64), np.asarray(light.v, np.float64)
    n = np.asarray(light.normal, np.float64)
    s, t = coordinate_system(n / np.linalg.norm(n))
    return c, s * (0.5 * light.size[0]), t * (0.5 * light.size[1])


def _disk_axes(light) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    c = np.asarray(light.center if light.center is not None else (0.0, 0.0, 0.0), np.float64)
    n = np.asarray(light.normal, np.float64)
    s, t = coordinate_system(n / np.linalg.norm(n))
    return c, s, t, float(light.radius)


def shape_frame(light) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(center, u, v) of a rectangle or disk light in world space (float64): its sample (a, b) of the unit
    square lies at center + x u + y v, (x, y) = (2a - 1, 2b - 1) on a rectangle and the concentric map of
    (a, b) on a disk (u and v then the radius along its axes); it emits along u x v."""
    if light.shape == "rectangle":
        return rectangle_axes(light)
    c, s, t, r = _disk_axes(light)
    return c, s * r, t * r


def _sphere_center(light) -> np.ndarray:
    return np.asarray(light.center if light.center is not None else (0.0, 0.0, 0.0), np.float64)


def light_normal(light) -> np.ndarray:
    """The unit normal of a shape light, the side it emits to."""
    if light.shape == "rectangle":
        _, u, v = rectangle_axes(light)
        n = np.cross(u, v)
    else:
        n = np.asarray(light.normal, np.float64)
    return n / np.linalg.norm(n)


@functools.lru_cache(maxsize=64)
def shape_object(light) -> SceneObject:
    """The triangles of a shape light, wound so that their normal is the light's (the same object for an
    equal light, so that a Geometry built from it is kept across frames)."""
    if light.shape == "rectangle":
        vertices = frame_corners(*rectangle_axes(light))
        faces = np.array([[0, 1, 2], [0, 2, 3]])
    elif light.shape == "sphere":
        from .shapes import sphere

        unit, faces = sphere(1.0, SPHERE_SUBDIVISIONS)
        vertices = _sphere_center(light) + light.radius * unit
    else:
        c, s, t, r = _disk_axes(light)
        theta = 2.0 * np.pi * np.arange(DISK_SEGMENTS) / DISK_SEGMENTS
        rim = c + r * (np.cos(theta)[:, None] * s + np.sin(theta)[:, None] * t)
        vertices = np.concatenate([c[None], rim])
        i = np.arange(DISK_SEGMENTS)
        faces = np.stack([np.zeros_like(i), 1 + i, 1 + (i + 1) % DISK_SEGMENTS], axis=1)
    return SceneObject(light.name or f"area light ({light.shape})", vertices, faces, EMITTER_MATERIAL_NAME)


def drawn_objects(scene) -> list:
    """The objects the tracer draws: the scene's, then each shape light's own triangles."""
    return list(scene.objects) + [shape_object(l) for l in scene.area_lights if l.shape is not None]


def emitter_of_triangles(scene) -> np.ndarray:
    """Per triangle of drawn_objects(scene), the index of the area light it belongs to among the scene's
    area lights (their order in scene.lights), or -1."""
    area = scene.area_lights
    out = [np.full(len(o.faces), -1, np.int32) for o in scene.objects]
    for j, light in enumerate(area):
        if light.object is not None:
            for i, o in enumerate(scene.objects):
                if o.name == light.object:
                    out[i][:] = j
    out += [np.full(len(shape_object(l).faces), j, np.int32) for j, l in enumerate(area) if l.shape is not None]
    return np.concatenate(out) if out else np.zeros(0, np.int32)


GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0  # 1 / phi


def fibonacci_lattice(n: int) -> tuple[np.ndarray, np.ndarray]:
    """(a, b): n points of the unit square, a_i = (i + 1/2) / phi mod 1, b_i = (i + 1/2) / n, i < n: every
    point its own b (its own place along a mesh's area), and a spread by the golden ratio."""
    i = np.arange(n) + 0.5
    return np.mod(i * GOLDEN, 1.0), i / n


def sample_coordinates(light, k: int) -> tuple[np.ndarray, np.ndarray]:
    """(a, b): the k*k points of the unit square an area light's samples are mapped from: the cell centres of
    a k x k grid for a shape light, the Fibonacci lattice for an object light (a mesh)."""
    return cell_centres(k) if light.shape is not None else fibonacci_lattice(k * k)


def cell_centres(k: int) -> tuple[np.ndarray, np.ndarray]:
    """(a, b): the centres of a k x k grid of cells on the unit square, row by row."""
    c = (np.arange(k) + 0.5) / k
    b, a = np.meshgrid(c, c, indexing="ij")
    return a.reshape(-1), b.reshape(-1)


def concentric_disk(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Shirley and Chiu's concentric map of the unit square onto the unit disk (Mitsuba's
    square_to_uniform_disk_concentric): area-preserving, so equal cells become equal areas."""
    x, y = 2.0 * a - 1.0, 2.0 * b - 1.0
    wide = np.abs(x) > np.abs(y)
    r = np.where(wide, x, y)
    safe_x = np.where(x == 0.0, 1.0, x)
    safe_y = np.where(y == 0.0, 1.0, y)
    phi = np.where(wide, 0.25 * np.pi * y / safe_x, 0.5 * np.pi - 0.25 * np.pi * x / safe_y)
    return np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1) * ((x != 0.0) | (y != 0.0))[:, None]


def emitter_samples(scene, light, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The k*k sample points of an area light in world space (float64): (points, unit normals, the area
    each stands for), the normals on the emitting side."""
    a, b = sample_coordinates(light, k)
    count = k * k
    if light.shape == "rectangle":
        c, u, v = rectangle_axes(light)
        points = c + (2.0 * a - 1.0)[:, None] * u + (2.0 * b - 1.0)[:, None] * v
        area = 4.0 * float(np.linalg.norm(np.cross(u, v)))
        normals = np.tile(light_normal(light), (count, 1))
    elif light.shape == "disk":
        c, s, t, r = _disk_axes(light)
        d = concentric_disk(a, b) * r
        points = c + d[:, :1] * s + d[:, 1:] * t
        area = math.pi * r * r
        normals = np.tile(light_normal(light), (count, 1))
    elif light.shape == "sphere":
        # Mitsuba's sphere sample_position: square_to_uniform_sphere (z = 1 - 2b, phi = 2 pi a) about the
        # world axes, scaled by the radius; the normal points out.
        z = 1.0 - 2.0 * b
        ring = np.sqrt(np.maximum(1.0 - z * z, 0.0))
        normals = np.stack([ring * np.cos(2.0 * np.pi * a), ring * np.sin(2.0 * np.pi * a), z], axis=1)
        points = _sphere_center(light) + light.radius * normals
        area = 4.0 * math.pi * light.radius ** 2
    else:
        tri = np.concatenate([o.vertices[o.faces] for o in scene.objects if o.name == light.object])
        cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        areas = 0.5 * np.linalg.norm(cross, axis=1)
        area = float(areas.sum())
        cdf = np.cumsum(areas) / area
        # Mitsuba's mesh sample_position: b picks a triangle by area and is reused within it, then
        # square_to_uniform_triangle(a, b'): barycentrics (1 - t, t b'), t = sqrt(1 - a).
        f = np.minimum(np.searchsorted(cdf, b, side="right"), len(areas) - 1)
        lo = np.where(f > 0, cdf[f - 1], 0.0)
        b_in = np.clip((b - lo) / np.maximum(cdf[f] - lo, 1e-300), 0.0, 1.0)
        t = np.sqrt(1.0 - a)
        b1, b2 = 1.0 - t, t * b_in
        p = tri[f]
        points = p[:, 0] * (1.0 - b1 - b2)[:, None] + p[:, 1] * b1[:, None] + p[:, 2] * b2[:, None]
        normals = cross[f] / np.maximum(np.linalg.norm(cross[f], axis=1, keepdims=True), 1e-300)
    return points, normals, np.full(count, area / count)


SHAPE_KINDS = {"rectangle": 0, "disk": 1, "sphere": 2}  # a shape light's kind, as the gradient's kernels number it


def local_coordinates(light, k: int) -> tuple[np.ndarray, np.ndarray]:
    """(samples, vertices): where a shape light's k*k sample points (emitter_samples) and its drawn triangles'
    vertices (shape_object) lie in its own frame, (N, 3) float64: the world point is center + x A + y B + z C,
    (A, B) a rectangle's half-edges or a disk's axes times its radius (shape_frame) and z = 0, a sphere's axes
    times its radius (the world's). What moves with the light's center, size, normal and radius is the frame,
    not these."""
    a, b = sample_coordinates(light, k)
    if light.shape == "rectangle":
        samples = np.stack([2.0 * a - 1.0, 2.0 * b - 1.0, np.zeros_like(a)], axis=1)
        vertices = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]])
    elif light.shape == "disk":
        samples = np.concatenate([concentric_disk(a, b), np.zeros((len(a), 1))], axis=1)
        theta = 2.0 * np.pi * np.arange(DISK_SEGMENTS) / DISK_SEGMENTS
        vertices = np.concatenate([[[0.0, 0.0, 0.0]], np.stack([np.cos(theta), np.sin(theta),
                                                                  np.zeros_like(theta)], axis=1)])
    else:
        from .shapes import sphere

        z = 1.0 - 2.0 * b
        ring = np.sqrt(np.maximum(1.0 - z * z, 0.0))
        samples = np.stack([ring * np.cos(2.0 * np.pi * a), ring * np.sin(2.0 * np.pi * a), z], axis=1)
        vertices = sphere(1.0, SPHERE_SUBDIVISIONS)[0]
    return samples, vertices


def emitter_area(scene, light) -> float:
    """The emitting area of an area light."""
    return float(emitter_samples(scene, light, 1)[2].sum())


def emitting_triangles(scene, light) -> np.ndarray:
    """The triangles an area light emits from, (T, 3, 3) float64 in world space, each wound counter-clockwise
    about its emitting normal, as render.area_estimator = "analytic" integrates them in closed form: a
    rectangle's two, an object light's own; none (0, 3, 3) for a disk or a sphere, which stay on their sample
    points."""
    if light.shape == "rectangle":
        return frame_corners(*rectangle_axes(light))[[[0, 1, 2], [0, 2, 3]]]
    if light.shape is not None:
        return np.zeros((0, 3, 3))
    return np.concatenate([o.vertices[o.faces] for o in scene.objects if o.name == light.object])


FLAT = 1.0e-6  # how far, relative to its extent, a mesh light's vertices may leave its plane to count as flat


def light_hull(scene, light) -> np.ndarray | None:
    """A planar quadrilateral holding every point an area light is sampled at, (4, 3) float64 in world space,
    corners in order around it (kernels/clearance.py proves shadow rays clear of the pyramid over it): a
    rectangle's own corners, a disk's circumscribed square, a flat object light's bounding rectangle in its
    plane; None for a sphere or an object light that is not flat."""
    if light.shape in ("rectangle", "disk"):
        return frame_corners(*shape_frame(light))
    if light.shape is not None:
        return None
    points = emitting_triangles(scene, light).reshape(-1, 3)
    if not len(points):
        return None
    centre = points.mean(axis=0)
    vt = np.linalg.svd(points - centre)[2]
    n = vt[2]
    extent = float(np.ptp(points, axis=0).max())
    if extent == 0.0 or np.abs((points - centre) @ n).max() > FLAT * extent:
        return None
    s, t = coordinate_system(n)
    a, b = (points - centre) @ s, (points - centre) @ t
    corners = [(a.min(), b.min()), (a.max(), b.min()), (a.max(), b.max()), (a.min(), b.max())]
    return np.array([centre + x * s + y * t for x, y in corners])


def spread_strata(light, k: int, spp: int) -> np.ndarray:
    """Per sample point of an area light (emitter_samples' order), the pixel sample that takes it under
    render.light_spread: a shape light's k x k grid cell (i, j) goes to pixel-sample stratum (i mod m, j mod m)
    of the m x m pixel samples, so that each pixel sample's share is itself a grid spread over the whole light;
    an object light's Fibonacci point n (spread along the mesh's area already) to n mod spp. Every point goes
    to exactly one pixel sample: the pixel's average is the full sum, each point weighted spp times."""
    n = np.arange(k * k)
    if light.shape is None:
        return n % spp
    m = math.isqrt(spp)
    row, col = n // k, n % k
    return (row % m) * m + col % m
