"""The edges seen in planar mirrors, for the gradient's boundary term (image/grad_mirror_edges.py launches them):
what a camera ray sees through a chain of planar mirrors is the scene reflected across their planes, so an
edge seen there (a silhouette, a shadow's edge) is that edge of the reflected scene seen from the eye. Its
signed distance in the image as a differentiable function of the edge, the light, the receiver, the mirrors'
own vertices and the camera (mirrored_point, make_mirrored_distances; a spot's hard cone on a receiver too, as
spot_edges.cone_distance's), and the faces a camera ray meets on its way through the mirrors
(make_mirror_faces_kernel)."""

import functools  # no "from __future__ import annotations": a kernel factory's types are its locals

from .._warp import wp
from ..geometry import SceneData
from .edges import make_mirror_path, plane_distance
from .mirror import Mirrors
from .raster import Fragments
from .shadow_edges import shadow_plane
from .spot_edges import cone_distance

EDGE = 0  # a mirrored distances kernel's point of a mesh edge
POINT_SHADOW = 1  # of a shadow's edge cast from a point (a point or spot light, an area light's sample point)
DIRECTIONAL_SHADOW = 2  # of a shadow's edge cast by a directional light
CONE = 3  # of a spot's hard cone on a receiver (v0: the spot's axis, a direction; the light: its position)


@wp.func
def mirror_normal(m0: wp.vec3, m1: wp.vec3, m2: wp.vec3) -> wp.vec3:
    """The unit normal of a mirror face's plane (its winding's: either serves, a reflection's sign is none)."""
    return wp.normalize(wp.cross(m1 - m0, m2 - m0))


@wp.func
def mirrored_point(p: wp.vec3, m0: wp.vec3, m1: wp.vec3, m2: wp.vec3) -> wp.vec3:
    """The point p reflected across the plane of the mirror face m0 m1 m2: p - 2 ((p - m0) . n) n."""
    n = mirror_normal(m0, m1, m2)
    return p - 2.0 * wp.dot(p - m0, n) * n


@wp.func
def mirrored_direction(u: wp.vec3, m0: wp.vec3, m1: wp.vec3, m2: wp.vec3) -> wp.vec3:
    """The direction u reflected across the plane of the mirror face m0 m1 m2: u - 2 (u . n) n."""
    n = mirror_normal(m0, m1, m2)
    return u - 2.0 * wp.dot(u, n) * n


@functools.cache
def make_mirrored_distances(levels: int):
    """The kernel of the signed distances, in pixels, of image points from the edges they lie on as seen through
    up to ``levels`` planar mirrors. Per point j: ``geometry[6 j:6 j + 6]`` its edge v0 v1, and for a shadow's
    edge (``kind[j]``: EDGE, POINT_SHADOW, DIRECTIONAL_SHADOW) the light (a point, or a direction of travel) and
    the receiver face p0 p1 p2 (for a spot's cone, CONE: v0 its axis, the light its position, cos_cutoff[j]); ``mirrors[3 levels j + 3 i:...+ 3]`` the face its ray meets at bounce i (its
    first first), ``level[j]`` of them. The scene seen through them is the real one reflected across the last
    mirror's plane, then each before it (the unfolded scene): so are v0, v1, the light and the receiver, and
    the distance is then edge_distance's (plane_distance of the plane through the eye and the edge), or for a
    shadow's edge shadow_distance's (plane_distance of shadow_plane), for a cone cone_distance's, with the camera ``camera[3 j:3 j + 3]``
    (eye, center, up) and fovy[j]: each point its own copies, so that each adjoint is a point's alone and the
    host sums them in a fixed order."""

    @wp.kernel(module="unique")
    def mirrored_distances(geometry: wp.array(dtype=wp.vec3), mirrors: wp.array(dtype=wp.vec3),
                           kind: wp.array(dtype=int), level: wp.array(dtype=int), cos_cutoff: wp.array(dtype=float),
                           camera: wp.array(dtype=wp.vec3), fovy: wp.array(dtype=float), near: float, width: int,
                           height: int, at: wp.array(dtype=wp.vec2), distance: wp.array(dtype=float)):
        j = wp.tid()
        v0, v1, light = wp.vec3(geometry[6 * j]), wp.vec3(geometry[6 * j + 1]), wp.vec3(geometry[6 * j + 2])
        p0, p1, p2 = wp.vec3(geometry[6 * j + 3]), wp.vec3(geometry[6 * j + 4]), wp.vec3(geometry[6 * j + 5])
        for step in range(wp.static(levels)):  # unrolled (Warp replays no dynamic loop backwards): last mirror first
            i = wp.static(levels) - 1 - step
            if i < level[j]:
                at_i = wp.static(3 * levels) * j + 3 * i
                m0 = wp.vec3(mirrors[at_i])  # copies: the unrolled levels each bind their own
                m1 = wp.vec3(mirrors[at_i + 1])
                m2 = wp.vec3(mirrors[at_i + 2])
                v0 = wp.where(kind[j] == wp.static(CONE), mirrored_direction(v0, m0, m1, m2),
                              mirrored_point(v0, m0, m1, m2))
                v1 = mirrored_point(v1, m0, m1, m2)
                light = wp.where(kind[j] == wp.static(DIRECTIONAL_SHADOW), mirrored_direction(light, m0, m1, m2),
                                 mirrored_point(light, m0, m1, m2))
                p0 = mirrored_point(p0, m0, m1, m2)
                p1 = mirrored_point(p1, m0, m1, m2)
                p2 = mirrored_point(p2, m0, m1, m2)
        eye = camera[3 * j]
        if kind[j] == wp.static(CONE):  # apart: a shadow plane of an axis and no v1 would be NaN, its adjoint too
            distance[j] = cone_distance(light, v0, cos_cutoff[j], p0, p1, p2, eye, camera[3 * j + 1],
                                        camera[3 * j + 2], fovy[j], near, width, height, at[j][0], at[j][1])
        else:
            n = wp.cross(v0 - eye, v1 - eye)
            if kind[j] != wp.static(EDGE):
                directional = wp.where(kind[j] == wp.static(DIRECTIONAL_SHADOW), 1, 0)
                n = shadow_plane(v0, v1, light, directional, p0, p1, p2, eye)
            distance[j] = plane_distance(n, eye, camera[3 * j + 1], camera[3 * j + 2], fovy[j], near, width, height,
                                         at[j][0], at[j][1])

    return mirrored_distances


@functools.cache
def make_mirror_faces_kernel(fx):
    """The kernel that writes, per camera ray along ``dirs[j]`` (unit) and level k, the face its ray of level k
    meets (edges.make_mirror_path: through the mirrors as the forward's walk bounces; -1 where the path ended
    before): the mirror faces an edge point is seen through."""
    mirror_path = make_mirror_path(fx)

    @wp.kernel(module="unique", enable_backward=False)
    def mirror_faces(s: SceneData, eye: wp.vec3, frags: Fragments, mir: Mirrors, dirs: wp.array(dtype=wp.vec3),
                     faces: wp.array2d(dtype=int)):
        j, k = wp.tid()
        faces[j, k] = mirror_path(s, frags, mir, eye, dirs[j], k).face

    return mirror_faces
