"""Gradients of a supersampled image (render.spp = k^2 > 1): the record follows each of a pixel's k x k
camera rays from where the trace kernel puts it (the centre of its stratum), the replay shades each and
the image is their mean. Checked three ways, each with a control that fails:

- the replayed image is the forward's, to float32 rounding (the control: the pixel centres' rays alone);
- directional derivatives along a random direction equal central finite differences of the forward
  (pixels where the differences at h and h/2 disagree, an edge crossed, masked; none here), the mirroring
  floor's second level included (the control: the gradient of the centres' rays alone);
- the floor's vertices, through the hit of every sample's ray.

Measured (24 x 18, spp 4, two levels): relative errors 1.4e-5 to 1.9e-4; the centres' rays alone 1e-2 to
0.51 (the controls take those above 3e-2).
"""

from __future__ import annotations

import numpy as np
import pytest

import warprt
from warprt.scene import resolve_effects

from .directional import backward_masked, directional, random_direction
from .test_first_hit_gradients import floor_scene, scene

WIDTH, HEIGHT = 24, 18
REL = 2e-3  # measured: 1e-5 to 2e-4
NAMES = ["materials.ball.kd", "materials.floor.ks", "materials.ball.shininess", "materials.floor.reflectivity",
         "lights.0.position", "lights.1.color", "lights.1.position"]


def supersampled(spp: int = 4, max_depth: int = 2):
    """The shiny sphere on a mirroring floor (k_r 0.5, 0.4, 0.3) under two lights, with shadows."""
    return scene({"materials.floor.reflectivity": [0.5, 0.4, 0.3]}, max_depth=max_depth, spp=spp).with_camera(
        width=WIDTH, height=HEIGHT)


@pytest.fixture(scope="module")
def weights():
    return np.random.default_rng(11).random((HEIGHT, WIDTH, 3)).astype(np.float32)


def replayed(s) -> np.ndarray:
    r = warprt.Renderer(s)
    r.render()
    geom = r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    assert hits.samples == s.render.spp
    return warprt.image.replay_image(s, geom, hits, "cpu")


@pytest.mark.parametrize("spp, max_depth", [(4, 2), (9, 3)])
def test_the_replayed_image_is_the_forward_image(spp, max_depth):
    s = supersampled(spp, max_depth)
    forward = warprt.render(s, threads=1)[0]
    assert np.abs(replayed(s) - forward).max() <= 4e-7 * max(1.0, np.abs(forward).max())


def test_the_pixel_centres_alone_do_not_replay_it():
    """The control: the centre's ray of each pixel (the record of spp 1) misses the forward's image by
    far more than rounding where the samples of a pixel see different things (edges, shadows)."""
    forward = warprt.render(supersampled(4), threads=1)[0]
    assert np.abs(replayed(supersampled(1)) - forward).max() > 1e-2


@pytest.fixture(scope="module")
def checks(weights):
    """{name: (Directional along a random step of that parameter, its gradient, the centres' gradient)}."""
    s = supersampled()
    out = {}
    for name in NAMES:
        d = directional(s, random_direction(s, [name]), weights)
        out[name] = (d, backward_masked(s, weights, d), backward_masked(supersampled(1), weights, d))
    return out


@pytest.mark.parametrize("name", NAMES)
def test_supersampled_gradients_equal_central_differences(checks, name):
    d, grads, _ = checks[name]
    assert d.masked < 0.05
    assert d.error(grads) <= REL, (d.gradient(grads), d.fd)


@pytest.mark.parametrize("name", ["materials.ball.kd", "materials.ball.shininess", "materials.floor.reflectivity",
                                  "lights.0.position"])
def test_the_pixel_centres_gradients_do_not(checks, name):
    """The control: the same parameters' gradients from the centres' rays alone (spp 1) against the
    differences of the supersampled render."""
    d, _, centres = checks[name]
    assert d.error(centres) > 10 * REL


def test_vertex_gradients_of_every_sample_equal_central_differences(weights):
    """The floor's four vertices along a random direction, every sample's hit sliding over the moved
    triangles (floor_scene: no edge of the floor in view, no shadows). The floor's shading varies
    smoothly, so the centres' rays alone give nearly its gradient (2e-3 off): the control here is the
    gradient along another random direction."""
    s = floor_scene().with_camera(width=WIDTH, height=HEIGHT).with_render(spp=4)
    name = "objects.floor.vertices"
    d = directional(s, random_direction(s, [name], rel=0.05), weights)
    assert d.masked < 0.05
    grads = backward_masked(s, weights, d)
    assert d.error(grads) <= REL
    other = random_direction(s, [name], seed=4, rel=0.05)[name]
    assert abs((grads[name] * other).sum() - d.fd) > 0.1 * abs(d.fd)


def test_a_record_beyond_memory_is_refused_in_one_line():
    """16384^2 pixels of 4096 samples would need about 40 TB of record: refused before anything is
    allocated, naming the settings that reduce it."""
    s = warprt.load_dict({"camera": {"width": 16384, "height": 16384}, "render": {"spp": 4096},
                          "lights": [{"position": [0.0, 3.0, 3.0]}], "objects": [{"shape": "sphere"}]})
    with pytest.raises(warprt.SceneError, match="render.spp, render.max_depth or camera.width"):
        warprt.Renderer(s).render(grad=True)
