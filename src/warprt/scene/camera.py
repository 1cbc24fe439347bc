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


class FileCamera(NamedTuple):
    """A camera a model file defines, in the file's world space (float64): the seed's pinhole seen
    from eye towards center, with the file's vertical field of view and near distance. ``aspect``:
    the width / height the author framed for, where the file says (it does not set the image size)."""

    name: str
    kind: str  # "perspective" | "orthographic" (listed, not rendered: the seed's camera is a pinhole)
    eye: tuple
    center: tuple
    up: tuple
    fovy: float  # degrees
    near: float
    aspect: float | None = None

    def fields(self, subject=None) -> dict:
        """The camera table (TOML vocabulary) it sets: the image size stays the user's. ``subject``: a point
        (the model's centre) whose depth along the view the center is put at, so that an orbit about the
        center turns about the model; else the center is one unit ahead."""
        eye, center = np.asarray(self.eye), np.asarray(self.center)
        if subject is not None:
            forward = (center - eye) / np.linalg.norm(center - eye)
            center = eye + forward * max(float(np.dot(np.asarray(subject, np.float64) - eye, forward)), self.near)
        return {"eye": list(self.eye), "center": [float(x) for x in center], "up": list(self.up), "fovy": self.fovy,
                "near": self.near}


def look_from_matrix(to_world: np.ndarray, name: str, kind: str, fovy: float, near: float,
                     aspect: float | None = None) -> FileCamera:
    """A camera looking down its local -z with its local +y up (glTF's and USD's convention), placed
    by ``to_world`` (4x4, column vectors: p' = M p)."""
    m = np.asarray(to_world, np.float64)
    eye = m[:3, 3]
    forward = -m[:3, 2] / np.linalg.norm(m[:3, 2])
    up = m[:3, 1] / np.linalg.norm(m[:3, 1])
    as_tuple = lambda v: tuple(float(x) for x in v)  # noqa: E731
    return FileCamera(name, kind, as_tuple(eye), as_tuple(eye + forward), as_tuple(up), float(fovy), float(near),
                      None if aspect is None else float(aspect))


def find_camera(cameras, choice=None) -> FileCamera:
    """The camera ``choice`` names among a file's: its name, its index (an int or a string of digits), or
    None for the first. A LookupError says what the file has; an orthographic one is refused (the seed's
    camera is a pinhole)."""
    if not cameras:
        raise LookupError("the file defines no camera")
    if choice is None:
        cam = cameras[0]
    elif (isinstance(choice, int) and not isinstance(choice, bool)) or (isinstance(choice, str) and choice.isdigit()):
        if not int(choice) < len(cameras):
            raise LookupError(f"there is no camera {int(choice)}: the file has {len(cameras)} (0 to {len(cameras) - 1})")
        cam = cameras[int(choice)]
    else:
        cam = next((c for c in cameras if c.name == choice), None)
        if cam is None:
            raise LookupError(f"no camera named '{choice}'; the file has: {', '.join(c.name for c in cameras)}")
    if cam.kind != "perspective":
        raise LookupError(f"camera '{cam.name}' is {cam.kind}; warprt renders through a pinhole (perspective) "
                          "camera only")
    return cam


def aspect_note(cam: FileCamera, width: int, height: int) -> str | None:
    """What a warning says where the author framed for another aspect ratio than the image's. The image
    size wins and the vertical field of view is kept, as Blender and three.js do; None where they agree."""
    if cam.aspect is None or abs(cam.aspect - width / height) <= 1e-3 * cam.aspect:
        return None
    return (f"camera '{cam.name}' was framed for aspect ratio {cam.aspect:.4g}, the image is {width}x{height} "
            f"({width / height:.4g}): its vertical field of view is kept (set the width and height to match)")
