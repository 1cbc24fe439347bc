"""What a render reports: its result (image and stats), the stats record, and the timer of its phases."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import NamedTuple

import numpy as np

from ..timing import timed


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
    primary_query: str = "raytrace"  # where the first hits came from: "raytrace", or "zbuffer" (hybrid; same image)
    shadow_query: str = "bvh"  # what answered the shadow rays: "bvh", or "grid" (the light-space grid; same image)
    shadow_grid: dict = field(default_factory=dict)  # the grid's cells, lights, entries, bytes, build time
    reflection_query: str = "bvh"  # what answered the reflection rays: "bvh", or "mirrors" (virtual cameras; same image)
    mirrors: dict = field(default_factory=dict)  # the virtual cameras' chains, bytes, rays decided and their share
    shortcuts: dict = field(default_factory=dict)  # primary, shadows, reflections: why each query was answered so
    effects: str = ""
    variant: str = ""
    rays: dict = field(default_factory=dict)  # primary, shadow, reflection, refraction, total
    times: dict = field(default_factory=dict)  # seconds: load, bvh, compile, trace, write, total
    rays_per_second: float = 0.0
    memory: dict = field(default_factory=dict)  # bytes: geometry arrays and BVH by role, image, peak_rss
    # render(report_truncated=True): per pixel (H, W, 3), the weight of the rays max_depth cut off.
    truncated: np.ndarray | None = field(default=None, repr=False)
    geometry: dict = field(default_factory=dict)  # bvh: "built" | "reused" | "given", and the reason
    # render.adaptive: the pixels refined at spp (image/adaptive.py), their share, the threshold; {} when off
    adaptive: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """The stats as JSON values; the truncated weights, if reported, as their largest and mean value."""
        out = asdict(self)
        truncated = out.pop("truncated")
        if truncated is not None:
            out["truncated"] = {"max": float(truncated.max(initial=0.0)), "mean": float(truncated.mean())}
        return out

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


class _Frame(NamedTuple):
    image: np.ndarray  # float32 (H, W, 3), linear RGB, row 0 at the top
    stats: RenderStats


class RenderResult(_Frame):
    """What render() returns: a pair, unpacked as ``image, stats = render(scene)``, with the AOVs asked
    for (render(scene, aovs=[...])) as ``.aovs``, a dict of NumPy arrays by name (image/aovs.py)."""

    def __new__(cls, image, stats, aovs=None):
        self = super().__new__(cls, image, stats)
        self.aovs = dict(aovs or {})
        return self

    def __getnewargs__(self):  # pickling and copying keep the AOVs
        return (self.image, self.stats, self.aovs)

    @classmethod
    def _make(cls, iterable):  # namedtuple's own makes a bare tuple.__new__, without .aovs
        return cls(*iterable)

    def _replace(self, **fields):
        aovs = fields.pop("aovs", self.aovs)
        new = super()._replace(**fields)
        new.aovs = dict(aovs)
        return new
