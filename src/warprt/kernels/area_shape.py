"""A shape light (a rectangle, disk or sphere area light) as the gradient moves it: its frame (scene/area.py's
shape_frame: center, axes) as a differentiable function of its center, size, normal, radius (or a rectangle's
half-edges u and v), and the points, normals and areas of its sample points and its drawn triangles' vertices
made from their fixed places in that frame (scene.local_coordinates), each the forward's plus its move, so that
at the frame's values they are the forward's to the bit."""

from __future__ import annotations

from .._warp import wp
from ..scene import SHAPE_KINDS

RECTANGLE, DISK, SPHERE = SHAPE_KINDS["rectangle"], SHAPE_KINDS["disk"], SHAPE_KINDS["sphere"]


@wp.struct
class ShapeLights:
    """Per shape light (its row: scene.area_lights' order among those with a shape): its kind (SHAPE_KINDS) and
    whether it is a rectangle given by its half-edges (``by_edges``: u, v) rather than a normal and a size; its
    center (relative to the frame origin), normal, size (width, height), radius, u and v (unread where the
    light has none)."""

    kind: wp.array(dtype=int)
    by_edges: wp.array(dtype=int)
    center: wp.array(dtype=wp.vec3)
    normal: wp.array(dtype=wp.vec3)
    size: wp.array(dtype=wp.vec2)
    radius: wp.array(dtype=float)
    u: wp.array(dtype=wp.vec3)
    v: wp.array(dtype=wp.vec3)


@wp.func
def coordinate_system(n: wp.vec3):
    """Two unit vectors s, t with (s, t, n) right-handed and orthonormal, n unit: Mitsuba's coordinate_system
    (Duff et al. 2017), as scene.area.coordinate_system (its sign of a zero z: +1 for either zero here)."""
    sign = 1.0
    if n[2] < 0.0:
        sign = -1.0
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    s = wp.vec3(1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0])
    t = wp.vec3(b, sign + n[1] * n[1] * a, -n[1])
    return s, t


@wp.func
def shape_axes(lights: ShapeLights, i: int) -> wp.mat33:
    """The axes (A, B, C), as a matrix's rows, of shape light i's frame: a point at (x, y, z) in it lies at
    center + x A + y B + z C. A rectangle's half-edges (u, v, or its size's halves along coordinate_system of
    its normal), a disk's axes times its radius, a sphere's world axes times its radius."""
    kind = lights.kind[i]
    if kind == wp.static(SPHERE):
        r = lights.radius[i]
        return wp.mat33(r, 0.0, 0.0, 0.0, r, 0.0, 0.0, 0.0, r)
    if kind == wp.static(RECTANGLE) and lights.by_edges[i] != 0:
        return wp.matrix_from_rows(lights.u[i], lights.v[i], wp.vec3(0.0))
    s, t = coordinate_system(wp.normalize(lights.normal[i]))
    a = wp.vec2(lights.radius[i], lights.radius[i])
    if kind == wp.static(RECTANGLE):
        a = lights.size[i] * 0.5
    return wp.matrix_from_rows(s * a[0], t * a[1], wp.vec3(0.0))


@wp.func
def frame_point(lights: ShapeLights, i: int, local: wp.vec3) -> wp.vec3:
    """The point at ``local`` in shape light i's frame."""
    axes = shape_axes(lights, i)
    return lights.center[i] + local[0] * axes[0] + local[1] * axes[1] + local[2] * axes[2]


@wp.func
def shape_area(lights: ShapeLights, i: int) -> float:
    """Shape light i's emitting area: a rectangle's 4 |A x B|, a disk's pi |A x B|, a sphere's 4 pi r^2."""
    axes = shape_axes(lights, i)
    kind = lights.kind[i]
    if kind == wp.static(SPHERE):
        return 4.0 * wp.pi * lights.radius[i] * lights.radius[i]
    ab = wp.length(wp.cross(axes[0], axes[1]))
    if kind == wp.static(DISK):
        return wp.pi * ab
    return 4.0 * ab


@wp.kernel(module="unique")
def shape_points(lights: ShapeLights, frame: ShapeLights, light: wp.array(dtype=int), local: wp.array(dtype=wp.vec3),
                 forward: wp.array(dtype=wp.vec3), points: wp.array(dtype=wp.vec3)):
    """Each point of a shape light (``light``: its row, -1: another light's, left as it is) moved with it: the
    forward's point plus its place in the light's frame now less in the frame's (``frame``: the values the
    forward drew), differentiable in ``lights``."""
    q = wp.tid()
    i = light[q]
    p = forward[q]
    if i >= 0:
        p = p + (frame_point(lights, i, local[q]) - frame_point(frame, i, local[q]))
    points[q] = p


@wp.kernel(module="unique")
def shape_samples(lights: ShapeLights, frame: ShapeLights, light: wp.array(dtype=int), local: wp.array(dtype=wp.vec3),
                  count: wp.array(dtype=float), forward: wp.array(dtype=wp.vec3),
                  forward_normals: wp.array(dtype=wp.vec3), forward_dA: wp.array(dtype=float),
                  points: wp.array(dtype=wp.vec3), normals: wp.array(dtype=wp.vec3), dA: wp.array(dtype=float)):
    """The area lights' sample points (shape_points' move), their normals (a rectangle's or disk's A x B made
    unit: its normal; a sphere's, outward, held: its points move with the center and radius along them) and the
    area each stands for (the light's area over its ``count`` points), each the forward's plus its change."""
    q = wp.tid()
    i = light[q]
    p = forward[q]
    n = forward_normals[q]
    a = forward_dA[q]
    if i >= 0:
        p = p + (frame_point(lights, i, local[q]) - frame_point(frame, i, local[q]))
        if lights.kind[i] != wp.static(SPHERE):
            now = shape_axes(lights, i)
            was = shape_axes(frame, i)
            n = n + (wp.normalize(wp.cross(now[0], now[1])) - wp.normalize(wp.cross(was[0], was[1])))
        a = a + (shape_area(lights, i) - shape_area(frame, i)) / count[i]
    points[q] = p
    normals[q] = n
    dA[q] = a
