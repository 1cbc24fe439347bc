"""A sanity check of a binary USD (crate) file's table of contents before USD reads it: USD believes
the element counts a damaged file claims, and reserves memory for them (a flipped byte making 43
tokens 1.7 billion took 55 s and 14 GB of address space before USD's own error)."""

from __future__ import annotations

import struct

from ...errors import SceneError

MAGIC = b"PXR-USDC"
# The fewest bytes a section can spend per element: integers are packed at 2 bits or more and then
# LZ4-compressed (at most about 255 to 1), so a valid section holds at most about 1020 elements per
# byte. A claim beyond twice that is damage.
MAX_ELEMENTS_PER_BYTE = 2048
HEADER = 88  # the bootstrap: magic, version, the table of contents' offset, reserved words


def check_crate(src: str, path, size: int):
    """Refuse a crate file whose table of contents or section counts cannot be its own."""
    with open(path, "rb") as f:
        def read(offset: int, n: int) -> bytes:
            f.seek(offset)
            b = f.read(n)
            if len(b) != n:
                raise SceneError(src, None, f"not a valid USD crate file (it ends at byte {size}, "
                                            f"inside its table of contents)")
            return b

        toc = struct.unpack("<q", read(16, 8))[0]
        if not HEADER <= toc <= size - 8:
            raise SceneError(src, None, f"not a valid USD crate file (its table of contents is said to be at "
                                        f"byte {toc} of {size})")
        n = struct.unpack("<Q", read(toc, 8))[0]
        if n > (size - toc - 8) // 32:
            raise SceneError(src, None, f"not a valid USD crate file (its table of contents claims {n} sections)")
        for i in range(n):
            entry = read(toc + 8 + 32 * i, 32)
            name = entry[:16].split(b"\0", 1)[0].decode("ascii", "replace")
            start, length = struct.unpack("<qq", entry[16:])
            if start < HEADER or length < 8 or start + length > size:
                raise SceneError(src, None, f"not a valid USD crate file (its {name} section, {length} bytes at "
                                            f"byte {start}, lies outside the file's {size} bytes)")
            count = struct.unpack("<Q", read(start, 8))[0]
            if count > MAX_ELEMENTS_PER_BYTE * length:
                raise SceneError(src, None, f"not a valid USD crate file (its {name} section claims {count} "
                                            f"entries in {length} bytes)")
