"""Launching a kernel over an image: bands of pixels from a thread pool. A Warp CPU launch runs on one
thread and releases the GIL, so a pool of one worker per core runs that many bands at once."""

from __future__ import annotations

import os
import threading
from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait

import numpy as np

from .._warp import wp
from ..interrupt import raise_pending


def default_threads() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def launch_plan(threads: int | None, bands: int | None, device: str) -> tuple[int, int]:
    """Threads (``threads``, checked by RenderOptions, or every core) and bands for a render: on the
    CPU each band is one launch, and 8 per thread (16 at least) balance the load between threads; a
    GPU takes the whole image in one launch."""
    threads = default_threads() if threads is None else threads
    return threads, bands or (1 if device != "cpu" else max(16, 8 * threads))


def bands_of(n_items: int, n_bands: int) -> list[tuple[int, int]]:
    """Split [0, n_items) into n_bands contiguous ranges (first, count)."""
    n_bands = max(1, min(n_bands, n_items))
    edges = np.linspace(0, n_items, n_bands + 1).round().astype(int)
    return [(int(a), int(b - a)) for a, b in zip(edges[:-1], edges[1:]) if b > a]


POLL_SECONDS = 0.02  # how late a Ctrl-C may be noticed while bands run


def band_pool(threads: int) -> ThreadPoolExecutor:
    """A pool of ``threads`` band threads, every one started now, before any band is queued.
    ThreadPoolExecutor starts its threads on demand inside submit(), and records a thread only after its
    Thread.start() returns: a Ctrl-C landing in that window (start() waits for the thread) leaves a running
    thread that shutdown() does not join, and it went on taking the interrupted frame's bands after
    render() had raised, into buffers already let go (CI's segfault, caught in tests/cli/test_wild_inputs'
    SIGINT test). Here a frame's submit() never starts a thread."""
    pool = ThreadPoolExecutor(max_workers=threads, thread_name_prefix="warprt")
    gate = threading.Barrier(threads + 1)  # each start-up task holds its thread until all have started
    try:
        for _ in range(threads):
            pool.submit(gate.wait)
        gate.wait()
    except BaseException:
        gate.abort()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    return pool


def launch_bands(kernel, inputs_for, n_items: int, threads: int, bands: int, device: str, on_band=None,
                 pool: ThreadPoolExecutor | None = None):
    """Launch ``kernel`` over ranges of [0, n_items), with ``inputs_for(first)`` as its inputs; on the
    CPU ``threads`` bands run at once. ``on_band(first, count)`` is called when a band has finished,
    on the worker thread that ran it. ``pool``: the threads to run the bands on (a Renderer's, kept for
    its frames: handing a frame's bands to idle threads costs about 1 ms, starting the threads too about
    0.2-0.3 ms more); without one, a pool of ``threads`` lives for this call.

    An exception, a KeyboardInterrupt (Ctrl-C in the main thread, or raised by ``on_band``) included,
    cancels the bands not yet started and waits for the running ones before it propagates: a Warp
    launch cannot be stopped, and the bands still running would write into buffers the caller has let
    go (a next frame would reuse them)."""
    def band(first: int, count: int):
        wp.launch(kernel, dim=count, inputs=inputs_for(first), device=device)
        if on_band is not None:
            if device != "cpu":  # a GPU launch returns before the band is done
                wp.synchronize_device(device)
            on_band(first, count)

    if threads > 1 and device == "cpu":
        # Loaded (compiled, on a cold cache) here, not by the first launch of each band thread: two bands
        # starting at once would both load the module, and a load replaces the module the other may be
        # running (Warp's Module.load is not one critical section). About 8 us where it is loaded.
        wp.load_module(kernel.module, device=device)
    run_bands(band, n_items, threads, bands, device, pool)


def run_bands(run_band, n_items: int, threads: int, bands: int, device: str, pool: ThreadPoolExecutor | None = None):
    """Call ``run_band(first, count)`` (a band's launches) over ranges of [0, n_items): on the CPU ``threads``
    bands at once, on ``pool`` or a pool that lives for this call (launch_bands' ``pool``, and what an
    exception does); the caller loads the kernels' modules first (launch_bands' note)."""
    ranges = bands_of(n_items, bands)
    stop = threading.Event()

    def run(r):
        if stop.is_set():  # taken by a worker just before the others were cancelled
            return
        try:
            run_band(*r)
        except BaseException:
            stop.set()  # at once, not when the main thread gets to this band's result
            raise

    if threads <= 1 or len(ranges) <= 1 or device != "cpu":
        for r in ranges:
            raise_pending()
            run(r)
    elif pool is not None:
        _run_bands(pool, run, ranges, stop)
    else:
        own = band_pool(threads)
        try:
            _run_bands(own, run, ranges, stop)
        finally:
            own.shutdown(wait=True)
    wp.synchronize_device(device)


def _run_bands(pool: ThreadPoolExecutor, run, ranges, stop: threading.Event):
    """Submit a band per range and wait for them; see launch_bands for what an exception does."""
    futures = []
    try:
        for r in ranges:
            futures.append(pool.submit(run, r))
        # Waited for in short steps: a SIGINT that lands just before the main thread blocks does not
        # wake it (CPython runs the handler at its next bytecode), and Ctrl-C would then wait for
        # the whole frame (measured: 1 time in 12 when it came at the end of the first band).
        while True:
            done, running = wait(futures, timeout=POLL_SECONDS, return_when=FIRST_EXCEPTION)
            raise_pending()  # a Ctrl-C the command line noted that Python dropped (interrupt.py)
            failed = next((f for f in done if f.exception() is not None), None)
            if failed is not None:
                failed.result()
            if not running:
                break
    except BaseException:
        stop.set()
        for f in futures:
            f.cancel()
        wait(futures)
        raise
