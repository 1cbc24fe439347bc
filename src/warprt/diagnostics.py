"""Warnings: one line each on stderr, the render goes on. A reader that meets something it does not
use (a missing texture, an MTL statement it ignores) says so once, through warn(); -q silences them.
"""

from __future__ import annotations

import sys

_seen: set[str] = set()
_quiet = False


def warn(source, field, message):
    """``warprt: warning: source: field: message`` on stderr, once per distinct line (a file read twice,
    or a statement repeated a thousand times, warns once); nothing while quiet."""
    where = f"{source}: {field}" if field else str(source)
    line = "warprt: warning: " + " ".join(f"{where}: {message}".split())
    if _quiet or line in _seen:
        return
    _seen.add(line)
    print(line, file=sys.stderr)


def set_quiet(quiet: bool = True):
    """Silence (or restore) warnings: the command line's -q."""
    global _quiet
    _quiet = bool(quiet)
