"""Mitsuba scene files against Mitsuba's own loading of them: warprt's depth and object AOVs against
Mitsuba's ``aov`` integrator on the scene Mitsuba loads from the same file (its sensor, its analytic
sphere), images against the reference's render of that scene, and the units against Mitsuba's physics.

Thresholds: meshes (rectangle, cube) are the same triangles in both, so depth meets the AOV suite's
POSITION_REL and the objects agree wherever neither ray is a tie. Mitsuba's sphere is analytic and
warprt's its inscribed tessellation, whose surface lies at most r (1 - cos(pi / 128)) inside it: at
most that in depth over the cosine of incidence, and objects may differ where a ray passes the sphere
within that of its silhouette (checked with the sphere's closed form).
"""

import math
import re

import numpy as np
import pytest

import mitsuba_files as mf
import warprt
from reference import compare, mitsuba_variant, render_mitsuba_aovs
from reference.mitsuba_whitted import Switches
from warprt.scene import camera_basis, pixel_ray_directions, read_mitsuba_xml, resolve_effects

from accuracy.harness import check, unexplained as harness_unexplained
from accuracy.test_aovs_against_mitsuba import POSITION_REL, unexplained

pytestmark = pytest.mark.accuracy

SSIM_MIN = 0.999
SAGITTA = 1.0 - math.cos(math.pi / 128)  # of the tessellated sphere, per unit radius


@pytest.fixture(scope="module")
def mi():
    mitsuba_variant()  # the reference's variant (llvm_ad_rgb): its aov integrator and registry indices
    import mitsuba

    return mitsuba


def aovs(path):
    """warprt's and Mitsuba's depth and object AOVs of the file, and the scene warprt read."""
    scene = warprt.load_scene(path)
    a = warprt.render(scene, aovs=["depth", "object"]).aovs
    return scene, a, render_mitsuba_aovs(scene)


def agree_on_meshes(scene, a, m):
    hit = np.isfinite(a["depth"])
    both = hit & m["hit"]
    differ = (hit != m["hit"]) | (both & (a["object"] != m["object"]))
    bad = unexplained(scene, np.argwhere(differ))
    assert not bad, f"{len(bad)} pixels hit another object than Mitsuba's, not at a tie: {bad[:10]}"
    same = both & ~differ
    scale = np.abs(np.asarray(scene.camera.eye)).max() + m["depth"]
    err = (np.abs(a["depth"] - m["depth"]) / scale)[same]
    assert same.sum() > 0.3 * same.size and err.max() <= POSITION_REL, err.max()
    return int(differ.sum()), float(err.max())


def test_cornell_box_aovs_are_mitsubas(mi, tmp_path):
    scene, a, m = aovs(mf.write(tmp_path, "cornell.xml", mf.cornell_box(mi, width=96, height=72)))
    differ, err = agree_on_meshes(scene, a, m)
    print(f"cornell box 96x72: {differ} tie pixels, depth error <= {err:.2e} of |eye| + depth")


def test_textured_plane_aovs_are_mitsubas(mi, tmp_path):
    png = mf.checker_png(tmp_path / "t.png")
    scene, a, m = aovs(mf.write(tmp_path, "plane.xml", mf.textured_plane(mi, png, width=96, height=72)))
    differ, err = agree_on_meshes(scene, a, m)
    print(f"textured plane 96x72: {differ} tie pixels, depth error <= {err:.2e}")


@pytest.mark.parametrize("axis", ["x", "y", "diagonal", "smaller", "larger"])
def test_each_fov_axis_frames_as_mitsubas_sensor(mi, tmp_path, axis):
    d = mf.cornell_box(mi, width=80, height=50, fov_axis=axis)
    agree_on_meshes(*aovs(mf.write(tmp_path, "cornell.xml", d)))


def test_a_swapped_fov_axis_fails(mi, tmp_path):
    """The negative control: warprt reading the file as fov_axis x, Mitsuba loading it as y (without the
    area light, which the float64 oracle that explains differing pixels does not shade)."""
    box = {"width": 80, "height": 50, "area_light": False}
    ours = warprt.load_scene(mf.write(tmp_path, "x.xml", mf.cornell_box(mi, **box, fov_axis="x")))
    theirs = warprt.load_scene(mf.write(tmp_path, "y.xml", mf.cornell_box(mi, **box, fov_axis="y")))
    a = warprt.render(ours, aovs=["depth", "object"]).aovs
    with pytest.raises(AssertionError):
        agree_on_meshes(ours, a, render_mitsuba_aovs(theirs))


def test_glass_sphere_aovs_are_mitsubas_within_the_tessellation(mi, tmp_path):
    scene, a, m = aovs(mf.write(tmp_path, "glass.xml", mf.glass_sphere(mi, width=96, height=72)))
    glass = [o.name for o in scene.objects].index("glass")
    c, r = np.array(mf.GLASS["center"]), mf.GLASS["radius"]
    eye = np.asarray(scene.camera.eye, np.float64)
    # Each pixel's camera ray and its closest approach to the sphere's centre: within r of it and
    # outside the tessellation's inner radius, a silhouette pixel.
    d = pixel_ray_directions(camera_basis(scene.camera))
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    to_c = c - eye
    miss = np.linalg.norm(to_c - (d @ to_c)[..., None] * d, axis=-1)
    rim = (miss > r * (1.0 - 2.0 * SAGITTA)) & (miss < r * (1.0 + 1e-6))
    hit = np.isfinite(a["depth"])
    differ = (hit != m["hit"]) | (hit & m["hit"] & (a["object"] != m["object"]))
    assert not (differ & ~rim).any(), np.argwhere(differ & ~rim)[:10]
    on_sphere = hit & m["hit"] & (a["object"] == glass) & (m["object"] == glass)
    n = (m["position"] - c) / r
    cos_in = np.abs(np.sum(n * d, -1))
    steep = on_sphere & (cos_in > 0.5)
    assert steep.sum() > 100
    assert (np.abs(a["depth"] - m["depth"])[steep] <= r * SAGITTA / cos_in[steep] * 1.01 + 1e-5).all()
    floor = hit & m["hit"] & (a["object"] == m["object"]) & (a["object"] != glass)
    scale = np.abs(eye).max() + m["depth"]
    assert (np.abs(a["depth"] - m["depth"]) / scale)[floor].max() <= POSITION_REL
    print(f"glass sphere 96x72: {int(differ.sum())} silhouette pixels differ, "
          f"sphere depth error <= {np.abs(a['depth'] - m['depth'])[steep].max():.2e}")


@pytest.mark.parametrize("name", ["cornell", "plane"])
def test_diffuse_point_lit_images_match_the_reference_on_mitsubas_scene(mi, tmp_path, name):
    """Diffuse BSDFs and point lights map exactly: warprt's image against the reference's Whitted
    render of the scene Mitsuba loaded from the file (its shapes, its own bitmap and checkerboard),
    with the accuracy suite's thresholds and every differing pixel explained by the float64 oracle."""
    png = mf.checker_png(tmp_path / "t.png")
    d = mf.cornell_box(mi, 100, 75, area_light=False) if name == "cornell" else mf.textured_plane(mi, png, 100, 75)
    result = check(f"xml_{name}", warprt.load_scene(mf.write(tmp_path, f"{name}.xml", d)))
    print(f"{name} 100x75: {result.summary()}")
    assert result.mitsuba.max() > 0.05  # lit, not a black image on both sides


def test_cornell_box_corners_are_ties(mi, tmp_path):
    """The box's corner edges are the image's diagonals |x| = |y| about its centre, through pixel centres
    wherever W - H is even (96 x 72; 100 x 75, used above, has none): there Mitsuba's float32 rectangles
    meet (or leave a crack) and SSIM drops to 0.993, every differing pixel such a tie."""
    scene = warprt.load_scene(mf.write(tmp_path, "cornell.xml", mf.cornell_box(mi, 96, 72, area_light=False)))
    result = compare(scene)
    switches = Switches.for_effects(resolve_effects(scene), scene.render)
    print(f"cornell 96x72: {result.summary()}")
    assert result.off_mask.any() and not harness_unexplained(scene, switches, result)


def test_glass_sphere_image_matches_the_reference(mi, tmp_path):
    """Glass through the ray tree on Mitsuba's analytic sphere against warprt's tessellation of it."""
    scene = warprt.load_scene(mf.write(tmp_path, "glass.xml", mf.glass_sphere(mi, width=96, height=72)))
    result = compare(scene)
    print(f"glass sphere 96x72: {result.summary()}")
    assert "refraction" in result.effects
    assert result.ssim >= SSIM_MIN and result.frac_off <= 0.002, result.summary()


def test_units_are_mitsubas_physics(mi, tmp_path):
    """kd = reflectance / pi and C_l = intensity with inverse-square falloff: warprt's reading of a
    point-lit diffuse floor, evaluated at Mitsuba's own hit points (kd C_l n.L / r^2), is the radiance
    Mitsuba's ``direct`` integrator computes for the file (a delta light: exact at one sample)."""
    d = {"type": "scene", "sensor": mf.sensor(mi, (0.0, 2.0, 3.0), (0.0, 0.0, 0.0), width=48, height=36),
         "floor": mf.floor(mi, 2.0, {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.5, 0.3]}}),
         "light": {"type": "point", "position": [0.3, 1.5, -0.2], "intensity": {"type": "rgb", "value": [2.0, 3.0, 4.0]}}}
    path = mf.write(tmp_path, "floor.xml", d)
    scene = read_mitsuba_xml(path)
    m = render_mitsuba_aovs(warprt.load_scene(path))
    ms = mi.load_file(str(path))
    image = np.array(mi.render(ms, integrator=mi.load_dict({"type": "direct"}), spp=1, seed=0), np.float64)[..., :3]
    light, kd = scene.lights[0], np.asarray(scene.materials["diffuse"].kd)
    to_light = np.asarray(light.position) - m["position"]
    r2 = np.sum(to_light**2, -1)
    cos = np.maximum(to_light[..., 1] / np.sqrt(r2), 0.0)  # the floor's normal is +y
    expected = kd * np.asarray(light.color) * (cos / r2)[..., None]
    hit = m["hit"]
    assert hit.sum() > 0.5 * hit.size
    assert np.allclose(image[hit], expected[hit], rtol=1e-4, atol=1e-6), np.abs(image - expected)[hit].max()


def test_constant_emitter_lights_an_open_floor_as_mitsuba_does(mi, tmp_path):
    """Read as an environment light: an unoccluded diffuse floor under a constant sky L reflects
    reflectance x L, which Mitsuba's direct integrator gives averaged over many samples."""
    d = {"type": "scene", "sensor": mf.sensor(mi, (0.0, 2.0, 3.0), (0.0, 0.0, 0.0), width=16, height=12),
         "floor": mf.floor(mi, 3.0, {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.5, 0.3]}}),
         "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [0.5, 1.0, 2.0]}}}
    d["sensor"]["sampler"] = {"type": "independent", "sample_count": 1024}
    path = mf.write(tmp_path, "sky.xml", d)
    scene = read_mitsuba_xml(path)
    image = np.array(mi.render(mi.load_file(str(path)), integrator=mi.load_dict({"type": "direct"}), seed=1),
                     np.float64)[..., :3]
    ours = warprt.render(scene.with_render(light_samples=256)).image.astype(np.float64)
    inner = (slice(4, 8), slice(5, 11))  # well inside the floor
    assert np.allclose(ours[inner].mean((0, 1)), image[inner].mean((0, 1)), rtol=0.01), (ours[inner].mean((0, 1)), image[inner].mean((0, 1)))


def test_disk_and_cylinder_are_tessellated_where_mitsuba_puts_them(mi, tmp_path):
    """Scaled, rotated and moved: objects agree except within a pixel of a silhouette, and depth to the
    tessellation's sagitta (a flat disk: exactly) over the cosine of incidence."""
    T = mi.ScalarTransform4f()
    d = {"type": "scene", "sensor": mf.sensor(mi, (0.3, 1.8, 3.2), (0.0, 0.4, 0.0), width=96, height=72),
         "disk": {"type": "disk", "to_world": T.translate([-0.7, 0.0, 0.2]) @ T.rotate([1, 0, 0], -90) @ T.scale([0.6, 0.4, 1.0])},
         "pipe": {"type": "cylinder", "radius": 0.3, "p0": [0.6, 0.0, -0.2], "p1": [0.4, 1.0, 0.1]},
         "light": {"type": "point", "position": [0.0, 3.0, 2.0]}}
    scene, a, m = aovs(mf.write(tmp_path, "shapes.xml", d))
    hit = np.isfinite(a["depth"])
    differ = (hit != m["hit"]) | (hit & m["hit"] & (a["object"] != m["object"]))
    obj = np.pad(m["object"], 1, constant_values=-1)
    h, w = m["object"].shape
    edge = ~np.all([obj[1 + i:1 + i + h, 1 + j:1 + j + w] == m["object"] for i in (-1, 0, 1) for j in (-1, 0, 1)], 0)
    assert not (differ & ~edge).any(), np.argwhere(differ & ~edge)[:10]
    same = hit & m["hit"] & ~differ & ~edge
    assert {0, 1} <= set(np.unique(m["object"][same]))
    eye = np.asarray(scene.camera.eye, np.float64)
    view = (m["position"] - eye) / np.linalg.norm(m["position"] - eye, axis=-1, keepdims=True)
    cos_in = np.abs(np.sum(m["geo_normal"] * view, -1))
    tol = np.where(m["object"] == 1, 0.3 * (1 - math.cos(math.pi / 256)), 0.0) / np.maximum(cos_in, 0.2) + 1e-5
    assert (np.abs(a["depth"] - m["depth"]) <= tol)[same].all()


def test_compare_command_on_a_scene_file(mi, tmp_path, capsys):
    from warprt.cli import main

    path = mf.write(tmp_path, "cornell.xml", mf.cornell_box(mi, 100, 75, area_light=False))
    code = main(["compare", str(path), "-o", str(tmp_path / "cmp.png")])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert float(re.search(r"SSIM\s+([0-9.]+)", out).group(1)) >= SSIM_MIN
    assert (tmp_path / "cmp.png").exists() and "warning" not in err


@pytest.mark.parametrize("light", ["point", "spot", "directional"])
def test_render_is_mitsubas_direct_render(mi, tmp_path, light):
    """End to end: warprt's image of a diffuse floor under each light type (no ambient, no specular) is
    the radiance Mitsuba's direct integrator computes for the same file."""
    s = mf.SPOT
    lights = {"point": {"type": "point", "position": [0.3, 1.5, -0.2], "intensity": {"type": "rgb", "value": [2.0, 3.0, 4.0]}},
              "spot": mf.spot_lit_floor(mi)["lamp"],
              "directional": {"type": "directional", "direction": list(s["sun"]), "irradiance": {"type": "rgb", "value": list(s["irradiance"])}}}
    d = {"type": "scene", "sensor": mf.sensor(mi, (0.0, 2.0, 3.0), (0.0, 0.0, 0.0), width=48, height=36),
         "floor": mf.floor(mi, 2.0, {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.5, 0.3]}}),
         "light": lights[light]}
    path = mf.write(tmp_path, f"{light}.xml", d)
    ours = warprt.render(warprt.load_scene(path)).image.astype(np.float64)
    theirs = np.array(mi.render(mi.load_file(str(path)), integrator=mi.load_dict({"type": "direct"}), spp=1, seed=0),
                      np.float64)[..., :3]
    assert theirs.max() > 0.01
    assert np.allclose(ours, theirs, rtol=1e-3, atol=1e-5), np.abs(ours - theirs).max()


def test_compare_with_another_image_size_uses_warprts_camera_on_both_sides(mi, tmp_path):
    """--width/--height change the camera the file gave: both sides then render warprt's camera, which
    keeps the file's vertical fov (so the comparison still holds; the file's sensor would be stretched)."""
    path = mf.write(tmp_path, "cornell.xml", mf.cornell_box(mi, 100, 75, area_light=False))
    result = compare(warprt.load_scene(path, {"camera.width": 81, "camera.height": 60}))
    assert result.mitsuba.shape == (60, 81, 3) and result.ssim >= SSIM_MIN, result.summary()
