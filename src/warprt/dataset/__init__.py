"""Datasets: frame sequences and parameter sweeps from a job file, rendered by worker processes or a Ray
cluster, each frame with its AOVs and a line in the manifest (`warprt batch`, warprt.batch()).

    job.py (job file -> frames) -> worker.py (a worker's scene, renderer, files) -> local.py (processes),
    ray_pool.py (Ray actors) -> driver.py (batch(): checks, shards, resume, manifest.py, progress bar)

    result = warprt.batch("orbit.toml", "out", workers=2)    # local worker processes: result.rows, .rendered, ...
    result = warprt.batch("orbit.toml", "out", ray="local")  # a local Ray instance; ray="host:6379" joins one
"""

from .driver import BatchResult, batch, check_frames, default_start_method, progress_bar
from .job import Frame, Job, check_scene, load_job, orbit_eye, parse_shard, select_shard
from .manifest import Manifest, done, manifest_name, read_rows
from .ray_pool import RAY_MESSAGES, connect as connect_ray
from .worker import FrameScenes

__all__ = ["BatchResult", "Frame", "FrameScenes", "Job", "Manifest", "RAY_MESSAGES", "batch", "check_frames",
           "check_scene", "connect_ray", "default_start_method", "done", "load_job", "manifest_name", "orbit_eye",
           "parse_shard", "progress_bar", "read_rows", "select_shard"]

