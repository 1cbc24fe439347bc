"""The Mitsuba conversion's camera is warprt's camera: Mitsuba's perspective sensor, set up from
look_at(eye, center, up) and the vertical fov, shoots through every pixel centre the ray of the
seed's formula (tests/oracle/camera.py), for an 'up' that is not orthogonal to the view and a non-square image."""

import numpy as np
import pytest

from reference.mitsuba_whitted import MitsubaScene, mitsuba
from oracle import camera_rays
from scenekit import make_scene

pytestmark = pytest.mark.accuracy

OBJECT = [{"shape": "box", "size": 1.0}]
CAMERAS = {
    "rolled_wide": {"eye": [4.0, 2.5, 3.0], "center": [0.2, 0.4, -0.1], "up": [0.5, 1.0, 0.7],
                    "fovy": 35.0, "width": 37, "height": 23},
    "portrait_low_up": {"eye": [-3.0, -1.0, 2.0], "center": [0.0, 0.0, 0.0], "up": [0.2, 0.3, -1.0],
                        "fovy": 70.0, "width": 19, "height": 41},
}


def sensor_rays(camera_fields, sx=0.5, sy=0.5, spp=1):
    mi, _ = mitsuba()
    scene = make_scene(OBJECT, camera=camera_fields)
    cam = scene.camera
    sensor = MitsubaScene(scene).sensor(cam, spp)
    rows, cols = np.meshgrid(np.arange(cam.height), np.arange(cam.width), indexing="ij")
    # Film coordinates in [0, 1]^2, row 0 at the top, as Mitsuba's sampling integrator passes them.
    u = (cols.ravel() + sx) / cam.width
    v = (rows.ravel() + 1.0 - sy) / cam.height
    ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(mi.Float(u), mi.Float(v)), mi.Point2f(0.5, 0.5))
    shape = (cam.height, cam.width, 3)
    return scene, np.array(ray.o).T.reshape(shape), np.array(ray.d).T.reshape(shape)


@pytest.mark.parametrize("name", CAMERAS)
def test_sensor_rays_are_the_seed_camera_rays(name):
    scene, origins, directions = sensor_rays(CAMERAS[name])
    eye, expected = camera_rays(scene.camera)
    assert np.abs(directions - expected).max() < 5e-7  # float32 rounding of unit vectors
    # Rays start at the eye, moved along the ray by the sensor's tiny near clip.
    along = np.einsum("ijk,ijk->ij", origins - eye, expected)
    assert np.abs(origins - eye - along[..., None] * expected).max() < 1e-5
    assert 0.0 <= along.min() and along.max() < 1e-3


def test_sensor_rays_through_stratum_centres_match_the_seed_formula():
    """The sub-pixel positions a 3x3 stratified sample uses are the ones warprt uses."""
    fields = CAMERAS["rolled_wide"]
    for sx, sy in ((1 / 6, 1 / 6), (5 / 6, 1 / 2), (1 / 2, 5 / 6)):
        scene, _, directions = sensor_rays(fields, sx, sy, spp=9)
        _, expected = camera_rays(scene.camera, sx, sy)
        assert np.abs(directions - expected).max() < 5e-7
