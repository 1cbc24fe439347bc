"""Gradients with respect to an area light's position (issue 30 over issue 32's lights): lights.<i>.center of a
rectangle, disk or sphere light. Its sample points are its centre plus offsets the centre does not move, so
the replay translates the forward's points by the centre's move (kernels.translate_samples, on the tape before
kernels.replay_area), their normals and areas unchanged; which points each hit sees, and the emitter's face
met by a ray (its radiance, seen directly, a constant), are held fixed, as visibility is. Checked:

- the replayed image is the forward's, to the bit (the points moved by 0);
- directional derivatives along random directions of the centre equal central finite differences of the
  forward (tests/grad/directional.py: pixels a moving shadow's or the emitter's edge crosses masked), for
  each shape, through a mirror's level for the rectangle;
- warp.autograd.gradcheck of kernels.translate_samples;
- controls that fail: the points held where they are (the centre's adjoint dropped), the gradient read
  along another direction.
Mitsuba's AD of the same centre (its rectangle's to_world): tests/accuracy/test_gradients_against_mitsuba.py.
"""

from __future__ import annotations

import numpy as np
import pytest
import warp as wp
import warp.autograd

import warprt
from warprt.kernels import translate_samples
from warprt.scene import resolve_effects

from .directional import backward_masked, directional, random_direction

WIDTH, HEIGHT = 24, 18
TOL = 1e-2
LIGHTS = {"rectangle": {"shape": "rectangle", "center": [0.4, 2.6, 0.3], "normal": [0.0, -1.0, 0.5], "size": [1.2, 0.8]},
          "disk": {"shape": "disk", "center": [-0.3, 2.4, 0.6], "normal": [0.2, -1.0, 0.3], "radius": 0.5},
          "sphere": {"shape": "sphere", "center": [0.6, 2.2, 0.8], "radius": 0.3}}


def lit(shape: str = "rectangle", max_depth: int = 2):
    """tests/grad/test_area_light_gradients.py's soft(): a glossy sphere over a glossy, weakly mirroring floor
    (``max_depth`` levels), its soft shadow in view, under one area light of ``shape`` whose front is seen."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 1.6, 5.0], "center": [0.0, 1.0, 0.0], "width": WIDTH, "height": HEIGHT},
        "render": {"ambient": [0.05] * 3, "max_depth": max_depth, "light_samples": 16},
        "lights": [{"type": "area", **LIGHTS[shape], "radiance": [6.0, 5.0, 4.0]}],
        "materials": {"floor": {"kd": [0.4, 0.35, 0.3], "ks": [0.2] * 3, "shininess": 16.0, "reflectivity": [0.3] * 3},
                      "ball": {"kd": [0.6, 0.2, 0.1], "ks": [0.5] * 3, "shininess": 40.0}},
        "objects": [{"shape": "plane", "size": [8.0, 8.0], "material": "floor"},
                    {"shape": "sphere", "subdivisions": 2, "smooth": True, "translate": [0.0, 0.8, 0.0], "scale": 0.8,
                     "material": "ball"}]})


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(17).random((HEIGHT, WIDTH, 3)).astype(np.float32)


@pytest.mark.parametrize("shape", list(LIGHTS))
def test_the_replayed_image_is_the_forward_image(shape):
    s = lit(shape)
    r = warprt.Renderer(s)
    forward = r.render().image
    geom = r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    assert np.array_equal(warprt.image.replay_image(s, geom, hits, "cpu", centres=True), forward)
    r.close()


def centre_differences(s, weights, seed: int):
    return directional(s, random_direction(s, ["lights.0.center"], seed=seed, rel=0.05), weights, h=1e-2)


@pytest.mark.parametrize("shape", list(LIGHTS))
def test_the_centre_equals_central_differences(weights, shape):
    s = lit(shape, max_depth=2 if shape == "rectangle" else 1)
    d = centre_differences(s, weights, seed=3)
    assert d.masked < 0.1
    g = backward_masked(s, weights, d)
    assert d.error(g) <= TOL
    other = centre_differences(s, weights, seed=4)  # the control: the gradient read along another direction
    assert abs(other.gradient(g) - d.fd) > 0.1 * abs(d.fd)


def test_the_points_held_are_not_the_differences(weights):
    """The control: the replay with the sample points held where the forward put them (translate_samples left
    out, replay_area reading the forward's points) gives the centre no derivative; unedited, the hand-launched
    replay is backward()'s."""
    s = lit()
    d = centre_differences(s, weights, seed=3)

    def taped(held: bool) -> np.ndarray:
        r = warprt.Renderer(s)
        r.render()
        geom = r.geometry
        hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
        replay = warprt.image.build_replay(s, geom, hits, "cpu", centres=True)
        if held:
            replay.before = [b for b in replay.before if b[0] is not translate_samples]
            area = replay.data.area
            area.points = hits.data.area.points
            replay.data.area = area  # a nested Warp struct is held by value: set again
        tape = wp.Tape()
        with tape:
            replay.launch()
        tape.backward(grads={replay.colour: wp.array((weights * d.mask).reshape(-1, 3), dtype=wp.vec3)})
        r.close()
        return replay.arrays["center"].grad.numpy()[0].astype(np.float64)

    right = taped(held=False)
    np.testing.assert_allclose(right, backward_masked(s, weights, d)["lights.0.center"], rtol=1e-6, atol=1e-6)
    assert d.error({"lights.0.center": right}) <= TOL
    assert d.error({"lights.0.center": taped(held=True)}) > 0.1


def test_translate_samples_passes_warps_gradcheck():
    rng = np.random.default_rng(3)
    points = wp.array(rng.standard_normal((9, 3)).astype(np.float32), dtype=wp.vec3, requires_grad=True)
    light = wp.array(np.asarray([0, 0, 0, 0, 1, 1, 1, 2, 2], np.int32), dtype=int)
    shift = wp.array(rng.standard_normal((3, 3)).astype(np.float32), dtype=wp.vec3, requires_grad=True)
    out = wp.zeros(9, dtype=wp.vec3, requires_grad=True)
    assert warp.autograd.gradcheck(translate_samples, dim=9, inputs=[points, light, shift], outputs=[out], eps=1e-3,
                                   atol=2e-3, rtol=2e-3, show_summary=False, raise_exception=False)


def test_only_a_shape_lights_centre_is_a_parameter():
    """A shape light's centre is an r.params name backward() differentiates; an object light (Mitsuba's
    Cornell box's) has none: its points follow its object's vertices, held fixed."""
    r = warprt.Renderer(lit("sphere"))
    assert "lights.0.center" in r.params
    r.render(grad=True)
    assert set(r.backward(np.ones((HEIGHT, WIDTH, 3), np.float32), wrt=["lights.0.center"])) == {"lights.0.center"}
    r.close()
    from .test_area_light_gradients import cornell

    r = warprt.Renderer(cornell(4))
    assert "lights.0.center" not in r.params
    r.render(grad=True)
    with pytest.raises(warprt.SceneError, match="lights.0.center"):  # ArgumentError is one
        r.backward(np.ones((24, 24, 3), np.float32), wrt=["lights.0.center"])
    r.close()
