"""Point, spot and directional lights and inverse-square falloff on a wall whose hit points are known in
closed form: the irradiance law of a point light, a spot's profile across its cone, a sun's cos law and
its shadows at any distance; a cone a few degrees off must fail (the negative control)."""

import numpy as np
import pytest

import warprt
from scenekit import make_scene
from oracle import camera_rays, light_intensity, phong_terms, ray_plane, spot_profile

KD = np.array([0.5, 0.6, 0.7])
MAT = {"kd": KD.tolist(), "ks": [0.0, 0.0, 0.0]}
WALL = {"shape": "plane", "size": [20.0, 20.0], "rotate": [90.0, 0.0, 0.0], "material": "m"}  # z = 0, facing +z
N = np.array([0.0, 0.0, 1.0])
CAMERA = {"width": 128, "height": 96}


def wall_points(scene):
    """Every pixel's hit on the wall z = 0 (float64), and the view directions."""
    o, d = camera_rays(scene.camera)
    t = ray_plane(o, d, [0, 0, 0], N)
    return o + t[..., None] * d, d


def render(objects, light, **options):
    scene = make_scene(objects, {"m": MAT}, [light], camera=CAMERA)
    return scene, warprt.render(scene, **options).image


def close(image, expect) -> bool:
    # float32 geometry and arithmetic against float64: a wrong law or a cone a degree off is far outside.
    return bool(np.allclose(image, expect, rtol=2e-4, atol=2e-6))


def test_point_light_with_inverse_square_falloff_gives_I_h_over_r_cubed():
    """Irradiance from a point light of intensity I at height h over the wall, at distance r from it:
    I cos(theta) / r^2 = I h / r^3; the pixel is kd times that."""
    light = np.array([0.3, -0.2, 2.0])
    intensity = np.array([2.0, 1.5, 1.0])
    scene, image = render([WALL], {"position": light.tolist(), "color": intensity.tolist(), "falloff": "inverse_square"})
    p, _ = wall_points(scene)
    r = np.linalg.norm(p - light, axis=-1)
    expect = KD * intensity * (light[2] / r**3)[..., None]
    assert close(image, expect)
    assert expect.max() / expect.min() > 5  # the law is seen over a range of distances, not at one


def test_point_light_without_falloff_is_the_seeds():
    light = np.array([0.3, -0.2, 2.0])
    scene, image = render([WALL], {"position": light.tolist(), "color": [2.0, 1.5, 1.0]})
    p, _ = wall_points(scene)
    cos = light[2] / np.linalg.norm(p - light, axis=-1)
    assert close(image, KD * np.array([2.0, 1.5, 1.0]) * cos[..., None])


SPOT = {"type": "spot", "position": [0.2, 0.1, 3.0], "direction": [0.0, 0.0, -1.0], "cutoff_angle": 25.0,
        "beam_width": 10.0, "color": [1.0, 0.9, 0.8]}


def spot_expect(scene, cutoff, beam):
    """kd C_l profile(theta) cos(theta): theta the angle at the spot between its axis (straight down on
    the wall) and the wall point."""
    p, _ = wall_points(scene)
    h = SPOT["position"][2]
    r = np.linalg.norm(p - np.array(SPOT["position"]), axis=-1)
    theta = np.arccos(h / r)
    return KD * np.array(SPOT["color"]) * (spot_profile(theta, cutoff, beam) * h / r)[..., None], theta


def test_spot_profile_across_its_cone():
    """Flat within the beam, Mitsuba's linear ramp in the angle out to the cutoff, dark beyond."""
    scene, image = render([WALL], SPOT)
    expect, theta = spot_expect(scene, 25.0, 10.0)
    assert close(image, expect)
    ramp = (theta > np.radians(10.5)) & (theta < np.radians(24.5))
    assert ramp.sum() > 500 and (theta < np.radians(9.5)).sum() > 100 and (theta > np.radians(25.5)).sum() > 1000
    assert np.all(image[theta > np.radians(25.0) + 1e-4] == 0.0)


@pytest.mark.parametrize("cutoff, beam", [(28.0, 10.0), (22.0, 10.0), (25.0, 13.0), (25.0, 7.0)])
def test_a_cone_a_few_degrees_off_fails_the_profile_test(cutoff, beam):
    """The negative control: the closed form for a cone 3 degrees wider or narrower (cutoff or beam) does
    not match the render."""
    scene, image = render([WALL], SPOT)
    assert not close(image, spot_expect(scene, cutoff, beam)[0])


def test_spot_beam_width_defaults_to_three_quarters_of_the_cutoff():
    scene, image = render([WALL], {k: v for k, v in SPOT.items() if k != "beam_width"})
    assert close(image, spot_expect(scene, 25.0, 18.75)[0])
    assert not close(image, spot_expect(scene, 25.0, 10.0)[0])


def test_spot_given_by_its_target_is_the_same_light():
    by_target = {k: v for k, v in SPOT.items() if k != "direction"}
    by_target["target"] = [0.2, 0.1, -7.0]
    _, image = render([WALL], by_target)
    assert np.array_equal(image, render([WALL], SPOT)[1])


def test_spot_with_inverse_square_falloff_is_profile_times_I_h_over_r_cubed():
    scene, image = render([WALL], {**SPOT, "falloff": "inverse_square"})
    expect, _ = spot_expect(scene, 25.0, 10.0)
    r = np.linalg.norm(wall_points(scene)[0] - np.array(SPOT["position"]), axis=-1)
    assert close(image, expect / (r**2)[..., None])


SUN = np.array([0.3, -0.4, -1.0])  # the direction the light travels


def test_directional_light_follows_the_cos_law_everywhere():
    """kd E cos(alpha) at every pixel, alpha between the wall's normal and the light: no position, no
    falloff, the same value everywhere."""
    color = np.array([0.8, 0.9, 1.0])
    _, image = render([WALL], {"type": "directional", "direction": SUN.tolist(), "color": color.tolist()})
    cos_alpha = -SUN[2] / np.linalg.norm(SUN)
    assert close(image, np.broadcast_to(KD * color * cos_alpha, image.shape))


def test_directional_light_grazing_from_behind_lights_nothing():
    _, image = render([WALL], {"type": "directional", "direction": [0.3, -0.4, 1.0]})
    assert np.all(image == 0.0)


@pytest.mark.parametrize("shadows", ["bvh", "grid"])
def test_directional_shadow_rays_reach_a_blocker_at_any_distance(shadows):
    """A 2 x 2 blocker 30 units in front of the wall (behind the camera, out of view) casts its parallel
    projection along the sun's direction: the wall point p is shadowed where p + s L meets z = 30 inside
    the blocker. Inside, black; outside, the cos law."""
    L = -SUN / np.linalg.norm(SUN)
    shift = 30.0 * L[:2] / L[2]
    centre = np.array([0.5, 0.3])
    blocker = {"shape": "plane", "size": [2.0, 2.0], "rotate": [90.0, 0.0, 0.0], "material": "m",
               "translate": [*(centre + shift).tolist(), 30.0]}
    scene, image = render([WALL, blocker], {"type": "directional", "direction": SUN.tolist()}, shadow_query=shadows)
    p, _ = wall_points(scene)
    off = np.abs(p[..., :2] - centre).max(-1)
    inside, outside = off < 1.0 - 1e-3, off > 1.0 + 1e-3
    assert inside.sum() > 500 and outside.sum() > 5000
    assert np.all(image[inside] == 0.0)
    np.testing.assert_allclose(image[outside], np.broadcast_to(KD * L[2], image[outside].shape), rtol=2e-4)


def test_the_oracle_reads_the_scene_light_as_the_file_says():
    """The float64 model of the accuracy suite's oracle (phong_terms with the scene's Light objects) is
    the closed form above: a check of the oracle, not of warprt."""
    scene = make_scene([WALL], {"m": MAT}, [SPOT, {"type": "directional", "direction": SUN.tolist()},
                                            {"position": [0.0, 0.0, 2.0], "falloff": "inverse_square"}], camera=CAMERA)
    p, d = wall_points(scene)
    got = phong_terms(p, N, -d, scene.lights, MAT, [0.0] * 3)["diffuse"]
    r = np.linalg.norm(p - [0.0, 0.0, 2.0], axis=-1)
    want = spot_expect(scene, 25.0, 10.0)[0] + KD * -SUN[2] / np.linalg.norm(SUN) + KD * (2.0 / r**3)[..., None]
    np.testing.assert_allclose(got, want, rtol=1e-12)
    np.testing.assert_allclose(light_intensity(p, scene.lights[2]), (1.0 / r**2)[..., None] * np.ones(3), rtol=1e-12)
