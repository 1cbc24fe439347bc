"""Image output: the linear float image to PNG (sRGB 8-bit) or .npy (linear float32), written
atomically so that a failed write never leaves a partial file behind."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np

from .errors import SceneError

FORMATS = (".png", ".npy", ".exr")


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 encoding of linear values clamped to [0, 1]."""
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, np.float64)
    return np.where(x <= 0.04045, x / 12.92, np.power((x + 0.055) / 1.055, 2.4))


def to_srgb8(image: np.ndarray) -> np.ndarray:
    return np.round(linear_to_srgb(image) * 255.0).astype(np.uint8)


def check_output_path(path) -> Path:
    """Fail before rendering on an unknown extension or a folder we cannot write to."""
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in FORMATS:
        raise SceneError(str(path), "output", f"unknown image extension '{ext or '(none)'}'; expected one of: {', '.join(FORMATS)}")
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise SceneError(str(path), "output", f"folder does not exist: {parent}")
    if not os.access(parent, os.W_OK):
        raise SceneError(str(path), "output", f"folder is not writable: {parent}")
    if path.is_dir():
        raise SceneError(str(path), "output", "is a folder, not a file")
    return path


def _write_exr(fileobj, image: np.ndarray):
    try:
        import OpenEXR  # optional: the 'exr' extra
    except ImportError:
        raise SceneError("output", None, "writing EXR needs the OpenEXR package (pip install 'warprt[exr]')") from None
    h, w = image.shape[:2]
    channels = {c: np.ascontiguousarray(image[:, :, i], np.float32) for i, c in enumerate("RGB")}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, channels) as f:
        f.write(fileobj)


def write_image(path, image: np.ndarray) -> Path:
    """Write by extension; the file appears complete or not at all (temporary file, then rename)."""
    path = check_output_path(path)
    ext = path.suffix.lower()
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=ext, dir=path.parent if str(path.parent) else ".")
    os.close(fd)
    try:
        if ext == ".png":
            from PIL import Image

            Image.fromarray(to_srgb8(image), "RGB").save(tmp, format="PNG")
        elif ext == ".npy":
            with open(tmp, "wb") as f:
                np.save(f, np.asarray(image, np.float32))
        elif ext == ".exr":
            _write_exr(tmp, image)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def read_image(path) -> np.ndarray:
    """Read back a PNG (decoded to linear), .npy or .exr as float32 (H, W, 3)."""
    path = Path(path)
    ext = path.suffix.lower()
    if ext == ".npy":
        return np.load(path).astype(np.float32)
    if ext == ".exr":
        import OpenEXR

        with OpenEXR.File(str(path)) as f:
            ch = f.channels()
            if "RGB" in ch:
                return np.asarray(ch["RGB"].pixels, np.float32)
            return np.stack([np.asarray(ch[c].pixels, np.float32) for c in "RGB"], -1)
    from PIL import Image

    return srgb_to_linear(np.asarray(Image.open(path).convert("RGB"), np.float64) / 255.0).astype(np.float32)
