"""Gradients of a scene with vertex colours (issue 30): the colours multiply ka and kd at the hit,
interpolated at its barycentrics (shading.make_coefficients, interaction.make_surface); the replay calls those
very functions over a differentiable per-vertex array, so such scenes are differentiated for every parameter,
and objects.<name>.colors is one more. Checked:

- the replayed image is the forward's (camera rays and a mirror's level; the camera replay too);
- directional derivatives along random directions equal central finite differences of the forward
  (tests/grad/directional.py, edges masked): the colours alone, the colours with a material, a light's
  position and colour, and the coloured object's vertices with the camera's eye (the hits slide, the colours
  read at the moved barycentrics);
- warp.autograd.gradcheck of the hit record's colour (make_surface) in the colours and the moving ray's
  barycentrics: tests/grad/test_replay_functions.py;
- controls that fail: the colours ignored in the replay (kd's gradient then misses them), the colours'
  gradient read along another direction.
Mitsuba's AD of the same colours (its Attributes BSDF's vertex_color attribute):
tests/accuracy/test_gradients_against_mitsuba.py.
"""

from __future__ import annotations

import numpy as np
import pytest
import warp as wp
import warp.autograd

import warprt
from warprt.scene import resolve_effects

from .directional import backward_masked, directional, random_direction

WIDTH, HEIGHT = 24, 18
TOL = 1e-2
QUAD = [[-1.2, 0.1, -0.6], [1.2, 0.1, -0.4], [1.1, 1.7, -0.9], [-1.1, 1.6, -1.0]]
QUAD_COLORS = [[0.9, 0.2, 0.1], [0.2, 0.8, 0.3], [0.1, 0.3, 0.9], [0.8, 0.8, 0.2]]
FAN = [[-0.6, 0.05, 0.6], [0.2, 0.05, 0.9], [-0.1, 0.7, 0.5]]
FAN_COLORS = [[1.0, 0.5, 0.2], [0.3, 1.0, 0.6], [0.5, 0.4, 1.0]]


def scene(max_depth: int = 2):
    """A coloured quad standing on a weakly mirroring floor (its colours seen directly and in the floor), a
    coloured triangle before it casting a shadow on it, two lights (one with falloff); ``max_depth`` levels."""
    return warprt.load_dict({
        "camera": {"eye": [0.2, 1.4, 4.0], "center": [0.0, 0.6, 0.0], "width": WIDTH, "height": HEIGHT, "fovy": 45.0},
        "render": {"ambient": [0.2] * 3, "max_depth": max_depth},
        "lights": [{"position": [2.0, 4.0, 3.0], "color": [0.8, 0.8, 0.7]},
                   {"position": [-2.5, 2.5, 2.0], "color": [6.0, 5.0, 4.0], "falloff": "inverse_square"}],
        "materials": {"floor": {"kd": [0.4, 0.35, 0.3], "ks": [0.2] * 3, "shininess": 16.0, "reflectivity": [0.3] * 3},
                      "paint": {"kd": [0.8, 0.7, 0.9], "ks": [0.3] * 3, "shininess": 20.0},
                      "fan": {"kd": [0.7, 0.7, 0.7], "ka": [0.5, 0.4, 0.3], "ks": [0.4] * 3, "shininess": 30.0}},
        "objects": [{"shape": "plane", "name": "floor", "size": [30.0, 30.0], "material": "floor"},
                    {"shape": "triangles", "name": "quad", "vertices": QUAD, "faces": [[0, 1, 2], [0, 2, 3]],
                     "colors": QUAD_COLORS, "material": "paint"},
                    {"shape": "triangles", "name": "fan", "vertices": FAN, "faces": [[0, 1, 2]],
                     "colors": FAN_COLORS, "material": "fan"}]})


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(13).random((HEIGHT, WIDTH, 3)).astype(np.float32)


@pytest.mark.parametrize("camera", [False, True], ids=["recorded rays", "camera replay"])
def test_the_replayed_image_is_the_forward_image(camera):
    s = scene()
    r = warprt.Renderer(s)
    forward = r.render().image
    geom = r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    replayed = warprt.image.replay_image(s, geom, hits, "cpu", camera=camera)
    r.close()
    assert np.abs(replayed - forward).max() <= 2e-6 * max(1.0, float(forward.max()))
    assert resolve_effects(s).vertex_color


@pytest.fixture(scope="module")
def colour_differences(weights):
    s = scene()
    return directional(s, random_direction(s, ["objects.quad.colors", "objects.fan.colors"], seed=3, rel=0.2), weights,
                       h=1e-2)


def test_the_colours_gradient_equals_central_differences(weights, colour_differences):
    """The image is linear in the colours (no edge moves): nothing is masked."""
    d = colour_differences
    assert d.masked == 0.0
    g = backward_masked(scene(), weights, d)
    assert d.error(g) <= TOL
    other = directional(scene(), random_direction(scene(), list(d.direction), seed=4, rel=0.2), weights, h=1e-2)
    assert abs(other.gradient(g) - d.fd) > 0.1 * abs(d.fd)  # the control: read along another direction


def test_colours_materials_and_lights_together_equal_central_differences(weights):
    s = scene()
    names = ["objects.quad.colors", "materials.paint.kd", "materials.fan.ka", "lights.0.position", "lights.1.color"]
    d = directional(s, random_direction(s, names, seed=5, rel=0.01), weights, h=1e-2)
    assert d.masked < 0.1
    assert d.error(backward_masked(s, weights, d)) <= TOL


def test_the_coloured_objects_vertices_and_the_camera_equal_central_differences(weights):
    """The quad's and the triangle's vertices and the eye: the hits slide over the moved faces (seen directly
    and in the floor), each reading the colours at its moved barycentrics; the pixels whose face changes are
    masked (same_faces), as the silhouettes and the shadow's edge move."""
    s = scene()
    names = ["objects.quad.vertices", "objects.fan.vertices", "camera.eye"]
    d = directional(s, random_direction(s, names, seed=6, rel=0.01), weights, h=1e-2, same_faces=True)
    assert d.masked < 0.2
    assert d.error(backward_masked(s, weights, d)) <= TOL


def _taped_kd(s, weights, mask, white: bool) -> np.ndarray:
    """The paint's kd adjoint from the replay launched by hand (warprt.image.build_replay); with ``white``,
    its vertex colours (the replay's SceneData's) replaced by white: the control's replay that ignores them."""
    r = warprt.Renderer(s)
    r.render()
    geom = r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    replay = warprt.image.build_replay(s, geom, hits, "cpu")
    if white:
        replay.data.colors = wp.array(np.ones((len(geom.points_np), 3), np.float32), dtype=wp.vec3)
    tape = wp.Tape()
    with tape:
        replay.launch()
    tape.backward(grads={replay.colour: wp.array((weights * mask).reshape(-1, 3), dtype=wp.vec3)})
    r.close()
    slot = geom.material_names.index("paint")  # its ka follows kd: r.params' kd carries ka's gradient too
    return (replay.arrays["kd"].grad.numpy()[slot] + replay.arrays["ka"].grad.numpy()[slot]).astype(np.float64)


def test_the_colours_ignored_are_not_the_differences(weights):
    """The control: kd's gradient with the replay's colours white (as before vertex colours were replayed)
    misses their factor; unedited, the hand-launched replay is backward()'s."""
    s = scene(max_depth=1)
    d = directional(s, random_direction(s, ["materials.paint.kd"], seed=7, rel=0.2), weights, h=1e-2)
    right = _taped_kd(s, weights, d.mask, white=False)
    np.testing.assert_allclose(right, backward_masked(s, weights, d)["materials.paint.kd"], rtol=1e-6, atol=1e-6)
    assert d.error({"materials.paint.kd": right}) <= TOL
    assert d.error({"materials.paint.kd": _taped_kd(s, weights, d.mask, white=True)}) > 0.1


def test_colours_are_parameters_where_an_object_has_them():
    r = warprt.Renderer(scene())
    assert {n for n in r.params if n.endswith(".colors")} == {"objects.quad.colors", "objects.fan.colors"}
    np.testing.assert_array_equal(r.params["objects.quad.colors"], QUAD_COLORS)
    r.close()
