"""A progress object for tests of band threads: it counts the bands that finish, and may act on each."""

import threading


class BandCounter:
    """A progress object (begin, band_done, end, as image/progress.py's) that counts the bands that finish
    and, given ``then``, calls then(n) after the n-th, on the worker thread that ran the band."""

    def __init__(self, then=None):
        self.then, self.done, self.lock = then, 0, threading.Lock()

    def begin(self, tiles, pixels):
        pass

    def end(self):
        pass

    def band_done(self, pixels, rays):
        with self.lock:
            self.done += 1
            n = self.done
        if self.then is not None:
            self.then(n)
