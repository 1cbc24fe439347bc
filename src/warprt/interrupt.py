"""Ctrl-C that Python dropped. The command line's SIGINT handler (cli.run) notes the signal here before it
raises KeyboardInterrupt in the main thread; Python drops an exception raised while the main thread runs a
__del__ ("Exception ignored in": freeing a Warp array, say, as a loaded full run met in
tests/cli/test_wild_inputs.py's in-process SIGINT test), and the render then goes on to its end. The frame's band loop
(image/launch.py) reads the note at each of its polls and raises the interrupt again. A library caller's own
handler (Python's, a notebook's) is left alone: nothing is noted, and nothing changes."""
from __future__ import annotations

import signal
import threading

PENDING = threading.Event()


def handler(signum, frame):
    """The command line's SIGINT handler: noted, then Python's own KeyboardInterrupt."""
    PENDING.set()
    raise KeyboardInterrupt


def install() -> None:
    """handler() in place of Python's default one (not of an ignored SIGINT: a caller that ignores it keeps
    that); only from the main thread, as signal.signal requires."""
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, handler)


def raise_pending() -> None:
    """KeyboardInterrupt if a Ctrl-C was noted (and perhaps dropped), the note taken: what the band loop calls
    at each poll."""
    if PENDING.is_set():
        PENDING.clear()
        raise KeyboardInterrupt
