"""batch(): a job's frames rendered by a backend (local worker processes or Ray actors), its manifest
written by this process alone, one line per finished frame, with a progress bar on a terminal."""

from __future__ import annotations

import os
import sys
import time
import uuid
import warnings
from collections.abc import Sequence
from contextlib import closing, contextmanager
from dataclasses import dataclass, replace
from pathlib import Path

from ..errors import ArgumentError, SceneError
from ..image import default_threads, partial_files
from ..timing import timed
from .job import Frame, Job, check_scene, load_job, parse_shard, select_shard
from .manifest import Manifest, done, manifest_name, read_rows
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


@dataclass(frozen=True)
class BatchResult(Sequence):
    """What one batch() call did: the manifest rows of its frames (``rows``: this shard's, those ``resume``
    found done included, sorted by frame), its counts and its seconds. It reads as the sequence of its
    rows too (iterating, indexing, len), so code written when batch() returned the rows' list still works."""

    rows: tuple[dict, ...]
    manifest: Path  # this shard's manifest file, where this run appended its lines
    run: str  # the "run" of the lines this run wrote
    backend: str  # "local" or "ray"
    rendered: int  # frames rendered by this run; the others ``resume`` found done
    seconds: float  # the whole call
    check_seconds: float  # the job's scenes, the shard, the manifest read back on resume
    # None where nothing was left to render (no worker started):
    workers: int | None = None
    threads: int | None = None  # each worker's render threads
    frame_check_seconds: float | None = None  # every frame's scene, the output folders
    render_seconds: float | None = None  # first frame sent to last line written
    boot_seconds: tuple[float, ...] = ()  # each local worker's start to ready; Ray's actors do not say

    @property
    def frames(self) -> int:
        return len(self.rows)

    @property
    def skipped(self) -> int:
        return len(self.rows) - self.rendered

    @property
    def frames_per_second(self) -> float | None:
        """Rendered frames over ``render_seconds``; None where nothing rendered."""
        return self.rendered / self.render_seconds if self.rendered and self.render_seconds else None

    def __getitem__(self, i):
        return self.rows[i]

    def __len__(self) -> int:
        return len(self.rows)


def batch(job, output_dir=None, *, workers: int | None = None, ray=None, shard=None, resume: bool = False,
          quiet: bool = True, check: bool = True, on_frame=None, start_method: str | None = None,
          device: str = "cpu", summary: dict | None = None) -> BatchResult:
    """Render the frames of the job file ``job`` into ``output_dir`` (default: the job file's folder): a
    BatchResult, the manifest rows of this run's frames with its counts and seconds.

    ``ray``: None or False for local worker processes (``workers`` of them, default one per core, each
    rendering with cores // workers threads); True or "local" for a local Ray instance; an address
    ("auto", "host:6379") to join a cluster. ``shard``: (I, N) or "I/N", "auto", "auto/N" (frames k with
    k mod N = I). ``resume``: skip frames whose manifest line and files exist. ``check``: check every
    frame's scene here before any renders (a bad frame then fails at once; without, the worker that
    meets it fails the job). ``on_frame(row)`` is called here after each frame's line is written.
    ``device``: the Warp device the frames render on ("cpu", "cuda", "cuda:1"); on a GPU one local worker
    renders every frame unless ``workers`` says otherwise (the GPU is the parallelism, and one process
    holds its context), and Ray is refused (its actors would need a GPU resource each: not built yet).
    ``summary``, deprecated: a dict given the result's counts and seconds. Bad input raises SceneError
    naming the job file and the field or frame."""
    if summary is not None:
        warnings.warn("batch(summary=...) is deprecated: batch() returns a BatchResult with those counts and "
                      "seconds", DeprecationWarning, stacklevel=2)
    times, rendered, pool = {}, {}, None
    with timed(times, "seconds"):
        shard = _checked_arguments(shard, workers)
        _check_device(device, ray)
        j = replace(load_job(job, output_dir), device=device)
        # Without resume every frame of the shard is to render, so the local workers start now (forked, or
        # a fork server on a thread) and boot while this thread checks the job; a bad job terminates them.
        count = j.frame_count(shard)
        booting = _start_local(j, count, workers, start_method) if not ray and not resume and count else None
        try:
            with timed(times, "check"):
                previous, todo = _select(j, shard, resume)
            run_id, backend = uuid.uuid4().hex[:12], "ray" if ray else "local"
            if todo:
                if not ray and booting is None:
                    booting = _start_local(j, len(todo), workers, start_method)
                pool, booting = _open_pool(j, todo, check, ray, workers, booting, times), None  # _closing's now
                # The manifest is opened (and, without resume, emptied) only once the frames are checked.
                with (_closing(pool, j.output_dir, todo),
                      closing(Manifest(j.output_dir, shard, resume=resume)) as manifest,
                      timed(times, "render")):
                    rendered = _render(j, pool, todo, manifest, run_id, backend, quiet, on_frame)
        finally:
            _terminate_unused(booting)
    rows = {**previous, **rendered}
    result = BatchResult(
        rows=tuple(rows[k] for k in sorted(rows)), manifest=j.output_dir / manifest_name(shard), run=run_id,
        backend=backend, rendered=len(rendered), seconds=times["seconds"], check_seconds=times["check"],
        workers=None if pool is None else pool.n, threads=None if pool is None else pool.threads,
        frame_check_seconds=times.get("frame_check"), render_seconds=times.get("render"),
        boot_seconds=tuple(getattr(pool, "boot_seconds", None) or ()))
    if summary is not None:
        summary.update(_summary_dict(result))
    return result


def _check_device(device, ray):
    """A device this machine has (before any worker starts), and not with Ray."""
    if not isinstance(device, str) or not device:
        raise ArgumentError("batch", "device", f"expected a Warp device name ('cpu', 'cuda'), got {device!r}")
    if device == "cpu":
        return
    if ray:
        raise ArgumentError("batch", "device", f"'{device}' with Ray is not supported: Ray's actors render on the CPU")
    from .._warp import init_warp, wp

    init_warp()
    if not device.startswith("cuda") or not wp.is_cuda_available():
        raise ArgumentError("batch", "device", f"'{device}' is not available on this machine "
                                               f"(Warp's devices: {', '.join(d.alias for d in wp.get_devices())})")
    wp.get_device(device)  # a CUDA ordinal this machine lacks raises here, before any worker starts


def _checked_arguments(shard, workers):
    """``shard`` as (I, N) or None; a bad ``workers`` refused."""
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise ArgumentError("batch", "workers", f"expected an integer >= 1, got {workers!r}")
    return parse_shard(shard) if isinstance(shard, str) else shard


def _select(j: Job, shard, resume: bool) -> tuple[dict[int, dict], list[Frame]]:
    """The rows of the shard's frames that ``resume`` finds done (manifest line and files), and the frames
    left to render. The base scene, [set] and every swept value are checked first, before any frame renders."""
    check_scene(j)
    frames = select_shard(j.frames, shard)
    previous = done(read_rows(j.output_dir), frames, j.output_dir) if resume and j.output_dir.is_dir() else {}
    return previous, [f for f in frames if f.index not in previous]


def _open_pool(j: Job, todo: list[Frame], check: bool, ray, workers: int | None, booting, times: dict):
    """The pool that renders ``todo``: the local workers ``booting``, or Ray actors. Every frame is checked
    and the output folders made first: while local workers boot, and before Ray is started or joined,
    which takes seconds that a bad job should not wait for."""
    with timed(times, "frame_check"):
        if check:
            check_frames(j, todo)
        _make_folders(j, j.output_dir, todo)
    if not ray:
        return booting.result()
    from .ray_pool import RayPool

    return RayPool(j.spec(), None if ray is True or ray == "local" else str(ray), workers)


@contextmanager
def _closing(pool, out_dir: Path, todo: list[Frame]):
    """``pool`` closed after the block, terminated if it raised; then the temporary files that workers
    killed while writing left are removed (their frames were written again)."""
    try:
        yield pool
    except BaseException:
        pool.terminate()
        raise
    else:
        pool.close()
    finally:
        for f in todo:
            for rel in f.outputs.values():
                for stale in partial_files(out_dir / rel):
                    stale.unlink(missing_ok=True)


def _render(j: Job, pool, todo: list[Frame], manifest: Manifest, run_id: str, backend: str, quiet: bool,
            on_frame) -> dict[int, dict]:
    """``todo`` rendered on ``pool``: each finished frame's row appended to ``manifest`` as it comes, then
    given to ``on_frame``; the rows by frame. A frame that failed raises its error here."""
    by_index = {f.index: f for f in todo}
    rows = {}
    bar = progress_bar(len(todo), quiet)

    def on_result(res):
        f = by_index[res["frame"]]
        if not res["ok"]:
            raise _frame_error(j, f, res)
        row = _row(j, f, res, run_id, backend)
        manifest.append(row)
        rows[f.index] = row
        if bar is not None:
            bar.update(1)
        if on_frame is not None:
            on_frame(row)

    tasks = [{"frame": f.index, "overrides": f.overrides, "outputs": f.outputs} for f in todo]
    try:
        pool.run(tasks, on_result, lambda k: by_index[k].label)
    finally:
        if bar is not None:
            bar.close()
    return rows


def _row(job: Job, f: Frame, res: dict, run_id: str, backend: str) -> dict:
    return {"frame": f.index, "key": f.key, "camera": f.camera, "camera_index": f.camera_index,
            "sweep": f.sweep, "sweep_index": f.sweep_index, "overrides": f.overrides, "outputs": f.outputs,
            "aovs": list(job.aovs), "stats": res["stats"], "worker": res["worker"], "seconds": res["seconds"],
            "attempt": res.get("attempt", 1), "run": run_id, "backend": backend, "finished": time.time()}


def _frame_error(j: Job, f: Frame, res: dict) -> Exception:
    """A worker's failed frame as the error to raise: a SceneError naming the job file and the frame for
    bad input, else a RuntimeError with the worker's traceback."""
    if "error" in res:
        e = res["error"]
        where = f"{e['source']}: {e['field']}" if e["field"] else e["source"]
        return SceneError(j.source, f.label, f"{where}: {' '.join(e['message'].split())}")
    return RuntimeError(f"{f.label}: {res['internal']}\n{res.get('traceback', '')}")


def _terminate_unused(booting):
    """Local workers started for a job that failed before they were used, terminated."""
    if booting is None:
        return
    try:
        booting.result().terminate()
    except Exception:
        pass  # it failed to start: there is nothing to stop, and the job's own error is the one to show


def _summary_dict(r: BatchResult) -> dict:
    """What the deprecated ``summary`` dict was given: without workers, threads and the render's seconds
    where nothing was left to render, and boot_seconds only where workers reported them."""
    d = {"frames": r.frames, "skipped": r.skipped, "rendered": r.rendered, "backend": r.backend,
         "check_seconds": r.check_seconds, "seconds": r.seconds}
    if r.workers is not None:
        d.update(workers=r.workers, threads=r.threads, frame_check_seconds=r.frame_check_seconds,
                 render_seconds=r.render_seconds)
    if r.boot_seconds:
        d["boot_seconds"] = list(r.boot_seconds)
    return d


def _start_local(j: Job, frames: int, workers: int | None, start_method: str | None):
    """A LocalPool for ``frames`` frames, as a Future: ``workers`` processes (default one per core, at most
    one per frame), each rendering with cores // workers threads, so that workers x threads = cores.
    Forked here and now (milliseconds, and only from this one thread), or else started on a thread,
    since starting a fork server or spawning waits on a fresh interpreter's imports."""
    from concurrent.futures import Future, ThreadPoolExecutor

    from .local import LocalPool

    n = workers or (1 if j.device != "cpu" else max(1, min(default_threads(), frames)))
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
