"""Emissive materials (issue 32): a material's ``emission`` makes each of its objects an area light of that
radiance over the object's triangles, exactly the [[lights]] area light naming the object; glTF's
emissiveFactor times KHR_materials_emissive_strength, as Blender reads it; checked, listed and changed as
the other lights are."""

from __future__ import annotations

import numpy as np
import pytest

import warprt
from warprt import SceneError
from warprt.cli import main
from warprt.scene import resolve_effects

from formats.gltf_files import Gltf

L_E = (2.0, 1.0, 0.5)
FLOOR = {"shape": "plane", "size": [8.0, 8.0], "material": "floor"}
LAMP = {"shape": "box", "name": "lamp", "translate": [0.0, 1.5, 0.0], "scale": [0.6, 0.2, 0.6]}
CAMERA = {"eye": [2.5, 2.0, 3.0], "center": [0.0, 0.5, 0.0], "width": 40, "height": 30}


def room(lamp_material: dict, lights=(), **render) -> warprt.Scene:
    return warprt.load_dict({
        "camera": CAMERA, "render": {"ambient": [0.05] * 3, **render}, "lights": list(lights),
        "materials": {"floor": {"kd": [0.4, 0.4, 0.4], "ks": [0.2] * 3}, "lamp": {"kd": [0.1] * 3, **lamp_material}},
        "objects": [FLOOR, {**LAMP, "material": "lamp"}]})


def test_an_emissive_material_is_the_area_light_of_its_objects():
    """The same image, to the bit, as the plain material with an area light naming the object; and
    a scene with it compiles the area-light variant (a dark floor without)."""
    emissive = room({"emission": list(L_E)})
    explicit = room({}, lights=[{"type": "area", "radiance": list(L_E), "object": "lamp"}])
    image, _ = warprt.render(emissive)
    assert np.array_equal(image, warprt.render(explicit)[0])
    assert resolve_effects(emissive).area_lights
    assert image.mean() > 2 * warprt.render(room({}))[0].mean()  # the control: the lamp's light is there


def test_an_emissive_surface_shows_its_emission_from_its_front():
    """A face-on quad of zero ambient reflectance, seen from its front: its emission; from behind: black."""
    def seen_from(z):
        scene = warprt.load_dict({
            "camera": {"eye": [0.0, 0.0, z], "center": [0.0, 0.0, 0.0], "width": 1, "height": 1},
            "render": {"ambient": [0.0] * 3}, "materials": {"glow": {"kd": [0.0] * 3, "emission": list(L_E)}},
            "objects": [{"shape": "plane", "size": [2.0, 2.0], "rotate": [90.0, 0.0, 0.0], "material": "glow"}]})
        return warprt.render(scene, primary_query="raytrace")[0][0, 0]
    front, back = seen_from(2.0), seen_from(-2.0)
    assert np.array_equal(front, np.float32(L_E)) != np.array_equal(back, np.float32(L_E))
    assert {tuple(front), tuple(back)} == {tuple(np.float32(L_E)), (0.0, 0.0, 0.0)}


def test_gltf_emission_is_its_factor_times_its_strength(tmp_path, capsys):
    """emissiveFactor (0.5, 0.25, 1) with KHR_materials_emissive_strength 4: L_e (2, 1, 4), what the
    camera sees of the quad's front; `warprt info` lists it with its area and power (pi L_e A)."""
    g = Gltf()
    m = g.add("materials", {"name": "glow", "doubleSided": True, "emissiveFactor": [0.5, 0.25, 1.0],
                            "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]},
                            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}})
    g.doc["extensionsUsed"] = ["KHR_materials_emissive_strength"]
    g.node(mesh=g.mesh([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], [[0, 1, 2], [0, 2, 3]], material=m), name="panel")
    path = g.write(tmp_path / "panel.gltf")
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text(f'[camera]\neye = [0.0, 0.0, 3.0]\ncenter = [0.0, 0.0, 0.0]\nwidth = 1\nheight = 1\n'
                          f'[render]\nambient = [0.0, 0.0, 0.0]\n[[objects]]\nmesh = "{path.name}"\n')
    scene = warprt.load_scene(scene_file)
    (light,) = scene.emissive_lights
    assert light.radiance == (2.0, 1.0, 4.0)
    assert np.array_equal(warprt.render(scene)[0][0, 0], np.float32([2.0, 1.0, 4.0]))
    assert main(["info", str(scene_file)]) == 0
    out = capsys.readouterr().out
    assert "1 emissive objects" in out and "area 4 power [25.132741, 12.566371, 50.265482]" in out


def test_an_emissive_texture_is_a_warning_and_its_factor_emits(tmp_path, capsys):
    g = Gltf()
    g.add("images", {"uri": "missing.png"})
    g.add("textures", {"source": 0})
    m = g.add("materials", {"emissiveFactor": [1.0, 1.0, 1.0], "emissiveTexture": {"index": 0}})
    g.node(mesh=g.mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], material=m))
    path = g.write(tmp_path / "t.gltf")
    (tmp_path / "s.toml").write_text(f'[[objects]]\nmesh = "{path.name}"\n')
    scene = warprt.load_scene(tmp_path / "s.toml")
    assert "the emissive texture is not read" in capsys.readouterr().err  # load_scene's one-line warnings
    assert [l.radiance for l in scene.emissive_lights] == [(1.0, 1.0, 1.0)]


@pytest.mark.parametrize("change, field, message", [
    ({"materials": {"lamp": {"emission": [1.0, -1.0, 0.0]}}}, "materials.lamp.emission", "non-negative"),
    ({"objects": [FLOOR, {**LAMP, "material": "lamp"}, {**LAMP, "material": "floor", "translate": [2.0, 0.0, 0.0]}]},
     "objects[2].name", "give each emitting object its own name"),
    ({"lights": [{"type": "area", "radiance": [1.0] * 3, "object": "lamp"}]}, "lights[0].object", "emits already"),
])
def test_a_bad_emission_is_one_line_naming_its_field(change, field, message):
    doc = {"camera": CAMERA, "materials": {"floor": {"kd": [0.4] * 3}, "lamp": {"emission": list(L_E)}},
           "objects": [FLOOR, {**LAMP, "material": "lamp"}]}
    doc = {**doc, **change}
    if "lamp" in doc["materials"] and "emission" not in doc["materials"]["lamp"]:
        doc["materials"]["lamp"]["emission"] = list(L_E)
    with pytest.raises(SceneError, match=message) as e:
        warprt.load_dict(doc)
    assert e.value.field == field


def test_a_renderers_emission_parameter_renders_as_a_file_saying_it():
    r = warprt.Renderer(room({"emission": list(L_E)}))
    r.render()
    r.params["materials.lamp.emission"] = [0.5, 0.5, 3.0]
    assert np.array_equal(r.render().image, warprt.render(room({"emission": [0.5, 0.5, 3.0]}))[0])
