"""Gradients under spot and directional lights (shading's general light model): a spot's colour, position
and direction (its cone's linear ramp in angle, Mitsuba's ``spot``, over r^2), a directional light's colour
and direction, through two ray levels. Checked against central finite differences of the forward along
random directions (tests/grad/directional.py) and warp.autograd.gradcheck of the new functions, with
controls that fail: the spot taken for a point light (its cone dropped), and each direction's gradient
along another direction.

A light's direction is kept unit (Light normalises what it is given), so the image does not change along
the direction itself: its differences there are 0, and backward() projects its adjoint to match.

Measured (24 x 18, two levels): the replayed image equal to the forward's to the bit; relative errors
5e-5 to 3.3e-4.
"""

from __future__ import annotations

import numpy as np
import pytest
import warp as wp
import warp.autograd

import warprt
from warprt.kernels import light_factor, spot_cone
from warprt.scene import resolve_effects

from .directional import backward_masked, directional, random_direction

WIDTH, HEIGHT = 24, 18
REL = 2e-3
SPOT = {"type": "spot", "position": [1.0, 3.5, 1.5], "direction": [-0.3, -1.0, -0.4], "color": [9.0, 8.0, 7.0],
        "cutoff_angle": 35.0, "beam_width": 15.0, "falloff": "inverse_square"}
SUN = {"type": "directional", "direction": [0.5, -1.0, -0.6], "color": [0.6, 0.6, 0.7]}
NAMES = ["lights.0.color", "lights.0.position", "lights.0.direction", "lights.1.color", "lights.1.direction",
         "materials.floor.kd", "materials.floor.reflectivity"]


def lit(spot=None, spp: int = 1):
    """A glossy sphere on a mirroring floor (k_r 0.3, two levels) under a spot, whose cone's ramp crosses
    the floor in view, and a directional light, with shadows."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 2.0, 5.0], "center": [0.0, 0.5, 0.0], "width": WIDTH, "height": HEIGHT},
        "render": {"ambient": [0.1] * 3, "max_depth": 2, "spp": spp},
        "lights": [spot or SPOT, SUN],
        "materials": {"floor": {"kd": [0.4, 0.35, 0.3], "ks": [0.2] * 3, "shininess": 16.0, "reflectivity": [0.3] * 3},
                      "ball": {"kd": [0.6, 0.2, 0.1], "ks": [0.5] * 3, "shininess": 40.0}},
        "objects": [{"shape": "plane", "size": [8.0, 8.0], "material": "floor"},
                    {"shape": "sphere", "subdivisions": 3, "smooth": True, "translate": [0.0, 0.8, 0.0], "scale": 0.8,
                     "material": "ball"}]})


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(5).random((HEIGHT, WIDTH, 3)).astype(np.float32)


@pytest.mark.parametrize("spp", [1, 4])
def test_the_replayed_image_is_the_forward_image(spp):
    s = lit(spp=spp)
    r = warprt.Renderer(s)
    forward = r.render().image
    geom = r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    assert np.abs(warprt.image.replay_image(s, geom, hits, "cpu") - forward).max() <= 4e-7 * np.abs(forward).max()


@pytest.fixture(scope="module")
def checks(weights):
    s = lit()
    out = {}
    for name in NAMES:
        d = directional(s, random_direction(s, [name]), weights)
        out[name] = (d, backward_masked(s, weights, d))
    return out


@pytest.mark.parametrize("name", NAMES)
def test_light_gradients_equal_central_differences(checks, name):
    d, grads = checks[name]
    assert d.masked < 0.05
    assert d.error(grads) <= REL, (d.gradient(grads), d.fd)


@pytest.mark.parametrize("name", ["lights.0.direction", "lights.1.direction"])
def test_a_direction_along_itself_changes_nothing(weights, name):
    """Light keeps its direction unit: the differences along the direction itself are 0, and so is the
    gradient's component there (backward() projects it out)."""
    s = lit()
    unit = np.asarray(warprt.Renderer(s).params[name])
    d = directional(s, {name: unit}, weights)
    assert d.fd == 0.0
    g = backward_masked(s, weights, d)[name]
    assert abs(g @ unit) <= 1e-6 * np.abs(g).max()


def test_the_spot_taken_for_a_point_light_does_not(checks, weights):
    """The control: the spot's cone dropped (a point light of its position, colour and falloff) gives
    another position gradient than the spot's differences, by far more than the tolerance."""
    d, _ = checks["lights.0.position"]
    point = {k: v for k, v in SPOT.items() if k in ("position", "color", "falloff")}
    assert d.error(backward_masked(lit(point), weights, d)) > 0.1


@pytest.mark.parametrize("name", ["lights.0.direction", "lights.1.direction"])
def test_a_direction_gradient_along_another_direction_does_not(checks, name):
    """The control: the gradient read along another random step than the differences took."""
    d, grads = checks[name]
    other = random_direction(lit(), [name], seed=8)[name]
    assert abs((grads[name] * other).sum() - d.fd) > 0.1 * abs(d.fd)


@wp.kernel
def _cone(cone: wp.array(dtype=wp.vec4), cos_theta: wp.array(dtype=float), out: wp.array(dtype=float)):
    i = wp.tid()
    out[i] = spot_cone(cone[0], cos_theta[i])


@wp.kernel
def _factor(kind: wp.array(dtype=int), cone: wp.array(dtype=wp.vec4), inverse_square: wp.array(dtype=int),
            axis: wp.array(dtype=wp.vec3), to_light: wp.array(dtype=wp.vec3), out: wp.array(dtype=float)):
    i = wp.tid()
    out[i] = light_factor(kind[i], cone[i], inverse_square[i], axis[i], to_light[i], wp.normalize(to_light[i]))


def cone(cutoff: float = 35.0, beam: float = 15.0) -> list:
    c, b = np.radians(cutoff), np.radians(beam)
    return [np.cos(c), np.cos(b), c, 1.0 / (c - b)]


def test_the_cone_and_light_factor_pass_warps_gradcheck():
    """spot_cone in its ramp and on both sides of it (away from the kinks), and light_factor for a spot
    (ramp, with and without 1 / r^2), a directional light and a point light with falloff."""
    cos_theta = wp.array([0.5, 0.85, 0.9, 0.94, 0.99], dtype=float, requires_grad=True)
    assert warp.autograd.gradcheck(_cone, dim=5, inputs=[wp.array([cone()], dtype=wp.vec4), cos_theta],
                                   outputs=[wp.zeros(5, dtype=float, requires_grad=True)], eps=1e-4, atol=1e-3,
                                   rtol=1e-3, show_summary=False, raise_exception=False)
    axis = np.array([[0.0, -1.0, 0.0], [0.0, -1.0, 0.0], [0.6, -0.8, 0.0], [0.0, 0.0, -1.0]])
    to_light = [[0.3, 1.5, 0.2], [-0.4, 2.0, 0.1], [-0.6, 0.8, 0.0], [1.0, 2.0, 0.5]]
    inputs = [wp.array([1, 1, 2, 0], dtype=int), wp.array([cone()] * 4, dtype=wp.vec4), wp.array([1, 0, 0, 1], dtype=int),
              wp.array(axis, dtype=wp.vec3, requires_grad=True), wp.array(to_light, dtype=wp.vec3, requires_grad=True)]
    assert warp.autograd.gradcheck(_factor, dim=4, inputs=inputs, outputs=[wp.zeros(4, dtype=float, requires_grad=True)],
                                   eps=1e-4, atol=1e-3, rtol=1e-3, show_summary=False, raise_exception=False)
