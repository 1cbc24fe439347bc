"""Environment lights (issue 39): a constant sky's light at a point against its closed forms (tests/oracle/
environment.py: pi L on an open plane, less a disk's form factor under a disk), converging as light_samples
grows; the sky seen by camera and mirror rays; the scene file's checks; and kernels without environment code
for scenes without one.

Convention (kernels/shading.py): kd is a BRDF value, so a Lambertian plane of kd = rho / pi under a constant
radiance L (irradiance pi L) has radiance rho L, Mitsuba's diffuse reflectance rho under its constant emitter."""

from __future__ import annotations

import math

import numpy as np
import pytest

import warprt
from warprt import SceneError
from warprt.scene import EffectSet, resolve_effects

from oracle.environment import sky_irradiance, sky_irradiance_under_a_disk
from scenekit import trace_kernel_source

L = 0.8  # the sky's radiance
RHO = 0.6  # the plane's reflectance
MATERIALS = {"floor": {"kd": [RHO / math.pi] * 3, "ks": [0.0] * 3}, "black": {"kd": [0.0] * 3, "ks": [0.0] * 3},
             "mirror": {"kd": [0.0] * 3, "ks": [0.0] * 3, "reflectivity": 1.0}}
SKY = {"type": "environment", "radiance": [L] * 3}
R, D = 0.5, 1.0  # the disk above the point: radius, height
DISK = {"shape": "cylinder", "radius": R, "height": 0.001, "sections": 256, "translate": [0.0, D, 0.0],
        "material": "black"}
TILT = [25.0, 0.0, 10.0]


def plane_scene(samples: int, rotate=(0.0, 0.0, 0.0), objects=(), sky=SKY, spp: int = 1, spread: bool = False):
    """A 2 x 2 plane of reflectance RHO at the origin, turned by ``rotate``, and a one-pixel camera looking at its
    centre from above and aside (a 2 degree field: every pixel sample meets the plane), below every blocker."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 0.5, 3.0], "center": [0.0, 0.0, 0.0], "fovy": 2.0, "width": 1, "height": 1},
        "render": {"ambient": [0.0] * 3, "light_samples": samples, "max_depth": 1, "spp": spp, "light_spread": spread},
        "lights": [sky], "materials": MATERIALS,
        "objects": [{"shape": "plane", "size": [2.0, 2.0], "rotate": list(rotate), "material": "floor"}, *objects]})


def plane_point(samples: int, rotate=(0.0, 0.0, 0.0), objects=(), sky=SKY, **render) -> float:
    """The radiance of plane_scene's one pixel."""
    image, _ = warprt.render(plane_scene(samples, rotate, objects, sky), **render)
    return float(image[0, 0, 1])


# (a) the open plane: rho L ------------------------------------------------------------------------

def test_a_level_plane_under_a_constant_sky_is_its_reflectance_times_the_radiance():
    """Facing the environment's pole, the directions' heights integrate the cosine by the midpoint rule: exact
    to float32 (measured: 2e-7)."""
    expected = RHO / math.pi * sky_irradiance(L)
    assert plane_point(64) == pytest.approx(expected, rel=1e-5)


@pytest.fixture(scope="module")
def tilted_errors():
    expected = RHO / math.pi * sky_irradiance(L)
    return {n: abs(plane_point(n, TILT) / expected - 1.0) for n in (16, 256, 1024)}


def test_a_tilted_plane_under_a_constant_sky_is_its_reflectance_times_the_radiance(tilted_errors):
    """Turned off the pole, the lattice's error (measured: 0.9% at 16 directions, 0.06% at 256, 0.01% at 1,024)."""
    assert tilted_errors[1024] < 5e-4 and tilted_errors[256] < 2e-3


def test_the_tilted_planes_error_falls_as_the_light_samples_grow(tilted_errors):
    assert tilted_errors[16] > tilted_errors[256] > tilted_errors[1024]


def test_a_sky_two_percent_brighter_is_caught():
    """The negative control: the tolerance above tells a 2% error from the right answer."""
    expected = RHO / math.pi * sky_irradiance(L)
    assert abs(plane_point(1024, TILT, sky={**SKY, "scale": 1.02}) / expected - 1.0) > 10 * 5e-4


@pytest.mark.parametrize("n", [1024, 961])
def test_directions_spread_over_the_pixel_samples_keep_the_closed_form(n):
    """render.light_spread: each of 16 pixel samples takes every 16th direction of the lattice (64 of 1,024; of
    961 = 31^2 the first sample 61, the others 60), its weights 16 times theirs; over an open plane (the same light
    at every sample) the pixel is the whole lattice's sum, as close to rho L as every sample taking them all (a
    direction missed or taken twice: about 1e-3 off); the control, one sample's share alone (a lattice of 64
    directions), is not."""
    expected = RHO / math.pi * sky_irradiance(L)
    spread = warprt.render(plane_scene(n, TILT, spp=16, spread=True))
    every = warprt.render(plane_scene(n, TILT, spp=16))
    errors = [abs(float(x.image[0, 0, 1]) / expected - 1.0) for x in (spread, every)]
    print(f"spread {errors[0]:.2e}, every {errors[1]:.2e}, 64 alone {abs(plane_point(64, TILT) / expected - 1.0):.2e}")
    assert max(errors) < 5e-4 < abs(plane_point(64, TILT) / expected - 1.0)


def test_directions_spread_over_the_pixel_samples_trace_a_sixteenth_of_the_shadow_rays():
    """That spread is on: a sixteenth of the shadow rays."""
    spread = warprt.render(plane_scene(1024, TILT, spp=16, spread=True)).stats.rays["shadow"]
    every = warprt.render(plane_scene(1024, TILT, spp=16)).stats.rays["shadow"]
    assert 0 < spread and abs(spread / every - 1 / 16) < 1e-3


# (b) the disk overhead: its shadow ---------------------------------------------------------------

def test_a_disk_overhead_takes_its_form_factor_from_the_sky():
    """Measured: 0.02% off at 1,024 directions (2.7% at 64, 0.8% at 256: each direction its own height)."""
    expected = RHO / math.pi * sky_irradiance_under_a_disk(L, R, D)
    assert plane_point(1024, objects=[DISK]) == pytest.approx(expected, rel=2e-3)


def test_without_shadow_rays_the_disk_takes_nothing():
    """The negative control: the shadows switched off leave the open plane's rho L, 25% above the disk's answer."""
    expected = RHO / math.pi * sky_irradiance_under_a_disk(L, R, D)
    unshadowed = plane_point(1024, objects=[DISK], disable=("shadows",))
    assert unshadowed == pytest.approx(RHO * L, rel=1e-3) and unshadowed / expected - 1.0 > 0.2


# (c) the sky seen -------------------------------------------------------------------------------

def _mirror_and_sky(max_depth: int, algorithm: str = "raytrace"):
    scene = warprt.load_dict({
        "camera": {"eye": [0.0, 1.0, 3.0], "center": [0.0, 0.0, 0.0], "width": 16, "height": 12},
        "render": {"ambient": [0.0] * 3, "light_samples": 16, "max_depth": max_depth},
        "lights": [{"type": "environment", "radiance": [0.2, 0.5, 0.9]}], "materials": MATERIALS,
        "objects": [{"shape": "plane", "size": [1.0, 1.0], "material": "mirror"}]})
    return warprt.render(scene, algorithm=algorithm).image


def test_camera_and_mirror_rays_that_meet_nothing_see_the_sky():
    image = _mirror_and_sky(2)
    assert np.allclose(image[0, 0], [0.2, 0.5, 0.9], rtol=1e-6)  # the camera's ray, above the mirror
    assert np.allclose(image[6, 8], [0.2, 0.5, 0.9], rtol=1e-6)  # the mirror's: its kd and ks are 0


def test_a_mirror_without_its_reflection_ray_is_black():
    """The negative control: with one ray level the mirror shows nothing."""
    assert np.allclose(_mirror_and_sky(1)[6, 8], 0.0) and np.allclose(_mirror_and_sky(1)[0, 0], [0.2, 0.5, 0.9])


def test_the_zbuffer_shows_the_sky_where_the_tracer_does():
    image = _mirror_and_sky(1, "zbuffer")
    assert np.array_equal(image[0, 0], _mirror_and_sky(1)[0, 0])


def test_two_renders_are_the_same_to_the_bit():
    first = plane_point(64, TILT, objects=[DISK])
    assert first == plane_point(64, TILT, objects=[DISK]) and first > 0.0


# (d) bad input ----------------------------------------------------------------------------------

@pytest.mark.parametrize("light, field", [
    ({"type": "environment"}, "lights[0].image"),
    ({"type": "environment", "radiance": [1.0] * 3, "image": "sky.hdr"}, "lights[0].image"),
    ({"type": "environment", "radiance": [1.0, -1.0, 1.0]}, "lights[0].radiance"),
    ({"type": "environment", "radiance": [1.0] * 3, "scale": -1.0}, "lights[0].scale"),
    ({"type": "environment", "radiance": [1.0] * 3, "position": [0.0, 1.0, 0.0]}, "lights[0].position"),
    ({"type": "point", "position": [0.0, 1.0, 0.0], "scale": 2.0}, "lights[0].scale"),
    ({"type": "environment", "image": "no such sky.exr"}, "lights[0].image"),
])
def test_a_bad_environment_light_is_one_line_naming_its_field(light, field):
    with pytest.raises(SceneError) as e:
        warprt.load_dict({"lights": [light], "materials": MATERIALS, "objects": [{"shape": "plane", "material": "floor"}]})
    assert f": {field}: " in str(e.value) and "\n" not in str(e.value)


def test_a_background_beside_an_environment_is_refused():
    with pytest.raises(SceneError, match=r"render\.background: the environment light \(lights\[0\]\) is the background"):
        warprt.load_dict({"render": {"background": [0.1] * 3}, "lights": [SKY], "objects": [{"shape": "plane"}]})


def test_a_second_environment_is_refused():
    with pytest.raises(SceneError, match=r"lights\[1\]\.type: a scene has at most one environment light"):
        warprt.load_dict({"lights": [SKY, SKY], "objects": [{"shape": "plane"}]})


# (e) variants and gradients ---------------------------------------------------------------------

def test_only_scenes_with_an_environment_compile_its_variant():
    point = warprt.load_dict({"lights": [{"position": [0.0, 3.0, 0.0]}], "objects": [{"shape": "plane"}]})
    sky = warprt.load_dict({"lights": [SKY], "objects": [{"shape": "plane"}]})
    assert not resolve_effects(point).environment and "E" not in resolve_effects(point).variant
    assert resolve_effects(sky).environment and resolve_effects(sky).variant.endswith("E")


def test_the_environment_code_is_absent_from_the_other_variants():
    """A line of the environment's sum and of its radiance on a miss, as Warp quotes them in the C++."""
    markers = ("out = environment_light(s, hit, k, v, out, stratum)", "environment_radiance(s.env, d)")
    assert not any(m in trace_kernel_source(EffectSet()) for m in markers)
    assert all(m in trace_kernel_source(EffectSet(environment=True)) for m in markers)


def test_a_gradient_of_a_scene_with_an_environment_is_refused_in_one_line():
    scene = warprt.load_dict({"lights": [SKY], "objects": [{"shape": "plane"}], "camera": {"width": 8, "height": 6}})
    r = warprt.Renderer(scene)
    with pytest.raises(warprt.SceneError, match="environment light is not differentiated") as e:
        r.render(grad=True)
    assert "\n" not in str(e.value)
    with pytest.raises(warprt.SceneError, match=r"'lights\.0\.scale': an environment light's scale is not") as e:
        r.render(grad=["lights.0.scale"])


def test_an_environments_scale_is_a_renderer_parameter():
    scene = warprt.load_dict({"lights": [SKY], "render": {"ambient": [0.0] * 3, "light_samples": 16},
                              "objects": [{"shape": "plane", "material": "floor"}], "materials": MATERIALS,
                              "camera": {"width": 8, "height": 6}})
    r = warprt.Renderer(scene)
    before, _ = r.render()
    r.params["lights.0.scale"] = 2.0
    after, _ = r.render()
    assert float(r.params["lights.0.scale"]) == 2.0 and np.allclose(after, 2.0 * before, rtol=1e-6)
