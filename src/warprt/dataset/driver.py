"""batch(): a job's frames rendered by a backend (local worker processes or Ray actors), its manifest
written by this process alone, one line per finished frame, with a progress bar on a terminal."""

from __future__ import annotations

import os
import sys
import time
import uuid
from pathlib import Path

from ..errors import ArgumentError, SceneError
from ..image import default_threads, partial_files
from ..timing import timed
from .job import Frame, Job, check_scene, load_job, parse_shard, select_shard
from .manifest import Manifest, done, read_rows
from .worker import FrameScenes


def default_start_method() -> str:
    """How worker processes start. "fork" where it is safe: Linux, and this process has one thread and has
    not started Warp's runtime (`warprt batch` itself: the driver only reads scenes); a worker then starts
    with warprt and Warp already imported. Otherwise "forkserver" where there is one: workers fork from a
    server that imports warprt and Warp first (a fresh interpreter's imports, which every batch's start
    waits for) but starts neither Warp's runtime nor a thread; else "spawn". Never "fork" from a process
    that has rendered: it holds warprt's thread pool, whose threads do not exist in the child, so the
    child's first threaded frame waits for them for ever. What each start costs: benchmarks/ATTEMPTS.md."""
    import multiprocessing as mp
    import threading

    if not sys.platform.startswith("linux"):
        return "spawn"
    if threading.active_count() == 1 and ("warp" not in sys.modules or not _warp_started()):
        return "fork"
    return "forkserver" if "forkserver" in mp.get_all_start_methods() else "spawn"


def _warp_started() -> bool:
    from .._warp import warp_started

    return warp_started()


def check_frames(job: Job, frames: list[Frame]):
    """Each frame's scene as `warprt render` would load it, made here as the workers make it
    (worker.FrameScenes): a bad frame raises a SceneError naming the job file and the frame."""
    scenes = FrameScenes(job.scene_path)
    for f in frames:
        try:
            scenes.scene(f.overrides)
        except SceneError as e:
            raise SceneError(job.source, f.label, " ".join(str(e).split())) from None


def _row(job: Job, f: Frame, res: dict, run_id: str, backend: str) -> dict:
    return {"frame": f.index, "key": f.key, "camera": f.camera, "camera_index": f.camera_index,
            "sweep": f.sweep, "sweep_index": f.sweep_index, "overrides": f.overrides, "outputs": f.outputs,
            "aovs": list(job.aovs), "stats": res["stats"], "worker": res["worker"], "seconds": res["seconds"],
            "attempt": res.get("attempt", 1), "run": run_id, "backend": backend, "finished": time.time()}


def batch(job, output_dir=None, *, workers: int | None = None, ray=None, shard=None, resume: bool = False,
          quiet: bool = True, check: bool = True, on_frame=None, start_method: str | None = None,
          summary: dict | None = None) -> list[dict]:
    """Render the frames of the job file ``job`` into ``output_dir`` (default: the job file's folder) and
    return the manifest rows of this run's frames (this shard's, those ``resume`` found done included),
    sorted by frame.

    ``ray``: None or False for local worker processes (``workers`` of them, default one per core, each
    rendering with cores // workers threads); True or "local" for a local Ray instance; an address
    ("auto", "host:6379") to join a cluster. ``shard``: (I, N) or "I/N", "auto", "auto/N" (frames k with
    k mod N = I). ``resume``: skip frames whose manifest line and files exist. ``check``: check every
    frame's scene here before any renders (a bad frame then fails at once; without, the worker that
    meets it fails the job). ``on_frame(row)`` is called here after each frame's line is written;
    ``summary`` (a dict) receives counts and timings. Bad input raises SceneError naming the job file
    and the field or frame."""
    t0 = time.perf_counter()
    if isinstance(shard, str):
        shard = parse_shard(shard)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise ArgumentError("batch", "workers", f"expected an integer >= 1, got {workers!r}")
    j = load_job(job, output_dir)
    out_dir = j.output_dir
    # Without resume every frame of the shard is to render, so the local workers start now (forked, or
    # a fork server on a thread) and boot while this thread checks the job; a bad job terminates them.
    count = j.frame_count(shard)
    booting = _start_local(j, count, workers, start_method) if not ray and not resume and count else None
    manifest = None  # opened (and, without resume, emptied) only once the frames have been checked
    stats = {}
    try:
        t_check = time.perf_counter()
        check_scene(j)  # the base scene, [set] and every swept value, before any frame renders
        frames = select_shard(j.frames, shard)
        previous = done(read_rows(out_dir), frames, out_dir) if resume and out_dir.is_dir() else {}
        todo = [f for f in frames if f.index not in previous]
        by_index = {f.index: f for f in frames}
        run_id = uuid.uuid4().hex[:12]
        backend_name = "ray" if ray else "local"
        rows = dict(previous)
        stats.update(frames=len(frames), skipped=len(previous), rendered=0, backend=backend_name,
                     check_seconds=time.perf_counter() - t_check)

        def prepare():
            with timed(stats, "frame_check_seconds"):
                if check:
                    check_frames(j, todo)
                _make_folders(j, out_dir, todo)

        if todo:
            if not ray:
                if booting is None:
                    booting = _start_local(j, len(todo), workers, start_method)
                prepare()  # while the workers boot
                pool = booting.result()
                n, threads = pool.n, pool.threads
            else:
                prepare()  # first: starting or joining Ray takes seconds, a bad job should not wait for it
                from .ray_pool import RayPool

                pool = RayPool(j.spec(), None if ray is True or ray == "local" else str(ray), workers)
                n, threads = pool.n, pool.threads
            stats.update(workers=n, threads=threads)
            ok = False
            try:
                manifest = Manifest(out_dir, shard, resume=resume)
                tasks = [{"frame": f.index, "overrides": f.overrides, "outputs": f.outputs} for f in todo]
                bar = progress_bar(len(todo), quiet)
                t_run = time.perf_counter()

                def on_result(res):
                    f = by_index[res["frame"]]
                    if not res["ok"]:
                        if "error" in res:
                            e = res["error"]
                            where = f"{e['source']}: {e['field']}" if e["field"] else e["source"]
                            raise SceneError(j.source, f.label, f"{where}: {' '.join(e['message'].split())}")
                        raise RuntimeError(f"{f.label}: {res['internal']}\n{res.get('traceback', '')}")
                    row = _row(j, f, res, run_id, backend_name)
                    manifest.append(row)
                    rows[f.index] = row
                    stats["rendered"] += 1
                    if bar is not None:
                        bar.update(1)
                    if on_frame is not None:
                        on_frame(row)

                try:
                    pool.run(tasks, on_result, lambda k: by_index[k].label)
                finally:
                    if bar is not None:
                        bar.close()
                stats["render_seconds"] = time.perf_counter() - t_run
                ok = True
            finally:
                (pool.close if ok else pool.terminate)()
                if getattr(pool, "boot_seconds", None):
                    stats["boot_seconds"] = list(pool.boot_seconds)
                booting = None
                # A worker killed while writing leaves its temporary file; its frame was written again.
                for f in todo:
                    for rel in f.outputs.values():
                        for stale in partial_files(out_dir / rel):
                            stale.unlink(missing_ok=True)
    finally:
        if booting is not None:  # started, never used: the job failed its checks
            try:
                booting.result().terminate()
            except Exception:
                pass  # it failed to start: there is nothing to stop, and the job's own error is the one to show
        if manifest is not None:
            manifest.close()
        stats["seconds"] = time.perf_counter() - t0
        if summary is not None:
            summary.update(stats)
    return [rows[k] for k in sorted(rows)]


def _start_local(j: Job, frames: int, workers: int | None, start_method: str | None):
    """A LocalPool for ``frames`` frames, as a Future: ``workers`` processes (default one per core, at most
    one per frame), each rendering with cores // workers threads, so that workers x threads = cores.
    Forked here and now (milliseconds, and only from this one thread), or else started on a thread,
    since starting a fork server or spawning waits on a fresh interpreter's imports."""
    from concurrent.futures import Future, ThreadPoolExecutor

    from .local import LocalPool

    n = workers or max(1, min(default_threads(), frames))
    threads = max(1, default_threads() // n)
    method = start_method or default_start_method()
    if method == "fork":
        started = Future()
        started.set_result(LocalPool(j.spec(), n, threads, start_method=method))
        return started
    ex = ThreadPoolExecutor(1, thread_name_prefix="warprt-batch-start")
    started = ex.submit(LocalPool, j.spec(), n, threads, start_method=method)
    ex.shutdown(wait=False)  # the thread ends with its one task
    return started


def _make_folders(j: Job, out_dir: Path, frames):
    for d in sorted({(out_dir / rel).parent for f in frames for rel in f.outputs.values()} | {out_dir}):
        try:
            d.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise SceneError(j.source, "output", f"cannot create the folder {d}: {e.strerror or e}") from None


def progress_bar(total: int, quiet: bool):
    """tqdm on stderr, on a terminal only and not when quiet: frames done, frames/s, time left."""
    if quiet or not sys.stderr.isatty():
        return None
    from tqdm import tqdm

    try:
        size = os.get_terminal_size(sys.stderr.fileno())
    except (OSError, ValueError, AttributeError):
        size = os.terminal_size((0, 0))
    # A pty that reports a 0x0 size (script, docker exec -t, some CI runners) makes tqdm hide the bar
    # (its row 0 is past the last of 0 rows): 80x24 there.
    sized = size.columns > 0 and size.lines > 0
    return tqdm(total=total, unit="frame", desc="warprt batch", file=sys.stderr, smoothing=0.1,
                dynamic_ncols=sized, ncols=None if sized else 80, nrows=None if sized else 24)
