"""render.area_estimator = "analytic" and render.light_spread (issue 39): a rectangle's (or a mesh light's)
unshadowed diffuse term in closed form (Arvo's polygon irradiance, clipped to the receiver's hemisphere)
times the ratio estimate of its visibility over the light's points; and each pixel sample taking its own
share of the points. Checked against a textbook closed form with a single light sample, against the sampled
estimator at 64 x 64 points (the same function), and for what each option must leave alone; each with a
control that fails the same check."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import warprt
from warprt import SceneError

from marks import exhaustive
from oracle.area import corner_rectangle_irradiance, corner_rectangle_without_emitter_cosine

KD = 0.5
L_E = 2.0
A, B, C = 1.0, 0.6, 0.8  # the rectangle over a corner (Howell B-3)
CORNELL = Path(__file__).resolve().parents[2] / "scenes" / "cornell_box.xml"


def floor_point(light, samples: int, estimator: str, shadows: bool = True) -> float:
    """The radiance of a Lambertian floor (kd = KD) at the origin under ``light``: one pixel seen from the side."""
    scene = warprt.load_dict({
        "camera": {"eye": [3.0, 0.5, 0.0], "center": [0.0, 0.0, 0.0], "width": 1, "height": 1},
        "render": {"ambient": [0.0] * 3, "light_samples": samples, "max_depth": 1, "shadows": shadows,
                   "area_estimator": estimator},
        "lights": [light], "materials": {"floor": {"kd": [KD] * 3, "ks": [0.0] * 3}},
        "objects": [{"shape": "plane", "size": [12.0, 12.0], "material": "floor"}]})
    return float(warprt.render(scene, primary_query="raytrace").image[0, 0, 1])


def corner_rectangle() -> dict:
    return {"type": "area", "radiance": [L_E] * 3, "shape": "rectangle", "center": [A / 2, C, B / 2],
            "u": [A / 2, 0.0, 0.0], "v": [0.0, 0.0, B / 2]}


def test_an_unoccluded_point_is_the_closed_form_with_one_light_sample():
    """kd pi L F (Howell's parallel rectangle over a corner) from a single point and its shadow ray: the ratio
    estimate of an unoccluded point is 1, so only float32 rounding is left (measured: -5.6e-7). The controls:
    the sampled estimator's one point (-1.7%), and the closed form without the emitter's cosine (-17%)."""
    expected = KD * corner_rectangle_irradiance(L_E, A, B, C)
    analytic = floor_point(corner_rectangle(), 1, "analytic")
    assert analytic == pytest.approx(expected, rel=1e-5)
    assert abs(floor_point(corner_rectangle(), 1, "samples") / expected - 1.0) > 1e-2
    assert abs(analytic / (KD * corner_rectangle_without_emitter_cosine(L_E, A, B, C)) - 1.0) > 0.1


def test_the_closed_form_is_one_sided():
    """The rectangle turned to face up lights nothing below it, as with its samples."""
    up = {**corner_rectangle(), "v": [0.0, 0.0, -B / 2], "center": [A / 2, C, -B / 2]}
    assert floor_point(up, 16, "analytic") == 0.0 and floor_point(corner_rectangle(), 16, "analytic") > 0.0


def tilted_room(estimator: str, samples: int, shadows: bool = True, spp: int = 1, spread: bool = False):
    """A rectangle light and an emitting box (an object light) over a floor, a smooth sphere and a tilted
    panel: receivers whose horizon cuts through the lights (the clipped polygon) and soft shadows."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 2.5, 5.0], "center": [0.0, 0.6, 0.0], "fovy": 45, "width": 40, "height": 30},
        "render": {"ambient": [0.0] * 3, "light_samples": samples, "max_depth": 1, "shadows": shadows,
                   "area_estimator": estimator, "spp": spp, "light_spread": spread},
        "lights": [{"type": "area", "radiance": [3.0, 2.5, 2.0], "shape": "rectangle", "center": [-0.5, 1.6, 0.0],
                    "u": [0.8, 0.0, 0.0], "v": [0.0, 0.0, 0.5]},
                   {"type": "area", "radiance": [1.0, 1.5, 3.0], "object": "lamp"}],
        "materials": {"grey": {"kd": [0.3] * 3, "ks": [0.0] * 3}, "lamp": {"kd": [0.1] * 3}},
        "objects": [{"shape": "plane", "size": [8.0, 8.0], "material": "grey"},
                    {"shape": "sphere", "subdivisions": 3, "smooth": True, "translate": [0.0, 0.6, 0.0],
                     "scale": 0.6, "material": "grey"},
                    {"shape": "plane", "size": [1.5, 1.5], "rotate": [60.0, 30.0, 0.0], "translate": [1.4, 0.8, -0.5],
                     "material": "grey"},
                    {"shape": "box", "name": "lamp", "translate": [1.0, 1.7, 0.8], "scale": [0.2] * 3,
                     "material": "lamp"}]})


def mean_rel(a, b) -> float:
    return float(np.abs(a - b).mean() / b.mean())


@pytest.mark.parametrize("shadows", [pytest.param(False, marks=exhaustive), True])
def test_the_closed_form_is_the_sampled_integral_at_many_points(shadows):
    """Analytic against sampled at 64 x 64 points, both estimating the same integral: unshadowed, the closed
    form over the hemisphere-clipped polygons (the sphere's and the panel's horizons cut the lights); shadowed,
    its ratio estimate too (measured: 4.6e-5 and 5.3e-5 of the mean). The control: the sampled estimator at
    4 x 4 points is more than ten times as far from it (1.2e-2 and 2.4e-2; the analytic one at 4 x 4 points:
    4.6e-5 unshadowed, exact but for the 64 x 64 points' own error, and 1.5e-2 shadowed). make test runs the
    shadowed case, whose closed form is the unshadowed one's; make test-exhaustive both."""
    ours = warprt.render(tilted_room("analytic", 4096, shadows)).image
    sampled = warprt.render(tilted_room("samples", 4096, shadows)).image
    coarse = warprt.render(tilted_room("samples", 16, shadows)).image
    bound = 5e-4
    assert mean_rel(ours, sampled) < bound
    assert mean_rel(coarse, sampled) > 10 * mean_rel(ours, sampled) and mean_rel(coarse, sampled) > bound


def test_a_sphere_above_the_horizon_is_its_closed_form_with_one_light_sample():
    """A sphere light of radius R, its centre D above the point: kd pi L R^2 / D^2 from one point (measured:
    -1.9e-7); the sampled estimator's one point is the control (-82%; at 16 points +4.1%)."""
    sphere = {"type": "area", "radiance": [L_E] * 3, "shape": "sphere", "center": [0.3, 1.2, -0.2], "radius": 0.25}
    d2 = 0.3 ** 2 + 1.2 ** 2 + 0.2 ** 2
    expected = KD * np.pi * L_E * 0.25 ** 2 / d2 * (1.2 / np.sqrt(d2))
    assert floor_point(sphere, 1, "analytic") == pytest.approx(expected, rel=1e-5)
    assert abs(floor_point(sphere, 1, "samples") / expected - 1.0) > 0.1


def test_disks_and_spheres_the_horizon_cuts_stay_on_their_samples():
    """No closed form is used for a disk light, nor for a sphere light partly below a point's horizon: the
    analytic option renders them as the samples do, to the bit (a sphere light on the floor, half below every
    floor point's horizon); a rectangle beside them it changes (the control)."""
    disk = {"type": "area", "radiance": [2.0] * 3, "shape": "disk", "center": [0.3, 1.0, 0.2],
            "normal": [0.0, -1.0, 0.0], "radius": 0.3}
    sphere = {"type": "area", "radiance": [1.0] * 3, "shape": "sphere", "center": [-0.5, 0.0, 0.0], "radius": 0.2}

    def pixels(lights, estimator):
        return warprt.render(warprt.load_dict({
            "camera": {"eye": [0.0, 2.0, 3.0], "center": [0.0, 0.0, 0.0], "width": 16, "height": 12},
            "render": {"light_samples": 16, "area_estimator": estimator, "ambient": [0.0] * 3},
            "lights": lights, "objects": [{"shape": "plane", "size": [4.0, 4.0]}]})).image

    assert np.array_equal(pixels([disk, sphere], "analytic"), pixels([disk, sphere], "samples"))
    assert not np.array_equal(pixels([disk, corner_rectangle()], "analytic"), pixels([disk, corner_rectangle()], "samples"))


def test_spread_light_samples_trace_a_pixel_samples_share():
    """With light_spread, 4 pixel samples and 4 x 4 points each take 4 of them: a quarter of the shadow rays
    (the control: without it, every pixel sample traces all 16)."""
    spread = warprt.render(tilted_room("samples", 16, spp=4, spread=True)).stats.rays["shadow"]
    every = warprt.render(tilted_room("samples", 16, spp=4)).stats.rays["shadow"]
    assert 0 < spread and abs(spread / every - 0.25) < 0.01


def test_spread_light_samples_converge_to_the_same_image():
    """Spread over 4 pixel samples at 32 x 32 points against every pixel sample taking them all: the same
    function, the difference (the pixel samples' hit points differ) falling as the points grow (measured: 3.4e-3
    of the mean at 32 x 32, 1.6e-3 at 64 x 64); the control, 2 x 2 points taken by every sample, is far beyond
    (8.7e-2)."""
    spread = warprt.render(tilted_room("samples", 1024, spp=4, spread=True)).image
    every = warprt.render(tilted_room("samples", 1024, spp=4)).image
    coarse = warprt.render(tilted_room("samples", 4, spp=4)).image
    assert mean_rel(spread, every) < 6e-3 < mean_rel(coarse, every)


@pytest.mark.parametrize("algorithm", ["raytrace", "zbuffer"])
def test_spread_with_supersampling_switched_off_takes_every_point(algorithm):
    """One sample a pixel (disable=["supersampling"]) has nothing to spread over: light_spread then renders what
    every point gives, to the bit, in the tracer and the Z-buffer alike; with its 4 samples it does not (the
    control)."""
    def image(spread, **kw):
        return warprt.render(tilted_room("samples", 16, spp=4, spread=spread), algorithm=algorithm, **kw).image

    off = ["supersampling"]
    assert np.array_equal(image(True, disable=off), image(False, disable=off))
    assert not np.array_equal(image(True), image(False))


def test_the_gradient_refuses_the_new_estimators_in_one_line():
    """render(grad=True) names render.area_estimator (and render.light_spread) rather than differentiate a term
    its replay does not have; with the samples it renders (the control)."""
    for estimator, spread, field in (("analytic", False, "render.area_estimator"), ("samples", True, "render.light_spread")):
        with warprt.Renderer(tilted_room(estimator, 4, spp=4, spread=spread)) as r:
            with pytest.raises(SceneError, match=field.replace(".", r"\.")):
                r.render(grad=True)
    with warprt.Renderer(tilted_room("samples", 4, spp=4)) as r:
        r.render(grad=True)


def test_a_bad_estimator_is_one_line_naming_it():
    with pytest.raises(SceneError, match=r"render\.area_estimator"):
        warprt.load_dict({"render": {"area_estimator": "exact"}})
    with pytest.raises(SceneError, match=r"render\.light_spread"):
        warprt.load_dict({"render": {"light_spread": 1}})
    assert warprt.load_dict({"render": {"area_estimator": "analytic"}}).render.area_estimator == "analytic"


def test_the_flags_set_the_estimator_and_the_spread(tmp_path):
    """`warprt render --area-estimator analytic --light-spread` renders what the two --set overrides render, and
    not what the defaults render (the control): the flags reach the kernel."""
    from warprt.cli import main

    def render(*flags):
        out = tmp_path / f"{len(list(tmp_path.iterdir()))}.npy"
        assert main(["render", str(CORNELL), "--width", "24", "--height", "24", "--spp", "4", "-o", str(out), "-q",
                     *flags]) == 0
        return np.load(out)

    flags = render("--area-estimator", "analytic", "--light-spread")
    setting = render("--set", 'render.area_estimator="analytic"', "--set", "render.light_spread=true")
    assert np.array_equal(flags, setting) and not np.array_equal(flags, render())
