"""An object's pose as the gradient moves it: Rodrigues' rotation about the object's centre and a translation
(posed_point), and the replay's points made from each object's rest points and pose (posed_points), at the
frame's pose the forward's to the bit; image/params.py poses the forward's vertices the same way in float64."""

from __future__ import annotations

from .._warp import wp

POSE_TAYLOR = 1.0e-4  # |w|^2 (radians^2) below which rodrigues_coefficients are their Taylor series


@wp.func
def rodrigues_coefficients(theta2: float) -> wp.vec2:
    """(sin(a) / a, (1 - cos(a)) / a^2) of the angle a = sqrt(theta2), Rodrigues' formula's coefficients:
    below POSE_TAYLOR (a < 0.01) their Taylor series in theta2 to theta2^2 (the next terms below 1e-16), so
    that at a = 0 both and their derivatives are finite (sqrt has none there) and R's Jacobian is the
    cross product's; above, 1 - cos(a) as 2 sin^2(a / 2), without its cancellation."""
    if theta2 < wp.static(POSE_TAYLOR):
        return wp.vec2(1.0 - theta2 / 6.0 + theta2 * theta2 / 120.0, 0.5 - theta2 / 24.0 + theta2 * theta2 / 720.0)
    a = wp.sqrt(theta2)
    half = wp.sin(0.5 * a)
    return wp.vec2(wp.sin(a) / a, 2.0 * half * half / theta2)


@wp.func
def posed_point(v_rest: wp.vec3, c: wp.vec3, t: wp.vec3, w: wp.vec3) -> wp.vec3:
    """R(w) (v_rest - c) + c + t, R(w) the rotation by |w| radians about w / |w| (Rodrigues: R q = q +
    sin(a)/a w x q + (1 - cos(a))/a^2 w x (w x q)), written v_rest + t + (R(w) - I)(v_rest - c) as
    params.posed_vertices writes it: differentiable in t and w, its Jacobian in w at w = 0 the cross product's
    (d/dw at 0 of w x q), finite there (rodrigues_coefficients)."""
    q = v_rest - c
    k = rodrigues_coefficients(wp.dot(w, w))
    wq = wp.cross(w, q)
    return v_rest + t + k[0] * wq + k[1] * wp.cross(w, wq)


@wp.kernel(module="unique")
def posed_points(forward: wp.array(dtype=wp.vec3), rest: wp.array(dtype=wp.vec3), owner: wp.array(dtype=int),
                 centre: wp.array(dtype=wp.vec3), t0: wp.array(dtype=wp.vec3), w0: wp.array(dtype=wp.vec3),
                 t: wp.array(dtype=wp.vec3), w: wp.array(dtype=wp.vec3), points: wp.array(dtype=wp.vec3)):
    """The replay's points from the objects' poses: vertex i of object owner[i] (-1: none of the scene's, an
    area light's own shape, left as it is) is the forward's point plus its pose's change, posed_point of its
    rest point at (t, w) less at the frame's (t0, w0): at the frame's pose the forward's point to the bit (two
    equal values' difference is 0) and differentiable in t and w as posed_point is (the forward poses in
    float64 on the host and rounds; the replay's rest points and centres, relative to the frame origin, are
    float32, which only the derivative reads)."""
    i = wp.tid()
    o = owner[i]
    p = forward[i]
    if o >= 0:
        p = p + (posed_point(rest[i], centre[o], t[o], w[o]) - posed_point(rest[i], centre[o], t0[o], w0[o]))
    points[i] = p
