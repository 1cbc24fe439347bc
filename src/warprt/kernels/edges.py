"""The edges seen by camera rays, for the gradient's boundary term (image/grad_edges.py launches them): an
edge's signed distance in the image as a differentiable function of its vertices and the camera
(edge_distance, edge_distances; plane_distance, that of any plane through the eye; checker_edge_distances,
a checker's line on a triangle), the radiance either
side of it by the forward's own walk (make_edge_sides_kernel), and a camera ray followed through the mirrors
it meets to a given level's hit, as that walk follows it (make_mirror_path)."""

import functools  # no "from __future__ import annotations": a kernel factory's types are its locals

from .._warp import wp
from ..geometry import SceneData
from .aov import AovBuffers
from .camera import camera_of, image_plane_point
from .dielectric import absorbed
from .interaction import Ray, Surface, make_surface, mirror_ray
from .mirror import FROM_CAMERA, Mirrors
from .raster import Fragments
from .record import GradRecord
from .trace import TreeRay, make_first_hit, make_path


@wp.func
def image_frame(eye: wp.vec3, center: wp.vec3, up: wp.vec3, fovy: float, near: float, width: int, height: int,
                x: float, y: float) -> wp.mat33:
    """Rows d, d_x, d_y: the camera ray's image-plane point d(x) through the image point (x, y) (pixels from the
    lower-left corner; image_plane_point) and its derivatives in x and y, per pixel (d is affine in x, so its
    axes are differences of its points): what an edge function of the image is differentiated with."""
    c = camera_of(eye, center, up, fovy, near, width, height)
    px = x / float(width)
    py = y / float(height)
    d = image_plane_point(c, px, py)
    d_x = (image_plane_point(c, 1.0, py) - image_plane_point(c, 0.0, py)) / float(width)
    d_y = (image_plane_point(c, px, 1.0) - image_plane_point(c, px, 0.0)) / float(height)
    return wp.mat33(d[0], d[1], d[2], d_x[0], d_x[1], d_x[2], d_y[0], d_y[1], d_y[2])


@wp.func
def plane_distance(n: wp.vec3, eye: wp.vec3, center: wp.vec3, up: wp.vec3, fovy: float, near: float, width: int,
                   height: int, x: float, y: float) -> float:
    """The signed distance, in pixels, of the image point (x, y) (pixels from the lower-left corner) from the
    image of a plane through the eye of normal n (an edge's, a shadow's edge's): g / |grad_x g| for the edge
    function g(x) = n . d(x) (d: image_plane_point, affine in x, so its axes are differences of its points),
    positive where g is. On the line (g = 0) its derivative in any parameter is d_theta g / |grad_x g|: the
    line's speed along its normal, the boundary term's v . n (docs/gradients.md)."""
    f = image_frame(eye, center, up, fovy, near, width, height, x, y)
    g_x = wp.dot(n, f[1])
    g_y = wp.dot(n, f[2])
    return wp.dot(n, f[0]) / wp.sqrt(g_x * g_x + g_y * g_y)


@wp.func
def edge_distance(v0: wp.vec3, v1: wp.vec3, eye: wp.vec3, center: wp.vec3, up: wp.vec3, fovy: float, near: float,
                  width: int, height: int, x: float, y: float) -> float:
    """The signed distance, in pixels, of the image point (x, y) from the line an edge v0 v1 projects to:
    plane_distance for the plane through the eye and the edge, g(x) = det(v0 - eye, v1 - eye, d(x))."""
    return plane_distance(wp.cross(v0 - eye, v1 - eye), eye, center, up, fovy, near, width, height, x, y)


@wp.kernel(module="unique")
def edge_distances(v0: wp.array(dtype=wp.vec3), v1: wp.array(dtype=wp.vec3), camera: wp.array(dtype=wp.vec3),
                   fovy: wp.array(dtype=float), near: float, width: int, height: int, at: wp.array(dtype=wp.vec2),
                   distance: wp.array(dtype=float)):
    """Per point j of an edge, edge_distance of ``at[j]`` from its edge (v0[j], v1[j]) seen by the camera
    ``camera[3 j:3 j + 3]`` (eye, center, up; each point its own copy, so that each adjoint is a point's
    alone and the host sums them in a fixed order) with fovy[j]."""
    j = wp.tid()
    distance[j] = edge_distance(v0[j], v1[j], camera[3 * j], camera[3 * j + 1], camera[3 * j + 2], fovy[j], near,
                                width, height, at[j][0], at[j][1])


@wp.kernel(module="unique")
def checker_edge_distances(corners: wp.array(dtype=wp.vec3), weights: wp.array(dtype=wp.vec3),
                           camera: wp.array(dtype=wp.vec3), fovy: wp.array(dtype=float), near: float, width: int,
                           height: int, at: wp.array(dtype=wp.vec2), distance: wp.array(dtype=float)):
    """Per point j of a checker's line on a triangle, edge_distance of ``at[j]`` from the image of the
    segment whose ends are fixed barycentric combinations of the triangle's corners (``corners[3 j:3 j + 3]``
    weighted by ``weights[2 j]``, ``weights[2 j + 1]``: where the line u' = k or v' = k of its affine uv
    crosses the triangle's sides), seen by the camera ``camera[3 j:3 j + 3]`` with fovy[j]: each point its own
    copies, so that each adjoint is a point's alone and the host sums them in a fixed order."""
    j = wp.tid()
    p0 = corners[3 * j]
    p1 = corners[3 * j + 1]
    p2 = corners[3 * j + 2]
    w0 = weights[2 * j]
    w1 = weights[2 * j + 1]
    q0 = p0 * w0[0] + p1 * w0[1] + p2 * w0[2]
    q1 = p0 * w1[0] + p1 * w1[1] + p2 * w1[2]
    distance[j] = edge_distance(q0, q1, camera[3 * j], camera[3 * j + 1], camera[3 * j + 2], fovy[j], near, width,
                                height, at[j][0], at[j][1])


@functools.cache
def make_edge_sides_kernel(fx, stack: int):
    """The kernel that traces camera rays along given directions (``dirs``, unit) with the forward's walk
    (trace.make_path for the effect set ``fx``: full Whitted shading, every query the BVH's, nothing recorded)
    and writes each one's colour: the radiance just either side of an edge."""
    path = make_path(fx, False, stack, False, (), False, False, False)
    COUNTS = wp.vec4i if fx.refraction else wp.vec3i

    @wp.kernel(module="unique", enable_backward=False)
    def edge_sides(s: SceneData, eye: wp.vec3, max_depth: int, frags: Fragments, mir: Mirrors, aov: AovBuffers,
                   rec: GradRecord, dirs: wp.array(dtype=wp.vec3), color: wp.array(dtype=wp.vec3)):
        j = wp.tid()
        r = TreeRay(Ray(eye, dirs[j]), wp.vec3(1.0), eye, 0, s.eye_medium, FROM_CAMERA, -1)
        c, truncated, rays = path(s, frags, mir, aov, rec, r, max_depth, j, 0, 1, 0, 0, 0, wp.vec3(0.0), COUNTS())
        color[j] = c

    return edge_sides


@wp.struct
class MirrorEnd:
    """Where a camera ray's mirror path reaches a level: the hit's face (-1: the path ended before it, meeting
    nothing or a surface that reflects nothing), its hit record, the level's ray direction and its weight (the
    k_r of the mirrors before it, and with absorption Beer's law to its hit)."""

    face: int
    hit: Surface
    d: wp.vec3
    weight: wp.vec3


@functools.cache
def make_mirror_path(fx):
    """mirror_path(s, frags, mir, eye, d, level) -> MirrorEnd: the camera ray from ``eye`` along ``d`` followed
    as the forward's walk follows it through mirrors (trace.make_path: its nearest hit by the BVH, its weight
    through Beer's law, a bounce off a hit whose k_r is not 0 by mirror_ray, weighted by k_r) to its ray of
    level ``level`` (0: the camera ray) and that ray's hit. The frames it serves have no glass rays
    (grad_edges.edge_refusal), so the path is a chain: no dielectric child to choose."""
    first_hit = make_first_hit(False, False, fx.culling)
    surface = make_surface(fx.smooth, fx.texture, fx.vertex_color)
    ABSORPTION = fx.absorption

    @wp.func
    def mirror_path(s: SceneData, frags: Fragments, mir: Mirrors, eye: wp.vec3, d: wp.vec3, level: int) -> MirrorEnd:
        r = TreeRay(Ray(eye, d), wp.vec3(1.0), eye, 0, s.eye_medium, FROM_CAMERA, -1)
        end = MirrorEnd()
        end.face = -1
        going = bool(True)
        while going:
            going = False
            h = first_hit(s, frags, mir, r, 0, 0, 0, 0, 0)
            if h.face >= 0:
                hit = surface(s, h.face, h.u, h.v, h.normal, r.ray.d)
                weight = r.weight
                if wp.static(ABSORPTION):
                    weight = absorbed(s, weight, r.medium, r.start, hit)
                kr = s.kr[hit.material]
                if r.depth == level:
                    end = MirrorEnd(h.face, hit, r.ray.d, weight)
                elif wp.max(kr) > 0.0:  # the forward's follows_mirror, a mirror's ray in its parent's medium
                    r = TreeRay(mirror_ray(hit, r.ray.d), wp.cw_mul(weight, kr), hit.p, r.depth + 1, r.medium,
                                FROM_CAMERA, h.face)
                    going = True
        return end

    return mirror_path
