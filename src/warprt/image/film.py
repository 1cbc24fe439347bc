"""Image output: the linear float image to PNG (sRGB 8-bit), OpenEXR, .npy or .npz (linear float32), with
the AOVs asked for, and the output-path policy every file a command writes follows (atomic, through
symlinks, never onto an input)."""

from __future__ import annotations

import errno
import functools
import glob
import os
import shutil
import stat
import struct
import tempfile
import zlib
from pathlib import Path

import numpy as np

from ..errors import SceneError
from ..scene import srgb_to_linear
from .aovs import AOVS, CHANNELS, IDS

FORMATS = (".png", ".npy", ".exr", ".npz")
PNG_LEVEL = 1  # zlib level 1: 640x480 in about a third of level 6's time, files ~1.4x as large


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 encoding of linear values clamped to [0, 1]."""
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def to_srgb8(image: np.ndarray) -> np.ndarray:
    """round(255 sRGB(x)), sRGB evaluated in float64, a block of rows at a time: the float temporaries
    of the whole image would need several times the image's own memory (measured: 63 bytes per pixel
    at the write instead of 36). A float32 image goes through two tables instead of a power per value:
    the code at the start of each run of 2^16 float32 values, and the value where the next code
    starts (a run spans at most one step: 0.83 codes where sRGB is steepest in ln x). NaN gives 0."""
    image = np.asarray(image)
    if image.ndim == 0:
        return _srgb8_block(image)
    out = np.empty(image.shape, np.uint8)
    rows = max(1, (1 << 20) // max(1, image[0].size)) if len(image) else 1  # about a million values a block
    for r in range(0, len(image), rows):
        out[r:r + rows] = _srgb8_block(image[r:r + rows])
    return out


def _srgb8_block(image: np.ndarray) -> np.ndarray:
    if image.dtype != np.float32:
        x = np.fmin(np.fmax(np.asarray(image, np.float64), 0.0), 1.0)
        return np.round(linear_to_srgb(x) * 255.0).astype(np.uint8)
    # fmax/fmin take NaN to the bound; + 0: -0 becomes 0, whose bits index the first run.
    x = np.fmin(np.fmax(image, np.float32(0.0)), np.float32(1.0)) + np.float32(0.0)
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


# The output-path policy, one for every file a command writes (images, statistics):
# - a symlink is written through: the file it leads to is replaced, the link stays (as cp, convert and
#   a shell's '>' do); a device or pipe it leads to (/dev/null, /dev/full) is written in place;
# - a regular file appears complete or not at all: a temporary file beside the target, flushed to
#   the disk (fsync), then renamed onto it, so a full disk or a failed render leaves an earlier file
#   as it was; an existing target keeps its permissions;
# - an output may not be an input of the same command or another of its outputs (check_distinct).


def target_of(path) -> Path:
    """The file that writing ``path`` replaces: the path itself, or where its symlinks lead."""
    return Path(os.path.realpath(path))


def _check_writable(path: Path, field: str):
    target = target_of(path)
    through = f" (where the link {path} leads)" if path.is_symlink() else ""
    parent = target.parent
    if not parent.exists():
        shown = parent if through else (path.parent if str(path.parent) else Path("."))
        raise SceneError(str(path), field, f"folder does not exist: {shown}{through}")
    if not parent.is_dir():
        raise SceneError(str(path), field, f"not a folder: {path.parent}")
    if target.is_dir():
        raise SceneError(str(path), field, f"is a folder, not a file{through}")
    if target.exists() and not target.is_file():
        return  # a device or a pipe: written in place, no temporary file beside it
    # Permission bits do not tell (root ignores them; a read-only mount does not show in them):
    # create and remove a file where the output will go.
    try:
        fd, probe = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".probe", dir=parent)
        os.close(fd)
        os.unlink(probe)
    except OSError as e:
        shown = parent if through else (path.parent if str(path.parent) else Path("."))
        raise SceneError(str(path), field, f"cannot write to folder {shown}: {e.strerror or e}{through}") from None


def check_text_path(path, field: str) -> Path:
    """The same checks for a text output (the statistics file), whatever its extension."""
    path = Path(path)
    _check_writable(path, field)
    return path


def same_file(a, b) -> bool:
    """Whether two paths name one file: the same inode where both exist (hard links too), else the
    same place once symlinks are resolved."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return target_of(a) == target_of(b)


def check_distinct(outputs: dict, inputs=()):
    """Refuse, before anything runs, an output that is one of the command's inputs or that another of
    its outputs also names. ``outputs`` maps each output's flag to its path, ``inputs`` is (what, path)
    pairs ("scene file", "mesh file")."""
    named = list(outputs.items())
    for i, (field, path) in enumerate(named):
        for other, other_path in named[:i]:
            if same_file(path, other_path):
                raise SceneError(str(path), field, f"is also the {other} file ({other_path}); each output needs a file of its own")
        for what, input_path in inputs:
            if same_file(path, input_path):
                raise SceneError(str(path), field, f"is the {what} this command reads ({input_path}); "
                                                   "writing there would destroy it")


def _atomic(path: Path, write):
    """Write ``path`` by the output-path policy above; ``write(name)`` writes the whole file at ``name``."""
    target = target_of(path)
    in_place = target.exists() and not target.is_file()
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=target.suffix, dir=None if in_place else target.parent)
    os.close(fd)
    try:
        write(tmp)
        if in_place:
            with open(tmp, "rb") as src, open(target, "wb") as dst:
                shutil.copyfileobj(src, dst)
                dst.flush()
            return
        _fsync(tmp)
        mode = stat.S_IMODE(target.stat().st_mode) if target.exists() else 0o666 & ~_umask()
        os.chmod(tmp, mode)  # mkstemp makes it 0600
        os.replace(tmp, target)
        _fsync(target.parent, directory=True)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def partial_files(path) -> list[Path]:
    """The temporary files that writes of ``path`` killed midway left beside it (_atomic's names)."""
    target = target_of(path)
    return sorted(target.parent.glob(f".{glob.escape(target.name)}.*{glob.escape(target.suffix)}"))


def _fsync(path, directory: bool = False):
    """Flush a file (or a folder's entries, after a rename) to the disk: a full disk or a failing one
    is reported here, before the rename, rather than lost after the command said it wrote the file."""
    fd = os.open(path, os.O_RDONLY | (os.O_DIRECTORY if directory else 0))
    try:
        os.fsync(fd)
    except OSError as e:
        if not directory or e.errno not in (errno.EINVAL, errno.ENOTSUP):  # some file systems cannot sync folders
            raise
    finally:
        os.close(fd)


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _cannot_write(path: Path, field: str, e: OSError) -> SceneError:
    through = f" (writing {target_of(path)}, where the link leads)" if path.is_symlink() else ""
    return SceneError(str(path), field, f"cannot write: {e.strerror or e}{through}")


def write_text(path, text: str, field: str = "output") -> Path:
    path = check_text_path(path, field)
    try:
        _atomic(path, lambda tmp: Path(tmp).write_text(text))
    except OSError as e:  # a full disk, a folder removed meanwhile
        raise _cannot_write(path, field, e) from None
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
    try:
        with OpenEXR.File(header, channels) as f:
            f.write(fileobj)
    except RuntimeError as e:
        # OpenEXR reports a failed write (a full disk) as a RuntimeError with the C library's text.
        code = next((c for c in errno.errorcode if os.strerror(c) in str(e)), None)
        if code is None:
            raise
        raise OSError(code, os.strerror(code)) from None


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
            raise _cannot_write(sibling, field, e) from None

    def write(tmp):
        if ext == ".png":
            with open(tmp, "wb") as f:
                f.write(png_bytes(to_srgb8(image)))
        elif ext == ".npy":
            a = np.ascontiguousarray(image, np.float32)
            with open(tmp, "wb") as f:
                # np.save's own short-write error has no errno ("N requested and M written"); the
                # file object's write reports the system's reason (a full disk), with no copy either.
                np.lib.format.write_array_header_1_0(f, np.lib.format.header_data_from_array_1_0(a))
                f.write(memoryview(a).cast("B"))
        elif ext == ".exr":
            _write_exr(tmp, image, aovs)
        elif ext == ".npz":
            with open(tmp, "wb") as f:  # np.savez given a name would append ".npz" to the temporary one
                np.savez(f, color=np.asarray(image, np.float32), **aovs)

    try:
        _atomic(path, write)
    except OSError as e:  # a full disk, a folder removed meanwhile
        raise _cannot_write(path, field, e) from None
    return path


def png_bytes(rgb8: np.ndarray) -> bytes:
    """An (H, W, 3) uint8 image as a PNG file: every row filtered by 'Sub' (each byte less the one a pixel to
    its left), one zlib stream at level PNG_LEVEL. Written here rather than by PIL, whose import and adaptive
    filters cost a cold render about 20 ms more (1024x768) for a file of the same size."""
    h, w, _ = rgb8.shape
    rows = np.ascontiguousarray(rgb8, np.uint8).reshape(h, 3 * w)
    filtered = np.empty((h, 1 + 3 * w), np.uint8)
    filtered[:, 0] = 1  # the row's filter type: Sub
    filtered[:, 1:4] = rows[:, :3]
    np.subtract(rows[:, 3:], rows[:, :-3], out=filtered[:, 4:])  # modulo 256, as the filter is defined

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)  # 8-bit RGB, deflate, no interlace
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(filtered.tobytes(), PNG_LEVEL))
            + chunk(b"IEND", b""))


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
