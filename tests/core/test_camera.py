"""The camera: warprt's basis, ray directions and kernel rays against the seed's formulas
(tests/oracle/camera.py, written from them, not from warprt's code)."""

import numpy as np
import pytest
import warp as wp

from oracle import camera_rays, pinhole, pixel_directions, ray_directions
from warprt.kernels import CameraData, camera_data, camera_ray, init_warp
from warprt.scene import Camera, camera_basis, pixel_ray_directions


CAMERAS = [
    Camera(eye=(0, 1.5, 5), center=(0, 0.8, 0), up=(0, 1, 0), fovy=45, near=1, width=64, height=48),
    # Non-orthogonal up vector and a non-square (portrait) image.
    Camera(eye=(3, 2, -4), center=(0.5, 0.2, 1), up=(0.3, 1, 0.4), fovy=70, near=2.5, width=37, height=53),
]


@pytest.mark.parametrize("cam", CAMERAS)
def test_basis_is_the_seeds(cam):
    b, seed = camera_basis(cam), pinhole(cam)
    np.testing.assert_allclose(b.z_e, seed.z_e, atol=1e-15)
    np.testing.assert_allclose(b.x_e, seed.x_e, atol=1e-15)
    np.testing.assert_allclose(b.y_e, seed.y_e, atol=1e-15)
    assert b.d_f == seed.d_f and np.array_equal(b.eye, seed.eye)
    assert b.h == pytest.approx(seed.h, rel=1e-15)
    assert b.w == pytest.approx(seed.w, rel=1e-15)
    # Orthonormal and right-handed, whatever the up vector was.
    np.testing.assert_allclose(np.stack([b.x_e, b.y_e, b.z_e]) @ np.stack([b.x_e, b.y_e, b.z_e]).T, np.eye(3), atol=1e-14)


@pytest.mark.parametrize("cam", CAMERAS)
def test_pixel_directions(cam):
    """d = -d_f z_e + h(y/h_p - 1/2) y_e + w(x/w_p - 1/2) x_e at pixel centres, y from the bottom."""
    y, x = pinhole(cam).y_e, pinhole(cam).x_e
    d = pixel_ray_directions(camera_basis(cam))
    for row, col in [(0, 0), (cam.height - 1, cam.width - 1), (cam.height // 2, 3), (7, cam.width - 5)]:
        np.testing.assert_allclose(d[row, col], ray_directions(cam, col, row), atol=1e-14)
    # Row 0 is the top of the image: its rays point further along y_e than the bottom row's.
    assert d[0, 0] @ y > d[-1, 0] @ y and d[0, 0] @ x < d[0, -1] @ x


@pytest.mark.parametrize("cam", CAMERAS)
@pytest.mark.parametrize("sx, sy", [(1 / 6, 1 / 6), (5 / 6, 1 / 2), (0.25, 0.75)])
def test_sub_pixel_directions(cam, sx, sy):
    """The stratified samples' rays: the same formula at (x + sx, y + sy), for every pixel."""
    d = pixel_ray_directions(camera_basis(cam), sx, sy)
    np.testing.assert_allclose(d, pixel_directions(cam, sx, sy), atol=1e-14)


@wp.kernel
def _kernel_rays(c: CameraData, xs: wp.array(dtype=int), rows: wp.array(dtype=int), out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    out[i] = camera_ray(c, xs[i], rows[i], 0.5, 0.5)


@pytest.mark.parametrize("cam", CAMERAS)
def test_kernel_rays_match_the_formula(cam):
    """The tracer's own camera_ray, run in a Warp kernel, gives the formula's unit directions."""
    init_warp()
    rng = np.random.default_rng(1)
    cols = rng.integers(0, cam.width, 50)
    rows = rng.integers(0, cam.height, 50)
    out = wp.empty(50, dtype=wp.vec3, device="cpu")
    wp.launch(_kernel_rays, 50, inputs=[camera_data(camera_basis(cam)), wp.array(cols, dtype=int), wp.array(rows, dtype=int), out])
    _, d = camera_rays(cam)
    np.testing.assert_allclose(out.numpy(), d[rows, cols], atol=2e-7)
