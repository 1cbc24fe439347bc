"""The one clock of what warprt reports it spent: a block's seconds, written into a dict of times
(a render's phases, a scene's load, a structure's build)."""

from __future__ import annotations

import time
from contextlib import contextmanager


@contextmanager
def timed(times: dict, name: str):
    """Time the block as times[name], in seconds."""
    t = time.perf_counter()
    try:
        yield
    finally:
        times[name] = time.perf_counter() - t
