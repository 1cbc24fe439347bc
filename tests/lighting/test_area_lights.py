"""Area lights (issue 32): a disk's and a rectangle's light at a point against their closed forms
(tests/oracle/area.py), converging as light_samples grows; soft shadows; determinism; the scene file's
checks; and kernels without area-light code for scenes without area lights.

Convention (kernels/shading.py): kd is a BRDF value, so a Lambertian floor of kd under an emitter of
radiance L_e at irradiance E has radiance kd E (Mitsuba's reflectance / pi times E, kd = reflectance / pi)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import warprt
from warprt import SceneError
from warprt.scene import EffectSet, resolve_effects

from oracle.area import (corner_rectangle_irradiance, corner_rectangle_without_emitter_cosine,
                           disk_on_axis_irradiance, disk_on_axis_without_emitter_cosine)
from scenekit import trace_kernel_source

KD = 0.5
L_E = 2.0
FLOOR = {"shape": "plane", "size": [12.0, 12.0], "material": "floor"}
MATERIALS = {"floor": {"kd": [KD] * 3, "ks": [0.0] * 3}, "plate": {"kd": [0.0] * 3}}


def floor_point(lights, at=(0.0, 0.0, 0.0), samples=16, ambient=0.0, objects=()):
    """The radiance of the floor (y = 0, kd = KD) at ``at``: the one pixel of a camera looking at it from
    the side, below every light and blocker."""
    x, _, z = at
    scene = warprt.load_dict({
        "camera": {"eye": [x + 3.0, 0.5, z], "center": [x, 0.0, z], "width": 1, "height": 1},
        "render": {"ambient": [ambient] * 3, "light_samples": samples, "max_depth": 1},
        "lights": lights, "materials": MATERIALS, "objects": [FLOOR, *objects]})
    image, _ = warprt.render(scene, primary_query="raytrace")
    return float(image[0, 0, 1])


def disk(r, d, **kw):
    return {"type": "area", "radiance": [L_E] * 3, "shape": "disk", "center": [0.0, d, 0.0], "normal": [0.0, -1.0, 0.0],
            "radius": r, **kw}


def corner_rectangle(a, b, c):
    """An a x b rectangle at height c facing down, its corner (0, c, 0) above the origin."""
    return {"type": "area", "radiance": [L_E] * 3, "shape": "rectangle", "center": [a / 2, c, b / 2],
            "u": [a / 2, 0.0, 0.0], "v": [0.0, 0.0, b / 2]}


# (a) the disk on its axis ----------------------------------------------------------------------

R, D = 1.0, 1.0


@pytest.fixture(scope="module")
def disk_errors():
    expected = KD * disk_on_axis_irradiance(L_E, R, D)
    return {n: floor_point([disk(R, D)], samples=n) / expected - 1.0 for n in (16, 64, 256)}


def test_a_disk_lights_a_point_on_its_axis_as_its_closed_form_says(disk_errors):
    """kd L pi r^2 / (r^2 + d^2), within the midpoint rule's error on the disk's k x k cells (measured:
    about 5.7 %, 1.3 % and 0.33 % at 16, 64 and 256 points)."""
    for n, bound in ((16, 0.08), (64, 0.02), (256, 0.005)):
        assert abs(disk_errors[n]) < bound, (n, disk_errors)


def test_the_disks_error_falls_as_the_light_samples_grow(disk_errors):
    """Four times the points, about a quarter of the error: the cell centres' O(h^2) = O(1/N)."""
    e16, e64, e256 = (abs(disk_errors[n]) for n in (16, 64, 256))
    assert 3.0 < e16 / e64 < 5.0 and 3.0 < e64 / e256 < 5.0, disk_errors


def test_a_disk_without_the_emitters_cosine_is_not_what_is_rendered():
    """Negative control: the irradiance with the cosine at the emitter dropped (17 % more here) is far
    outside the stratification's error."""
    rendered = floor_point([disk(R, D)], samples=256)
    wrong = KD * disk_on_axis_without_emitter_cosine(L_E, R, D)
    assert abs(rendered / wrong - 1.0) > 0.1


# (b) the rectangle over a corner ----------------------------------------------------------------

A, B, C = 1.0, 0.6, 0.8


def test_a_rectangle_lights_a_point_below_its_corner_as_its_form_factor_says():
    """kd pi L F, F Howell's form factor of a parallel rectangle with a corner on the point's normal;
    the error falls about fourfold with each fourfold of points (measured: 0.38 %, 0.094 %, 0.024 %)."""
    expected = KD * corner_rectangle_irradiance(L_E, A, B, C)
    errors = [abs(floor_point([corner_rectangle(A, B, C)], samples=n) / expected - 1.0) for n in (16, 64, 256)]
    assert errors[0] < 0.006 and errors[1] < 0.0015 and errors[2] < 0.0005, errors
    assert 3.0 < errors[0] / errors[1] < 5.0 and 3.0 < errors[1] / errors[2] < 5.0, errors


def test_a_rectangle_without_the_emitters_cosine_is_not_what_is_rendered():
    rendered = floor_point([corner_rectangle(A, B, C)], samples=256)
    wrong = KD * corner_rectangle_without_emitter_cosine(L_E, A, B, C)
    assert abs(rendered / wrong - 1.0) > 0.1


def test_a_rectangle_emits_from_its_normals_side_only():
    """One-sided, as Mitsuba's area emitter: the same rectangle turned up lights nothing below it."""
    up = {**corner_rectangle(A, B, C), "v": [0.0, 0.0, -B / 2], "center": [A / 2, C, -B / 2]}
    assert floor_point([up], samples=16) == 0.0


def test_an_object_emits_as_an_area_light_over_its_triangles():
    """object = "lamp": the plane's own triangles, turned to face down, light the point below its corner as
    the rectangle's form factor says (the points area-weighted over its two triangles: a coarser
    stratification than the rectangle's own; measured -0.32 %, -0.055 %, +0.0014 % at 16, 64, 256 points)."""
    lamp = {"shape": "plane", "name": "lamp", "size": [A, B], "rotate": [180.0, 0.0, 0.0],
            "translate": [A / 2, C, B / 2], "material": "plate"}
    light = {"type": "area", "radiance": [L_E] * 3, "object": "lamp"}
    expected = KD * corner_rectangle_irradiance(L_E, A, B, C)
    assert floor_point([light], samples=256, objects=[lamp]) == pytest.approx(expected, rel=0.01)



def test_a_fine_mesh_lamp_gets_its_light_from_all_of_its_surface():
    """An emitting icosphere of 1,280 triangles (radius 0.5, centre 2 above the point): pi L_e R^2 / d^2,
    the sphere's closed form, within 1% at 1,024 and 4,096 points (measured -0.26%, -0.36%: the facets lie
    inside the sphere). The Fibonacci lattice gives every point its own place along the mesh's area; a
    k x k grid sampled k triangles, each along a line (measured -96% at 1,024). 16 points are a coarse
    quadrature of it (the control: more than 10% off)."""
    bulb = {"shape": "sphere", "name": "bulb", "subdivisions": 3, "smooth": False, "translate": [0.0, 2.0, 0.0],
            "scale": [0.5] * 3, "material": "plate"}
    light = {"type": "area", "radiance": [L_E] * 3, "object": "bulb"}
    expected = KD * math.pi * L_E * 0.25 / 4.0
    for samples in (1024, 4096):
        assert floor_point([light], samples=samples, objects=[bulb]) == pytest.approx(expected, rel=0.01)
    assert abs(floor_point([light], samples=16, objects=[bulb]) / expected - 1.0) > 0.1

@pytest.mark.parametrize("algorithm", ["raytrace", "zbuffer"])
def test_an_area_lights_own_surface_shows_its_radiance_from_the_front_only(algorithm):
    """The tracer's camera rays and the Z-buffer's visible samples alike."""
    def seen_from(y):
        scene = warprt.load_dict({
            "camera": {"eye": [0.0, y, 0.0], "center": [0.0, 1.0, 0.0], "up": [0.0, 0.0, -1.0], "width": 1, "height": 1},
            "render": {"ambient": [0.0] * 3}, "lights": [disk(0.5, 1.0)], "materials": MATERIALS, "objects": [FLOOR]})
        options = {"primary_query": "raytrace"} if algorithm == "raytrace" else {"algorithm": "zbuffer"}
        return warprt.render(scene, **options)[0][0, 0]
    assert np.array_equal(seen_from(0.5), [L_E] * 3)  # below, facing it: L_e
    assert np.array_equal(seen_from(3.0), [0.0] * 3)  # above: its back, black


def mirrored_light_scene(**camera):
    """A disk light over a floor, seen in a planar mirror: the light's own shape is drawn with a material
    the scene's materials do not name."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 1.5, 4.0], "center": [0.0, 0.8, 0.0], "width": 48, "height": 36, **camera},
        "lights": [disk(0.5, 2.0)],
        "materials": {**MATERIALS, "mirror": {"kd": [0.05] * 3, "reflectivity": [0.8] * 3}},
        "objects": [FLOOR, {"shape": "plane", "size": [4.0, 3.0], "rotate": [90.0, 0.0, 0.0],
                            "translate": [0.0, 1.0, -1.0], "material": "mirror"}]})


def test_a_mirror_shows_an_area_light_through_the_virtual_cameras_as_traced():
    """The mirrors' shortcut reads every material slot's reflectivity, the area light's own shape's
    included (a KeyError before): its image is the traced one, to the bit."""
    scene = mirrored_light_scene()
    traced, _ = warprt.render(scene, reflection_query="bvh")
    r = warprt.Renderer(scene, reflection_query="mirrors")
    r.render()
    kept = r.render()  # the second frame of a view uses the kept virtual cameras
    assert kept.stats.mirrors.get("rasters") == "reused" and np.array_equal(kept.image, traced)
    assert traced.max() >= L_E * 0.8 * 0.99  # the disk seen in the mirror: L_e k_r


def test_the_material_aov_of_an_area_lights_own_shape_is_minus_one():
    """Looking straight up at the disk: no material of the scene's (a ValueError before)."""
    scene = warprt.load_dict({
        "camera": {"eye": [0.0, 0.5, 0.0], "center": [0.0, 1.0, 0.0], "up": [0.0, 0.0, -1.0], "width": 1, "height": 1},
        "lights": [disk(0.5, 1.0)], "materials": MATERIALS, "objects": [FLOOR]})
    aovs = warprt.render(scene, aovs=["material"], primary_query="raytrace").aovs
    assert aovs["material"][0, 0] == -1


# (c) a blocker's penumbra -----------------------------------------------------------------------

AMBIENT = 0.1
STRIP = {"type": "area", "radiance": [L_E] * 3, "shape": "rectangle", "center": [0.0, 2.0, 0.0],
         "u": [0.5, 0.0, 0.0], "v": [0.0, 0.0, 0.5]}  # x in [-0.5, 0.5] at y = 2, facing down
# A plate at y = 1 over x < 0: a floor point at x is fully shadowed for x < -0.5, fully lit for x > 0.5.
PLATE = {"shape": "plane", "size": [10.0, 10.0], "translate": [-5.0, 1.0, 0.0], "material": "plate"}


def test_a_blocker_casts_a_penumbra():
    """Fully shadowed (x = -1.5): the ambient term only; fully lit (x = 0.6): the value without the plate;
    below the plate's edge (x = 0): strictly between, and the light's unblocked half x > 0 is two 0.5 x 0.5
    corner rectangles at height 2 (their closed form, within the stratification's error)."""
    shaded = {x: floor_point([STRIP], at=(x, 0.0, 0.0), ambient=AMBIENT, objects=[PLATE]) for x in (-1.5, 0.0, 0.6)}
    open_ = {x: floor_point([STRIP], at=(x, 0.0, 0.0), ambient=AMBIENT) for x in (-1.5, 0.0, 0.6)}
    ambient = AMBIENT * KD  # ka = kd
    assert shaded[-1.5] == pytest.approx(ambient, rel=1e-6) and open_[-1.5] > 2 * ambient
    assert shaded[0.6] == pytest.approx(open_[0.6], rel=1e-5)
    assert ambient < shaded[0.0] < open_[0.0]
    assert shaded[0.0] - ambient == pytest.approx(2 * KD * corner_rectangle_irradiance(L_E, 0.5, 0.5, 2.0), rel=0.01)


# (d) determinism --------------------------------------------------------------------------------

def test_two_renders_of_an_area_light_are_the_same_to_the_bit():
    scene = warprt.load_dict({
        "camera": {"eye": [0.0, 1.5, 4.0], "center": [0.0, 0.3, 0.0], "width": 24, "height": 18},
        "lights": [disk(0.4, 2.0)], "materials": MATERIALS,
        "objects": [FLOOR, {"shape": "sphere", "radius": 0.4, "translate": [0.0, 0.4, 0.0], "material": "floor"}]})
    first, _ = warprt.render(scene)
    second, _ = warprt.render(scene)
    assert np.array_equal(first, second) and first.max() > 0.0


# (e) bad input ----------------------------------------------------------------------------------

@pytest.mark.parametrize("change, field", [
    ({"render": {"light_samples": 10}}, "render.light_samples"),
    ({"lights": [disk(0.5, 1.0, radiance=[1.0, -1.0, 1.0])]}, "lights[0].radiance"),
    ({"lights": [{"type": "area", "radiance": [1.0] * 3, "object": "lamp"}]}, "lights[0].object"),
    ({"lights": [{"type": "area", "radiance": [1.0] * 3, "shape": "disk", "normal": [0.0, -1.0, 0.0]}]},
     "lights[0].radius"),
    ({"lights": [{"type": "area", "radiance": [1.0] * 3, "shape": "sphere", "radius": 0.0}]}, "lights[0].radius"),
    ({"lights": [{"type": "area", "radiance": [1.0] * 3, "shape": "sphere", "radius": 1.0, "normal": [0.0, 1.0, 0.0]}]},
     "lights[0].normal"),
])
def test_a_bad_area_light_is_one_line_naming_its_field(change, field):
    with pytest.raises(SceneError) as e:
        warprt.load_dict({"lights": [disk(0.5, 1.0)], "materials": MATERIALS, "objects": [FLOOR], **change})
    assert f": {field}: " in str(e.value) and "\n" not in str(e.value)


def test_a_light_from_python_is_checked_as_the_files():
    scene = warprt.Scene(lights=[warprt.Light(type="area", radiance=(1.0, 1.0, 1.0), object="lamp")],
                         objects=[warprt.SceneObject.from_shape("plane")])
    with pytest.raises(SceneError, match=r"lights\[0\]\.object: no object named 'lamp'"):
        warprt.render(scene)


# (f) variants -----------------------------------------------------------------------------------

def test_only_scenes_with_area_lights_compile_the_area_light_variant():
    point = warprt.load_dict({"lights": [{"position": [0.0, 3.0, 0.0]}], "materials": MATERIALS, "objects": [FLOOR]})
    area = warprt.load_dict({"lights": [disk(0.5, 1.0)], "materials": MATERIALS, "objects": [FLOOR]})
    assert not resolve_effects(point).area_lights and "A" not in resolve_effects(point).variant
    assert resolve_effects(area).area_lights and resolve_effects(area).variant.endswith("A")
    assert "area_lights" not in resolve_effects(area).names  # not an effect one names or disables


def test_the_area_light_code_is_absent_from_the_other_variants():
    """A line of the area lights' sum and of the emitted radiance, as Warp quotes them in the C++."""
    markers = ("out = area_light(s, hit, k, v, out, rec, j, stratum)", "emitted(s, h.face, r.ray.d)")
    assert not any(m in trace_kernel_source(EffectSet()) for m in markers)
    area = trace_kernel_source(EffectSet(area_lights=True))
    assert all(m in area for m in markers)
    # render.area_estimator = "analytic" and render.light_spread (issue 39) compile only where asked for
    spread = trace_kernel_source(EffectSet(area_lights=True, area_analytic=True, supersampling=True, light_spread=True))
    for marker in ("closed_integral(s, e, hit)", "a.first[e * a.strata + stratum]"):
        assert marker not in area and marker in spread


def test_the_light_samples_flag_sets_the_scenes_light_samples(tmp_path):
    """`warprt render --light-samples 4` renders what `--set render.light_samples=4` renders, and not what the
    default 16 points render: the flag reaches the kernel."""
    import subprocess
    import sys

    xml = Path(__file__).resolve().parents[2] / "scenes" / "cornell_box.xml"
    env = {**__import__("os").environ, "PYTHONPATH": str(Path(warprt.__file__).resolve().parents[1])}

    def render(*flags):
        out = tmp_path / f"{len(list(tmp_path.iterdir()))}.npy"
        r = subprocess.run([sys.executable, "-m", "warprt", "render", str(xml), "--width", "24", "--height", "24",
                            "-o", str(out), "-q", *flags], capture_output=True, text=True, env=env)
        assert r.returncode == 0, r.stderr
        return np.load(out)

    flag, setting, default = render("--light-samples", "4"), render("--set", "render.light_samples=4"), render()
    assert np.array_equal(flag, setting) and not np.array_equal(flag, default)


def test_an_area_lights_radiance_is_a_renderer_parameter():
    def scene(radiance):
        return warprt.load_dict({"camera": {"eye": [2.0, 1.5, 2.0], "center": [0.0, 0.0, 0.0], "width": 24, "height": 18},
                                 "lights": [disk(0.5, 1.0, radiance=radiance)], "materials": MATERIALS, "objects": [FLOOR]})
    r = warprt.Renderer(scene([L_E] * 3))
    before = r.render().image
    assert "lights.0.radiance" in r.params and np.array_equal(r.params["lights.0.radiance"], [L_E] * 3)
    assert "lights.0.color" not in r.params  # an area light has none (its light is its radiance)
    r.params["lights.0.radiance"] = [1.0, 2.0, 3.0]
    after = r.render().image
    assert np.array_equal(after, warprt.render(scene([1.0, 2.0, 3.0]))[0]) and not np.array_equal(after, before)



# (f) a sphere light ---------------------------------------------------------------------------------

def test_a_sphere_light_lights_a_point_below_it_as_its_closed_form_says():
    """A sphere of radiance L_e and radius R centred d above a floor point: irradiance pi L_e (R / d)^2
    (its visible cap, all above the horizon); the samples lie on the true sphere (Mitsuba's
    square_to_uniform_sphere), half of them facing away, and the error falls as they grow."""
    R, D = 0.5, 2.0
    expected = KD * math.pi * L_E * (R / D) ** 2
    sphere = {"type": "area", "radiance": [L_E] * 3, "shape": "sphere", "center": [0.0, D, 0.0], "radius": R}
    errors = {n: abs(floor_point([sphere], samples=n) / expected - 1.0) for n in (16, 64, 256)}
    assert errors[16] < 0.03 and errors[256] < 0.002
    assert errors[256] < errors[64] < errors[16]


def test_a_sphere_light_is_drawn_at_its_radiance():
    scene = warprt.load_dict({
        "camera": {"eye": [0.0, 1.0, 3.0], "center": [0.0, 1.0, 0.0], "width": 1, "height": 1},
        "render": {"ambient": [0.0] * 3},
        "lights": [{"type": "area", "radiance": [L_E] * 3, "shape": "sphere", "center": [0.0, 1.0, 0.0], "radius": 0.5}],
        "materials": MATERIALS, "objects": [FLOOR]})
    assert np.array_equal(warprt.render(scene, primary_query="raytrace")[0][0, 0], [L_E] * 3)
