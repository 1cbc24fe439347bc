"""The edges seen by camera rays, for the gradient's boundary term (image/grad_edges.py launches them): an
edge's signed distance in the image as a differentiable function of its vertices and the camera
(edge_distance, edge_distances; plane_distance, that of any plane through the eye), and the radiance either
side of it by the forward's own walk (make_edge_sides_kernel)."""

import functools  # no "from __future__ import annotations": a kernel factory's types are its locals

from .._warp import wp
from ..geometry import SceneData
from .aov import AovBuffers
from .camera import camera_of, image_plane_point
from .interaction import Ray
from .mirror import FROM_CAMERA, Mirrors
from .raster import Fragments
from .record import GradRecord
from .trace import TreeRay, make_path


@wp.func
def plane_distance(n: wp.vec3, eye: wp.vec3, center: wp.vec3, up: wp.vec3, fovy: float, near: float, width: int,
                   height: int, x: float, y: float) -> float:
    """The signed distance, in pixels, of the image point (x, y) (pixels from the lower-left corner) from the
    image of a plane through the eye of normal n (an edge's, a shadow's edge's): g / |grad_x g| for the edge
    function g(x) = n . d(x) (d: image_plane_point, affine in x, so its axes are differences of its points),
    positive where g is. On the line (g = 0) its derivative in any parameter is d_theta g / |grad_x g|: the
    line's speed along its normal, the boundary term's v . n (docs/gradients.md)."""
    c = camera_of(eye, center, up, fovy, near, width, height)
    px = x / float(width)
    py = y / float(height)
    d = image_plane_point(c, px, py)
    d_x = (image_plane_point(c, 1.0, py) - image_plane_point(c, 0.0, py)) / float(width)
    d_y = (image_plane_point(c, px, 1.0) - image_plane_point(c, px, 0.0)) / float(height)
    g_x = wp.dot(n, d_x)
    g_y = wp.dot(n, d_y)
    return wp.dot(n, d) / wp.sqrt(g_x * g_x + g_y * g_y)


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
