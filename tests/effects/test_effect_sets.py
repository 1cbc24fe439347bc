"""Effect sets: derived from the scene, narrowed by the user, never widened; one compiled variant
per set, with the code of disabled effects absent from the generated source."""

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
import warp as wp

import warprt
from marks import slow
from scenekit import make_scene, write_scene
from warprt.kernels import init_warp, make_trace_kernel, stack_size
from warprt.scene import EFFECTS, EffectSet, resolve_effects, scene_effects

LIGHT = {"position": [0.0, 3.0, 4.0]}
PLAIN = {"kd": [0.5, 0.5, 0.5]}
WALL = {"shape": "plane", "size": [20.0, 20.0], "rotate": [90.0, 0.0, 0.0], "material": "m"}


def fx_of(material=PLAIN, lights=(LIGHT,), objects=None, **render):
    return scene_effects(make_scene(objects or [WALL], {"m": material}, lights, **{"ambient": [0.1] * 3, **render}))


def test_a_plain_diffuse_scene_needs_only_ambient_diffuse_and_shadows():
    assert fx_of() == EffectSet(ambient=True, diffuse=True, specular=False, shadows=True, reflection=False)


def test_each_effect_appears_only_where_the_scene_calls_for_it():
    assert not fx_of(ambient=[0.0, 0.0, 0.0]).ambient                      # C_amb = 0
    assert not fx_of({"kd": [0.5] * 3, "ka": [0.0] * 3}).ambient           # ka = 0
    assert fx_of({"kd": [0.5] * 3, "ka": [0.0, 0.1, 0.0]}).ambient         # one channel is enough
    no_lights = fx_of(lights=())
    assert not (no_lights.diffuse or no_lights.specular or no_lights.shadows)
    assert not fx_of(lights=({"position": [0, 3, 4], "color": [0, 0, 0]},)).diffuse  # a black light lights nothing
    assert not fx_of(shadows=False).shadows
    assert fx_of({"kd": [0.5] * 3, "ks": [0.2] * 3}).specular
    assert not fx_of({"kd": [0.5] * 3, "reflectivity": 0.5}, max_depth=1).reflection  # needs a second ray level
    assert fx_of({"kd": [0.5] * 3, "reflectivity": 0.5}, max_depth=2).reflection
    assert not fx_of().reflection                                           # k_r = 0 everywhere
    assert fx_of(spp=4).supersampling and not fx_of(spp=1).supersampling
    assert fx_of(objects=[{**WALL, "smooth": True}]).smooth and not fx_of().smooth
    checker = {"kd_texture": {"checker": [[1, 1, 1], [0, 0, 0]]}}
    assert fx_of(checker).texture and not fx_of().texture
    assert fx_of({"kd": [0.5] * 3, "ks_texture": {"checker": [[1, 1, 1], [0, 0, 0]]}}).texture  # any textured colour
    colored = {"shape": "triangles", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "faces": [[0, 1, 2]],
               "colors": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "material": "m"}
    assert fx_of(objects=[WALL, colored]).vertex_color and not fx_of().vertex_color


def test_unused_materials_do_not_switch_effects_on():
    scene = make_scene([WALL], {"m": PLAIN, "mirror": {"reflectivity": 1.0, "ks": [1.0] * 3},
                                "tiles": {"kd_texture": {"checker": [[1, 1, 1], [0, 0, 0]]}}}, [LIGHT], max_depth=4)
    fx = scene_effects(scene)
    assert not fx.reflection and not fx.specular and not fx.texture


def test_users_can_switch_effects_off_but_never_on():
    scene = make_scene([WALL], {"m": PLAIN}, [LIGHT], ambient=[0.1] * 3)
    assert resolve_effects(scene, disable=["shadows"]) == EffectSet(True, True, False, False, False)
    assert resolve_effects(scene, allow=["ambient"]) == EffectSet(True, False, False, False, False)
    # Asking for every effect gives only what the scene has.
    assert resolve_effects(scene, allow=list(EFFECTS)) == scene_effects(scene)
    # Shadows only dim lit terms: with neither diffuse nor specular, no shadow rays.
    assert not resolve_effects(scene, disable=["diffuse"]).shadows
    with pytest.raises(warprt.SceneError, match="unknown effect 'textures'"):
        resolve_effects(scene, allow=["textures"])


GLASS = {"ior": 1.5, "ka": [0.0] * 3, "kd": [0.0] * 3}
BALL = {"shape": "sphere", "radius": 0.5, "subdivisions": 1, "translate": [0.0, 0.0, 1.0], "material": "glass"}


def test_refraction_only_where_a_used_material_has_ior_and_there_is_a_second_ray_level():
    def glass(max_depth=3, **material):
        scene = make_scene([WALL, BALL], {"m": PLAIN, "glass": {**GLASS, **material}}, [LIGHT], max_depth=max_depth)
        return scene_effects(scene)

    assert glass().refraction and not glass().absorption
    assert not glass(max_depth=1).refraction  # no secondary rays
    assert glass(absorption=[0.0, 0.5, 0.0]).absorption
    assert not scene_effects(make_scene([WALL], {"m": PLAIN, "glass": GLASS}, [LIGHT], max_depth=3)).refraction  # unused
    assert not fx_of(max_depth=3).refraction and not fx_of(max_depth=3).absorption


def test_absorption_acts_on_the_first_ray_level_too():
    """An eye inside absorbing glass sees through it at max_depth 1: Beer's law needs no second level."""
    scene = make_scene([WALL, BALL], {"m": PLAIN, "glass": {**GLASS, "absorption": 0.5}}, [LIGHT], max_depth=1)
    fx = scene_effects(scene)
    assert fx.absorption and not fx.refraction


@slow
def test_scene_file_effects_setting_and_cli_flags(tmp_path):
    path = write_scene(tmp_path, {
        "camera": {"eye": [0, 0, 5], "center": [0, 0, 0], "width": 16, "height": 12},
        "render": {"effects": ["ambient", "diffuse", "reflection"], "max_depth": 3},
        "lights": [{"position": [0, 3, 4]}],
        "materials": {"m": {"kd": [0.5, 0.5, 0.5], "ks": [0.5, 0.5, 0.5], "reflectivity": 0.5}},
        "objects": [{"shape": "plane", "rotate": [90, 0, 0], "material": "m"}],
    }, "s.toml")
    scene = warprt.load_scene(path)
    assert str(resolve_effects(scene)) == "ambient,diffuse,reflection"
    r = subprocess.run([sys.executable, "-m", "warprt", "render", str(path), "-o", str(tmp_path / "o.png"),
                        "--stats", "--effects", "ambient,diffuse,specular", "--max-depth", "1"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    import json

    stats = json.loads(r.stdout)
    assert stats["effects"] == "ambient,diffuse" and stats["variant"] == "trace_ad_zprimary"
    assert stats["primary_query"] == "zbuffer"  # the default: two triangles over 192 samples are rasterized
    assert stats["rays"] == {"primary": 16 * 12, "shadow": 0, "reflection": 0, "refraction": 0, "total": 16 * 12}


def _generated_source(fx, aovs=()) -> str:
    init_warp()
    kernel = make_trace_kernel(fx, stack=stack_size(4) if fx.refraction else 0, aovs=aovs)
    wp.load_module(kernel.module, device="cpu")
    (module_exec,) = kernel.module.execs.values()
    return Path(module_exec.binary_path).with_suffix("").with_suffix(".cpp").read_text()


# A line of each effect's Python source, as Warp's code generator quotes it in the C++ it compiles.
MARKERS = {
    "ambient": "out.color = wp.cw_mul(s.ambient, k.ka)",
    "diffuse": "phong_diffuse(k.kd, n_dot_l)",
    "specular": "phong_specular(k.ks, shininess, n, L, v, n_dot_l)",
    "shadows": "wp::mesh_query_ray_anyhit(",
    "reflection": "kr = s.kr[hit.material]",
    "supersampling": "sx = (float(sample % k) + 0.5) / float(k)",
    "smooth": "ns = s.normals[i0] * u",
    "texture": "c.kd = wp.cw_mul(c.kd, texel(s.texels, s.kd_map[m], hit.uv))",
    "vertex_color": "out.color = s.colors[j0] * u",
    "refraction": "t, transmits = refract(d, m, eta_rel)",
    "absorption": "weight = beer(weight, s.absorption[medium], wp.length(hit.p - start))",
}


@slow
@pytest.mark.parametrize("off", EFFECTS)
def test_disabled_effect_code_is_absent_from_the_compiled_variant(off):
    full = EffectSet(supersampling=True, smooth=True, texture=True, vertex_color=True, refraction=True, absorption=True)
    assert all(m in _generated_source(full) for m in MARKERS.values())
    source = _generated_source(EffectSet(**{**{e: getattr(full, e) for e in EFFECTS}, off: False}))
    assert MARKERS[off] not in source
    assert all(MARKERS[e] in source for e in EFFECTS if e != off)


@pytest.mark.parametrize("lights, general", [
    ([LIGHT, {"position": [1.0, 2.0, 3.0], "falloff": "none"}], False),
    ([LIGHT, {"position": [1.0, 2.0, 3.0], "falloff": "inverse_square"}], True),
    ([{"type": "spot", "position": [0.0, 3.0, 4.0], "direction": [0.0, -1.0, -1.0]}], True),
    ([{"type": "directional", "direction": [0.0, -1.0, -1.0]}], True),
])
def test_the_general_light_model_is_asked_for_only_by_lights_beyond_the_seeds(lights, general):
    fx = fx_of(lights=lights)
    assert fx.light_model == general and fx.names == fx_of().names  # not an effect one names or disables
    assert resolve_effects(make_scene([WALL], {"m": PLAIN}, lights), disable=["specular"]).light_model == general


def test_the_general_light_model_is_absent_from_the_seeds_variants():
    """Scenes of point lights without falloff compile the seed's shading, without the spot profile or
    the falloff (the same code as before the new lights, so their images are the same to the bit)."""
    marker = "weight = light_weight(shape, to_light, L)"
    assert marker not in _generated_source(EffectSet())
    assert marker in _generated_source(EffectSet(light_model=True))


def test_back_face_culling_is_compiled_in_only_where_a_material_is_single_sided():
    """A scene file's materials are double-sided: its variants keep the code they had (the same images,
    to the bit); one single-sided material asks for culling, which is not an effect one names or disables."""
    marker = "while q.result and culled(s, q.face, ray.d)"
    assert marker not in _generated_source(EffectSet())
    assert marker in _generated_source(EffectSet(culling=True))
    single = make_scene([WALL], {"m": {**PLAIN, "double_sided": False}}, [LIGHT])
    fx = resolve_effects(single, disable=["specular"])
    assert fx.culling and not scene_effects(make_scene([WALL], {"m": PLAIN}, [LIGHT])).culling
    assert fx.variant.endswith("C") and "culling" not in fx.names


# A line of each AOV's recording code, as above.
AOV_MARKERS = {
    "depth": "a.depth[pixel] = a.depth[pixel] + wp.length(hit.p - o)",
    "uv": "a.uv[pixel] = a.uv[pixel] + uv",
    "face": "a.face[pixel] = f - a.object_first_face[obj]",
}


@slow
def test_aov_code_is_compiled_in_only_for_the_aovs_asked_for():
    fx = EffectSet()
    plain = _generated_source(fx)
    assert "record_first_hit" not in plain and not any(m in plain for m in AOV_MARKERS.values())
    depth = _generated_source(fx, aovs=("depth",))
    assert "record_first_hit" in depth and AOV_MARKERS["depth"] in depth
    assert AOV_MARKERS["uv"] not in depth and AOV_MARKERS["face"] not in depth
    assert all(m in _generated_source(fx, aovs=tuple(AOV_MARKERS)) for m in AOV_MARKERS.values())


@slow
def test_a_second_process_loads_the_variant_from_the_disk_cache(tmp_path):
    """Warp caches compiled modules on disk: the second process start must not compile again."""
    script = textwrap.dedent(f"""
        import warp as wp
        wp.config.kernel_cache_dir = {str(tmp_path / 'cache')!r}
        import warprt
        scene = warprt.load_scene().with_camera(width=8, height=6)
        image, stats = warprt.render(scene)
        print(stats.variant)
    """)

    def snapshot():
        return {p: p.stat().st_mtime_ns for p in (tmp_path / "cache").rglob("*") if p.is_file()}

    first = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert first.returncode == 0, first.stderr
    built = snapshot()
    assert any(str(p).endswith(".o") for p in built), "the first start compiles into the cache"
    second = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert second.returncode == 0, second.stderr
    assert second.stdout == first.stdout
    assert snapshot() == built, "the second start wrote to the cache: it compiled again"
