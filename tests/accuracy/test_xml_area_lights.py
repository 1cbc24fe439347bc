"""Mitsuba's Cornell box (scenes/cornell_box.xml, mi.cornell_box() as Mitsuba writes it) lit by its own
``area`` emitter: warprt's deterministic area light against Mitsuba's ``direct`` integrator on the same
file, converged, and two wrong readings of the emitter that the comparison must catch.

Both images are box-filtered pixel means (warprt: SPP stratified samples; Mitsuba: the file's sensor with
a box filter instead of its gaussian, MITSUBA_SPP independent samples), so that they differ only by
Mitsuba's noise and warprt's LIGHT_SAMPLES stratified points on the emitter. Measured (64 x 64):
SSIM 0.9984, mean |difference| 1.8% of the mean (Mitsuba against itself at another seed: 0.9997, 0.9%).
"""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import warprt
from reference import mitsuba_variant
from reference.compare import metrics
from reference.mitsuba_direct import render_direct

pytestmark = [pytest.mark.accuracy, pytest.mark.slow]

SCENE = Path(__file__).resolve().parents[2] / "scenes" / "cornell_box.xml"
SSIM_MIN = 0.98
MEAN_REL_MAX = 0.03  # mean |warprt - Mitsuba| over Mitsuba's mean, both clamped as metrics() clamps
MITSUBA_SPP = 1024
LIGHT_SAMPLES = 64
SPP = 16


@pytest.fixture(scope="module")
def mi():
    mitsuba_variant()
    import mitsuba

    return mitsuba


def mean_rel(ours, theirs) -> float:
    a, b = np.clip(ours, 0.0, 1.0), np.clip(theirs, 0.0, 1.0)
    return float(np.abs(a - b).mean() / b.mean())


@pytest.fixture(scope="module")
def scene():
    return warprt.load_scene(SCENE, {"render.light_samples": LIGHT_SAMPLES, "render.spp": SPP})


@pytest.fixture(scope="module")
def theirs(mi):
    return render_direct(SCENE, MITSUBA_SPP, seed=0)


def render(scene) -> np.ndarray:
    return warprt.render(scene).image.astype(np.float64)


def with_area_light(scene, **changes):
    """The scene with its one area light changed."""
    (i,) = [i for i, l in enumerate(scene.lights) if l.area]
    lights = list(scene.lights)
    lights[i] = replace(lights[i], **changes)
    return replace(scene, lights=lights)


def test_mitsubas_noise_is_well_below_the_threshold(mi, theirs):
    other = render_direct(SCENE, MITSUBA_SPP, seed=1)
    ssim = metrics(theirs, other)[0]
    print(f"Mitsuba direct {MITSUBA_SPP} spp, seed 0 against seed 1: SSIM {ssim:.4f}, mean |diff| {mean_rel(other, theirs):.4f}")
    assert 1.0 - ssim <= 0.25 * (1.0 - SSIM_MIN)


def test_cornell_box_is_mitsubas_direct_render(scene, theirs):
    ours = render(scene)
    ssim, rel = metrics(ours, theirs)[0], mean_rel(ours, theirs)
    ratio = np.clip(ours, 0.0, 1.0).mean() / np.clip(theirs, 0.0, 1.0).mean()
    print(f"warprt (light_samples {LIGHT_SAMPLES}, spp {SPP}) vs Mitsuba direct ({MITSUBA_SPP} spp): "
          f"SSIM {ssim:.4f}, mean |diff| {rel:.4f} of the mean, ratio of means {ratio:.4f}")
    assert ssim >= SSIM_MIN and rel <= MEAN_REL_MAX


@pytest.mark.parametrize("spread", [False, True])
def test_the_analytic_estimator_is_mitsubas_direct_render_too(scene, theirs, spread):
    """render.area_estimator = "analytic" (the emitter's diffuse term in closed form, its points estimating
    its visibility), with and without light_spread: the same function as Mitsuba's (measured: SSIM 0.9984,
    mean |diff| 1.73%; spread (4 of the 64 points a pixel sample): 0.9983, 1.85%; the sampled estimator's: 0.9984,
    1.79%; Mitsuba's own noise at 1024 spp dominates them all)."""
    ours = render(scene.with_render(area_estimator="analytic", light_spread=spread))
    ssim, rel = metrics(ours, theirs)[0], mean_rel(ours, theirs)
    print(f"warprt analytic{' spread' if spread else ''} vs Mitsuba direct: SSIM {ssim:.4f}, mean |diff| {rel:.4f}")
    assert ssim >= SSIM_MIN and rel <= MEAN_REL_MAX


def test_the_analytic_light_from_the_wrong_side_fails(scene, theirs):
    """The negative control of the closed form: the emitter's triangles wound the other way light nothing
    below them in the closed form either (it is one-sided, as Mitsuba's area emitter)."""
    name = next(l.object for l in scene.lights if l.area)
    objects = [replace(o, faces=o.faces[:, ::-1].copy()) if o.name == name else o for o in scene.objects]
    ours = render(replace(scene, objects=objects).with_render(area_estimator="analytic"))
    ssim, rel = metrics(ours, theirs)[0], mean_rel(ours, theirs)
    print(f"analytic, emitting upwards: SSIM {ssim:.4f}, mean |diff| {rel:.4f}")
    assert ssim < SSIM_MIN and rel > MEAN_REL_MAX


def test_halved_radiance_fails(scene, theirs):
    light = next(l for l in scene.lights if l.area)
    ours = render(with_area_light(scene, radiance=tuple(0.5 * x for x in light.radiance)))
    ssim, rel = metrics(ours, theirs)[0], mean_rel(ours, theirs)
    print(f"radiance halved: SSIM {ssim:.4f}, mean |diff| {rel:.4f}")
    assert ssim < SSIM_MIN or rel > MEAN_REL_MAX
    assert rel > 10 * MEAN_REL_MAX / 3  # not a near miss


def test_light_from_the_wrong_side_fails(scene, theirs):
    """The emitter's triangles wound the other way: it lights the ceiling a centimetre above it."""
    name = next(l.object for l in scene.lights if l.area)
    objects = [replace(o, faces=o.faces[:, ::-1].copy()) if o.name == name else o for o in scene.objects]
    ours = render(replace(scene, objects=objects))
    ssim, rel = metrics(ours, theirs)[0], mean_rel(ours, theirs)
    print(f"emitting upwards: SSIM {ssim:.4f}, mean |diff| {rel:.4f}")
    assert ssim < SSIM_MIN and rel > MEAN_REL_MAX


def test_info_gives_the_emitters_area_and_power_as_mitsuba_measures_them(mi, capsys):
    """`warprt info`'s area is Mitsuba's own shape.surface_area() of the emitting shape, and its power
    pi L_e A per channel (a one-sided Lambertian emitter's flux); a light at half the radiance reads half."""
    from warprt.cli import main

    assert main(["info", str(SCENE)]) == 0
    import re

    found = re.search(r"radiance \[[^]]*\] area (\S+) power \[([^]]*)\]", capsys.readouterr().out)
    area, power = float(found[1]), [float(x) for x in found[2].split(",")]
    shape = next(s for s in mi.load_file(str(SCENE)).shapes() if s.is_emitter())
    theirs = float(np.asarray(shape.surface_area()).ravel()[0])
    assert area == pytest.approx(theirs, rel=1e-5)
    radiance = np.asarray(mi.traverse(shape.emitter())["radiance.value"]).ravel()
    assert power == pytest.approx([np.pi * float(c) * theirs for c in radiance], rel=1e-5)
    # The negative control: the power is not the radiance times the area without pi.
    assert power != pytest.approx([float(c) * theirs for c in radiance], rel=1e-2)


def test_compare_refuses_the_estimators_its_reference_does_not_integrate(scene, mi):
    """`warprt compare`'s reference sums warprt's own light points (the sampled estimator): the analytic one and the
    spread are refused in one line naming their field, not shown as a difference; the sampled one is compared
    (the control)."""
    from reference import compare

    small = scene.with_camera(width=16, height=16).with_render(spp=4, light_samples=4)
    for changes, field in ((dict(area_estimator="analytic"), r"render\.area_estimator"), (dict(light_spread=True), r"render\.light_spread")):
        with pytest.raises(warprt.SceneError, match=field):
            compare(small.with_render(**changes))
    assert compare(small).ssim > 0.99
