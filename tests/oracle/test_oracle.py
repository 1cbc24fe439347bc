"""The oracle checked on its own, against answers worked out by hand: if a closed form here were
wrong, every test built on it would be measuring against the wrong thing."""

from types import SimpleNamespace

import numpy as np
import pytest

from oracle import (Whitted, camera_rays, nearest_triangle, phong, phong_terms, pinhole, pixel_directions, pose_jacobian,
                    posed, ray_directions, ray_plane, ray_sphere_distance, ray_triangle, rotation, rotation_vector,
                    vertex_normals)
from scenekit import make_scene
from warprt.scene import Camera, shapes

CAM = Camera(eye=(0.0, 0.0, 5.0), center=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), fovy=90.0, near=2.0, width=5, height=3)


def test_camera_looks_from_eye_to_center_with_up_in_the_image():
    c = pinhole(CAM)
    np.testing.assert_array_equal(c.z_e, [0, 0, 1])
    np.testing.assert_array_equal(c.x_e, [1, 0, 0])
    np.testing.assert_array_equal(c.y_e, [0, 1, 0])
    assert c.h == pytest.approx(4.0) and c.w == pytest.approx(4.0 * 5 / 3)  # 2 d_f tan 45 = 2 d_f


def test_camera_rays_cross_the_image_plane_at_the_pixel_centres():
    """The middle pixel of an odd-sized image looks straight ahead; the top-left pixel's centre lies
    half a pixel inside the plane's top-left corner (-w/2, h/2) at distance d_f."""
    d = pixel_directions(CAM)
    np.testing.assert_allclose(d[1, 2], [0, 0, -2.0], atol=1e-15)
    w, h = 4.0 * 5 / 3, 4.0
    np.testing.assert_allclose(d[0, 0], [-w / 2 + w / 10, h / 2 - h / 6, -2.0], atol=1e-15)
    np.testing.assert_allclose(ray_directions(CAM, 0, 2, 0.0, 0.0), [-w / 2, -h / 2, -2.0], atol=1e-15)  # bottom-left corner
    eye, unit = camera_rays(CAM)
    np.testing.assert_allclose(np.linalg.norm(unit, axis=-1), 1.0)
    assert np.array_equal(eye, [0, 0, 5])


def test_ray_triangle_gives_the_hit_point_as_barycentrics():
    a, b, c = np.array([0.0, 0, 0]), np.array([2.0, 0, 0]), np.array([0.0, 4, 0])
    o, d = np.array([0.5, 1.0, 3.0]), np.array([0.0, 0.0, -1.5])
    h = ray_triangle(o, d, a, b, c)
    assert h.hit and h.t == pytest.approx(2.0)
    np.testing.assert_allclose(o + h.t * d, (1 - h.u - h.v) * a + h.u * b + h.v * c)
    assert (h.u, h.v) == pytest.approx((0.25, 0.25)) and h.margin == pytest.approx(0.25)
    # Outside across the hypotenuse: the margin is negative; behind the origin: no hit.
    assert ray_triangle([1.5, 3.0, 3.0], d, a, b, c).margin < 0
    assert not ray_triangle(o, -d, a, b, c).hit
    # In the triangle's plane: no hit, whatever the arithmetic gives.
    assert not ray_triangle([-1.0, 1.0, 0.0], [1.0, 0.0, 0.0], a, b, c).hit


def test_nearest_triangle_keeps_the_nearer_and_skips_zero_area():
    near = [[-1, -1, 1.0], [1, -1, 1.0], [0, 1, 1.0]]
    far = [[-1, -1, -1.0], [1, -1, -1.0], [0, 1, -1.0]]
    flat = [[-1, 0, 2.0], [1, 0, 2.0], [0, 0, 2.0]]  # collinear corners
    t, face, edge = nearest_triangle(np.array([0.0, 0, 5]), np.array([[0.0, 0, -1]]), np.array([far, flat, near]))
    assert t[0] == pytest.approx(4.0) and face[0] == 2 and edge[0] == pytest.approx(0.25)


def test_ray_plane_and_sphere():
    o, d = np.array([0.0, 0.0, 5.0]), np.array([[0.0, 0.6, -0.8], [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(ray_plane(o, d, [0, 0, 1.0], [0, 0, 1.0]), [5.0, np.inf])
    dist, t = ray_sphere_distance(o, d[0], [0.0, 0.0, 0.0])
    assert t == pytest.approx(4.0) and dist == pytest.approx(3.0)  # 3-4-5


@pytest.mark.parametrize("rotate, point, expect", [
    ([90, 0, 0], [0, 1, 0], [0, 0, 1]),   # about x: y -> z
    ([0, 90, 0], [0, 0, 1], [1, 0, 0]),   # about y: z -> x
    ([0, 0, 90], [1, 0, 0], [0, 1, 0]),   # about z: x -> y
    ([90, 90, 0], [0, 1, 0], [1, 0, 0]),  # x first (y -> z), then y (z -> x)
    ([0, 90, 90], [0, 0, 1], [0, 1, 0]),  # y first (z -> x), then z (x -> y)
])
def test_rotation_turns_about_x_then_y_then_z(rotate, point, expect):
    np.testing.assert_allclose(rotation(rotate) @ point, expect, atol=1e-15)


def test_rotation_is_a_rotation():
    R = rotation([23.0, -141.0, 67.5])
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(R) == pytest.approx(1.0)


def test_a_rotation_vector_turns_by_its_length_about_itself():
    """A quarter turn about z takes x to y; scipy's Rotation.from_rotvec (the convention r.params names) agrees."""
    from scipy.spatial.transform import Rotation

    np.testing.assert_allclose(rotation_vector([0.0, 0.0, np.pi / 2]) @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], atol=1e-15)
    w = np.array([0.3, -1.1, 0.7])
    np.testing.assert_allclose(rotation_vector(w), Rotation.from_rotvec(w).as_matrix(), atol=1e-15)
    assert np.array_equal(rotation_vector(np.zeros(3)), np.eye(3))


@pytest.mark.parametrize("w", [[0.0, 0.0, 0.0], [1e-3, -2e-3, 5e-4], [0.3, -1.1, 0.7], [2.0, 1.5, -2.5]])
def test_the_pose_jacobian_is_the_poses_central_differences(w):
    """Gallego and Yezzi's formula against float64 central differences of posed(), at w = 0 (the cross
    product's matrix) and away from it; the control, the same points rotated about the origin, is not it."""
    rng = np.random.default_rng(4)
    rest, centre, t = rng.normal(size=(5, 3)), np.array([0.4, -0.2, 1.0]), np.array([0.1, 0.2, 0.3])
    w, h = np.asarray(w, np.float64), 1e-6
    fd = np.stack([(posed(rest, centre, t, w + h * e) - posed(rest, centre, t, w - h * e)) / (2 * h) for e in np.eye(3)], -1)
    np.testing.assert_allclose(pose_jacobian(rest, centre, w), fd, atol=1e-8)
    assert np.abs(pose_jacobian(rest, np.zeros(3), w) - fd).max() > 0.1


def test_phong_at_the_mirror_direction_and_behind():
    """Light and eye mirrored about n at 45 degrees: n.L = cos 45, r = v so r.v = 1; a light behind
    the surface leaves only the ambient term; with r.v < 0 there is no highlight even at exponent 0."""
    mat = {"ka": [0.1, 0.2, 0.3], "kd": [0.5, 0.5, 0.5], "ks": [0.4, 0.3, 0.2], "shininess": 0.0}
    p, n = np.zeros(3), np.array([0.0, 0.0, 1.0])
    v = np.array([1.0, 0.0, 1.0]) / np.sqrt(2)
    terms = phong_terms(p, n, v, [([-3.0, 0.0, 3.0], [1.0, 0.5, 2.0])], mat, [1.0, 1.0, 1.0])
    np.testing.assert_allclose(terms["ambient"], [0.1, 0.2, 0.3])
    np.testing.assert_allclose(terms["diffuse"], np.array([1.0, 0.5, 2.0]) * 0.5 / np.sqrt(2))
    np.testing.assert_allclose(terms["specular"], [0.4, 0.15, 0.4])
    behind = phong(p, n, v, [([0.0, 0.0, -3.0], [1.0, 1.0, 1.0])], mat, [1.0, 1.0, 1.0])
    np.testing.assert_allclose(behind, [0.1, 0.2, 0.3])
    overhead = phong_terms(p, n, np.array([0.0, 0.6, -0.8]), [([0.0, 0.0, 3.0], [1.0, 1.0, 1.0])], mat, [0, 0, 0])
    assert not overhead["specular"].any() and overhead["diffuse"] == pytest.approx([0.5] * 3)
    shadowed = phong(p, n, v, [([-3.0, 0.0, 3.0], [1.0, 1.0, 1.0])], mat, [1.0, 1.0, 1.0], visible=np.array([False]))
    np.testing.assert_allclose(shadowed, [0.1, 0.2, 0.3])


def test_vertex_normals_of_a_box_corner_and_a_split_sheet():
    """At a box corner three faces meet at right angles (each split into triangles whose angles
    there add up to 90 degrees): the normal is the diagonal. A flat sheet split into two meshes
    with duplicated vertices along the cut keeps +z everywhere."""
    v, f = shapes.box((2.0, 2.0, 2.0))
    n = vertex_normals(v, f)
    np.testing.assert_allclose(n, v / np.linalg.norm(v, axis=1, keepdims=True), atol=1e-15)
    sheet = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [1, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0.0]])
    faces = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    np.testing.assert_allclose(vertex_normals(sheet, faces), np.tile([0.0, 0.0, 1.0], (8, 1)), atol=1e-15)


def test_whitted_traces_the_local_model_and_the_mirror_bounce():
    """Ambient only, a facing wall: C_amb ka. A mirror (k_r) facing the camera, nothing else: its
    reflected ray escapes, so the pixel is k_r times the background."""
    wall = {"shape": "plane", "size": [20.0, 20.0], "rotate": [90.0, 0.0, 0.0], "material": "m"}
    sw = SimpleNamespace(ambient=True, diffuse=True, specular=True, shadows=True, smooth=True, max_depth=2, spp=4,
                         reflection=True, refraction=False, absorption=False, texture=False, vertex_color=False)
    scene = make_scene([wall], {"m": {"ka": [0.2, 0.4, 0.6], "kd": [0, 0, 0], "reflectivity": [0.5, 0.25, 0.1]}},
                       ambient=[0.5, 0.5, 0.5], background=[1.0, 2.0, 3.0])
    trace = Whitted(scene, sw).pixel(10, 20)
    np.testing.assert_allclose(trace.color, [0.1 + 0.5, 0.2 + 0.5, 0.3 + 0.3])
    assert trace.margin > 0.01  # a pixel far from every edge and tie


def test_cylinder_quadrature_meets_the_infinite_cylinders_closed_form():
    """The CylinderLight oracle is a quadrature: a cylinder 1000 times longer than its height is the
    infinite one, E = pi L r / h (Howell's F = r / h), to 1e-6; a short one gets less."""
    import math

    from oracle.area import cylinder_below_irradiance

    assert cylinder_below_irradiance(2.0, 0.25, 1500.0, 1.5) == pytest.approx(math.pi * 2.0 * 0.25 / 1.5, rel=1e-6)
    assert cylinder_below_irradiance(2.0, 0.25, 1.0, 1.5) < 0.5 * math.pi * 2.0 * 0.25 / 1.5
