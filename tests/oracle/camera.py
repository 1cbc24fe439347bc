"""The seed's pinhole camera in float64, written from its formulas (not from warprt's camera code):
the rays every closed-form test and the brute-force tracer start from."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np


class Pinhole(NamedTuple):
    eye: np.ndarray
    z_e: np.ndarray  # from center to eye: the camera looks along -z_e
    x_e: np.ndarray
    y_e: np.ndarray
    d_f: float  # distance of the image plane (the camera's near)
    h: float  # image-plane height
    w: float  # image-plane width
    width: int  # w_p
    height: int  # h_p


def pinhole(cam) -> Pinhole:
    """z_e = (eye - center)/|eye - center|, x_e = (up x z_e)/|up x z_e|, y_e = z_e x x_e,
    h = 2 d_f tan(fovy/2) (fovy in degrees, d_f = near), w = h w_p/h_p. ``cam`` is a
    warprt.scene.Camera or anything with its fields; a Pinhole is returned as it is."""
    if isinstance(cam, Pinhole):
        return cam
    eye, center, up = (np.asarray(v, np.float64) for v in (cam.eye, cam.center, cam.up))
    z_e = (eye - center) / math.dist(eye, center)
    x_e = np.cross(up, z_e) / np.linalg.norm(np.cross(up, z_e))
    y_e = np.cross(z_e, x_e)
    h = 2.0 * cam.near * math.tan(math.radians(cam.fovy) / 2.0)
    return Pinhole(eye, z_e, x_e, y_e, float(cam.near), h, h * cam.width / cam.height, int(cam.width), int(cam.height))


def ray_directions(cam, cols, rows, sx=0.5, sy=0.5) -> np.ndarray:
    """Un-normalised directions (..., 3) through the point (sx, sy) of pixels (cols, rows), row 0
    at the top (arrays broadcast together):
        d = -d_f z_e + h((y + sy)/h_p - 1/2) y_e + w((x + sx)/w_p - 1/2) x_e,
    x = col, y = h_p - 1 - row counted from the bottom row."""
    c = pinhole(cam)
    x = np.asarray(cols, np.float64)
    y = c.height - 1 - np.asarray(rows, np.float64)
    a = c.h * ((y + sy) / c.height - 0.5)
    b = c.w * ((x + np.asarray(sx, np.float64)) / c.width - 0.5)
    a, b = np.broadcast_arrays(a, b)
    return -c.d_f * c.z_e + a[..., None] * c.y_e + b[..., None] * c.x_e


def pixel_directions(cam, sx=0.5, sy=0.5) -> np.ndarray:
    """ray_directions for every pixel: (h_p, w_p, 3), un-normalised (the z_e part is -d_f)."""
    c = pinhole(cam)
    rows, cols = np.meshgrid(np.arange(c.height), np.arange(c.width), indexing="ij")
    return ray_directions(c, cols, rows, sx, sy)


def camera_rays(cam, sx=0.5, sy=0.5):
    """The eye and the unit directions (h_p, w_p, 3) through the point (sx, sy) of every pixel."""
    c = pinhole(cam)
    d = pixel_directions(c, sx, sy)
    return c.eye, d / np.linalg.norm(d, axis=-1, keepdims=True)
