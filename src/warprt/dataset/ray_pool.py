"""The Ray backend (pip install 'warprt[ray]'): workers are Ray actors holding a FrameRenderer,
frames are actor tasks. batch(ray=True) starts a local Ray instance, batch(ray=ADDRESS) joins a cluster.

Failures: actors are created with max_restarts / max_task_retries, so an actor whose process dies
(os.kill, OOM, a lost node) is restarted (its __init__ loads the scene again) and its queued and
running tasks are retried there; when its restarts are used up the driver replaces it and sends its
frames again. A worker writes a frame's files at fixed paths, atomically (temporary file in the
same folder, then os.replace), so a retried frame rewrites the same file: nothing lost, nothing
doubled. Results (and bad input, as data, not as an exception) come back to the driver, which
alone writes the manifest. On a cluster, the output folder must be one shared filesystem path
(the same on every node).

A local instance is started loopback-only, without the dashboard, usage statistics or log
forwarding: RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0 (read by Ray at import: its only switch that makes
every Ray process bind 127.0.0.1), RAY_USAGE_STATS_ENABLED=0, include_dashboard=False,
log_to_driver=False, logging_level=ERROR, address="local" (never attach to a cluster found through
RAY_ADDRESS or /tmp/ray by accident).
"""

from __future__ import annotations

import collections
import logging
import os
import sys
import threading

from ..errors import ArgumentError, SceneError
from ..image import default_threads
from .local import stall_timeout

OBJECT_STORE_BYTES = 96 * 2**20  # results are small dicts; Ray's minimum is 75 MiB
READY_TIMEOUT_S = float(os.environ.get("WARPRT_RAY_READY_TIMEOUT", "120"))
INFLIGHT_PER_ACTOR = 2  # one rendering, one queued: an actor never waits on the driver
MAX_RESTARTS = 3


def _import_ray(local: bool):
    if local and "ray" not in sys.modules:
        os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")  # bind loopback only
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    try:
        import ray
    except ImportError:
        raise ArgumentError("batch", "ray", "needs Ray: pip install 'warprt[ray]'") from None
    return ray


def connect(address: str | None, num_cpus: int | None = None) -> bool:
    """Start (address None/"local") or join (an address, or "auto") a Ray instance, unless this
    process is connected already. Returns whether this call connected (and so should shut down)."""
    local = address in (None, "local")
    ray = _import_ray(local)
    _quiet_ray_messages()
    if ray.is_initialized():
        return False
    common = dict(log_to_driver=False, logging_level=logging.ERROR, configure_logging=True)
    if local:
        ray.init(address="local", num_cpus=num_cpus or default_threads(), include_dashboard=False,
                 object_store_memory=OBJECT_STORE_BYTES, **common)
    else:
        _probe(address)
        try:
            ray.init(address=address, **common)
        except ConnectionError as e:
            raise ArgumentError("batch", "ray", f"cannot join the Ray cluster at {address}: {e}") from None
    return True


RAY_MESSAGES: list = []  # what Ray's driver would have printed: kept for --debug / failure reports


def _quiet_ray_messages():
    """Ray's driver prints the messages its raylets publish (a worker died, a task will be retried,
    ...) on *stdout*, prefixed "(raylet)", whatever log_to_driver says; there is no switch for
    them. They go to RAY_MESSAGES instead (and to the 'warprt.batch.ray' logger at DEBUG). Ray
    internals: if the name moves, nothing is patched and the messages show as before."""
    try:
        from ray._private import worker as ray_worker
    except ImportError:
        return
    original = getattr(ray_worker, "print_to_stdstream", None)
    if original is None or getattr(original, "_warprt_quiet", False):
        return
    log = logging.getLogger("warprt.batch.ray")

    def quiet(data, *args, **kwargs):
        if isinstance(data, dict) and data.get("pid") == "raylet":
            for line in data.get("lines", []):
                RAY_MESSAGES.append(line)
                log.debug("%s", line)
            return None
        return original(data, *args, **kwargs)

    quiet._warprt_quiet = True
    ray_worker.print_to_stdstream = quiet


def _probe(address: str, timeout: float = 5.0):
    """ray.init(address=HOST:PORT) with nothing listening there does not fail: it retries for
    minutes (measured: still retrying after 5.5 min), printing C++ warnings. Try the TCP port first."""
    import socket

    text = address[len("ray://"):] if address.startswith("ray://") else address
    if text == "auto" or ":" not in text:
        return  # "auto": Ray finds the address itself (RAY_ADDRESS, /tmp/ray) and fails fast when none
    host, _, port = text.rpartition(":")
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout):
            pass
    except ValueError:
        raise ArgumentError("batch", "ray", f"expected HOST:PORT or 'auto', got {address!r}") from None
    except OSError as e:
        raise ArgumentError("batch", "ray", f"cannot reach a Ray cluster at {address}: "
                                                  f"{e.strerror or e}") from None


class RayFrameWorker:
    """The actor. Bad input in the base scene is kept and reported, not raised (a raising
    __init__ would be restarted, and SceneError does not pickle). It runs INFLIGHT_PER_ACTOR tasks on
    as many threads, one rendering at a time: a frame's files are written while the next renders."""

    def __init__(self, spec, threads):
        import socket

        import ray

        from .worker import FrameRenderer, error_record

        self.host, self.pid = socket.gethostname(), os.getpid()
        self.rendering = threading.Lock()
        self.node = ray.get_runtime_context().get_node_id()
        self.init_error = None
        try:
            self.r = FrameRenderer(spec, threads)
        except SceneError as e:
            self.init_error = error_record(e)

    def ready(self):
        return {"host": self.host, "pid": self.pid, "node": self.node, "error": self.init_error}

    def render(self, task):
        if self.init_error is not None:
            return {"ok": False, "frame": task["frame"], "error": self.init_error}
        with self.rendering:
            rendered = self.r.render(task)
        res = self.r.write(rendered)
        if res["ok"]:
            res["worker"]["node"] = self.node
        return res


class RayPool:
    """N actors (default: one per CPU of the cluster), each with the cluster's CPUs shared out as
    threads; frames sent INFLIGHT_PER_ACTOR at a time per actor; run() and close() as LocalPool's."""

    def __init__(self, spec: dict, address: str | None, workers: int | None, max_attempts: int = 3):
        self.started = connect(address)
        import ray

        self.ray = ray
        self.spec, self.max_attempts = spec, max_attempts
        self.stall_timeout = stall_timeout()
        nodes = [n for n in ray.nodes() if n.get("Alive")]
        node_cpus = [int(n["Resources"].get("CPU", 0)) for n in nodes] or [1]
        total = max(1, int(ray.cluster_resources().get("CPU", 1)))
        self.n = workers or total
        self.threads = max(1, min(max(node_cpus), total // self.n))
        self.actor_cls = ray.remote(num_cpus=self.threads, max_restarts=MAX_RESTARTS, max_task_retries=MAX_RESTARTS,
                                    max_concurrency=INFLIGHT_PER_ACTOR)(RayFrameWorker)
        self.actors = [self._new_actor() for _ in range(self.n)]  # they boot while the driver validates

    def _new_actor(self):
        return self.actor_cls.options(scheduling_strategy="SPREAD").remote(self.spec, self.threads)

    def info(self) -> list[dict]:
        return self.ray.get([a.ready.remote() for a in self.actors], timeout=READY_TIMEOUT_S)

    def run(self, tasks: list[dict], on_result, label_of):
        ray = self.ray
        from ray.exceptions import GetTimeoutError, RayActorError, RayTaskError

        try:
            infos = self.info()
        except GetTimeoutError:
            raise RuntimeError(f"Ray actors did not start within {READY_TIMEOUT_S:.0f} s (each asks for "
                               f"{self.threads} CPUs; cluster: {ray.cluster_resources()})") from None
        for info in infos:
            if info["error"]:
                e = info["error"]
                raise SceneError(e["source"], e["field"], e["message"])
        queue = collections.deque(tasks)
        attempts = collections.Counter()
        remaining = {t["frame"] for t in tasks}
        inflight = {}  # ref -> (actor slot, task)
        load = collections.Counter()
        while remaining:
            for slot in range(len(self.actors)):
                while queue and load[slot] < INFLIGHT_PER_ACTOR:
                    task = queue.popleft()
                    attempts[task["frame"]] += 1
                    actor = self.actors[slot]
                    inflight[actor.render.remote(task)] = (slot, actor, task)
                    load[slot] += 1
            ready, _ = ray.wait(list(inflight), num_returns=1, timeout=self.stall_timeout)
            if not ready:
                raise RuntimeError(f"no Ray worker reported for {self.stall_timeout:.0f} s (WARPRT_BATCH_STALL_TIMEOUT); "
                                   f"cluster: {ray.cluster_resources()}")
            for ref in ready:
                slot, actor, task = inflight.pop(ref)
                load[slot] -= 1
                try:
                    res = ray.get(ref)
                except RayActorError:  # restarts used up (or the node is gone): a new actor
                    k = task["frame"]
                    if attempts[k] >= self.max_attempts:
                        raise RuntimeError(f"{label_of(k)}: its Ray worker died {attempts[k]} times") from None
                    if k in remaining:
                        queue.appendleft(task)
                    if self.actors[slot] is actor:  # its other frames fail too: replace it once
                        self._replace(slot)
                    continue
                except RayTaskError as e:  # an exception in our code on the worker: a bug
                    raise RuntimeError(f"{label_of(task['frame'])}: {e}") from None
                if res["frame"] in remaining:
                    remaining.discard(res["frame"])
                    res["attempt"] = attempts[res["frame"]]
                    on_result(res)

    def _replace(self, slot):
        old = self.actors[slot]
        try:
            self.ray.kill(old, no_restart=True)
        except Exception:
            pass
        self.actors[slot] = self._new_actor()

    def close(self):
        for a in self.actors:
            try:
                self.ray.kill(a, no_restart=True)
            except Exception:
                pass
        self.actors = []
        if self.started:
            self.ray.shutdown()

    terminate = close
