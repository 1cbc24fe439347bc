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
from warprt.geometry import LightShape, SceneData, light_shape
from warprt.kernels import Coefficients, Surface, light_weight, make_light_arrival, make_light_terms
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


@wp.func
def light_shape_of(kind: int, direction: wp.vec3, inverse_square: int) -> LightShape:
    """A LightShape as geometry.light_shape makes one: a spot's 35-degree cone with a 15-degree beam (CONE)."""
    shape = LightShape()
    shape.kind = kind
    shape.direction = direction
    shape.cos_cutoff = wp.static(float(np.cos(np.radians(35.0))))
    shape.cos_beam = wp.static(float(np.cos(np.radians(15.0))))
    shape.cutoff = wp.static(float(np.radians(35.0)))
    shape.inv_ramp = wp.static(float(1.0 / np.radians(20.0)))
    shape.inverse_square = inverse_square
    return shape


@wp.kernel
def _weight(kind: wp.array(dtype=int), inverse_square: wp.array(dtype=int), axis: wp.array(dtype=wp.vec3),
            to_light: wp.array(dtype=wp.vec3), out: wp.array(dtype=float)):
    """shading.light_weight (a spot's profile, spot_profile, and 1 / r^2) of the shape made from the inputs."""
    i = wp.tid()
    shape = light_shape_of(kind[i], wp.normalize(axis[i]), inverse_square[i])
    out[i] = light_weight(shape, to_light[i], wp.normalize(to_light[i]))


LIGHT_ARRIVAL = make_light_arrival(True)
WHITTED_TERM = make_light_terms(True, True)[0]


@wp.kernel
def _lit(light_pos: wp.array(dtype=wp.vec3), light_color: wp.array(dtype=wp.vec3), shapes: wp.array(dtype=LightShape),
         p: wp.array(dtype=wp.vec3), n: wp.array(dtype=wp.vec3), kd: wp.array(dtype=wp.vec3),
         ks: wp.array(dtype=wp.vec3), out: wp.array(dtype=wp.vec3)):
    """What the replay adds for a light a hit sees: whitted_term of light_arrival (the general light model)."""
    i = wp.tid()
    s = SceneData()
    s.light_pos = light_pos
    s.light_color = light_color
    s.light_shape = shapes
    hit = Surface()
    hit.p = p[i]
    hit.n = wp.normalize(n[i])
    k = Coefficients()
    k.kd = kd[i]
    k.ks = ks[i]
    out[i] = WHITTED_TERM(LIGHT_ARRIVAL(s, hit, i % 3), k, 20.0, hit.n, wp.vec3(0.0, 0.6, 0.8))


def test_the_light_model_passes_warps_gradcheck():
    """The forward's light model as the replay differentiates it: light_weight for a spot (ramp, with and
    without 1 / r^2), a directional light and a point light with falloff, in the spot's axis and the offset
    to the light; and light_arrival then whitted_term, in the lights' positions and colours, the hit and its
    colours, for a spot in its ramp, a point light and a sun."""
    axis = np.array([[0.0, -1.0, 0.0], [0.0, -1.0, 0.0], [0.6, -0.8, 0.0], [0.0, 0.0, -1.0]])
    to_light = [[0.3, 1.5, 0.2], [-0.4, 2.0, 0.1], [-0.6, 0.8, 0.0], [1.0, 2.0, 0.5]]
    inputs = [wp.array([1, 1, 2, 0], dtype=int), wp.array([1, 0, 0, 1], dtype=int),
              wp.array(axis, dtype=wp.vec3, requires_grad=True), wp.array(to_light, dtype=wp.vec3, requires_grad=True)]
    assert warp.autograd.gradcheck(_weight, dim=4, inputs=inputs, outputs=[wp.zeros(4, dtype=float, requires_grad=True)],
                                   eps=1e-4, atol=1e-3, rtol=1e-3, show_summary=False, raise_exception=False)
    shapes = [light_shape(warprt.Light(type="spot", position=(0.4, 2.0, 0.3), direction=(-0.2, -1.0, -0.1),
                                       cutoff_angle=35.0, beam_width=15.0, falloff="inverse_square")),
              light_shape(warprt.Light(position=(0.0, 1.0, 0.0), falloff="inverse_square")),
              light_shape(warprt.Light(type="directional", direction=(0.3, -1.0, -0.2)))]
    vec = lambda rows: wp.array(np.asarray(rows, np.float32), dtype=wp.vec3, requires_grad=True)  # noqa: E731
    inputs = [vec([[0.4, 2.0, 0.3], [-0.3, 1.2, 0.4], [0.0, 0.0, 0.0]]), vec([[5.0, 4.0, 3.0], [2.0, 2.0, 1.0],
                                                                               [0.5, 0.6, 0.7]]),
              wp.array(shapes, dtype=LightShape), vec([[0.1, 0.0, 0.2], [0.3, 0.0, -0.2], [-0.1, 0.0, 0.1]]),
              vec([[0.0, 1.0, 0.1], [0.1, 1.0, 0.0], [0.0, 1.0, -0.2]]), vec([[0.5, 0.4, 0.3]] * 3),
              vec([[0.3, 0.3, 0.3]] * 3)]
    assert warp.autograd.gradcheck(_lit, dim=3, inputs=inputs, outputs=[wp.zeros(3, dtype=wp.vec3, requires_grad=True)],
                                   eps=1e-4, atol=2e-3, rtol=2e-3, show_summary=False, raise_exception=False)
