"""An object's pose as two parameters (issue 38): objects.<name>.translation and rotation (a rotation vector
about the centre of the rest vertices' bounding box), their gradients on the replay's tape through
kernels.posed_points (posed_point's Rodrigues formula, ahead of the normals made from the points), so that
they get what the vertices get: mirror rays, a smooth object's normals following, glass's ray tree.

Checked: warp.autograd.gradcheck of posed_points at w = 0, in its Taylor branch and beyond, and posed_point's
Jacobian against Gallego and Yezzi's closed form (tests/oracle/transform.py); the replay's points the
forward's to the bit at the frame's pose, and its image the forward's; central finite differences of the
forward along random directions of a pose (tests/grad/directional.py, the pixels an edge crosses masked), at
the load's pose 0 and at a pose away from it. Controls that fail: a naive Rodrigues kernel at w = 0 (NaN),
the pose's Jacobian about the world origin or taken at w = 0, and another object's gradient. Mitsuba's AD of
the same vertices chained through the same Jacobian: tests/accuracy/test_gradients_against_mitsuba.py.

Measured (24 x 18): posed_points' Jacobian within 4e-7 of the closed form's (largest 2.9); the replayed
image within 1.4e-6 (mirrors) and 6.4e-6 (glass) of the forward's largest value; central differences within
1.2e-3 (the box at pose 0), 5.9e-4 (the box posed), 1.3e-3 (the smooth sphere), 2.8e-3 and 5e-4 (the glass
sphere at pose 0 and posed). The controls: NaN (the naive kernel), 0.26 and 0.20 off (about the origin), 0.15
(the Jacobian at w = 0 for a pose of 0.46 rad), 9.8 (the floor's gradient).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import warp as wp
import warp.autograd

import warprt
from oracle import pose_gradients, pose_jacobian, rotation_vector
from warprt.image import object_poses, pose_points
from warprt.kernels import posed_points
from warprt.scene import resolve_effects

from .directional import directional, random_direction
from .test_glass_gradients import sphere as glass_sphere
from .test_vertex_gradients import HEIGHT, WIDTH, mirror_scene, smooth_scene

TOL = 1e-2
CRATE = ["objects.crate.translation", "objects.crate.rotation"]
OFF_CENTRE = [-0.8, 0.0, 0.3]  # the box's move from tests/grad/test_vertex_gradients.py's, off the world origin
# A pose away from 0 (|w| = 0.46 rad): the rotation's Jacobian there is not the cross product's.
POSED = {"objects.crate.translation": [0.1, 0.0, -0.1], "objects.crate.rotation": [0.1, 0.4, -0.2]}


def crate_scene():
    """tests/grad/test_vertex_gradients.py's turned box on its tilted mirroring floor (three levels, two lights,
    a wall behind), the box moved off the world origin to (-0.8, 0.5, 0.3): a rotation about the origin is
    then far from one about the box's centre (the control)."""
    s = mirror_scene()
    objects = list(s.objects)
    objects[1] = replace(objects[1], vertices=objects[1].vertices + OFF_CENTRE)
    return replace(s, objects=objects)


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(11).random((HEIGHT, WIDTH, 3)).astype(np.float32)


def _vec3(rows, grad=False):
    return wp.array(np.asarray(rows, np.float32).reshape(-1, 3), dtype=wp.vec3, requires_grad=grad)


def _pose_inputs(rest, centre, t, w, owner):
    """posed_points' inputs for a few points: the forward's points those posed at (t, w) (float64, rounded)."""
    forward = np.concatenate([(rest[owner == o] - centre[o]) @ rotation_vector(w[o]).T + centre[o] + t[o]
                              for o in range(len(t))])
    return [_vec3(forward), _vec3(rest), wp.array(owner.astype(np.int32), dtype=int), _vec3(centre), _vec3(t), _vec3(w),
            _vec3(t, True), _vec3(w, True)]


@pytest.mark.parametrize("w", [[0.0, 0.0, 0.0], [2e-3, -1e-3, 3e-3], [0.4, -1.1, 0.7]],
                         ids=["zero", "taylor", "beyond"])
def test_posed_points_pass_warps_gradcheck(w):
    """posed_points against Warp's own finite differences in t and w, two objects, at w = 0, within the Taylor
    branch (|w| < 0.01) and beyond it."""
    rng = np.random.default_rng(3)
    rest, owner = rng.normal(size=(6, 3)), np.array([0, 0, 0, 1, 1, 1])
    centre, t = np.array([[0.2, -0.1, 0.3], [1.0, 0.5, -0.5]]), np.array([[0.1, 0.2, 0.3], [0.0, 0.0, 0.0]])
    ws = np.array([w, [0.3, 0.2, -0.1]], np.float64)
    out = wp.zeros(6, dtype=wp.vec3, requires_grad=True)
    assert warp.autograd.gradcheck(posed_points, dim=6, inputs=_pose_inputs(rest, centre, t, ws, owner),
                                   outputs=[out], eps=1e-3, atol=2e-3, rtol=2e-3, show_summary=False,
                                   raise_exception=False)


@wp.func
def _naive_posed_point(v_rest: wp.vec3, c: wp.vec3, t: wp.vec3, w: wp.vec3) -> wp.vec3:
    a = wp.length(w)  # no Taylor branch: sin(a) / a and (1 - cos a) / a^2 are 0 / 0 at w = 0
    q = v_rest - c
    wq = wp.cross(w, q)
    return v_rest + t + (wp.sin(a) / a) * wq + ((1.0 - wp.cos(a)) / (a * a)) * wp.cross(w, wq)


@wp.kernel
def _naive_posed_points(forward: wp.array(dtype=wp.vec3), rest: wp.array(dtype=wp.vec3), owner: wp.array(dtype=int),
                        centre: wp.array(dtype=wp.vec3), t0: wp.array(dtype=wp.vec3), w0: wp.array(dtype=wp.vec3),
                        t: wp.array(dtype=wp.vec3), w: wp.array(dtype=wp.vec3), points: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    o = owner[i]
    points[i] = forward[i] + (_naive_posed_point(rest[i], centre[o], t[o], w[o])
                              - _naive_posed_point(rest[i], centre[o], t0[o], w0[o]))


def test_a_rodrigues_without_its_taylor_branch_fails_gradcheck_at_zero():
    """The control: Rodrigues' coefficients taken as written, sin(a) / a, at the load's pose w = 0."""
    rest, owner = np.random.default_rng(3).normal(size=(3, 3)), np.zeros(3, np.int64)
    inputs = _pose_inputs(rest, np.zeros((1, 3)), np.zeros((1, 3)), np.zeros((1, 3)), owner)
    out = wp.zeros(3, dtype=wp.vec3, requires_grad=True)
    assert not warp.autograd.gradcheck(_naive_posed_points, dim=3, inputs=inputs, outputs=[out], eps=1e-3, atol=2e-3,
                                       rtol=2e-3, show_summary=False, raise_exception=False)


@pytest.mark.parametrize("w", [[0.0, 0.0, 0.0], [2e-3, -1e-3, 3e-3], [0.4, -1.1, 0.7], [2.0, 1.5, -2.5]],
                         ids=["zero", "taylor", "beyond", "large"])
def test_posed_points_jacobian_is_the_closed_forms(w):
    """posed_points' adjoint in w (one object per point, one backward pass per coordinate) against Gallego and
    Yezzi's d(R u)/dw in float64 (oracle.pose_jacobian), within float32's rounding; the control, the same
    Jacobian about the world origin, is not it."""
    rng = np.random.default_rng(5)
    n = 4
    rest, centre = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    ws, t = np.tile(np.asarray(w, np.float64), (n, 1)), np.zeros((n, 3))
    inputs = _pose_inputs(rest, centre, t, ws, np.arange(n))
    jacobian = np.zeros((n, 3, 3))
    for k in range(3):
        out = wp.zeros(n, dtype=wp.vec3, requires_grad=True)
        tape = wp.Tape()
        with tape:
            wp.launch(posed_points, dim=n, inputs=inputs, outputs=[out])
        tape.backward(grads={out: wp.array(np.tile(np.eye(3)[k], (n, 1)).astype(np.float32), dtype=wp.vec3)})
        jacobian[:, k, :] = inputs[-1].grad.numpy()
        np.testing.assert_allclose(inputs[-2].grad.numpy(), np.tile(np.eye(3)[k], (n, 1)), atol=0)  # t: identity
        tape.zero()
    expected = np.stack([pose_jacobian(rest[i:i + 1], centre[i], ws[i])[0] for i in range(n)])
    np.testing.assert_allclose(jacobian, expected, atol=1e-6 * max(1.0, np.abs(expected).max()))
    about_origin = np.stack([pose_jacobian(rest[i:i + 1], np.zeros(3), ws[i])[0] for i in range(n)])
    assert np.abs(jacobian - about_origin).max() > 0.1


# --- The replay's points and image ------------------------------------------------------------------------

def _recorded(s, start):
    """A Renderer at ``start`` (r.params values) after its forward frame, its frame's record and poses."""
    r = warprt.Renderer(s)
    r.params.update(start)
    forward = r.render().image
    s, geom = r.scene, r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    return r, forward, hits, object_poses(s, r.poses)


@pytest.mark.parametrize("start", [{}, POSED], ids=["rest", "posed"])
def test_the_replayed_points_are_the_forwards(start):
    """At the frame's pose the replay's points are the forward's to the bit, at pose 0 and away from it:
    posed_points adds the pose's change, posed_point at (t, w) less at the frame's (t0, w0), exactly 0 there
    (the forward poses in float64 and rounds; the replay's rest points are float32, read by the derivative
    alone)."""
    r, _, _, poses = _recorded(crate_scene(), start)
    points, _, (kernel, dim, inputs, outputs) = pose_points(r.scene, r.geometry, poses, "cpu")
    wp.launch(kernel, dim=dim, inputs=inputs, outputs=outputs)
    assert np.array_equal(points.numpy(), r.geometry.points_np)
    assert np.array_equal(r.params["objects.crate.vertices"], crate_scene().objects[1].vertices) == (start == {})
    r.close()


@pytest.mark.parametrize("make, name", [(crate_scene, "crate"), (glass_sphere, "sphere")], ids=["mirrors", "glass"])
def test_the_replayed_image_at_a_pose_is_the_forwards(make, name):
    """The replay with the posed points (the chain's, and glass's tree) makes the forward's image to float32
    rounding: each hit re-intersected on its posed face (the moving replay's Moller-Trumbore, where the
    forward's is Warp's mesh query), as the camera's replay does (1e-5 there too). Measured: 1.4e-6 of the
    largest value (mirrors), 6.4e-6 (glass)."""
    r, forward, hits, poses = _recorded(make(), {f"objects.{name}.translation": [0.05, -0.02, 0.03],
                                            f"objects.{name}.rotation": [0.2, -0.3, 0.1]})
    image = warprt.image.replay_image(r.scene, r.geometry, hits, "cpu", poses=poses)
    print(f"replayed image: {np.abs(image - forward).max() / np.abs(forward).max():.2g} of the largest value")
    assert np.abs(image - forward).max() <= 1e-5 * np.abs(forward).max()
    r.close()


# --- Central differences of the forward --------------------------------------------------------------------

def _backward(s, weights, d, names, start=None) -> dict:
    r = warprt.Renderer(s)
    r.params.update(start or {})
    r.render(grad=True)
    g = r.backward((weights * d.mask).astype(np.float32), wrt=names, edges=False)
    r.close()
    return g


@pytest.fixture(scope="module")
def crate_checks(weights):
    """The box's pose on the mirroring floor, at the load's pose 0 and at POSED: the differences, and the
    gradients of the box's pose and vertices and of the floor's pose (for the controls)."""
    out = {}
    names = CRATE + ["objects.crate.vertices", "objects.floor.translation", "objects.floor.rotation"]
    for key, start in (("rest", {}), ("posed", POSED)):
        s = crate_scene()
        d = directional(s, random_direction(s, CRATE, seed=7, rel=0.1), weights, h=1e-2, start=start)
        out[key] = (d, _backward(s, weights, d, names, start), start)
    return out


@pytest.mark.parametrize("key", ["rest", "posed"])
def test_a_boxs_pose_through_mirror_rays_equals_central_differences(crate_checks, key):
    """The box seen directly and in the tilted mirroring floor (three levels): its translation and rotation at
    once, at pose 0 and at a pose of 0.46 rad."""
    d, g, _ = crate_checks[key]
    print(f"box at {key}: {d.error(g):.2g} of the differences, {d.masked:.3f} masked")
    assert d.masked < 0.1
    assert d.error(g) <= TOL, (d.gradient(g), d.fd)


@pytest.mark.parametrize("key", ["rest", "posed"])
def test_the_pose_gradients_chain_the_vertex_gradients(crate_checks, key):
    """The translation's gradient is the sum of the vertices', the rotation's sum_i J_i^T g_i with J the
    closed form's (oracle.pose_gradients) about the rest box's centre at the pose's w."""
    d, g, start = crate_checks[key]
    r = warprt.Renderer(crate_scene())
    r.params.update(start)
    pose = object_poses(r.scene, r.poses)[1]
    t, w = pose_gradients(g["objects.crate.vertices"], pose.rest, pose.centre, pose.rotation)
    np.testing.assert_allclose(g["objects.crate.translation"], t, rtol=1e-5, atol=1e-5 * np.abs(t).max())
    np.testing.assert_allclose(g["objects.crate.rotation"], w, rtol=1e-4, atol=1e-4 * np.abs(w).max())


def test_the_vertex_gradients_are_the_same_with_the_pose_named(crate_checks, weights):
    """Naming the pose too leaves the vertices' gradient as it was (the posed points keep their adjoint:
    retain_grad, where Warp would clear it once read backwards)."""
    d, g, start = crate_checks["posed"]
    alone = _backward(crate_scene(), weights, d, ["objects.crate.vertices"], start)
    np.testing.assert_allclose(alone["objects.crate.vertices"], g["objects.crate.vertices"], rtol=1e-6, atol=1e-7)


@pytest.mark.parametrize("key", ["rest", "posed"])
def test_the_pose_about_the_origin_is_not_the_differences(crate_checks, key):
    """The control: the box's vertex gradients chained through the rotation's Jacobian about the world origin
    rather than the box's centre (and, away from 0, through the Jacobian at w = 0, the cross product's)."""
    d, g, start = crate_checks[key]
    r = warprt.Renderer(crate_scene())
    r.params.update(start)
    pose = object_poses(r.scene, r.poses)[1]
    _, about_origin = pose_gradients(g["objects.crate.vertices"], pose.rest, np.zeros(3), pose.rotation)
    print(f"about the origin ({key}): {d.error({**g, 'objects.crate.rotation': about_origin}):.2g} off")
    assert d.error({**g, "objects.crate.rotation": about_origin}) > 0.1
    if key == "posed":
        _, at_zero = pose_gradients(g["objects.crate.vertices"], pose.rest, pose.centre, np.zeros(3))
        print(f"the Jacobian at w = 0: {d.error({**g, 'objects.crate.rotation': at_zero}):.2g} off")
        assert d.error({**g, "objects.crate.rotation": at_zero}) > 0.1


def test_another_objects_pose_gradient_is_not_the_differences(crate_checks):
    """The control: the floor's translation and rotation gradients read along the box's direction."""
    d, g, _ = crate_checks["rest"]
    other = {"objects.crate.translation": g["objects.floor.translation"],
             "objects.crate.rotation": g["objects.floor.rotation"]}
    print(f"the floor's pose gradient: {d.error(other):.2g} off")
    assert d.error(other) > 0.1


def test_a_smooth_objects_pose_turns_its_normals_and_equals_central_differences(weights):
    """The smooth sphere's pose: the replay's vertex normals made from the posed points (moving_normals after
    posed_points) turn with it; the pixels whose face changes masked (a crease crossing a ray: a kink)."""
    s = smooth_scene()
    names = ["objects.ball.translation", "objects.ball.rotation"]
    start = {"objects.ball.rotation": [0.3, 0.2, -0.4]}
    d = directional(s, random_direction(s, names, seed=7, rel=0.02), weights, h=5e-3, same_faces=True, start=start)
    g = _backward(s, weights, d, names, start)
    print(f"smooth sphere: {d.error(g):.2g} of the differences, {d.masked:.3f} masked")
    assert d.masked < 0.1
    assert d.error(g) <= TOL


@pytest.mark.parametrize("start", [{}, {"objects.sphere.rotation": [0.1, -0.2, 0.3]}], ids=["rest", "posed"])
def test_a_glass_spheres_pose_through_the_ray_tree_equals_central_differences(start):
    """The glass sphere over its textured floor (tests/grad/test_glass_gradients.py): every level of the tree
    re-intersected on the posed faces, the smooth normals made from the posed points. Steps of 3e-5 (units,
    radians): a refracted ray crossing from one of the sphere's triangles to the next bends its pixel's
    differences (a kink the h / h/2 test does not always see), more often the longer the step."""
    s = glass_sphere()
    w = np.random.default_rng(5).random((HEIGHT, WIDTH, 3)).astype(np.float32)
    names = ["objects.sphere.translation", "objects.sphere.rotation"]
    d = directional(s, random_direction(s, names, seed=3, rel=0.01), w, h=3e-3, start=start)
    g = _backward(s, w, d, names, start)
    print(f"glass sphere: {d.error(g):.2g} of the differences, {d.masked:.3f} masked")
    assert d.masked < 0.1
    assert d.error(g) <= TOL


# --- Names ------------------------------------------------------------------------------------------------

def test_every_objects_pose_is_differentiated_by_default(weights):
    """backward() with no ``wrt`` gives each object's translation and rotation, (3,) float64."""
    r = warprt.Renderer(crate_scene())
    r.render(grad=True)
    g = r.backward(weights, edges=False)
    for name in ("floor", "crate", "wall"):
        for key in ("translation", "rotation"):
            assert g[f"objects.{name}.{key}"].shape == (3,) and g[f"objects.{name}.{key}"].dtype == np.float64
    r.close()


def test_an_area_lights_objects_pose_is_refused():
    """An emitting object's pose, as its vertices: its sample points are held fixed, so backward() refuses it
    in one line naming it, and leaves it out by default."""
    from .test_area_light_gradients import lamp, weights_for

    s = lamp()
    r = warprt.Renderer(s)
    r.render(grad=True)
    w = weights_for(s)
    with pytest.raises(warprt.SceneError, match="objects.lamp.rotation.*area light.*held fixed"):
        r.backward(w, wrt=["objects.lamp.rotation"])
    everything = r.backward(w)
    assert "objects.lamp.translation" not in everything and "objects.ball.translation" in everything
    r.close()
