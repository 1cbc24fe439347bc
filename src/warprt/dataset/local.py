"""The local backend: N worker processes, each holding a FrameRenderer (scene loaded once, Warp
initialized once, kernels and geometry warm), fed two frames at a time over a pipe, writing one frame's
files on a second thread while rendering the next.

Not concurrent.futures.ProcessPoolExecutor: a worker that dies there breaks the whole pool (every
worker is stopped, every pending future fails) and multiprocessing.Pool never returns the task of
a dead worker. Here a dead worker (os.kill, OOM killer) is noticed by its process sentinel, its frames
go back to the front of the queue, and one new worker takes its place; the others keep going.

Processes are started as driver.default_start_method() says: forked from a driver that has one thread
and has not started Warp (`warprt batch`), else from a fork server or spawned; never forked from a parent
that has rendered: it holds warprt's ThreadPoolExecutor, whose threads do not exist in a forked child, and
the child's first multi-threaded frame hangs (measured).
"""

from __future__ import annotations

import collections
import multiprocessing as mp
import os
import queue
import signal
import threading
import time
from multiprocessing.connection import wait

from ..errors import SceneError
from .worker import FrameRenderer, error_record

IN_FLIGHT = 2  # frames sent to a worker at a time: one rendering, one waiting in its pipe, so that it
# starts the next frame at once rather than after the driver has read the result and written its line


def _worker_main(conn, spec, threads):
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the driver's to handle
    try:
        r = FrameRenderer(spec, threads)
    except SceneError as e:
        conn.send(("init_error", error_record(e)))
        return
    conn.send(("ready", os.getpid()))
    # The writer thread encodes and writes a frame's files and sends its result while this thread
    # renders the next one (Warp's launches, zlib and the file writes all release the GIL). One
    # frame waits for it at most: a slow disk holds the renders back rather than filling memory.
    rendered = queue.Queue(maxsize=1)

    def write():
        while (item := rendered.get()) is not None:
            try:
                conn.send(("result", r.write(item)))
            except OSError:  # the driver is gone: the main thread finds the pipe closed too
                pass

    writer = threading.Thread(target=write, name="warprt-batch-writer", daemon=True)
    writer.start()
    while True:
        try:
            task = conn.recv()
        except (EOFError, OSError):  # the driver is gone
            break
        if task is None:
            break
        rendered.put(r.render(task))
    rendered.put(None)
    writer.join()
    conn.close()
    os._exit(0)  # every file is written and renamed; tearing down Warp/LLVM only costs time


def stall_timeout() -> float | None:
    """Seconds without any result after which a run fails instead of waiting on (a hung worker, an
    actor that can never be placed): off unless WARPRT_BATCH_STALL_TIMEOUT is set (the test suite sets it)."""
    v = os.environ.get("WARPRT_BATCH_STALL_TIMEOUT")
    return float(v) if v else None


class _Worker:
    """One worker process, its end of the pipe, and the frame it has in hand."""

    def __init__(self, ctx, spec, threads):
        self.conn, child = ctx.Pipe()
        self.proc = ctx.Process(target=_worker_main, args=(child, spec, threads), daemon=True, name="warprt-batch-worker")
        self.proc.start()
        child.close()
        self.tasks = collections.deque()  # the frames sent to it, oldest first: results come back in order
        self.ready = False
        self.t_start = time.perf_counter()
        self.boot_seconds = None

    @property
    def pid(self):
        return self.proc.pid


class LocalPool:
    """Start the workers at once (they boot while the driver validates the frames), then run()."""

    def __init__(self, spec: dict, workers: int, threads: int, start_method: str = "spawn", max_attempts: int = 3):
        self.ctx = mp.get_context(start_method)
        if start_method == "forkserver":
            # Imported once in the fork server; each worker forks from it and only initializes
            # Warp and loads the scene. Nothing here has started a thread or Warp's runtime.
            self.ctx.set_forkserver_preload([f"{__package__}.worker", "warprt.image.renderer", "numpy", "PIL.Image"])
        self.spec, self.threads, self.max_attempts = spec, threads, max_attempts
        self.n = workers
        self.deaths = 0
        self.boot_seconds = []  # per worker: start to ready (scene loaded, Warp warmed up)
        self.stall_timeout = stall_timeout()
        self.workers = [_Worker(self.ctx, spec, threads) for _ in range(workers)]

    def pids(self):
        return [w.pid for w in self.workers]

    def run(self, tasks: list[dict], on_result, label_of):
        """Render every task; on_result(result) in the driver for each finished frame. A frame
        whose worker dies is rendered again (max_attempts in all); bad input raises SceneError."""
        todo = collections.deque(tasks)
        attempts = collections.Counter()
        remaining = {t["frame"] for t in tasks}
        while remaining:
            for w in self.workers:
                while todo and len(w.tasks) < IN_FLIGHT:
                    task = todo.popleft()
                    w.tasks.append(task)
                    attempts[task["frame"]] += 1
                    try:
                        w.conn.send(task)
                    except (BrokenPipeError, OSError):
                        break  # it died: its sentinel says so below
            handles = {}
            for w in self.workers:
                handles[w.conn] = w
                handles[w.proc.sentinel] = w
            ready = wait(list(handles), timeout=self.stall_timeout)
            if not ready:
                busy = [label_of(w.tasks[0]["frame"]) for w in self.workers if w.tasks]
                raise RuntimeError(f"no worker reported for {self.stall_timeout:.0f} s (WARPRT_BATCH_STALL_TIMEOUT); "
                                   f"rendering: {', '.join(busy) or 'nothing'}")
            for h in ready:
                w = handles[h]
                if w not in self.workers:
                    continue  # already replaced in this round
                msg = None
                if h is w.conn:
                    try:
                        msg = w.conn.recv()
                    except (EOFError, OSError):
                        msg = None
                if msg is None:  # death: sentinel fired, or the pipe closed under recv
                    if w.proc.is_alive() and h is w.conn:
                        w.proc.join(timeout=5)
                    self._replace(w, todo, attempts, label_of)
                    continue
                kind, payload = msg
                if kind == "ready":
                    w.ready = True
                    w.boot_seconds = time.perf_counter() - w.t_start
                    self.boot_seconds.append(w.boot_seconds)
                elif kind == "init_error":
                    raise SceneError(payload["source"], payload["field"], payload["message"])
                elif kind == "result":
                    w.tasks.popleft()
                    if payload["frame"] in remaining:
                        remaining.discard(payload["frame"])
                        payload["attempt"] = attempts[payload["frame"]]
                        on_result(payload)

    def _replace(self, w, todo, attempts, label_of):
        self.deaths += 1
        i = self.workers.index(w)
        if w.proc.is_alive():
            w.proc.kill()
            w.proc.join(timeout=5)
        w.conn.close()
        for task in w.tasks:
            k = task["frame"]
            if attempts[k] >= self.max_attempts:
                raise RuntimeError(f"{label_of(k)}: its worker process died {attempts[k]} times "
                                   f"(last exit code {w.proc.exitcode})")
        todo.extendleft(reversed(w.tasks))  # its frames first, in their order
        if self.deaths > 3 * self.n + 10:
            raise RuntimeError(f"worker processes keep dying ({self.deaths} so far, last exit code {w.proc.exitcode})")
        self.workers[i] = _Worker(self.ctx, self.spec, self.threads)

    def close(self):
        for w in self.workers:
            if not w.ready:  # still booting (a replacement nobody needed in the end): holds nothing
                w.proc.kill()
                continue
            try:
                w.conn.send(None)
            except (BrokenPipeError, OSError):
                pass
        for w in self.workers:
            w.proc.join(timeout=5)
            if w.proc.is_alive():
                w.proc.kill()
                w.proc.join(timeout=5)
            w.conn.close()
        self.workers = []

    def terminate(self):
        for w in self.workers:
            if w.proc.is_alive():
                w.proc.kill()
        for w in self.workers:
            w.proc.join(timeout=5)
            w.conn.close()
        self.workers = []
