"""A glTF and a USD camera against Mitsuba's ``aov`` integrator: warprt renders the file from its own
camera; Mitsuba renders the same objects from a camera this test sets from the numbers written into
the file (eye from the node's translations, the view from Rodrigues' rotations, fovy from yfov or
2 atan(aperture / 2 focal length)). Depth, object and face must agree at every pixel that is not a
float32 tie, as in test_aovs_against_mitsuba.py; a camera off by the aspect (yfov read as the
horizontal field) or by an axis (up along x) must fail (the negative control)."""

import math
from dataclasses import replace

import numpy as np
import pytest

import warprt
from reference import render_mitsuba_aovs
from warprt.scene import Camera

from accuracy.test_aovs_against_mitsuba import POSITION_REL, unexplained
from formats.gltf_files import Gltf, box, quaternion, quaternion_product, rotation_matrix, usd_box

pytestmark = pytest.mark.accuracy

W, H = 96, 64
YAW, PITCH = 30.0, -25.0
BOXES = ([0.6, 0.5, 0.2], [1.0, 1.0, 1.0]), ([-1.2, 0.9, -0.8], [0.7, 1.8, 0.7]), ([0.2, 0.3, 1.6], [2.0, 0.6, 0.5])


def turn():
    return rotation_matrix([0, 1, 0], YAW) @ rotation_matrix([1, 0, 0], PITCH)


def gltf_file(tmp_path):
    g = Gltf()
    g.node(mesh=g.mesh([[-4, 0, -4], [4, 0, -4], [4, 0, 4], [-4, 0, 4]], [[0, 2, 1], [0, 3, 2]]))
    for center, size in BOXES:
        g.node(mesh=g.mesh(*box(center, size)))
    cam = g.add("cameras", {"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.1}})
    child = g.node(root=False, name="Shot", camera=cam, translation=[2.5, 1.5, 5.0],
                   rotation=quaternion_product(quaternion([0, 1, 0], YAW), quaternion([1, 0, 0], PITCH)))
    g.node(name="Rig", translation=[0.0, 0.5, 0.0], children=[child])
    path = g.write(tmp_path / "shot.gltf")
    r = turn()
    eye = np.array([2.5, 2.0, 5.0])
    return path, Camera(eye=eye, center=eye + r @ [0, 0, -1.0], up=r @ [0, 1.0, 0], fovy=math.degrees(0.7),
                        near=0.1, width=W, height=H)


def usd_file(tmp_path):
    from pxr import Gf, Usd, UsdGeom

    stage = Usd.Stage.CreateNew(str(tmp_path / "shot.usda"))
    for k, (center, size) in enumerate(((np.zeros(3), [8.0, 0.02, 8.0]),) + BOXES):
        usd_box(stage, f"/World/Box{k}", center, size)
    cam = UsdGeom.Camera.Define(stage, "/World/Shot")
    cam.CreateFocalLengthAttr(30.0)
    cam.CreateVerticalApertureAttr(20.0)
    cam.CreateHorizontalApertureAttr(30.0)
    xf = UsdGeom.Xformable(cam)
    xf.AddTranslateOp().Set(Gf.Vec3d(2.5, 2.0, 5.0))
    xf.AddRotateYOp().Set(YAW)
    xf.AddRotateXOp().Set(PITCH)
    stage.GetRootLayer().Save()
    r = turn()
    eye = np.array([2.5, 2.0, 5.0])
    return tmp_path / "shot.usda", Camera(eye=eye, center=eye + r @ [0, 0, -1.0], up=r @ [0, 1.0, 0],
                                          fovy=math.degrees(2 * math.atan(10.0 / 30.0)), width=W, height=H)


def disagreement(scene, a, camera):
    """Mitsuba's AOVs of ``scene``'s objects seen by ``camera``: the pixels whose hit, object or face
    differ from warprt's ``a``, and the largest depth difference (over |eye| + depth) where they agree."""
    expected = replace(scene, camera=camera)
    m = render_mitsuba_aovs(expected)
    hit = np.isfinite(a["depth"])
    both = hit & m["hit"]
    differ = (hit != m["hit"]) | (both & ((a["object"] != m["object"]) | (a["face"] != m["face"])))
    same = both & ~differ
    scale = np.abs(np.asarray(camera.eye)).max() + m["depth"]
    depth = float((np.abs(a["depth"] - m["depth"]) / scale)[same].max()) if same.any() else np.inf
    return expected, np.argwhere(differ), depth, same


@pytest.mark.parametrize("writer", [gltf_file, usd_file], ids=["gltf", "usd"])
def test_file_camera_aovs_match_mitsuba_from_the_files_numbers(tmp_path, writer):
    path, camera = writer(tmp_path)
    scene = warprt.load_scene(path, {"camera.width": W, "camera.height": H})
    a = warprt.render(scene, aovs=["depth", "object", "face"]).aovs
    expected, differ, depth, same = disagreement(scene, a, camera)
    assert same.sum() > 0.5 * same.size
    bad = unexplained(expected, differ)
    assert not bad, f"{len(bad)} pixels hit another surface than Mitsuba's, not at a tie: {bad[:10]}"
    assert depth <= POSITION_REL, depth

    # The negative control: the same comparison with the camera planted wrong.
    tan_half = math.tan(math.radians(camera.fovy) / 2)
    as_horizontal = replace(camera, fovy=math.degrees(2 * math.atan(tan_half * H / W)))
    forward = np.subtract(camera.center, camera.eye)
    sideways = replace(camera, up=tuple(np.cross(forward, camera.up)))
    for wrong in (as_horizontal, sideways):
        _, differ, _, _ = disagreement(scene, a, wrong)
        assert len(differ) > 0.02 * W * H, wrong
