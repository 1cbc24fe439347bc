"""A warm frame of an unchanged scene: a Renderer's next frame against render()'s of the same scene.

    python -m benchmarks.renderer_warm              # this checkout: through a Renderer
    (cd OLD && python -m benchmarks.renderer_warm)  # a checkout before the Renderer: render() and its module cache

Each scene at 320x240: three frames to warm (kernels, BVH, the auto policies' kept grids and rasters), then
the median of ``--frames`` frames, in milliseconds. Run the two checkouts alternately on a quiet machine
and divide: issue 29 asks the Renderer's warm frame to be no slower.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

import warprt

SCENES = Path(__file__).resolve().parent.parent / "scenes"


def warm_frames(scene, frames: int) -> list[float]:
    if hasattr(warprt, "Renderer"):
        frame = warprt.Renderer(scene).render
    else:  # before the Renderer: render() kept the geometry and caches in module state
        frame = lambda: warprt.render(scene)  # noqa: E731
    for _ in range(3):
        frame()
    out = []
    for _ in range(frames):
        t = time.perf_counter()
        frame()
        out.append(time.perf_counter() - t)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=15)
    ap.add_argument("--scenes", nargs="+", default=["default", "cornell", "whitted", "mirrors", "bunny"])
    args = ap.parse_args(argv)
    rows = {}
    for name in args.scenes:
        scene = warprt.load_scene(None if name == "default" else SCENES / f"{name}.toml",
                                  {"camera.width": 320, "camera.height": 240})
        rows[name] = 1e3 * statistics.median(warm_frames(scene, args.frames))
    print(json.dumps({"renderer": hasattr(warprt, "Renderer"), "ms": rows}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
