"""The progress line on stderr: tiles done, rays per second and time left, for a render that runs
longer than about a second; silent when stderr is not a terminal (a log, a pipe) or with -q."""

from __future__ import annotations

import os
import shutil
import sys
import threading
import time

# Seconds before the line appears: a quick render prints nothing but its result.
# WARPRT_PROGRESS_AFTER changes it (0: at once), for demonstrations and tests.
DELAY = 1.0
INTERVAL = 0.25  # redraw period: the line moves while a long band runs, not only when one ends


class Progress:
    """Counts finished bands from the render's worker threads and redraws one status line."""

    def __init__(self, stream=None, enabled: bool | None = None, delay: float | None = None):
        self.stream = stream if stream is not None else sys.stderr
        if enabled is None:
            enabled = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.enabled = enabled
        if delay is None:
            try:
                delay = float(os.environ.get("WARPRT_PROGRESS_AFTER", DELAY))
            except ValueError:
                delay = DELAY
        self.delay = delay
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = None
        self.drawn = False
        self.tiles = self.pixels = 0
        self.tiles_done = self.pixels_done = self.rays = 0
        self.t0 = self.t_last = time.perf_counter()

    def begin(self, tiles: int, pixels: int):
        self.tiles, self.pixels = tiles, pixels
        self.tiles_done = self.pixels_done = self.rays = 0
        self.t0 = self.t_last = time.perf_counter()
        if self.enabled:
            self._stop.clear()
            self._thread = threading.Thread(target=self._tick, name="warprt-progress", daemon=True)
            self._thread.start()

    def band_done(self, pixels: int, rays: int):
        """Called on the worker thread that finished the band."""
        with self._lock:
            self.tiles_done += 1
            self.pixels_done += pixels
            self.rays += rays
            self.t_last = time.perf_counter()

    def end(self):
        if self._thread is not None:
            self._stop.set()
            try:
                self._thread.join()
            except RuntimeError:  # interrupted before the thread started: nothing was drawn
                pass
            self._thread = None
        if self.drawn:
            self.stream.write("\r\x1b[K")  # leave the terminal line clean for the result line
            self.stream.flush()

    def line(self, now: float | None = None) -> str:
        """The status text: bar, tiles, rays per second, time left. Rate and time left come from
        the bands finished so far (their rays are exact), not from the time since the last one."""
        now = time.perf_counter() if now is None else now
        with self._lock:
            tiles_done, pixels_done, rays, t_last = self.tiles_done, self.pixels_done, self.rays, self.t_last
        frac = pixels_done / self.pixels if self.pixels else 0.0
        width = 24
        filled = int(round(frac * width))
        bar = "#" * filled + "." * (width - filled)
        busy = max(t_last - self.t0, 1e-9)
        rate = _rate(rays / busy) + "rays/s" if tiles_done else "-- rays/s"
        left = _duration(max(busy * (1.0 - frac) / frac - (now - t_last), 0.0)) if frac > 0 else "--"
        return (f"[{bar}] {tiles_done}/{self.tiles} tiles  {rate}  "
                f"{_duration(now - self.t0)} elapsed, {left} left")

    def _tick(self):
        while not self._stop.wait(INTERVAL if self.drawn else max(0.0, self.delay - self._elapsed())):
            if self._elapsed() >= self.delay:
                self._draw()

    def _elapsed(self) -> float:
        return time.perf_counter() - self.t0

    def _draw(self):
        columns = shutil.get_terminal_size((80, 24)).columns
        # A line longer than the terminal wraps, and '\r' would then redraw only its last row.
        self.stream.write("\r" + self.line()[: max(columns - 1, 10)] + "\x1b[K")
        self.stream.flush()
        self.drawn = True


def _rate(x: float) -> str:
    for scale, unit in ((1e9, "G"), (1e6, "M"), (1e3, "k")):
        if x >= scale:
            return f"{x / scale:.1f} {unit}"
    return f"{x:.0f} "


def _duration(s: float) -> str:
    if s < 9.95:
        return f"{s:.1f} s"
    s = int(round(s))
    return f"{s // 60}:{s % 60:02d}" if s >= 60 else f"{s} s"
