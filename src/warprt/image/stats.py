"""What a render reports: its result (image and stats), the stats record, and the timer of its phases."""

from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from typing import NamedTuple

import numpy as np


@dataclass
class RenderStats:
    width: int = 0
    height: int = 0
    spp: int = 1
    max_depth: int = 1
    triangles: int = 0
    lights: int = 0
    device: str = "cpu"
    threads: int = 1
    bands: int = 1
    algorithm: str = "raytrace"
    primary: str = "raytrace"  # where the first hits came from: "raytrace", or "zbuffer" (hybrid; same image)
    shadows: str = "bvh"  # what answered the shadow rays: "bvh", or "grid" (the light-space grid; same image)
    shadow_grid: dict = field(default_factory=dict)  # the grid's cells, lights, entries, bytes, build time
    reflections: str = "bvh"  # what answered the reflection rays: "bvh", or "mirrors" (virtual cameras; same image)
    mirrors: dict = field(default_factory=dict)  # the virtual cameras' chains, bytes, rays decided and their share
    effects: str = ""
    variant: str = ""
    rays: dict = field(default_factory=dict)  # primary, shadow, reflection, total
    times: dict = field(default_factory=dict)  # seconds: load, bvh, compile, trace, write, total
    rays_per_second: float = 0.0
    memory: dict = field(default_factory=dict)  # bytes: geometry arrays and BVH by role, image, peak_rss
    geometry: dict = field(default_factory=dict)  # bvh: "built" | "reused" | "given", and the reason

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def begin(cls, scene, fx, *, threads: int, bands: int, device, algorithm: str, variant: str,
              max_depth: int) -> "RenderStats":
        """The stats of a render of ``scene`` with EffectSet ``fx``, as far as they are known before it runs."""
        cam = scene.camera
        stats = cls(width=cam.width, height=cam.height, spp=scene.render.spp, max_depth=max_depth,
                    lights=len(scene.lights), device=str(device), threads=threads, bands=bands,
                    algorithm=algorithm, effects=str(fx), variant=variant)
        if getattr(scene, "load_seconds", None) is not None:
            stats.times["load"] = scene.load_seconds
        return stats

    def phase(self, name: str):
        """Time the block as times[name], in seconds."""
        return timed(self.times, name)


@contextmanager
def timed(times: dict, name: str):
    """Time the block as times[name], in seconds."""
    t = time.perf_counter()
    try:
        yield
    finally:
        times[name] = time.perf_counter() - t


class RenderResult(NamedTuple):
    image: np.ndarray  # float32 (H, W, 3), linear RGB, row 0 at the top
    stats: RenderStats
