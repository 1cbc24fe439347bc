"""Image output: the linear float image to PNG (sRGB 8-bit), OpenEXR or .npy (linear float32),
written atomically so that a failed write never leaves a partial file behind."""

from __future__ import annotations

import functools
import os
import tempfile
from pathlib import Path

import numpy as np

from ..errors import SceneError

FORMATS = (".png", ".npy", ".exr")
PNG_LEVEL = 1


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 encoding of linear values clamped to [0, 1]."""
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, np.float64)
    return np.where(x <= 0.04045, x / 12.92, np.power((x + 0.055) / 1.055, 2.4))


def to_srgb8(image: np.ndarray) -> np.ndarray:
    """round(255 sRGB(x)), sRGB evaluated in float64. A float32 image goes through two tables instead of
    a power per value: the code at the start of each run of 2^16 float32 values, and the value where
    the next code starts (a run spans at most one step: 0.83 codes where sRGB is steepest in ln x)."""
    image = np.asarray(image)
    if image.dtype != np.float32:
        return np.round(linear_to_srgb(np.asarray(image, np.float64)) * 255.0).astype(np.uint8)
    x = np.clip(image, np.float32(0.0), np.float32(1.0)) + np.float32(0.0)  # + 0: -0 becomes 0
    first, step = _srgb8_tables()
    run = x.view(np.uint32) >> 16
    return first[run] + (x >= step[run])


def _srgb8_code(bits: np.ndarray) -> np.ndarray:
    return np.round(linear_to_srgb(bits.view(np.float32).astype(np.float64)) * 255.0).astype(np.uint8)


@functools.cache
def _srgb8_tables() -> tuple[np.ndarray, np.ndarray]:
    """Per run of float32 values in [0, 1] (their bit patterns >> 16, which order non-negative floats
    as their values): the code at its first value, and the least value with the next code (found by
    bisection on the bit patterns; above 1 where there is none)."""
    runs = (np.float32(1.0).view(np.uint32) >> 16) + 1
    first = _srgb8_code(np.arange(runs, dtype=np.uint32) << 16)
    lo = np.zeros(256, np.uint32)  # the code at lo is below k, at hi it is k or more
    hi = np.full(256, np.float32(1.0).view(np.uint32), np.uint32)
    k = np.arange(1, 257)
    while np.any(hi - lo > 1):
        mid = lo + (hi - lo) // 2
        up = _srgb8_code(mid) >= k
        hi, lo = np.where(up, mid, hi), np.where(up, lo, mid)
    steps = hi.view(np.float32).copy()
    steps[-1] = np.float32(2.0)  # no code after 255
    return first, steps[first]


def check_output_path(path, field: str = "output") -> Path:
    """Fail before rendering on an unknown extension or a folder we cannot write to: a render
    that cannot be saved should not run."""
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in FORMATS:
        raise SceneError(str(path), field, f"unknown image extension '{ext or '(none)'}'; expected one of: {', '.join(FORMATS)}")
    _check_writable(path, field)
    return path


def _check_writable(path: Path, field: str):
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.exists():
        raise SceneError(str(path), field, f"folder does not exist: {parent}")
    if not parent.is_dir():
        raise SceneError(str(path), field, f"not a folder: {parent}")
    if path.is_dir():
        raise SceneError(str(path), field, "is a folder, not a file")
    # Permission bits do not tell (root ignores them; a read-only mount does not show in them):
    # create and remove a file where the output will go.
    try:
        fd, probe = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".probe", dir=parent)
        os.close(fd)
        os.unlink(probe)
    except OSError as e:
        raise SceneError(str(path), field, f"cannot write to folder {parent}: {e.strerror or e}") from None


def check_text_path(path, field: str) -> Path:
    """The same checks for a text output (--stats-file), whatever its extension."""
    path = Path(path)
    _check_writable(path, field)
    return path


def _atomic(path: Path, write):
    """Write through a temporary file in the target folder, then rename: the file appears complete
    or not at all, and an earlier file of that name survives a failed write."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent if str(path.parent) else ".")
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes it 0600; an image gets the usual mode
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_text(path, text: str, field: str = "output") -> Path:
    path = check_text_path(path, field)
    try:
        _atomic(path, lambda tmp: Path(tmp).write_text(text))
    except OSError as e:
        raise SceneError(str(path), field, f"cannot write: {e.strerror or e}") from None
    return path


def _write_exr(fileobj, image: np.ndarray):
    try:
        import OpenEXR
    except ImportError:
        raise SceneError("output", None, "writing EXR needs the OpenEXR package (pip install OpenEXR)") from None
    h, w = image.shape[:2]
    channels = {c: np.ascontiguousarray(image[:, :, i], np.float32) for i, c in enumerate("RGB")}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, channels) as f:
        f.write(fileobj)


def write_image(path, image: np.ndarray, field: str = "output") -> Path:
    """Write by extension; the file appears complete or not at all (temporary file, then rename)."""
    path = check_output_path(path, field)
    ext = path.suffix.lower()

    def write(tmp):
        if ext == ".png":
            from PIL import Image

            # zlib level 1: 640x480 in about a third of the default level 6's time, files ~1.4x as large
            Image.fromarray(to_srgb8(image), "RGB").save(tmp, format="PNG", compress_level=PNG_LEVEL)
        elif ext == ".npy":
            with open(tmp, "wb") as f:
                np.save(f, np.asarray(image, np.float32))
        elif ext == ".exr":
            _write_exr(tmp, image)

    try:
        _atomic(path, write)
    except OSError as e:  # a full disk, a folder removed meanwhile
        raise SceneError(str(path), field, f"cannot write: {e.strerror or e}") from None
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
