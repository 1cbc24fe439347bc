"""The edge of a spot light's hard cone seen by camera rays, for the gradient's boundary term
(image/grad_spot_edges.py launches it): where the cone dot(normalize(y - light), axis) = cos(cutoff) meets
a receiver triangle, a conic; an image point's signed distance from that curve's image as a differentiable
function of the light, the receiver and the camera (cone_distance, spot_edge_distances)."""

from .._warp import wp
from .edges import image_frame


@wp.func
def cone_distance(light: wp.vec3, axis: wp.vec3, cos_cutoff: float, p0: wp.vec3, p1: wp.vec3, p2: wp.vec3,
                  eye: wp.vec3, center: wp.vec3, up: wp.vec3, fovy: float, near: float, width: int, height: int,
                  x: float, y: float) -> float:
    """g / |grad_x g| at the image point (x, y) for g(x) = dot(normalize(y(x) - light), axis) - cos(cutoff),
    y(x) = eye + t d(x) where the camera ray through x meets the receiver's plane (p0, p1, p2): positive inside
    the cone (lit). grad_x g by the chain rule through y(x) (d affine in x, as plane_distance's); on the curve
    (g = 0) its derivative in any parameter is d_theta g / |grad_x g|, the curve's speed along its image
    normal."""
    f = image_frame(eye, center, up, fovy, near, width, height, x, y)
    d = f[0]
    d_x = f[1]
    d_y = f[2]
    n_r = wp.cross(p1 - p0, p2 - p0)
    n_d = wp.dot(n_r, d)
    t = wp.dot(n_r, p0 - eye) / n_d
    r = eye + t * d - light
    length = wp.length(r)
    u = r / length
    cos_theta = wp.dot(u, axis)
    dg = (axis - cos_theta * u) / length  # d g / d y
    g_x = wp.dot(dg, t * (d_x - (wp.dot(n_r, d_x) / n_d) * d))
    g_y = wp.dot(dg, t * (d_y - (wp.dot(n_r, d_y) / n_d) * d))
    return (cos_theta - cos_cutoff) / wp.sqrt(g_x * g_x + g_y * g_y)


@wp.kernel(module="unique")
def spot_edge_distances(geometry: wp.array(dtype=wp.vec3), cos_cutoff: wp.array(dtype=float),
                        camera: wp.array(dtype=wp.vec3), fovy: wp.array(dtype=float), near: float, width: int,
                        height: int, at: wp.array(dtype=wp.vec2), distance: wp.array(dtype=float)):
    """Per point j of a spot's cone edge, cone_distance of ``at[j]`` (``geometry[5 j:5 j + 5]``: the light's
    position, its axis, the receiver's p0, p1, p2; cos_cutoff[j]) seen by the camera ``camera[3 j:3 j + 3]``
    with fovy[j]: each point its own copies, so that each adjoint is a point's alone and the host sums them in a
    fixed order."""
    j = wp.tid()
    distance[j] = cone_distance(geometry[5 * j], geometry[5 * j + 1], cos_cutoff[j], geometry[5 * j + 2],
                                geometry[5 * j + 3], geometry[5 * j + 4], camera[3 * j], camera[3 * j + 1],
                                camera[3 * j + 2], fovy[j], near, width, height, at[j][0], at[j][1])
