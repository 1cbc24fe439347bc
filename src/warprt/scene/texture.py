"""Textures on the host: an image file decoded once to linear float (sRGB data decoded before any
filtering), or the procedural checker, with the affine map from a surface's uv to the texture's.

Conventions, shared with the kernels and the Mitsuba reference: uv as OBJ, USD and Mitsuba give it
(v = 0 at the image's bottom row), images stored with row 0 at v = 0 (flipped once on load), texel
(i, j) centred at ((i + 0.5) / W, (j + 0.5) / H), bilinear filtering, and per axis the file's wrap:
repeat (the default), clamp (to the edge texels) or mirror (mirrored repeat), applied to the mapped uv.
"""

from __future__ import annotations

import io
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import SceneError, one_line

IDENTITY_UV = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0)  # u' = a u + b v + c, v' = d u + e v + f
WRAP_MODES = ("repeat", "clamp", "mirror")
_MAGIC_EXR = b"\x76\x2f\x31\x01"


@dataclass(frozen=True, eq=False)  # compared by identity: an image is too large to compare or hash
class Texture:
    """A texture a material multiplies one of its colours by: ``image`` (H, W, 3) float32 linear RGB,
    row 0 at v = 0, or ``checker``, two colours alternating on the unit squares of the mapped uv
    (floor(u') + floor(v') even: the first). ``uv_transform`` maps a surface's uv to the texture's."""

    image: np.ndarray | None = field(default=None, repr=False)
    checker: tuple | None = None  # ((r, g, b), (r, g, b))
    uv_transform: tuple = IDENTITY_UV
    source: str = ""  # the file, for messages and `warprt info`
    wrap: tuple = ("repeat", "repeat")  # along u and v: one of WRAP_MODES each (images; the checker repeats)

    def __post_init__(self):
        if len(self.wrap) != 2 or any(w not in WRAP_MODES for w in self.wrap):
            raise ValueError(f"wrap: expected two of {WRAP_MODES}, got {self.wrap!r}")

    @property
    def peak(self) -> float:
        """The largest channel value the texture can return (bilinear filtering never exceeds it)."""
        if self.checker is not None:
            return float(max(max(self.checker[0]), max(self.checker[1])))
        return float(self.image.max()) if self.image is not None and self.image.size else 0.0

    def describe(self) -> str:
        if self.checker is not None:
            return f"checker {list(self.checker[0])}/{list(self.checker[1])} x{self.uv_transform[0]:g}"
        h, w = self.image.shape[:2]
        wrap = "" if self.wrap == ("repeat", "repeat") else f" wrap {self.wrap[0]}/{self.wrap[1]}"
        return f"{Path(self.source).name} {w}x{h}{wrap}"

    def mapped(self, uv_transform: tuple) -> "Texture":
        """The same image with another uv map (an MTL's -s/-o, glTF's KHR_texture_transform)."""
        return Texture(self.image, self.checker, tuple(float(x) for x in uv_transform), self.source, self.wrap)

    def wrapped(self, wrap_u: str, wrap_v: str) -> "Texture":
        """The same image sampled with other wrap modes outside [0, 1) (glTF's sampler, MTL's -clamp)."""
        return Texture(self.image, self.checker, self.uv_transform, self.source, (wrap_u, wrap_v))


def checker_texture(c0, c1, scale=(1.0, 1.0), offset=(0.0, 0.0)) -> Texture:
    """Checks of colours c0 and c1, ``scale`` checks per unit of uv along u and v."""
    su, sv = scale
    return Texture(checker=(tuple(map(float, c0)), tuple(map(float, c1))),
                   uv_transform=(float(su), 0.0, float(offset[0]), 0.0, float(sv), float(offset[1])), source="checker")


def srgb_to_linear(c) -> np.ndarray:
    """IEC 61966-2-1 decoding, float64 (what Mitsuba does to an 8-bit bitmap before filtering)."""
    c = np.asarray(c, np.float64)
    return np.where(c <= 0.04045, c / 12.92, np.power((c + 0.055) / 1.055, 2.4))


_cache: dict = {}
_CACHE_SIZE = 16


def image_texture(src, srgb: bool | None = None, source: str | None = None, field_name: str | None = None,
                  uv_transform: tuple = IDENTITY_UV) -> Texture:
    """A Texture from an image file (a path) or its bytes (glTF's embedded images). 8- and 16-bit
    images are sRGB unless ``srgb`` is False; float images (EXR, 32-bit TIFF) are linear. The same
    file read again (another material, the next frame) is decoded once. Failures are SceneErrors
    naming ``source`` and ``field_name``."""
    if isinstance(src, (bytes, bytearray)):
        name = source or "<embedded image>"
        key = None
    else:
        path = Path(src)
        name = source or str(path)
        try:
            st = path.stat()
        except FileNotFoundError:
            raise SceneError(name, field_name, "texture file not found") from None
        except OSError as e:
            raise SceneError(name, field_name, f"cannot read texture file: {e.strerror or e}") from None
        if path.is_dir():
            raise SceneError(name, field_name, "is a folder, not an image")
        key = (str(path.resolve()), st.st_mtime_ns, st.st_size, srgb)
    image = _cache.get(key) if key else None
    if image is None:
        data = bytes(src) if key is None else Path(src).read_bytes()
        image = _decode(data, srgb, name, field_name)
        image.setflags(write=False)  # shared by every material that names the file
        if key:
            _cache[key] = image
            while len(_cache) > _CACHE_SIZE:
                _cache.pop(next(iter(_cache)))
    return Texture(image=image, uv_transform=tuple(float(x) for x in uv_transform), source=str(name))


def _decode(data: bytes, srgb: bool | None, name: str, field) -> np.ndarray:
    """Bytes of an image file -> float32 linear RGB (H, W, 3), row 0 at v = 0."""
    if data[:4] == _MAGIC_EXR:
        rgb, is_float = _read_exr(data, name, field), True
    elif data[:2] == b"#?":
        rgb, is_float = _read_hdr(data, name, field), True
    else:
        from PIL import Image, UnidentifiedImageError

        try:
            im = Image.open(io.BytesIO(data))
            im.load()
        except UnidentifiedImageError:
            raise SceneError(name, field, "not an image file read here (PNG, JPEG, TIFF, BMP, TGA, WebP, ... "
                                          "through Pillow; EXR)") from None
        except (OSError, ValueError) as e:
            raise SceneError(name, field, f"cannot read image: {one_line(e, 'damaged file')}") from None
        if im.mode in ("I;16", "I;16B", "I;16L", "I;16N", "I"):
            # 16-bit grey (Pillow keeps 16 bits only for grey images); 'I' PNGs hold 16-bit values too
            rgb = np.repeat((np.asarray(im, np.float64) / 65535.0)[..., None], 3, -1)
            is_float = False
        elif im.mode == "F":
            rgb, is_float = np.repeat(np.asarray(im, np.float64)[..., None], 3, -1), True
        else:  # P, L, LA, RGB, RGBA, CMYK, ...: 8 bits per channel
            rgb, is_float = np.asarray(im.convert("RGB"), np.float64) / 255.0, False
    if rgb.ndim != 3 or rgb.shape[0] == 0 or rgb.shape[1] == 0:
        raise SceneError(name, field, "the image is empty")
    if not np.all(np.isfinite(rgb)):
        raise SceneError(name, field, "the image contains NaN or Inf")
    if (srgb if srgb is not None else not is_float):
        rgb = srgb_to_linear(rgb)
    return np.ascontiguousarray(np.flipud(np.maximum(rgb, 0.0)), np.float32)


def _read_exr(data: bytes, name: str, field) -> np.ndarray:
    import tempfile

    import OpenEXR

    fd, tmp = tempfile.mkstemp(suffix=".exr")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        with OpenEXR.File(tmp) as f:
            ch = f.channels()
            if "RGB" in ch or "RGBA" in ch:
                rgb = np.asarray(ch["RGB" if "RGB" in ch else "RGBA"].pixels, np.float64)[..., :3]
            elif all(c in ch for c in "RGB"):
                rgb = np.stack([np.asarray(ch[c].pixels, np.float64) for c in "RGB"], -1)
            elif "Y" in ch:
                rgb = np.repeat(np.asarray(ch["Y"].pixels, np.float64)[..., None], 3, -1)
            else:
                raise SceneError(name, field, f"EXR without R, G, B or Y channels (it has {', '.join(ch)})")
    except SceneError:
        raise
    except Exception as e:
        raise SceneError(name, field, f"cannot read EXR image: {one_line(e)}") from None
    finally:
        os.unlink(tmp)
    return rgb


def _read_hdr(data: bytes, name: str, field) -> np.ndarray:
    """A Radiance RGBE (.hdr) image, flat or run-length encoded, -Y H +X W (the usual orientation), as float64."""
    end = data.find(b"\n\n")
    size = data.find(b"\n", end + 2)
    if end < 0 or size < 0 or b"FORMAT=32-bit_rle_rgbe" not in data[:end]:
        raise SceneError(name, field, "cannot read HDR image: not a 32-bit_rle_rgbe Radiance file")
    parts = data[end + 2:size].split()
    if len(parts) != 4 or parts[0] != b"-Y" or parts[2] != b"+X":
        raise SceneError(name, field, f"cannot read HDR image: orientation {data[end + 2:size]!r} is not read (-Y H +X W)")
    h, w = int(parts[1]), int(parts[3])
    buf, pos = np.frombuffer(data, np.uint8), size + 1
    out = np.empty((h, w, 4), np.uint8)
    try:
        for y in range(h):
            if w < 8 or w > 0x7FFF or buf[pos] != 2 or buf[pos + 1] != 2:  # flat pixels from here to the end
                out[y:] = buf[pos:pos + (h - y) * w * 4].reshape(h - y, w, 4)
                break
            pos += 4
            for c in range(4):
                x = 0
                while x < w:
                    n = int(buf[pos])
                    if n > 128:
                        out[y, x:x + n - 128, c] = buf[pos + 1]
                        x, pos = x + n - 128, pos + 2
                    else:
                        out[y, x:x + n, c] = buf[pos + 1:pos + 1 + n]
                        x, pos = x + n, pos + 1 + n
    except (IndexError, ValueError):
        raise SceneError(name, field, "cannot read HDR image: the pixel data is cut short or damaged") from None
    e = out[..., 3].astype(np.int32)
    scale = np.where(e > 0, np.ldexp(1.0, e - 136), 0.0)  # m / 256 * 2^(e - 128): Walter's rgbe.c, as Mitsuba reads it
    return out[..., :3].astype(np.float64) * scale[..., None]


def affine(scale=(1.0, 1.0), offset=(0.0, 0.0)) -> tuple:
    """The uv map uv' = uv * scale + offset (per axis), as a 6-tuple."""
    return (float(scale[0]), 0.0, float(offset[0]), 0.0, float(scale[1]), float(offset[1]))
