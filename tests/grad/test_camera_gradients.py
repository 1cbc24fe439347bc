"""Camera gradients (issue 30): d(image)/d(camera.eye, center, up, fovy) with each camera ray's face and each
light's visibility held fixed. The replay makes the camera rays again from the camera (the forward's
camera_ray from a basis made in Warp by camera_of, float32, as scene.camera_basis makes it) and re-intersects
each recorded face from the moved eye along the moved direction (the differentiable Moller-Trumbore test the
vertex gradients use), then shades.

Checked here:
- the replayed image with the camera path on is the forward's to float32 rounding;
- warp.autograd.gradcheck of the camera rays (camera_of, camera_ray) against Warp's own finite differences;
- per component (eye, center, up: 3 each, fovy) and along a random direction of all ten, central
  differences of the forward (tests/grad/directional.py): a moving camera moves every edge (silhouettes,
  the shadows' edges in the image), and the pixels where the differences at h and h/2 disagree, where the
  visibility-fixed derivative does not apply, are masked out;
- controls that fail: the rays' origin held fixed (eye), fovy's derivative from the vertical axis alone (the
  image plane's width held), the gradient read along another direction;
- with a mirroring floor (two ray levels), the same: the mirror rays' origins and directions move with the
  camera (the hit's reflected direction, spawned off the surface as the tracer does);
- under area lights (an emissive square, Mitsuba's Cornell box): a random direction.

Measured (CPU, 24 x 18): replay - forward within 2e-6 of the image's maximum (5e-6 with the mirror); per
component relative errors 2e-5 to 4e-3 (the larger ones on the smallest derivatives, eye x, up z and fovy, where
the forward's float32 noise is; with the mirror fovy's is 4.5e-3 at h = 4e-2 degrees, 1.6e-2 at 4e-3), 0.2 to
1.9% of the pixels masked; a random direction 8e-6 (spp 1) and 6e-4 (spp 4, h = 1e-3); under area lights 6e-5
(lamp), 5e-5 (Cornell box). The
controls: the origin held, 1.4 off (eye z); fovy from the vertical axis alone, 0.88 off; another direction.
Mitsuba's AD of the same camera: tests/accuracy/test_gradients_against_mitsuba.py (within 1.1e-4).
"""

from __future__ import annotations

import numpy as np
import pytest
import warp as wp
import warp.autograd

import warprt
from warprt.kernels import camera_of, camera_ray, sample_offset
from warprt.scene import resolve_effects

from .directional import backward_masked, directional, random_direction

WIDTH, HEIGHT = 24, 18
CAMERA = ("camera.eye", "camera.center", "camera.up", "camera.fovy")
TOL = 1e-2


def scene(mirror: bool = False, spp: int = 1, **camera):
    """A glossy sphere and a box on a floor (flat), two point lights (one inverse-square), shadows; the
    camera looking down a little off-axis, up tilted, so that no component's derivative is 0 by symmetry."""
    return warprt.load_dict({
        "camera": {"eye": [0.6, 2.2, 4.5], "center": [0.1, 0.5, 0.0], "up": [0.1, 1.0, 0.05], "fovy": 50.0,
                   "width": WIDTH, "height": HEIGHT, **camera},
        "render": {"ambient": [0.2] * 3, "max_depth": 2 if mirror else 1, "spp": spp},
        "lights": [{"position": [2.0, 4.0, 3.0], "color": [0.8, 0.8, 0.7]},
                   {"position": [-3.0, 2.5, 1.0], "color": [6.0, 5.0, 4.0], "falloff": "inverse_square"}],
        "materials": {"floor": {"kd": [0.4, 0.35, 0.3], "ks": [0.3] * 3, "shininess": 12.0,
                                **({"reflectivity": [0.3] * 3} if mirror else {})},
                      "ball": {"kd": [0.6, 0.2, 0.1], "ks": [0.5] * 3, "shininess": 30.0}},
        "objects": [{"shape": "plane", "size": [30.0, 30.0], "material": "floor"},
                    {"shape": "sphere", "subdivisions": 3, "smooth": True, "translate": [0.0, 0.8, 0.0], "scale": 0.8,
                     "material": "ball"},
                    {"shape": "box", "translate": [1.4, 0.3, 0.6], "scale": 0.6, "material": "ball"}]})


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(11).random((HEIGHT, WIDTH, 3)).astype(np.float32)


def unit(name: str, c: int | None) -> dict:
    """A step of 1 in component c of parameter ``name`` (fovy: its one value)."""
    if c is None:
        return {name: np.float64(1.0)}
    v = np.zeros(3)
    v[c] = 1.0
    return {name: v}


@pytest.mark.parametrize("spp, mirror", [(1, False), (4, False), (1, True)])
def test_the_replayed_image_is_the_forward_one(spp, mirror):
    s = scene(mirror, spp=spp)
    r = warprt.Renderer(s)
    forward = r.render(grad=True).image
    geom = r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    replayed = warprt.image.replay_image(s, geom, hits, "cpu", camera=True)
    assert np.abs(replayed - forward).max() <= (1e-5 if mirror else 2e-6) * np.abs(forward).max()


@pytest.mark.parametrize("mirror", [False, True], ids=["camera rays", "mirror rays"])
@pytest.mark.parametrize("name, c", [(n, c) for n in CAMERA[:3] for c in range(3)] + [("camera.fovy", None)])
def test_each_component_equals_central_differences(weights, name, c, mirror):
    """h = 4e-3 for eye, center and up (world units), 4e-2 for fovy (degrees): about 1e-3 of each one's
    scale; at 1e-3 the forward's float32 noise reaches 1e-2 of the smaller derivatives (eye x, fovy). With
    the mirroring floor, the reflected rays' origins and directions move with the camera too."""
    s = scene(mirror)
    d = directional(s, unit(name, c), weights, h=4e-2 if name == "camera.fovy" else 4e-3)
    assert d.masked < 0.25
    g = backward_masked(s, weights, d)
    assert d.error(g) <= TOL, (d.gradient(g), d.fd, d.masked)


@pytest.mark.parametrize("spp, h", [(1, 4e-3), (4, 1e-3)])
def test_a_random_direction_of_the_whole_camera_equals_central_differences(weights, spp, h):
    """All ten components at once. Supersampled, the step is smaller: an edge sweeping over several of a
    pixel's four samples within the step changes the pixel in steps that the h / h/2 test takes for a slope
    (the supersampled image's boundary term, which the visibility-fixed derivative leaves out); at h = 4e-3
    that made the differences 0.2 off."""
    s = scene(spp=spp)
    d = directional(s, random_direction(s, CAMERA, seed=5, rel=0.3), weights, h=h)
    assert d.masked < 0.3
    g = backward_masked(s, weights, d)
    assert d.error(g) <= TOL
    other = directional(s, random_direction(s, CAMERA, seed=6, rel=0.3), weights, h=h)  # the control
    assert abs(other.gradient(g) - d.fd) > 0.1 * abs(d.fd)


@pytest.mark.parametrize("which, h", [("lamp", 1e-3), ("cornell", 2.5e-4)])
def test_under_area_lights_a_random_direction_equals_central_differences(which, h):
    """The camera over area lights (test_area_light_gradients' lamp and Mitsuba's Cornell box at 16 samples):
    the sample points' terms follow the sliding hits. In the Cornell box's penumbrae a step of 1e-3 flips
    some of the 16 shadow rays of many pixels, jumps of 1/16 of a light each that the h / h/2 test does not
    all catch (the differences 0.1 off); at 2.5e-4 they agree to 5e-5 (and at 1e-3 without shadows, 2e-5)."""
    from .test_area_light_gradients import cornell, lamp, weights_for

    s = lamp() if which == "lamp" else cornell(16)
    w = weights_for(s)
    d = directional(s, random_direction(s, CAMERA, seed=5, rel=0.3), w, h=h)
    assert d.masked < 0.1
    assert d.error(backward_masked(s, w, d)) <= TOL


def _taped(s, weights, mask, edit=None) -> dict:
    """The camera's adjoints from the replay launched by hand (warprt.image.build_replay with the camera),
    ``edit(replay)`` changing it first: the controls' way to drop one term."""
    r = warprt.Renderer(s)
    r.render()
    geom = r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    replay = warprt.image.build_replay(s, geom, hits, "cpu", camera=True)
    if edit is not None:
        edit(replay)
    tape = wp.Tape()
    with tape:
        replay.launch()
    tape.backward(grads={replay.colour: wp.array((weights * mask).reshape(-1, 3), dtype=wp.vec3)})
    cam = replay.arrays["camera"].grad.numpy().astype(np.float64)
    return {"camera.eye": cam[0], "camera.center": cam[1], "camera.up": cam[2],
            "camera.fovy": np.float64(replay.arrays["fovy"].grad.numpy()[0])}


def test_the_hand_launched_replay_is_backwards(weights):
    """The controls below launch the replay by hand: unedited, it gives backward()'s gradients."""
    s = scene()
    mask = np.ones((HEIGHT, WIDTH, 1), np.float32)
    ours = warprt.Renderer(s)
    ours.render(grad=True)
    g = ours.backward(weights, wrt=list(CAMERA), edges=False)
    h = _taped(s, weights, mask)
    for name in CAMERA:
        np.testing.assert_allclose(h[name], g[name], rtol=1e-6, atol=1e-6 * np.abs(g[name]).max())


def test_the_eye_with_the_rays_origin_held_fixed_is_not_the_differences(weights):
    """The control: the rays' origin held at the eye's value (its adjoint dropped, the directions still
    following the eye) gives another gradient than the differences along the eye."""
    s = scene()
    d = directional(s, unit("camera.eye", 2), weights, h=4e-3)

    def hold_origin(replay):
        replay.camera.origin = wp.array(replay.arrays["camera"].numpy(), dtype=wp.vec3)  # no adjoint: held

    wrong = _taped(s, weights, d.mask, hold_origin)
    assert d.error(wrong) > 0.1


def test_fovy_with_the_hits_held_is_not_the_differences(weights):
    """The control: the camera rays turning with fovy but each hit held where the forward found it (not
    recomputed from the moving ray on its face) misses the hits' slide; unedited, the differences."""
    s = scene()
    d = directional(s, unit("camera.fovy", None), weights, h=4e-2)

    def held(replay):
        replay.moving = False

    right = _taped(s, weights, d.mask)
    wrong = _taped(s, weights, d.mask, held)
    assert d.error(right) <= TOL
    assert d.error(wrong) > 0.1


@wp.kernel
def camera_rays(camera: wp.array(dtype=wp.vec3), fovy: wp.array(dtype=float), near: float, width: int, height: int,
                k: int, dirs: wp.array(dtype=wp.vec3)):
    """The camera rays as the replay makes them (replay.make_replay_ray): the forward's camera_ray from a basis
    made in Warp by camera_of, at each pixel's stratum centres."""
    ray = wp.tid()
    pixel = ray / (k * k)
    offset = sample_offset(ray % (k * k), k)
    c = camera_of(camera[0], camera[1], camera[2], fovy[0], near, width, height)
    dirs[ray] = camera_ray(c, pixel % width, pixel / width, offset[0], offset[1])


def test_camera_rays_pass_warps_gradcheck():
    """camera_rays' (camera_of's and camera_ray's) adjoints for the eye, center, up and fovy against Warp's own finite
    differences, at 2 x 2 supersampled pixels of a 4 x 3 image."""
    camera = wp.array(np.asarray([[0.6, 2.2, 4.5], [0.1, 0.5, 0.0], [0.1, 1.0, 0.05]], np.float32), dtype=wp.vec3,
                      requires_grad=True)
    fovy = wp.array([50.0], dtype=float, requires_grad=True)
    dirs = wp.zeros(4 * 3 * 4, dtype=wp.vec3, requires_grad=True)
    assert warp.autograd.gradcheck(camera_rays, dim=len(dirs), inputs=[camera, fovy, 1.0, 4, 3, 2], outputs=[dirs],
                                   eps=1e-3, atol=2e-3, rtol=2e-3, show_summary=False, raise_exception=False)


def test_camera_gradients_with_mirrors_are_given_with_the_vertices(weights):
    """The camera's rays move through the mirror levels in the replay, and so do a vertex's (checked in
    test_vertex_gradients.py): both are given by default."""
    s = scene(mirror=True)
    r = warprt.Renderer(s)
    r.render(grad=True)
    assert set(CAMERA) | {f"objects.{s.objects[0].name}.vertices"} <= set(r.backward(weights, edges=False))
