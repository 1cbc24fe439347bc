"""A parameter's true derivative where its value switches an effect off (issue 30: "the gradient render
includes the effects that wrt names, or inverse rendering could never start from zero"):

- a reflectivity of 0: the tracer spawns no mirror ray there, but the derivative is the colour the mirror
  would show. render(grad=[names]) records the named materials' mirror rays whatever their k_r; backward()
  refuses, in one line, a reflectivity of 0 the frame did not record (never a silent 0);
- a ks of 0: the replay shades the specular term whatever the values (the image is the same);
- (a light of colour 0: test_area_light_gradients.py's test_a_dark_light_has_the_shadowed_gradient.)

Each is checked against a one-sided difference from 0: for a fixed ray tree the image is linear in k_r and
in ks (k_r weighs the mirror ray's colour, ks the specular term), so (loss(h e_c) - loss(0)) / h is the
derivative at 0 up to float32 rounding, at any h that changes no face or visibility; here h = 0.1.
"""

from __future__ import annotations

import numpy as np
import pytest
import warp as wp

import warprt
from warprt import SceneError
from warprt.scene import resolve_effects

WIDTH, HEIGHT = 24, 18
REL = 1e-4
H = 0.1


def scene(max_depth: int = 3, **ball):
    """A glossy sphere on a floor of reflectivity 0 (the default), two point lights, shadows."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 2.0, 5.0], "center": [0.0, 0.5, 0.0], "width": WIDTH, "height": HEIGHT},
        "render": {"ambient": [0.2] * 3, "max_depth": max_depth},
        "lights": [{"position": [2.0, 4.0, 3.0], "color": [0.8, 0.8, 0.7]},
                   {"position": [-3.0, 2.5, 1.0], "color": [6.0, 5.0, 4.0], "falloff": "inverse_square"}],
        "materials": {"floor": {"kd": [0.4, 0.35, 0.3], "ks": [0.2] * 3, "shininess": 16.0},
                      "ball": {"kd": [0.6, 0.2, 0.1], "ks": [0.5] * 3, "shininess": 40.0, **ball}},
        "objects": [{"shape": "plane", "size": [8.0, 8.0], "material": "floor"},
                    {"shape": "sphere", "subdivisions": 3, "smooth": True, "translate": [0.0, 0.8, 0.0], "scale": 0.8,
                     "material": "ball"}]})


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(7).random((HEIGHT, WIDTH, 3)).astype(np.float32)


def one_sided(s, name: str, weights) -> np.ndarray:
    """(loss(h e_c) - loss(0)) / h per component of parameter ``name``, at 0."""
    r = warprt.Renderer(s)

    def loss(value) -> float:
        r.params[name] = value
        return float((weights.astype(np.float64) * r.render().image).sum())

    zero = loss([0.0, 0.0, 0.0])
    out = np.asarray([(loss(list(H * e)) - zero) / H for e in np.eye(3)])
    r.close()
    return out


def relative(a, b) -> float:
    return float(np.abs(np.asarray(a) - b).max() / np.abs(b).max())


REFLECTIVITY = "materials.floor.reflectivity"


@pytest.fixture(scope="module")
def reflectivity_differences(weights):
    return one_sided(scene(), REFLECTIVITY, weights)


def test_a_named_reflectivity_of_0_has_the_mirrors_derivative(weights, reflectivity_differences):
    """render(grad=[the floor's reflectivity]): the same image to the bit, the floor's mirror rays recorded
    over max_depth levels, and d/dk_r at 0 the mirrored colour's, as the differences from 0 say."""
    s = scene()
    r = warprt.Renderer(s)
    assert np.array_equal(r.render(grad=[REFLECTIVITY]).image, warprt.render(s).image)
    g = r.backward(weights, wrt=[REFLECTIVITY], edges=False)[REFLECTIVITY]
    assert np.abs(reflectivity_differences).min() > 0.1  # the sphere and the background, mirrored
    assert relative(g, reflectivity_differences) <= REL, (g, reflectivity_differences)
    assert REFLECTIVITY in r.backward(weights, edges=False)  # by default too, once recorded


def test_an_unrecorded_reflectivity_of_0_is_refused_in_one_line(weights, reflectivity_differences):
    """The control: render(grad=True) records no mirror ray at k_r = 0 (the tracer spawns none), and the
    replay of that record gives the reflectivity a derivative of 0, which is wrong; backward() refuses it,
    naming the way to record it, and leaves it out of its default."""
    s = scene()
    r = warprt.Renderer(s)
    r.render(grad=True)
    with pytest.raises(SceneError, match=r"render with grad=\['materials.floor.reflectivity'\]"):
        r.backward(weights, wrt=["materials.ball.kd", REFLECTIVITY])
    assert REFLECTIVITY not in r.backward(weights, edges=False)
    geom = r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    replay = warprt.image.build_replay(s, geom, hits, "cpu")
    tape = wp.Tape()
    with tape:
        replay.launch()
    tape.backward(grads={replay.colour: wp.array(weights.reshape(-1, 3), dtype=wp.vec3)})
    old = replay.arrays["reflectivity"].grad.numpy()[geom.material_names.index("floor")]
    assert np.all(old == 0.0) and relative(old, reflectivity_differences) == 1.0


def test_where_the_frame_cannot_reflect_a_reflectivity_of_0_has_the_derivative_0(weights):
    """At max_depth 1 the tracer follows no mirror ray whatever k_r: the image does not depend on it, and
    its derivative, 0, is given (not refused)."""
    s = scene(max_depth=1)
    r = warprt.Renderer(s)
    r.render(grad=True)
    g = r.backward(weights, wrt=[REFLECTIVITY], edges=False)[REFLECTIVITY]
    assert np.all(g == 0.0) and np.all(one_sided(s, REFLECTIVITY, weights) == 0.0)


def test_grad_names_only_parameters():
    with pytest.raises(SceneError, match="materials.floor.shine"):
        warprt.Renderer(scene()).render(grad=["materials.floor.shine"])


def test_a_ks_of_0_has_the_specular_derivative(weights):
    """Every ks 0 (the ball's; the floor's too): the forward shades no highlight, the replay shades the
    specular term, its derivative the highlight's."""
    s = scene(ks=[0.0] * 3)
    r = warprt.Renderer(s)
    r.params["materials.floor.ks"] = [0.0] * 3
    r.render(grad=True)
    g = r.backward(weights, wrt=["materials.ball.ks"], edges=False)["materials.ball.ks"]
    fd = one_sided(r.scene, "materials.ball.ks", weights)
    r.close()
    assert np.abs(fd).min() > 0.01
    assert relative(g, fd) <= REL, (g, fd)
