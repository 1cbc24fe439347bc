"""Cameras and lights as the authors of glTF and USD files placed them: each number read back is
computed here from the numbers written into the file (rotations by Rodrigues' formula, glTF's yfov,
USD's 2 atan(aperture / 2 focal length), intensity x 2^exposure x colour), never from the reader."""

import math

import numpy as np
import pytest

import warprt
from warprt.scene import read_mesh_file

from formats.gltf_files import Gltf, box, quaternion, quaternion_product, rotation_matrix, usd_box
from scenekit import write_scene

YAW, PITCH = 35.0, -20.0  # the camera turns about y, then about its own x


def camera_gltf(path, ortho_second=False, aspect=None):
    """Two boxes on a floor; camera 'Main' under a translated parent, turned by YAW then PITCH;
    camera 'Side' at (-6, 1, 0) looking down +x (a quarter turn about y)."""
    g = Gltf()
    floor = (np.array([[-4, 0, -4], [4, 0, -4], [4, 0, 4], [-4, 0, 4]]), np.array([[0, 2, 1], [0, 3, 2]]))
    for v, f in (floor, box([0.5, 0.5, 0], [1, 1, 1]), box([-1.5, 1.0, -1.0], [0.8, 2.0, 0.8])):
        g.node(mesh=g.mesh(v, f))
    perspective = {"yfov": math.radians(40.0), "znear": 0.25, "zfar": 100.0}
    if aspect is not None:
        perspective["aspectRatio"] = aspect
    main = g.add("cameras", {"type": "perspective", "perspective": perspective})
    child = g.node(root=False, name="Main", camera=main, translation=[3.0, 1.0, 6.0],
                   rotation=quaternion_product(quaternion([0, 1, 0], YAW), quaternion([1, 0, 0], PITCH)))
    g.node(name="Rig", translation=[0.0, 1.0, 0.0], children=[child])
    if ortho_second:
        side = g.add("cameras", {"type": "orthographic", "orthographic": {"xmag": 2, "ymag": 2, "znear": 0.1, "zfar": 50}})
    else:
        side = g.add("cameras", {"type": "perspective", "perspective": {"yfov": math.radians(55.0), "znear": 0.5}})
    g.node(name="Side", camera=side, translation=[-6.0, 1.0, 0.0], rotation=quaternion([0, 1, 0], -90.0))
    return g.write(path)


def expected_main():
    """Eye, forward and up of 'Main' from the file's numbers: R = Ry(YAW) Rx(PITCH); the camera looks
    down its -z with +y up."""
    r = rotation_matrix([0, 1, 0], YAW) @ rotation_matrix([1, 0, 0], PITCH)
    return np.array([3.0, 2.0, 6.0]), r @ [0.0, 0.0, -1.0], r @ [0.0, 1.0, 0.0]


def assert_camera(cam, eye, forward, up, fovy, near):
    np.testing.assert_allclose(cam.eye, eye, atol=1e-12)
    d = np.subtract(cam.center, cam.eye)
    np.testing.assert_allclose(d / np.linalg.norm(d), forward, atol=1e-12)
    # up need only lie in the plane of the true up and forward, on the up side (camera_basis orthogonalises)
    u = np.asarray(cam.up, np.float64)
    forward, up = np.asarray(forward, np.float64), np.asarray(up, np.float64)
    u_perp = u - np.dot(u, forward) * forward
    np.testing.assert_allclose(u_perp / np.linalg.norm(u_perp), up, atol=1e-12)
    assert cam.fovy == pytest.approx(fovy, rel=1e-12)
    assert cam.near == pytest.approx(near, rel=1e-12)


# --- glTF cameras ---------------------------------------------------------------------------------------


def test_gltf_first_camera_is_the_view_of_a_bare_file(tmp_path):
    scene = warprt.load_scene(camera_gltf(tmp_path / "c.gltf"))
    eye, forward, up = expected_main()
    assert_camera(scene.camera, eye, forward, up, 40.0, 0.25)
    assert (scene.camera.width, scene.camera.height) == (640, 480)  # the image size stays warprt's default
    assert [c.name for c in scene.cameras] == ["Main", "Side"]


def test_gltf_camera_by_name_and_by_index(tmp_path):
    path = camera_gltf(tmp_path / "c.gltf")
    by_name = warprt.load_scene(path, camera="Side")
    by_index = warprt.load_scene(path, camera="1")
    for scene in (by_name, by_index):
        assert_camera(scene.camera, [-6.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 55.0, 0.5)


def test_camera_auto_frames_the_mesh_as_before(tmp_path):
    """--camera auto is the framing a file without cameras gets: the same boxes without the camera nodes."""
    path = camera_gltf(tmp_path / "c.gltf")
    auto = warprt.load_scene(path, camera="auto")
    g = Gltf()
    floor = (np.array([[-4, 0, -4], [4, 0, -4], [4, 0, 4], [-4, 0, 4]]), np.array([[0, 2, 1], [0, 3, 2]]))
    for v, f in (floor, box([0.5, 0.5, 0], [1, 1, 1]), box([-1.5, 1.0, -1.0], [0.8, 2.0, 0.8])):
        g.node(mesh=g.mesh(v, f))
    plain = warprt.load_scene(g.write(tmp_path / "plain.gltf"))
    assert auto.camera == plain.camera


def test_user_camera_fields_override_the_file_camera(tmp_path):
    scene = warprt.load_scene(camera_gltf(tmp_path / "c.gltf"), {"camera.width": 300, "camera.fovy": 30.0})
    eye, forward, up = expected_main()
    assert_camera(scene.camera, eye, forward, up, 30.0, 0.25)
    assert (scene.camera.width, scene.camera.height) == (300, 480)


def test_aspect_ratio_that_differs_from_the_image_warns_once(tmp_path, capsys):
    """The image size wins and yfov stays vertical (as Blender and three.js read it), with one warning."""
    scene = warprt.load_scene(camera_gltf(tmp_path / "c.gltf", aspect=16 / 9))
    err = capsys.readouterr().err.splitlines()  # load_scene turns its warnings into warprt's one-line ones
    assert len([x for x in err if "aspect ratio" in x]) == 1
    assert "aspect ratio 1.778, the image is 640x480 (1.333): its vertical field of view is kept" in err[0]
    assert scene.camera.fovy == pytest.approx(40.0)
    warprt.load_scene(camera_gltf(tmp_path / "d.gltf", aspect=640 / 480))
    assert "aspect" not in capsys.readouterr().err


@pytest.mark.parametrize("choice, message", [("Nope", "no camera named 'Nope'; the file has: Main, Side"),
                                             ("7", "there is no camera 7: the file has 2"),
                                             ("Side", "camera 'Side' is orthographic")])
def test_bad_camera_choice_is_one_line_naming_the_flag(tmp_path, choice, message):
    path = camera_gltf(tmp_path / "c.gltf", ortho_second=True)
    with pytest.raises(warprt.SceneError) as e:
        warprt.load_scene(path, camera=choice)
    assert message in str(e.value) and "camera" in str(e.value) and "\n" not in str(e.value)


def test_cli_camera_flag_and_info(tmp_path):
    from warprt.cli import main

    path = camera_gltf(tmp_path / "c.gltf", ortho_second=True)
    assert main(["render", str(path), "--camera", "Nope", "-o", str(tmp_path / "x.png"), "-q"]) == 2
    assert not (tmp_path / "x.png").exists()


def test_info_lists_cameras_and_lights(tmp_path, capsys):
    from warprt.cli import main

    path = camera_gltf(tmp_path / "c.gltf", ortho_second=True)
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "cameras    2 in the file" in out
    assert "Main             perspective fovy 40 near 0.25" in out
    assert "Side             orthographic" in out


def test_scene_file_camera_from_a_model_file(tmp_path):
    camera_gltf(tmp_path / "c.gltf")
    write_scene(tmp_path, {"camera": {"from": "c.gltf", "name": "Side", "width": 200, "height": 100},
                           "objects": [{"mesh": "c.gltf"}]}, "s.toml")
    scene = warprt.load_scene(tmp_path / "s.toml")
    assert_camera(scene.camera, [-6.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 55.0, 0.5)
    assert (scene.camera.width, scene.camera.height) == (200, 100)
    assert any(str(f).endswith("c.gltf") for f in scene.files)


@pytest.mark.parametrize("camera, field, message", [
    ('{ from = "c.gltf", name = "Back" }', "camera.name", "no camera named 'Back'"),
    ('{ from = "missing.gltf" }', "camera.from", "not found"),
    ('{ name = "Side" }', "camera.name", "camera.from"),
    ('{ from = "c.gltf", name = true }', "camera.name", "expected a camera's name or index")])
def test_scene_file_camera_errors_name_the_file_and_field(tmp_path, camera, field, message):
    camera_gltf(tmp_path / "c.gltf")
    (tmp_path / "s.toml").write_text(f'camera = {camera}\n[[objects]]\nshape = "cube"\n')
    with pytest.raises(warprt.SceneError) as e:
        warprt.load_scene(tmp_path / "s.toml")
    text = str(e.value)
    assert text.startswith(f"{tmp_path / 's.toml'}: {field}:") and message in text, text


# --- USD cameras ----------------------------------------------------------------------------------------


def camera_usd(path, meters=None, up_axis=None):
    from pxr import Gf, Usd, UsdGeom

    stage = Usd.Stage.CreateNew(str(path))
    if meters is not None:
        UsdGeom.SetStageMetersPerUnit(stage, meters)
    if up_axis is not None:
        UsdGeom.SetStageUpAxis(stage, up_axis)
    usd_box(stage, "/World/Box", [0, 0.5, 0], [1, 1, 1])
    cam = UsdGeom.Camera.Define(stage, "/World/Shot")
    cam.CreateFocalLengthAttr(35.0)
    cam.CreateVerticalApertureAttr(24.0)
    cam.CreateHorizontalApertureAttr(36.0)
    cam.CreateClippingRangeAttr(Gf.Vec2f(0.1, 1000.0))
    xf = UsdGeom.Xformable(cam)
    xf.AddTranslateOp().Set(Gf.Vec3d(2.0, 3.0, 7.0))
    xf.AddRotateYOp().Set(YAW)
    xf.AddRotateXOp().Set(PITCH)
    stage.GetRootLayer().Save()
    return path


def test_usd_camera_focal_length_and_aperture(tmp_path, capsys):
    """fovy = 2 atan(verticalAperture / 2 focalLength); xformOps apply translate, then rotateY, then
    rotateX to the camera's points (the first op outermost), so R = Ry(YAW) Rx(PITCH)."""
    scene = warprt.load_scene(camera_usd(tmp_path / "c.usda"))
    assert "camera 'Shot' was framed for aspect ratio 1.5" in capsys.readouterr().err
    r = rotation_matrix([0, 1, 0], YAW) @ rotation_matrix([1, 0, 0], PITCH)
    assert_camera(scene.camera, [2.0, 3.0, 7.0], r @ [0, 0, -1.0], r @ [0, 1.0, 0], math.degrees(2 * math.atan(12 / 35)),
                  float(np.float32(0.1)))  # clippingRange is a float2


def test_usd_camera_in_centimetres_is_placed_in_metres(tmp_path):
    scene = warprt.load_scene(camera_usd(tmp_path / "c.usda", meters=0.01), {"camera.height": 400})
    r = rotation_matrix([0, 1, 0], YAW) @ rotation_matrix([1, 0, 0], PITCH)
    assert_camera(scene.camera, [0.02, 0.03, 0.07], r @ [0, 0, -1.0], r @ [0, 1.0, 0], math.degrees(2 * math.atan(12 / 35)),
                  float(np.float32(0.1)) * 0.01)


# --- glTF lights ----------------------------------------------------------------------------------------


def lights_gltf(path, with_range=False):
    g = Gltf()
    g.node(mesh=g.mesh(*box([0, 0, 0], [1, 1, 1])))
    point = {"type": "point", "color": [1.0, 0.5, 0.25], "intensity": 8.0}
    if with_range:
        point["range"] = 3.0
    spot = {"type": "spot", "name": "lamp", "intensity": 20.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}}
    sun = {"type": "directional", "color": [0.9, 0.9, 1.0], "intensity": 3.0}
    if with_range:
        sun["range"] = 10.0  # not allowed on a directional light, but warned about once with the point's
    g.node(name="Bulb", translation=[1.0, 4.0, 2.0],
           extensions={"KHR_lights_punctual": {"light": g.light(point)}})
    spot_node = g.node(root=False, extensions={"KHR_lights_punctual": {"light": g.light(spot)}},
                       translation=[0.0, 0.0, 3.0], rotation=quaternion([1, 0, 0], -60.0))
    g.node(name="Stand", translation=[0.0, 2.0, 0.0], rotation=quaternion([0, 1, 0], 30.0), children=[spot_node])
    g.node(name="Sun", rotation=quaternion([1, 0, 0], -45.0),
           extensions={"KHR_lights_punctual": {"light": g.light(sun)}})
    return g.write(path)


def test_gltf_point_spot_and_directional_lights(tmp_path):
    point, spot, sun = read_mesh_file(lights_gltf(tmp_path / "l.gltf")).lights
    assert (point.type, point.name, point.falloff) == ("point", "Bulb", "inverse_square")
    np.testing.assert_allclose(point.position, [1.0, 4.0, 2.0])
    np.testing.assert_allclose(point.color, [8.0, 4.0, 2.0])  # colour x intensity (candela)

    ry, rx = rotation_matrix([0, 1, 0], 30.0), rotation_matrix([1, 0, 0], -60.0)
    assert (spot.type, spot.name, spot.falloff) == ("spot", "lamp", "inverse_square")
    np.testing.assert_allclose(spot.position, np.array([0.0, 2.0, 0.0]) + ry @ [0.0, 0.0, 3.0], atol=1e-12)
    np.testing.assert_allclose(spot.direction, ry @ rx @ [0.0, 0.0, -1.0], atol=1e-12)
    np.testing.assert_allclose(spot.color, [20.0] * 3)
    assert spot.cutoff_angle == pytest.approx(math.degrees(0.5)) and spot.beam_width == pytest.approx(math.degrees(0.2))

    assert (sun.type, sun.position) == ("directional", None)
    np.testing.assert_allclose(sun.direction, rotation_matrix([1, 0, 0], -45.0) @ [0.0, 0.0, -1.0], atol=1e-12)
    np.testing.assert_allclose(sun.color, [2.7, 2.7, 3.0])  # colour x intensity (lux)


def test_gltf_light_range_is_warned_about_once(tmp_path):
    with pytest.warns(UserWarning) as w:
        read_mesh_file(lights_gltf(tmp_path / "l.gltf", with_range=True))
    assert sum("range is ignored" in str(x.message) for x in w) == 1


def test_bare_gltf_with_point_lights_uses_them(tmp_path):
    g = Gltf()
    g.node(mesh=g.mesh(*box([0, 0, 0], [1, 1, 1])))
    g.node(name="Key", translation=[2.0, 3.0, 4.0],
           extensions={"KHR_lights_punctual": {"light": g.light({"type": "point", "intensity": 5.0})}})
    scene = warprt.load_scene(g.write(tmp_path / "p.gltf"))
    assert len(scene.lights) == 1
    np.testing.assert_allclose(scene.lights[0].position, [2.0, 3.0, 4.0])
    np.testing.assert_allclose(scene.lights[0].color, [5.0] * 3)


def test_bad_spot_cone_is_one_line_naming_the_light(tmp_path):
    g = Gltf()
    g.node(mesh=g.mesh(*box([0, 0, 0], [1, 1, 1])))
    bad = {"type": "spot", "spot": {"innerConeAngle": 0.6, "outerConeAngle": 0.5}}
    g.node(extensions={"KHR_lights_punctual": {"light": g.light(bad)}})
    with pytest.raises(warprt.SceneError, match=r"KHR_lights_punctual.lights\[0\].spot: expected 0 <= innerConeAngle"):
        read_mesh_file(g.write(tmp_path / "b.gltf"))


# --- USD lights -----------------------------------------------------------------------------------------


def test_usd_lux_lights(tmp_path):
    from pxr import Gf, Usd, UsdGeom, UsdLux

    stage = Usd.Stage.CreateNew(str(tmp_path / "l.usda"))
    usd_box(stage, "/World/Box", [0, 0.5, 0], [1, 1, 1])
    sphere = UsdLux.SphereLight.Define(stage, "/World/Bulb")
    sphere.CreateIntensityAttr(30.0)
    sphere.CreateExposureAttr(2.0)
    sphere.CreateColorAttr(Gf.Vec3f(1.0, 0.5, 0.25))
    sphere.CreateRadiusAttr(0.1)
    UsdGeom.Xformable(sphere).AddTranslateOp().Set(Gf.Vec3d(1.0, 5.0, -2.0))
    sun = UsdLux.DistantLight.Define(stage, "/World/Sun")
    sun.CreateIntensityAttr(2.0)
    UsdGeom.Xformable(sun).AddRotateXOp().Set(-50.0)
    disk = UsdLux.DiskLight.Define(stage, "/World/Lamp")
    disk.CreateIntensityAttr(10.0)
    disk.CreateRadiusAttr(0.0)
    shaping = UsdLux.ShapingAPI.Apply(disk.GetPrim())
    shaping.CreateShapingConeAngleAttr(30.0)
    shaping.CreateShapingConeSoftnessAttr(0.25)
    UsdGeom.Xformable(disk).AddTranslateOp().Set(Gf.Vec3d(0.0, 3.0, 0.0))
    UsdGeom.Xformable(disk).AddRotateXOp().Set(-90.0)
    point = UsdLux.SphereLight.Define(stage, "/World/Dot")  # treatAsPoint: a point by its author, no warning
    point.CreateTreatAsPointAttr(True)
    UsdGeom.Xformable(point).AddTranslateOp().Set(Gf.Vec3d(0.0, 9.0, 0.0))
    UsdLux.RectLight.Define(stage, "/World/Panel")
    UsdLux.PortalLight.Define(stage, "/World/Sky")  # a DomeLight is an environment light (test_dome_light.py)
    stage.GetRootLayer().Save()

    with pytest.warns(UserWarning) as w:
        lights = read_mesh_file(tmp_path / "l.usda").lights
    messages = [str(x.message) for x in w]
    assert not any("/World/Bulb" in m for m in messages)  # a sphere light now (radius 0.1)
    assert not any("/World/Panel" in m for m in messages)  # an area light now (test_usd_area_lights)
    assert sum("/World/Sky" in m and "PortalLight is not a Whitted light: skipped" in m for m in messages) == 1
    assert not any("/World/Dot" in m for m in messages)
    bulb, sun, lamp, dot, panel = lights
    assert (panel.type, panel.shape) == ("area", "rectangle")
    np.testing.assert_allclose(dot.position, [0.0, 9.0, 0.0])
    assert (bulb.type, bulb.name, bulb.shape) == ("area", "Bulb", "sphere")
    np.testing.assert_allclose(bulb.center, [1.0, 5.0, -2.0])
    assert bulb.radius == pytest.approx(0.1)
    np.testing.assert_allclose(bulb.radiance, np.array([1.0, 0.5, 0.25]) * 30.0 * 2.0 ** 2)
    assert sun.type == "directional" and sun.position is None
    np.testing.assert_allclose(sun.direction, rotation_matrix([1, 0, 0], -50.0) @ [0, 0, -1.0], atol=1e-7)
    np.testing.assert_allclose(sun.color, [2.0] * 3)
    assert lamp.type == "spot"
    np.testing.assert_allclose(lamp.position, [0.0, 3.0, 0.0])
    np.testing.assert_allclose(lamp.direction, [0.0, -1.0, 0.0], atol=1e-7)  # -z turned -90 degrees about x
    assert lamp.cutoff_angle == pytest.approx(30.0) and lamp.beam_width == pytest.approx(30.0 * 0.75)


def test_usd_area_lights(tmp_path):
    """UsdLux's RectLight (width along its x, height along its y) and DiskLight (radius > 0) emit along the
    prim's -z: turned -90 degrees about x at y = 3 they face down. Radiance intensity x 2^exposure x colour,
    over the area with normalize; lengths in metres (metersPerUnit 0.5 halves them)."""
    from pxr import Gf, Usd, UsdGeom, UsdLux

    stage = Usd.Stage.CreateNew(str(tmp_path / "a.usda"))
    UsdGeom.SetStageMetersPerUnit(stage, 0.5)
    usd_box(stage, "/World/Box", [0, 0.5, 0], [1, 1, 1])
    rect = UsdLux.RectLight.Define(stage, "/World/Panel")
    rect.CreateWidthAttr(4.0)
    rect.CreateHeightAttr(2.0)
    rect.CreateIntensityAttr(3.0)
    rect.CreateColorAttr(Gf.Vec3f(1.0, 0.5, 0.25))
    UsdGeom.Xformable(rect).AddTranslateOp().Set(Gf.Vec3d(0.0, 6.0, 0.0))
    UsdGeom.Xformable(rect).AddRotateXOp().Set(-90.0)
    disk = UsdLux.DiskLight.Define(stage, "/World/Lamp")
    disk.CreateRadiusAttr(1.0)
    disk.CreateIntensityAttr(2.0)
    disk.CreateNormalizeAttr(True)
    UsdGeom.Xformable(disk).AddTranslateOp().Set(Gf.Vec3d(2.0, 6.0, 0.0))
    UsdGeom.Xformable(disk).AddRotateXOp().Set(-90.0)
    stage.GetRootLayer().Save()

    panel, lamp = read_mesh_file(tmp_path / "a.usda").lights
    assert (panel.type, panel.shape, lamp.type, lamp.shape) == ("area", "rectangle", "area", "disk")
    np.testing.assert_allclose(panel.center, [0.0, 3.0, 0.0], atol=1e-12)
    # local y (height 2 -> 1 m, half 0.5) turned to -z; local x (width 4 -> 2 m, half 1) stays x: u x v points down
    np.testing.assert_allclose(panel.u, [0.0, 0.0, -0.5], atol=1e-12)
    np.testing.assert_allclose(panel.v, [1.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(panel.radiance, [3.0, 1.5, 0.75])
    np.testing.assert_allclose(lamp.center, [1.0, 3.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(lamp.normal, [0.0, -1.0, 0.0], atol=1e-12)
    assert lamp.radius == pytest.approx(0.5)
    np.testing.assert_allclose(lamp.radiance, [2.0 / (math.pi * 0.25)] * 3)  # normalize: over its area


# --- glTF's default material ----------------------------------------------------------------------------


def test_gltf_primitive_without_material_gets_the_specifications_default(tmp_path):
    """The glTF 2.0 spec: a primitive without a material uses the default one, whose base colour is 1
    (metallic 1, roughness 1: no Phong highlight). Lit by a point light at the eye (C_l 1, no ambient),
    a face-on quad is kd (n . l) = cos of the angle to the eye, not warprt's grey 0.7 with a highlight."""
    from oracle import camera_rays, ray_plane

    g = Gltf()
    g.node(mesh=g.mesh([[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]], [[0, 1, 2], [0, 2, 3]]))
    g.write(tmp_path / "q.gltf")
    write_scene(tmp_path, {
        "camera": {"eye": [0.0, 0.0, 4.0], "center": [0.0, 0.0, 0.0], "width": 64, "height": 48},
        "render": {"ambient": [0.0, 0.0, 0.0], "max_depth": 1},
        "lights": [{"position": [0.0, 0.0, 4.0]}],
        "objects": [{"mesh": "q.gltf"}],
    }, "s.toml")
    scene = warprt.load_scene(tmp_path / "s.toml")
    (obj,) = scene.objects
    material = scene.materials[obj.material]
    assert material.kd == (1.0, 1.0, 1.0) and material.ks == (0.0, 0.0, 0.0)
    image, _ = warprt.render(scene)
    eye, d = camera_rays(scene.camera)
    p = eye + ray_plane(eye, d, np.zeros(3), np.array([0.0, 0.0, 1.0]))[..., None] * d
    on = (np.abs(p[..., :2]) < 1.98).all(-1)
    to_light = eye - p
    cos = to_light[..., 2] / np.linalg.norm(to_light, axis=-1)
    np.testing.assert_allclose(image[on], np.repeat(cos[on][:, None], 3, 1), atol=2e-6)


def test_a_file_light_out_of_reach_is_the_files_error_not_the_framings(tmp_path):
    from warprt.scene import MAX_REACH

    g = Gltf()
    g.node(mesh=g.mesh(*box([0, 0, 0], [1, 1, 1])))
    g.node(name="Far", translation=[0.0, 10 * MAX_REACH, 0.0],
           extensions={"KHR_lights_punctual": {"light": g.light({"type": "point"})}})
    with pytest.raises(warprt.SceneError) as e:
        warprt.load_scene(g.write(tmp_path / "far.gltf"))
    assert str(e.value).startswith(f"{tmp_path / 'far.gltf'}: lights[0].position: ") and "frame" not in str(e.value)


def segment_hits_box(p, q, lo, hi) -> np.ndarray:
    """Slab test: whether the segments p -> q (N, 3) pass through the box [lo, hi]."""
    d = q - p
    with np.errstate(divide="ignore", invalid="ignore"):
        t0, t1 = (lo - p) / d, (hi - p) / d
    near = np.nanmax(np.minimum(t0, t1), -1)
    far = np.nanmin(np.maximum(t0, t1), -1)
    return (near <= far) & (far >= 0) & (near <= 1)


def test_bare_gltf_is_rendered_from_its_camera_with_its_point_light(tmp_path):
    """A box on a floor, seen from the file's camera and lit by the file's point light: a floor pixel
    is shadowed (C_amb ka, the framing's ambient 0.15 times glTF's default base colour 1) exactly where
    the segment from its point to the light at the file's position passes through the box, lit (brighter)
    elsewhere, whatever the light's falloff."""
    from oracle import camera_rays, ray_plane

    light = np.array([1.5, 3.0, 0.5])
    g = Gltf()
    g.node(mesh=g.mesh([[-4, 0, -4], [4, 0, -4], [4, 0, 4], [-4, 0, 4]], [[0, 2, 1], [0, 3, 2]]))
    g.node(mesh=g.mesh(*box([0, 0.5, 0], [1, 1, 1])))
    g.node(name="Key", translation=light.tolist(),
           extensions={"KHR_lights_punctual": {"light": g.light({"type": "point", "intensity": 40.0})}})
    cam = g.add("cameras", {"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.1}})
    g.node(name="Top", camera=cam, translation=[0.0, 7.0, 3.0], rotation=quaternion([1, 0, 0], -65.0))
    scene = warprt.load_scene(g.write(tmp_path / "lit.gltf"), {"camera.width": 80, "camera.height": 60})
    image, _ = warprt.render(scene, effects=["ambient", "diffuse", "shadows"])
    eye, d = camera_rays(scene.camera)
    p = eye + ray_plane(eye, d, np.zeros(3), np.array([0.0, 1.0, 0.0]))[..., None] * d
    floor = (np.abs(p[..., 0]) < 3.9) & (np.abs(p[..., 2]) < 3.9) & ~((np.abs(p[..., 0]) < 0.55) & (np.abs(p[..., 2]) < 0.55))
    # seen past the box? the camera ray must miss it too
    seen = ~segment_hits_box(np.broadcast_to(eye, p.shape).reshape(-1, 3), p.reshape(-1, 3),
                             np.array([-0.52, 0.0, -0.52]), np.array([0.52, 1.02, 0.52])).reshape(p.shape[:2])
    pts = p.reshape(-1, 3)
    to = np.broadcast_to(light, pts.shape)
    shadowed = segment_hits_box(pts, to, np.array([-0.48, 0.02, -0.48]), np.array([0.48, 0.98, 0.48])).reshape(p.shape[:2])
    lit = ~segment_hits_box(pts, to, np.array([-0.52, -0.02, -0.52]), np.array([0.52, 1.02, 0.52])).reshape(p.shape[:2])
    dark, bright = floor & seen & shadowed, floor & seen & lit
    assert dark.sum() > 50 and bright.sum() > 500
    np.testing.assert_allclose(image[dark], 0.15, atol=1e-6)
    assert image[bright].min() > 0.2


def test_scene_file_camera_from_a_z_up_stage_is_turned_with_its_objects(tmp_path):
    """An [[objects]] entry turns a z-up stage so that its z is the scene's y: (x, y, z) -> (x, z, -y).
    The camera taken from it is turned the same way, so it sees the object as the author framed it."""
    camera_usd(tmp_path / "c.usda", up_axis="Z")
    write_scene(tmp_path, {"camera": {"from": "c.usda", "name": "Shot", "width": 300, "height": 200},
                           "objects": [{"mesh": "c.usda"}]}, "s.toml")
    scene = warprt.load_scene(tmp_path / "s.toml")
    r = rotation_matrix([0, 1, 0], YAW) @ rotation_matrix([1, 0, 0], PITCH)
    z_to_y = lambda v: np.array([v[0], v[2], -v[1]])  # noqa: E731
    assert_camera(scene.camera, z_to_y([2.0, 3.0, 7.0]), z_to_y(r @ [0, 0, -1.0]), z_to_y(r @ [0, 1.0, 0]),
                  math.degrees(2 * math.atan(12 / 35)), float(np.float32(0.1)))
    lo, hi = scene.bounds()  # and the box, z from -0.5 to 0.5 in the file, has that as its y here
    np.testing.assert_allclose([lo[1], hi[1]], [-0.5, 0.5], atol=1e-12)


def test_file_camera_center_is_at_the_models_depth(tmp_path):
    """The center (what an orbit turns about) lies on the view axis at the depth of the model's centre."""
    scene = warprt.load_scene(camera_gltf(tmp_path / "c.gltf"))
    eye, forward, _ = expected_main()
    middle = np.array([0.0, 1.0, 0.0])  # the floor spans y 0..0 and x, z -4..4; the tall box reaches y = 2
    np.testing.assert_allclose(scene.camera.center, eye + forward * np.dot(middle - eye, forward), atol=1e-12)
