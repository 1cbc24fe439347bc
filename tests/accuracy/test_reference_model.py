"""The Mitsuba reference checked on its own against closed forms, so that agreeing with it means
something: Phong terms on a plane, hard shadows, mirror levels, the switches, the mesh conversion,
and the scalar_rgb fallback when Dr.Jit finds no LLVM."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from oracle import camera_rays, phong_terms, ray_plane
from reference.mitsuba_whitted import MitsubaScene, Switches, mitsuba
from scenekit import make_scene
from warprt.scene import vertex_normals

pytestmark = pytest.mark.accuracy

ROOT = Path(__file__).resolve().parents[2]
# A plane through the origin facing the camera (+z), larger than the view.
WALL = {"shape": "plane", "size": [40.0, 40.0], "rotate": [90.0, 0.0, 0.0], "material": "wall"}
WALL_MATERIAL = {"ka": [0.3, 0.5, 0.7], "kd": [0.6, 0.4, 0.2], "ks": [0.5, 0.5, 0.5], "shininess": 20.0}
LIGHT = {"position": [0.7, 0.5, 2.0], "color": [0.9, 0.8, 1.0]}
AMBIENT = [0.5, 0.25, 1.0]


def render(scene, **switches):
    return MitsubaScene(scene, switches.get("smooth", True)).render(Switches(**switches))


def wall_points(scene):
    eye, d = camera_rays(scene.camera)
    t = ray_plane(eye, d, np.zeros(3), np.array([0.0, 0.0, 1.0]))
    return eye, d, eye + t[..., None] * d


def test_ambient_only_is_C_amb_times_ka_everywhere():
    scene = make_scene([WALL], {"wall": WALL_MATERIAL}, [LIGHT], ambient=AMBIENT)
    image = render(scene, diffuse=False, specular=False, shadows=False, max_depth=1)
    expected = np.asarray(AMBIENT) * np.asarray(WALL_MATERIAL["ka"])
    assert np.abs(image - expected).max() < 1e-6


def test_phong_terms_on_a_plane_match_the_closed_form():
    """I = C_amb ka + C_l (kd n.L + ks (r.v)^n), n = +z, at every pixel."""
    scene = make_scene([WALL], {"wall": WALL_MATERIAL}, [LIGHT], ambient=AMBIENT)
    image = render(scene, max_depth=1)
    eye, d, p = wall_points(scene)
    terms = phong_terms(p, np.array([0.0, 0.0, 1.0]), -d, [LIGHT], WALL_MATERIAL, AMBIENT)
    expected = terms["ambient"] + terms["diffuse"] + terms["specular"]
    assert np.abs(image - expected).max() < 2e-5
    # Switching a term off removes exactly that term.
    no_spec = render(scene, specular=False, max_depth=1)
    assert np.abs(no_spec - (expected - terms["specular"])).max() < 2e-5


def test_light_behind_the_surface_gives_no_light():
    """Two-sided surface, n faces the viewer: a light on the far side has n.L <= 0."""
    behind = {"position": [0.3, 0.2, -2.0], "color": [1.0, 1.0, 1.0]}
    scene = make_scene([WALL], {"wall": WALL_MATERIAL}, [behind], ambient=AMBIENT)
    image = render(scene, max_depth=1)
    assert np.abs(image - np.asarray(AMBIENT) * WALL_MATERIAL["ka"]).max() < 1e-6


def test_hard_shadow_of_a_box_matches_segment_box_intersection():
    """A pixel is shadowed iff the segment from its wall point to the light crosses the box."""
    box_min, box_max = np.array([-0.3, -0.2, 0.8]), np.array([0.2, 0.3, 1.2])
    box = {"shape": "box", "size": list(box_max - box_min), "translate": list((box_min + box_max) / 2),
           "material": "dark"}
    light = {"position": [1.2, 0.9, 3.0], "color": [1.0, 1.0, 1.0]}
    materials = {"wall": {"kd": [0.8, 0.8, 0.8], "ka": [0.0, 0.0, 0.0]}, "dark": {"kd": [0.0, 0.0, 0.0]}}
    scene = make_scene([WALL, box], materials, [light], camera={"eye": [0.0, 0.0, 6.0], "width": 96, "height": 72})
    image = render(scene, max_depth=1)
    eye, d, p = wall_points(scene)

    def crosses(lo, hi, o, v, t_max):
        """Slab test: does o + t v, 0 < t < t_max, pass through the box [lo, hi]?"""
        with np.errstate(divide="ignore", invalid="ignore"):
            t0, t1 = (lo - o) / v, (hi - o) / v
        t_near, t_far = np.minimum(t0, t1).max(-1), np.maximum(t0, t1).min(-1)
        return (t_near < t_far) & (t_far > 0) & (t_near < t_max)

    seg = np.asarray(light["position"]) - p
    shadowed = crosses(box_min, box_max, p, seg, 1.0)
    # Pixels near the shadow's outline (the box grown or shrunk by 1 cm decides otherwise) and
    # pixels where the camera sees the box itself are left out.
    near_outline = (crosses(box_min - 0.01, box_max + 0.01, p, seg, 1.0)
                    != crosses(box_min + 0.01, box_max - 0.01, p, seg, 1.0))
    clear = ~near_outline & ~crosses(box_min, box_max, eye, d, np.inf)
    lit = image[..., 0] > 1e-3
    assert shadowed[clear].sum() > 50 and (~shadowed[clear]).sum() > 50  # both kinds present
    assert np.array_equal(lit[clear], ~shadowed[clear])


def test_mirror_levels_between_two_facing_mirrors():
    """The camera between two parallel mirrors: every ray bounces between them for ever, so with
    ambient light only the pixel is C_amb ka (1 + kr + ... + kr^(D-1)) after D ray levels."""
    mirror = {"ka": [0.2, 0.1, 0.05], "kd": [0.0, 0.0, 0.0], "reflectivity": [0.5, 0.25, 0.8]}
    # Wide enough that the corner pixels' rays, drifting sideways 4 units per level, stay on them.
    front = {**WALL, "size": [400.0, 400.0], "material": "mirror"}
    back = {**front, "translate": [0.0, 0.0, 6.0]}
    scene = make_scene([front, back], {"mirror": mirror}, ambient=[1.0, 1.0, 1.0], max_depth=8)
    kr, ka = np.asarray(mirror["reflectivity"]), np.asarray(mirror["ka"])
    for depth in (1, 2, 3, 6):
        image = render(scene, diffuse=False, specular=False, shadows=False, max_depth=depth)
        assert np.abs(image - ka * (1 - kr**depth) / (1 - kr)).max() < 1e-5, depth


def test_mirror_shows_the_background_weighted_by_kr():
    mirror = {"ka": [0.0, 0.0, 0.0], "kd": [0.0, 0.0, 0.0], "reflectivity": [0.5, 0.25, 0.8]}
    scene = make_scene([{**WALL, "material": "mirror"}], {"mirror": mirror}, background=[0.2, 0.4, 0.6])
    image = render(scene, max_depth=2)
    assert np.abs(image - np.asarray([0.1, 0.1, 0.48])).max() < 1e-6
    assert np.abs(render(scene, max_depth=1)).max() == 0.0  # one level: the mirror's local term only


def test_mesh_conversion_keeps_positions_faces_and_given_normals():
    """Mitsuba recomputes vertex normals whenever positions change; the conversion must end with
    the scene's normals on smooth objects and none on flat ones."""
    mi, _ = mitsuba()
    objects = [{"shape": "sphere", "radius": 0.5, "subdivisions": 2, "smooth": True, "scale": [1.0, 0.6, 1.3]},
               {"shape": "box", "size": 0.4, "translate": [1.0, 0.0, 0.0]}]
    scene = make_scene(objects)
    converted = MitsubaScene(scene)
    by_name = {s.id(): mi.traverse(s) for s in converted.mi_scene.shapes()}
    sphere, box = (by_name[f"object_{i:05d}"] for i in range(2))
    obj = scene.objects[0]
    assert np.array_equal(np.array(sphere["vertex_positions"]).reshape(-1, 3), obj.vertices.astype(np.float32))
    assert np.array_equal(np.array(sphere["faces"]).reshape(-1, 3), obj.faces)
    assert np.array_equal(np.array(sphere["vertex_normals"]).reshape(-1, 3),
                          vertex_normals(obj.vertices, obj.faces).astype(np.float32))
    assert len(np.array(box["vertex_normals"])) == 0
    flat = MitsubaScene(scene, smooth=False)
    assert all(len(np.array(mi.traverse(s)["vertex_normals"])) == 0 for s in flat.mi_scene.shapes())


def test_scalar_fallback_without_llvm_renders_the_same_image(tmp_path):
    """With no usable LLVM the reference says so and renders in scalar_rgb: the same image."""
    script = (
        "import sys, numpy as np, warprt\n"
        "from reference.mitsuba_whitted import render_mitsuba, mitsuba_variant\n"
        "s = warprt.load_scene(sys.argv[1], {'camera.width': 24, 'camera.height': 18})\n"
        "np.save(sys.argv[2], render_mitsuba(s))\n"
        "open(sys.argv[3], 'w').write(mitsuba_variant())\n"
    )
    env = {**os.environ, "DRJIT_LIBLLVM_PATH": str(tmp_path / "no-such-libLLVM.so"),
           "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), str(ROOT)])}
    env.pop("WARPRT_MITSUBA_VARIANT", None)
    scene_path = ROOT / "scenes" / "seed.toml"
    out = tmp_path / "scalar.npy"
    variant = tmp_path / "variant.txt"
    proc = subprocess.run([sys.executable, "-c", script, str(scene_path), str(out), str(variant)], env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert variant.read_text() == "scalar_rgb"
    assert "falling back to Mitsuba's scalar_rgb" in proc.stderr
    import warprt
    from reference.mitsuba_whitted import render_mitsuba

    llvm = render_mitsuba(warprt.load_scene(scene_path, {"camera.width": 24, "camera.height": 18}))
    assert np.abs(np.load(out) - llvm).max() < 1e-4


def test_repeated_renders_reuse_the_compiled_kernels():
    """The integrator is traced again for each render, but its kernels are found in Dr.Jit's cache:
    for the same scene, and for another scene with other light colours and materials (the tables
    are kernel inputs, not constants), nothing is compiled."""
    import drjit as dr

    import warprt
    from reference.mitsuba_whitted import mitsuba_scene

    size = {"camera.width": 32, "camera.height": 24}
    scene = warprt.load_scene(ROOT / "scenes" / "seed.toml", size)
    mitsuba_scene(scene).render(Switches(max_depth=3))
    other = warprt.load_scene(ROOT / "scenes" / "seed.toml", {**size, "lights[0].color": [1.0, 0.5, 0.25],
                                                              "materials.orange.kd": [0.2, 0.3, 0.9]})
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history()  # clears it
        mitsuba_scene(scene).render(Switches(max_depth=3))
        mitsuba_scene(other).render(Switches(max_depth=3))
        launched = [k for k in dr.kernel_history() if k["type"] == dr.KernelType.JIT]
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert launched and all(k["cache_hit"] for k in launched)


def test_the_ray_tree_gives_the_integrators_image_where_there_is_no_glass():
    """reference/ray_tree.py traces level by level what mi.render's integrator traces path by path: on a
    scene of mirrors (8 levels) and with 2x2 samples the two images agree to float32 rounding."""
    import warprt
    from reference import render_tree

    for spp in (1, 4):
        scene = warprt.load_scene(ROOT / "scenes" / "mirrors.toml", {"camera.width": 48, "camera.height": 36,
                                                                     "render.spp": spp})
        converted = MitsubaScene(scene)
        switches = Switches(max_depth=8, spp=spp)
        tree = render_tree(converted, switches)
        assert np.abs(tree.image - converted.render(switches)).max() < 1e-6
        assert tree.rays_per_level[0] == 48 * 36 * spp and tree.truncated.max() > 0  # mirrors 8 deep: some cut off


def test_the_reference_finds_the_eyes_medium_with_its_own_rays():
    """Counting crossings of Mitsuba's surfaces along rays from the eye: inside the water box its row,
    outside air (row 0), as the winding number says."""
    import warprt
    from reference.ray_tree import eye_medium_row

    scene = warprt.load_scene(ROOT / "scenes" / "inside_glass.toml", {"camera.width": 16, "camera.height": 12})
    converted = MitsubaScene(scene)
    water = converted.integrator.tables.row_of_object[0]
    assert water in converted.integrator.tables.dielectric_rows
    assert eye_medium_row(converted, scene.camera.eye) == water
    assert eye_medium_row(converted, [0.0, 6.0, 9.0]) == 0


# Mitsuba's own emitters, checked against the closed forms: the agreement of warprt's new lights with
# the reference then means that both follow Mitsuba's light model, not that they share a mistake.
SPOT = {"type": "spot", "position": [0.2, 0.1, 3.0], "direction": [0.0, 0.0, -1.0], "cutoff_angle": 25.0,
        "beam_width": 10.0, "color": [1.0, 0.9, 0.8]}
NEW_LIGHTS = {
    "spot": SPOT,
    "spot_inverse_square": {**SPOT, "falloff": "inverse_square"},
    "spot_default_beam": {k: v for k, v in SPOT.items() if k != "beam_width"},
    "point_inverse_square": {"position": [0.3, -0.2, 2.0], "color": [2.0, 1.5, 1.0], "falloff": "inverse_square"},
    "directional": {"type": "directional", "direction": [0.3, -0.4, -1.0], "color": [0.8, 0.9, 1.0]},
}


@pytest.mark.parametrize("name", NEW_LIGHTS)
def test_mitsubas_emitters_match_the_closed_forms(name):
    """Mitsuba's spot, point (1/r^2, or times r^2 for falloff "none") and directional emitters through the
    reference's integrator: the Phong terms with the oracle's light model, at every pixel."""
    scene = make_scene([WALL], {"wall": WALL_MATERIAL}, [NEW_LIGHTS[name]], ambient=AMBIENT,
                       camera={"width": 128, "height": 96})
    image = render(scene, max_depth=1)
    eye, d, p = wall_points(scene)
    terms = phong_terms(p, np.array([0.0, 0.0, 1.0]), -d, scene.lights, WALL_MATERIAL, AMBIENT)
    expected = terms["ambient"] + terms["diffuse"] + terms["specular"]
    assert np.abs(image - expected).max() < 2e-5 * max(1.0, float(expected.max()))
    assert (terms["diffuse"] > 1e-3).mean() > 0.1


def test_a_spot_cone_3_degrees_wider_in_the_closed_form_fails_against_mitsuba():
    """The negative control of the test above."""
    scene = make_scene([WALL], {"wall": WALL_MATERIAL}, [SPOT], ambient=AMBIENT, camera={"width": 128, "height": 96})
    eye, d, p = wall_points(scene)
    wider = make_scene([WALL], {"wall": WALL_MATERIAL}, [{**SPOT, "cutoff_angle": 28.0}], ambient=AMBIENT,
                       camera={"width": 128, "height": 96})
    terms = phong_terms(p, np.array([0.0, 0.0, 1.0]), -d, wider.lights, WALL_MATERIAL, AMBIENT)
    assert np.abs(render(scene, max_depth=1) - sum(terms.values())).max() > 1e-2
