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


# --- emission from files: USD's emissiveColor and CylinderLight, OBJ's Ke ---------------------------------

def _face_on(tmp_path, mesh_name: str) -> warprt.Scene:
    """A scene of one mesh file, seen face-on from z = 3 by a one-pixel camera, no ambient, no light."""
    (tmp_path / "s.toml").write_text('[camera]\neye = [0.0, 0.0, 3.0]\ncenter = [0.0, 0.0, 0.0]\nwidth = 1\nheight = 1\n'
                                     f'[render]\nambient = [0.0, 0.0, 0.0]\n[[objects]]\nmesh = "{mesh_name}"\n')
    return warprt.load_scene(tmp_path / "s.toml")


def test_usd_emissive_color_is_the_materials_emission(tmp_path):
    """UsdPreviewSurface's emissiveColor (2, 1, 0.5) on a quad facing the camera: the pixel is L_e, and the
    quad is an area light; emissiveColor 0 (its default) emits nothing."""
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade

    def stage(path, emissive):
        stage = Usd.Stage.CreateNew(str(path))
        quad = UsdGeom.Mesh.Define(stage, "/World/Panel")
        quad.CreatePointsAttr([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)])
        quad.CreateFaceVertexCountsAttr([4])
        quad.CreateFaceVertexIndicesAttr([0, 1, 2, 3])
        material = UsdShade.Material.Define(stage, "/World/Glow")
        shader = UsdShade.Shader.Define(stage, "/World/Glow/Surface")
        shader.CreateIdAttr("UsdPreviewSurface")
        shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(0.0, 0.0, 0.0))
        shader.CreateInput("emissiveColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*emissive))
        material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
        UsdShade.MaterialBindingAPI.Apply(quad.GetPrim()).Bind(material)
        stage.GetRootLayer().Save()

    stage(tmp_path / "glow.usda", (2.0, 1.0, 0.5))
    scene = _face_on(tmp_path, "glow.usda")
    assert [l.radiance for l in scene.emissive_lights] == [(2.0, 1.0, 0.5)]
    assert np.array_equal(warprt.render(scene)[0][0, 0], np.float32([2.0, 1.0, 0.5]))
    stage(tmp_path / "dark.usda", (0.0, 0.0, 0.0))
    assert not _face_on(tmp_path, "dark.usda").emissive_lights


def test_obj_ke_is_the_materials_emission_and_blenders_zero_ke_emits_nothing(tmp_path):
    (tmp_path / "q.obj").write_text("mtllib q.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nusemtl glow\nf 1 2 3 4\n")
    (tmp_path / "q.mtl").write_text("newmtl glow\nKd 0 0 0\nKe 2 1 0.5\n")
    scene = _face_on(tmp_path, "q.obj")
    assert [l.radiance for l in scene.emissive_lights] == [(2.0, 1.0, 0.5)]
    assert np.array_equal(warprt.render(scene)[0][0, 0], np.float32([2.0, 1.0, 0.5]))
    (tmp_path / "q.mtl").write_text("newmtl glow\nKd 0.8 0.8 0.8\nKe 0.000000 0.000000 0.000000\n")  # as Blender writes
    assert not _face_on(tmp_path, "q.obj").emissive_lights


def cylinder_light_stage(path, radius=0.25, length=2.0, height=1.5, normalize=False, **attrs):
    """A UsdLux CylinderLight of intensity 2 (white), its axis along x at y = ``height``."""
    from pxr import Gf, Usd, UsdGeom, UsdLux

    stage = Usd.Stage.CreateNew(str(path))
    tube = UsdLux.CylinderLight.Define(stage, "/World/Tube")
    tube.CreateLengthAttr(length)
    tube.CreateRadiusAttr(radius)
    tube.CreateIntensityAttr(2.0)
    tube.CreateNormalizeAttr(normalize)
    for name, value in attrs.items():
        getattr(tube, f"Create{name}Attr")(value)
    UsdGeom.Xformable(tube).AddTranslateOp().Set(Gf.Vec3d(0.0, height, 0.0))
    stage.GetRootLayer().Save()
    return path


def floor_under(tmp_path, mesh_name: str, samples: int) -> float:
    """The radiance of a floor (kd 0.5, y = 0) at the origin under the mesh file's lights: one pixel."""
    scene = warprt.load_dict({
        "camera": {"eye": [0.0, 0.5, 3.0], "center": [0.0, 0.0, 0.0], "width": 1, "height": 1},
        "render": {"ambient": [0.0] * 3, "light_samples": samples, "max_depth": 1},
        "materials": {"floor": {"kd": [0.5] * 3, "ks": [0.0] * 3}},
        "objects": [{"shape": "plane", "size": [12.0, 12.0], "material": "floor"}, {"mesh": mesh_name}]}, tmp_path, "t")
    return float(warprt.render(scene, primary_query="raytrace")[0][0, 0, 1])


def test_a_usd_cylinder_light_lights_a_floor_as_the_emitting_cylinder_does(tmp_path):
    """A CylinderLight (UsdLux: along its x, emitting outwards from its side, not its caps) of radius 0.25
    and length 2 at height 1.5 over a floor point below its middle: the floor's irradiance is the integral
    of L cos cos' / r^2 over the cylinder's side (tests/oracle/area.py, a quadrature checked against the
    infinite cylinder's closed form), within 1% at 1,024 points (measured +0.21%) and 4,096; the same tube
    read along y instead (the control) is far off."""
    from oracle.area import cylinder_below_irradiance

    cylinder_light_stage(tmp_path / "tube.usda")
    expected = 0.5 * cylinder_below_irradiance(2.0, 0.25, 2.0, 1.5)
    for samples in (1024, 4096):
        assert floor_under(tmp_path, "tube.usda", samples) == pytest.approx(expected, rel=0.01)
    along_y = 0.5 * cylinder_below_irradiance(2.0, 0.25, 0.25 * 2.0, 1.5)  # what a misread axis would roughly give
    assert abs(along_y / expected - 1.0) > 0.2


def test_a_usd_cylinder_lights_radiance_and_its_quirks(tmp_path, capsys):
    """Normalize divides the intensity by the tube's area (2 pi r l, less 1e-4 for the polygon); the tube shows
    its radiance from outside; treatAsLine is read as the cylinder, with a warning; a zero radius is skipped."""
    from warprt.scene import read_mesh_file

    cylinder_light_stage(tmp_path / "n.usda", normalize=True)
    (part,) = read_mesh_file(tmp_path / "n.usda").parts
    (_, material), = read_mesh_file(tmp_path / "n.usda").materials
    area = 2.0 * np.pi * 0.25 * 2.0
    assert material.emission[0] == pytest.approx(2.0 / area, rel=2e-4) and material.kd == (0.0, 0.0, 0.0)
    (tmp_path / "s.toml").write_text('[camera]\neye = [0.0, 1.5, 3.0]\ncenter = [0.0, 1.5, 0.0]\nwidth = 1\nheight = 1\n'
                                     '[render]\nambient = [0.0, 0.0, 0.0]\n[[objects]]\nmesh = "n.usda"\n')
    assert warprt.render(warprt.load_scene(tmp_path / "s.toml"))[0][0, 0, 0] == pytest.approx(material.emission[0])
    with pytest.warns(UserWarning, match="treatAsLine is not read"):
        read_mesh_file(cylinder_light_stage(tmp_path / "line.usda", TreatAsLine=True))
    with pytest.warns(UserWarning, match="emits from no surface: skipped"), pytest.raises(SceneError, match="no triangles"):
        read_mesh_file(cylinder_light_stage(tmp_path / "flat.usda", radius=0.0))  # the stage's one prim skipped
