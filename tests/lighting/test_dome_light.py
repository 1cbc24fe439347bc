"""USD DomeLights (issue 39) as environment lights, their orientation checked against UsdLux's words, not the
reader's: the texture is written from the OpenEXR latlong layout the DomeLight schema quotes (pixel (x, y) at
latitude pi/2 - pi y / (H - 1) and longitude pi - 2 pi x / (W - 1); latitude +pi/2 the +y direction, longitude
0 +z, pi/2 +x; DomeLight_1's Z pole: +z, longitude 0 -y), painted with a sky linear in the direction,
L(d) = c + b.d, whose irradiance on a plane of normal n is pi c + (2 pi / 3) b.n (tests/oracle/environment.py).
Six planes facing +-x, +-y, +-z tell every axis and sign of the mapping apart; the mirrored image, the pole left
at +y and the dome turned the other way are the negative controls. The reader places a column's centre at
(x + 1/2) / W of the turn (Mitsuba's envmap), OpenEXR at x / (W - 1): half a texel apart at most, which the
tolerance covers: the error falls as 1 / W (1.35%, 0.70%, 0.38% at W = 64, 128, 256), and painted at (x + 1/2) / W
the same planes are within 0.2%, 0.04%, 0.03% of the closed form (1,024 light directions)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

import warprt
from warprt import SceneError
from warprt.scene import read_mesh_file

from oracle.environment import linear_sky_irradiance, sky_irradiance

H, W = 64, 128  # the texture's rows, columns
C, B = 1.0, np.array([0.3, 0.45, 0.6])  # the sky's radiance c + b.d, d the schema's direction of a pixel
GAIN = np.array([1.0, 0.5, 0.25]) * 2.0 * 2.0 ** 1  # colour x intensity 2 x 2^exposure 1
NORMALS = np.concatenate([np.eye(3), -np.eye(3)])
TURNS = ([0, 0, -90], [0, 0, 0], [90, 0, 0], [0, 0, 90], [180, 0, 0], [-90, 0, 0])  # the plane's +y to each normal
ROT_Z90 = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # USD's rotateZ 90: x to y, y to -x
REL_TOL = 0.01  # measured below: 0.7% at most (the half texel; 0.04% where the image is painted at (x + 1/2) / W)


def latlong_direction(lat, long, pole: str):
    """The schema's direction of (latitude, longitude): with the Y pole, (sin long cos lat, sin lat, cos long cos
    lat); with the Z pole, latitude +pi/2 is +z, longitude 0 -y and pi/2 +x."""
    x, up, forward = np.sin(long) * np.cos(lat), np.sin(lat), np.cos(long) * np.cos(lat)
    return np.stack([x, up, forward] if pole == "Y" else [x, -forward, up], -1)


def sky_image(pole: str, mirrored: bool = False) -> np.ndarray:
    """(H, W, 3) float32, row 0 the image's top (data window min y): c + b.d at each pixel's direction; mirrored,
    the longitudes run the other way."""
    y, x = np.mgrid[0:H, 0:W].astype(np.float64)
    lat, long = math.pi / 2 - math.pi * y / (H - 1), math.pi - 2 * math.pi * x / (W - 1)
    d = latlong_direction(lat, -long if mirrored else long, pole)
    return np.repeat((C + d @ B)[..., None], 3, -1).astype(np.float32)


def write_exr(path, image):
    import OpenEXR

    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}, {"RGB": image}) as f:
        f.write(str(path))


def dome_stage(path, up="Y", kind="DomeLight", pole=None, rotate_z=None, texture="sky.exr", layout=None):
    """A stage with one triangle and a dome light (intensity 2, exposure 1, colour (1, 0.5, 0.25))."""
    from pxr import Gf, Usd, UsdGeom, UsdLux

    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, up)
    mesh = UsdGeom.Mesh.Define(stage, "/World/Tri")
    mesh.CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    mesh.CreateFaceVertexCountsAttr([3])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2])
    dome = getattr(UsdLux, kind).Define(stage, "/World/Sky")
    dome.CreateIntensityAttr(2.0)
    dome.CreateExposureAttr(1.0)
    dome.CreateColorAttr(Gf.Vec3f(1.0, 0.5, 0.25))
    if texture:
        dome.CreateTextureFileAttr(texture)
    if layout:
        dome.CreateTextureFormatAttr(layout)
    if pole:
        dome.CreatePoleAxisAttr(pole)
    if rotate_z is not None:
        UsdGeom.Xformable(dome).AddRotateZOp().Set(rotate_z)
    stage.GetRootLayer().Save()
    return path


def dome(folder, image, **stage):
    """The light read_mesh_file reads of dome_stage(**stage) with ``image`` as its sky.exr."""
    folder.mkdir(parents=True, exist_ok=True)
    write_exr(folder / "sky.exr", image)
    (light,) = read_mesh_file(dome_stage(folder / "dome.usda", **stage)).lights
    return light


@pytest.fixture(scope="module")
def planes():
    """Six scenes: a 2 x 2 plane of kd 1 / pi at the origin facing each of NORMALS, seen in one pixel from in
    front of it and a little aside; its radiance is E / pi."""
    return [warprt.load_dict({
        "camera": {"eye": list(3.0 * n + 0.5 * np.roll(n, 1)), "center": [0.0, 0.0, 0.0], "width": 1, "height": 1},
        "render": {"ambient": [0.0] * 3, "light_samples": 256, "max_depth": 1},
        "lights": [{"type": "environment", "radiance": [1.0] * 3}],
        "materials": {"m": {"kd": [1.0 / math.pi] * 3, "ks": [0.0] * 3}},
        "objects": [{"shape": "plane", "size": [2.0, 2.0], "rotate": turn, "material": "m"}]})
        for n, turn in zip(NORMALS, TURNS)]


def irradiance(planes, light) -> np.ndarray:
    """(6, 3): E on the plane facing each of NORMALS under ``light``."""
    return np.array([math.pi * warprt.render(replace(p, lights=[light])).image[0, 0].astype(np.float64)
                     for p in planes])


def expected(rotation=np.eye(3)) -> np.ndarray:
    """(6, 3): the closed form for the sky c + b.(R^T w) at world directions w (b turned by R), times the gain."""
    return np.array([[linear_sky_irradiance(C, rotation @ B, n)] for n in NORMALS]) * GAIN


def off(measured, wanted) -> float:
    return float(np.abs(measured / wanted - 1.0).max())


CASES = {  # the stage, the image's pole and the dome's expected rotation of the schema's directions
    "DomeLight on a Y-up stage": ({}, "Y", np.eye(3)),
    "DomeLight_1 on a Z-up stage (poleAxis scene)": ({"up": "Z", "kind": "DomeLight_1"}, "Z", np.eye(3)),
    "DomeLight_1 with poleAxis Z on a Y-up stage": ({"kind": "DomeLight_1", "pole": "Z"}, "Z", np.eye(3)),
    "DomeLight_1 with poleAxis Y on a Z-up stage": ({"up": "Z", "kind": "DomeLight_1", "pole": "Y"}, "Y", np.eye(3)),
    "DomeLight on a Z-up stage (its pole +y always)": ({"up": "Z"}, "Y", np.eye(3)),
    "DomeLight turned 90 degrees about z": ({"rotate_z": 90.0}, "Y", ROT_Z90),
}


@pytest.mark.parametrize("case", list(CASES))
def test_a_dome_lights_planes_as_the_schema_places_its_image(planes, tmp_path, case):
    """Measured: 0.70% at most, each case."""
    stage, pole, rotation = CASES[case]
    light = dome(tmp_path, sky_image(pole), **stage)
    assert light.type == "environment"
    assert off(irradiance(planes, light), expected(rotation)) < REL_TOL


CONTROLS = {  # a reading the check must catch: the image, the stage, and the rotation wrongly expected
    "the longitudes mirrored": (sky_image("Y", mirrored=True), {}, np.eye(3)),
    "the Z pole left at +y": (sky_image("Z"), {"up": "Z"}, np.eye(3)),  # DomeLight: +y, not the stage's up
    "the dome turned the other way": (sky_image("Y"), {"rotate_z": -90.0}, ROT_Z90),
}


@pytest.mark.parametrize("control", list(CONTROLS))
def test_a_wrong_orientation_is_caught(planes, tmp_path, control):
    """The negative controls, measured: 49%, 118% and 85% off."""
    image, stage, rotation = CONTROLS[control]
    assert off(irradiance(planes, dome(tmp_path, image, **stage)), expected(rotation)) > 10 * REL_TOL


def test_a_dome_without_a_texture_is_a_constant_sky_of_its_colour_times_its_intensity(planes, tmp_path):
    """E = pi L on every plane (oracle: sky_irradiance), L = colour x intensity x 2^exposure (measured: 0.04% off,
    the lattice's error on planes off the pole); the negative control: the exposure left out, 50% off."""
    (light,) = read_mesh_file(dome_stage(tmp_path / "dome.usda", texture=None)).lights
    assert light.image is None
    wanted = np.tile(sky_irradiance(1.0) * GAIN, (6, 1))
    assert off(irradiance(planes, light), wanted) < 1e-3
    assert off(irradiance(planes, replace(light, radiance=tuple(GAIN / 2.0 ** 1))), wanted) > 0.4


def test_a_scaled_dome_is_warned_and_turned_by_its_rotation(tmp_path):
    from pxr import Usd, UsdGeom

    write_exr(tmp_path / "sky.exr", sky_image("Y"))
    turned = read_mesh_file(dome_stage(tmp_path / "turned.usda", rotate_z=90.0)).lights[0]
    path = dome_stage(tmp_path / "scaled.usda", rotate_z=90.0)
    stage = Usd.Stage.Open(str(path))
    UsdGeom.Xformable(stage.GetPrimAtPath("/World/Sky")).AddScaleOp().Set((2.0, 2.0, 2.0))
    stage.GetRootLayer().Save()
    with pytest.warns(UserWarning, match="/World/Sky.*not a rotation: its nearest rotation is read"):
        scaled = read_mesh_file(path).lights[0]
    assert np.allclose(scaled.rotate, turned.rotate, atol=1e-9) and not np.allclose(turned.rotate, 0.0)


@pytest.mark.parametrize("layout", ["mirroredBall", "angular", "cubeMapVerticalCross"])
def test_a_texture_not_latlong_is_refused_in_one_line(tmp_path, layout):
    write_exr(tmp_path / "sky.exr", sky_image("Y"))
    with pytest.raises(SceneError) as e:
        read_mesh_file(dome_stage(tmp_path / "dome.usda", layout=layout))
    assert f"/World/Sky.inputs:texture:format: a {layout} dome texture is not read" in str(e.value)
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("content", [None, b"not an image"])
def test_a_missing_or_unreadable_texture_is_one_line_naming_it(tmp_path, content):
    if content is not None:
        (tmp_path / "sky.exr").write_bytes(content)
    with pytest.raises(SceneError) as e:
        read_mesh_file(dome_stage(tmp_path / "dome.usda"))
    text = str(e.value)
    assert "/World/Sky.inputs:texture:file: " in text and "sky.exr" in text and "\n" not in text


def test_a_bare_stage_with_a_dome_renders_and_its_gradient_is_refused(tmp_path):
    """Loaded as a bare file (warprt.load_scene): the dome is the scene's environment light, and a gradient
    of the scene is refused as for any environment light."""
    write_exr(tmp_path / "sky.exr", sky_image("Y"))
    scene = warprt.load_scene(dome_stage(tmp_path / "dome.usda"), overrides={"camera.width": 8, "camera.height": 6})
    assert scene.environment is not None and scene.environment.name == "Sky"
    r = warprt.Renderer(scene)
    with pytest.raises(SceneError, match="environment light is not differentiated") as e:
        r.render(grad=True)
    assert "\n" not in str(e.value)
