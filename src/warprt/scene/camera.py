"""The seed's pinhole camera: the basis (z_e, x_e, y_e) and the image-plane size (h, w).

One definition, used by the tracer, the Z-buffer and the tests of the Mitsuba conversion.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np


class CameraBasis(NamedTuple):
    eye: np.ndarray  # float64, world space
    z_e: np.ndarray  # points from center to eye (the camera looks along -z_e)
    x_e: np.ndarray
    y_e: np.ndarray
    d_f: float  # distance of the image plane (near)
    h: float  # image-plane height, 2 d_f tan(fovy / 2)
    w: float  # image-plane width, h * width / height
    width: int
    height: int


def camera_basis(cam) -> CameraBasis:
    """z_e = (eye - center)/|eye - center|, x_e = (up x z_e)/|up x z_e|, y_e = z_e x x_e."""
    eye, center, up = (np.asarray(v, np.float64) for v in (cam.eye, cam.center, cam.up))
    z_e = (eye - center) / np.linalg.norm(eye - center)
    x_e = np.cross(up, z_e)
    x_e /= np.linalg.norm(x_e)
    y_e = np.cross(z_e, x_e)
    d_f = float(cam.near)
    h = 2.0 * d_f * math.tan(math.radians(cam.fovy) / 2.0)
    w = h * cam.width / cam.height
    return CameraBasis(eye, z_e, x_e, y_e, d_f, h, w, int(cam.width), int(cam.height))


def pixel_ray_directions(basis: CameraBasis, sx: float = 0.5, sy: float = 0.5) -> np.ndarray:
    """Un-normalised directions (height, width, 3) through the point (sx, sy) of each pixel, with
    row 0 at the top: d = -d_f z_e + h((y + sy)/h_p - 1/2) y_e + w((x + sx)/w_p - 1/2) x_e,
    y counted from the bottom row."""
    b = basis
    x = (np.arange(b.width) + sx) / b.width - 0.5
    y = (np.arange(b.height)[::-1] + sy) / b.height - 0.5
    return (-b.d_f * b.z_e + b.h * y[:, None, None] * b.y_e + b.w * x[None, :, None] * b.x_e)
