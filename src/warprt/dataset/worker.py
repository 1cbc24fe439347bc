"""What a worker holds (a local worker process or a Ray actor): the scene loaded once, each frame's scene
made from it (scene.with_overrides), Warp's kernels and the geometry kept warm across its frames, and the
frame's files written by warprt's own film writer."""

from __future__ import annotations

import itertools
import json
import os
import socket
import tempfile
import time
import traceback
from pathlib import Path
from typing import NamedTuple

from ..errors import SceneError
from ..scene import load_scene, resolve_effects, sets_in_place, validate_scene, with_overrides
from ..timing import timed


class FrameScenes:
    """Frame scenes from one scene file: the file is loaded once per distinct set of the fields that
    change more than the camera and render settings (a swept light colour, an object's transform:
    the last few kept), and each frame's camera.* and render.* are set on that (with_overrides), so
    frames that differ only in those share objects, and the renderer's geometry with them."""

    def __init__(self, path, keep: int = 3):
        self.path = Path(path)
        self.keep = keep
        self._loaded = {}  # the other fields' values (JSON) -> (the scene loaded with them, its checked content)

    def scene(self, overrides: dict):
        """warprt.load_scene(path, overrides), equal field by field; a SceneError as load_scene's. A frame
        re-checks only what its camera and render settings change (validate_view): the loaded scene's
        lights, materials and objects were checked once, and nothing here changes them."""
        rest = {k: v for k, v in overrides.items() if not sets_in_place(k, self.path)}
        key = json.dumps(rest, sort_keys=True)
        loaded = self._loaded.pop(key, None)
        if loaded is None:
            base = load_scene(self.path, rest)
            loaded = base, validate_scene(base)
        self._loaded[key] = loaded
        while len(self._loaded) > self.keep:
            self._loaded.pop(next(iter(self._loaded)))
        return with_overrides(loaded[0], self.path, overrides, rest, loaded[1])


class _warmup_lock:
    """An exclusive lock on a file in the temporary folder, one per machine and user (a no-op where
    fcntl is missing): with a cold kernel cache, N workers would each compile the same kernels at once
    (measured: 46 s for two workers against 17 s for one on 2 cores); under it, the first compiles into
    Warp's disk cache and the others load from there."""

    def __enter__(self):
        try:
            import fcntl
        except ImportError:
            self.f = None
            return self
        self.f = open(os.path.join(tempfile.gettempdir(), f"warprt-batch-warmup-{os.getuid()}.lock"), "a")
        fcntl.flock(self.f, fcntl.LOCK_EX)
        return self

    def __exit__(self, *exc):
        if self.f is not None:
            import fcntl

            fcntl.flock(self.f, fcntl.LOCK_UN)
            self.f.close()


def error_record(e: SceneError) -> dict:
    """A SceneError as data: it crosses process boundaries, where the exception itself does not (its
    __init__ takes three arguments, so it does not unpickle)."""
    return {"source": e.source, "field": e.field, "message": e.message}


class FrameRenderer:
    """Renders frames of one job and writes their files; used by both backends. ``spec`` is Job.spec()."""

    def __init__(self, spec: dict, threads: int | None):
        from .. import image

        self.image = image
        self.threads = threads
        self.device = spec.get("device", "cpu")
        self.aovs = tuple(spec["aovs"])
        self.output_dir = Path(spec["output_dir"])
        self.scenes = FrameScenes(spec["scene"])
        self._renderers: dict = {}  # id of a loaded scene's objects -> (the objects, their Renderer)
        t = time.perf_counter()
        # Warp's start (about 0.6 s) and the warm-up frames' scenes first, outside the lock: the
        # workers do that at once. Then, one worker at a time, every kernel variant the job's frames
        # use, compiled or loaded now at 1x1 pixel rather than in the first frames; with first hits
        # from the Z-buffer where render()'s policy takes them from there at the frame's own size.
        from .._warp import init_warp

        init_warp()
        tiny_frames = []
        for overrides in spec["warmup"]:
            try:
                frame = self.scenes.scene(overrides)
                cam, settings = frame.camera, frame.render
                samples = cam.width * cam.height * (settings.spp if resolve_effects(frame).supersampling else 1)
                primary = "zbuffer" if image.raster_is_cheaper(frame.triangle_count, samples) else "raytrace"
                tiny_frames.append((frame.with_camera(width=1, height=1), primary))
            except SceneError:
                pass  # a bad frame reports itself when it is rendered
        t_lock = time.perf_counter()
        with _warmup_lock():
            self.lock_seconds = time.perf_counter() - t_lock
            for tiny, primary in tiny_frames:
                try:
                    image.render(tiny, threads=threads, aovs=self.aovs, primary_query=primary, device=self.device)
                except SceneError:
                    pass  # a bad frame reports itself when it is rendered
        self.warmup_seconds = time.perf_counter() - t
        self._done = itertools.count(1)  # next() is atomic: a Ray actor writes frames on two threads

    def render_frame(self, task: dict) -> dict:
        """task: frame, overrides, outputs (relative to the output folder). Returns a result record;
        bad input comes back as {"ok": False, "error": error_record(...)}. A frame is render() then
        write(): a worker with a writer thread runs write() of one frame during render() of the next."""
        return self.write(self.render(task))

    def render(self, task: dict):
        """The frame's scene and image (a _Rendered), or the result record of a failure."""
        seconds = {}
        try:
            with timed(seconds, "scene"):
                scene = self.scenes.scene(task["overrides"])
            with timed(seconds, "render"):
                result = self._renderer(scene).render()
        except SceneError as e:
            return {"ok": False, "frame": task["frame"], "error": error_record(e)}
        except Exception as e:  # a bug: not bad input
            return _internal(task, e)
        return _Rendered(task, result, seconds)

    def _renderer(self, scene):
        """The Renderer for frames of ``scene``'s objects (FrameScenes shares them between the frames of one
        loaded scene), set to this frame; one per loaded scene FrameScenes keeps. The scene comes checked."""
        key = id(scene.objects)
        kept = self._renderers.pop(key, None)
        if kept is None or kept[0] is not scene.objects:
            kept = (scene.objects, self.image.Renderer(scene, threads=self.threads, aovs=self.aovs, device=self.device))
        else:
            kept[1].set_scene(scene, checked=True)
        self._renderers[key] = kept
        while len(self._renderers) > self.scenes.keep:
            self._renderers.pop(next(iter(self._renderers)))
        return kept[1]

    def write(self, rendered) -> dict:
        """The frame's files (image and AOVs, each renamed into place) and its result record."""
        if isinstance(rendered, dict):
            return rendered  # a failure, already a record
        task, result, seconds = rendered
        seconds = dict(seconds)
        try:
            with timed(seconds, "write"):
                self.image.write_image(self.output_dir / task["outputs"]["color"], result.image, "output", result.aovs)
        except SceneError as e:
            return {"ok": False, "frame": task["frame"], "error": error_record(e)}
        except Exception as e:  # a failed write (a full disk): not bad input
            return _internal(task, e)
        return {"ok": True, "frame": task["frame"], "stats": result.stats.to_dict(),
                "worker": {"host": socket.gethostname(), "pid": os.getpid(), "device": self.device, "threads": self.threads,
                           "frames_done": next(self._done)},
                "seconds": seconds}


class _Rendered(NamedTuple):
    task: dict
    result: object  # image.RenderResult
    seconds: dict  # scene, render


def _internal(task: dict, e: Exception) -> dict:
    return {"ok": False, "frame": task["frame"], "internal": f"{type(e).__name__}: {e}",
            "traceback": traceback.format_exc()}
