"""Image output: the linear float image to PNG (sRGB 8-bit), OpenEXR, .npy or .npz (linear float32), with
the AOVs asked for, written atomically so that a failed write never leaves a partial file behind."""

from __future__ import annotations

import glob
import os
import tempfile
from pathlib import Path

import numpy as np

from ..errors import SceneError
from ..scene import srgb_to_linear
from .aovs import AOVS, CHANNELS, IDS

FORMATS = (".png", ".npy", ".exr", ".npz")


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 encoding of linear values clamped to [0, 1]."""
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def to_srgb8(image: np.ndarray) -> np.ndarray:
    return np.round(linear_to_srgb(image) * 255.0).astype(np.uint8)


def check_output_path(path, field: str = "output", aovs=()) -> Path:
    """Fail before rendering on an unknown extension or a folder we cannot write to: a render
    that cannot be saved should not run. With ``aovs`` (names), their files too (aov_paths)."""
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in FORMATS:
        raise SceneError(str(path), field, f"unknown image extension '{ext or '(none)'}'; expected one of: {', '.join(FORMATS)}")
    if aovs and ext == ".npy":
        raise SceneError(str(path), field, "a .npy file holds the colour only; for AOVs write .npz, .exr, or .png "
                                           "(the AOVs beside it as <stem>.<aov>.exr)")
    _check_writable(path, field)
    for sibling in aov_paths(path, aovs).values():
        _check_writable(sibling, field)
    return path


def aov_paths(path, aovs) -> dict:
    """The files the AOVs ``aovs`` (names) of an image written to ``path`` go to besides it: none for
    .exr and .npz, which hold them; for a .png, <stem>.<aov>.exr beside it, one per AOV."""
    path = Path(path)
    if path.suffix.lower() != ".png":
        return {}
    return {name: path.with_name(f"{path.stem}.{name}.exr") for name in aovs}


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


def partial_files(path) -> list[Path]:
    """The temporary files that writes of ``path`` killed midway left beside it (_atomic's names)."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    return sorted(folder.glob(f".{glob.escape(path.name)}.*{glob.escape(path.suffix)}"))


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


def _exr_channels(aovs: dict) -> dict:
    """Each AOV's channels (aovs.CHANNELS): float32, the IDs as UINT holding their int32 bits."""
    channels = {}
    for name, a in aovs.items():
        a = np.asarray(a)
        planes = a[..., None] if a.ndim == 2 else a
        for i, c in enumerate(CHANNELS[name]):
            plane = np.ascontiguousarray(planes[..., i], np.int32 if name in IDS else np.float32)
            channels[c] = plane.view(np.uint32) if name in IDS else plane
    return channels


def _write_exr(fileobj, image: np.ndarray | None, aovs: dict | None = None):
    try:
        import OpenEXR
    except ImportError:
        raise SceneError("output", None, "writing EXR needs the OpenEXR package (pip install OpenEXR)") from None
    channels = {} if image is None else {c: np.ascontiguousarray(image[:, :, i], np.float32) for i, c in enumerate("RGB")}
    channels.update(_exr_channels(aovs or {}))
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, channels) as f:
        f.write(fileobj)


def write_image(path, image: np.ndarray, field: str = "output", aovs: dict | None = None) -> Path:
    """Write by extension; the file appears complete or not at all (temporary file, then rename).
    ``aovs`` (name -> array, as render() returns them) go into the .exr or .npz file itself, or one
    EXR each beside a .png (aov_paths), written before it: once the PNG is there, so are they."""
    aovs = aovs or {}
    path = check_output_path(path, field, tuple(aovs))
    ext = path.suffix.lower()
    for name, sibling in aov_paths(path, aovs).items():
        try:
            _atomic(sibling, lambda tmp: _write_exr(tmp, None, {name: aovs[name]}))
        except OSError as e:
            raise SceneError(str(sibling), field, f"cannot write: {e.strerror or e}") from None

    def write(tmp):
        if ext == ".png":
            from PIL import Image

            Image.fromarray(to_srgb8(image), "RGB").save(tmp, format="PNG")
        elif ext == ".npy":
            with open(tmp, "wb") as f:
                np.save(f, np.asarray(image, np.float32))
        elif ext == ".exr":
            _write_exr(tmp, image, aovs)
        elif ext == ".npz":
            with open(tmp, "wb") as f:  # np.savez given a name would append ".npz" to the temporary one
                np.savez(f, color=np.asarray(image, np.float32), **aovs)

    try:
        _atomic(path, write)
    except OSError as e:  # a full disk, a folder removed meanwhile
        raise SceneError(str(path), field, f"cannot write: {e.strerror or e}") from None
    return path


def read_image(path) -> np.ndarray:
    """Read back a PNG (decoded to linear), .npy, .npz or .exr as float32 (H, W, 3)."""
    path = Path(path)
    ext = path.suffix.lower()
    if ext == ".npy":
        return np.load(path).astype(np.float32)
    if ext == ".npz":
        with np.load(path) as z:
            return z["color"].astype(np.float32)
    if ext == ".exr":
        import OpenEXR

        with OpenEXR.File(str(path)) as f:
            ch = f.channels()
            if "RGB" in ch:
                return np.asarray(ch["RGB"].pixels, np.float32)
            return np.stack([np.asarray(ch[c].pixels, np.float32) for c in "RGB"], -1)
    from PIL import Image

    return srgb_to_linear(np.asarray(Image.open(path).convert("RGB"), np.float64) / 255.0).astype(np.float32)


def read_aovs(path) -> dict:
    """The AOVs written with an image (write_image's ``aovs``), by name: from a .npz as they were
    written (position in float64), from EXR channels in float32 (IDs int32 again), for a .png from the
    EXR files beside it."""
    path = Path(path)
    ext = path.suffix.lower()
    if ext == ".npz":
        with np.load(path) as z:
            return {name: z[name] for name in AOVS if name in z.files}
    if ext == ".png":
        out = {}
        for name in AOVS:
            sibling = path.with_name(f"{path.stem}.{name}.exr")
            if sibling.is_file():
                out.update(read_aovs(sibling))
        return out
    import OpenEXR

    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = {name: c.pixels for name, c in f.channels().items()}
    out = {}
    for name in AOVS:
        if all(c in ch for c in CHANNELS[name]):
            planes = [ch[c].view(np.int32) if name in IDS else ch[c] for c in CHANNELS[name]]
            out[name] = planes[0] if len(planes) == 1 else np.stack(planes, -1)
    return out
