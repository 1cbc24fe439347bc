"""Issue 37's probe: a warm 1024x768 frame of a five-object scene (two point lights, shadows, a reflective
floor: benchmarks/atrium.toml), its trace phase, a gradient frame against it, and Mitsuba's warm frame of the
same Whitted model, in this checkout.

    python -m benchmarks.atrium [--frames 7] [--mitsuba]
    (cd OLD && PYTHONPATH=src python /path/to/this/benchmarks/atrium.py)    # another commit, the same probe

Run two checkouts alternately on a quiet machine and compare medians: the numbers of REPORT.md's "One tracer
for the image and its derivative" were taken so (7936d2d, a5fa2d4 and the fix, four alternations each).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
import warnings
from pathlib import Path

import warprt

SCENE = Path(__file__).resolve().parent / "atrium.toml"


def medians(frame, frames: int) -> tuple[float, object]:
    """The median seconds of ``frames`` calls after three untimed ones, and the last result."""
    for _ in range(3):
        result = frame()
    times = []
    for _ in range(frames):
        t = time.perf_counter()
        result = frame()
        times.append(time.perf_counter() - t)
    return statistics.median(times), result


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=7)
    ap.add_argument("--mitsuba", action="store_true", help="also Mitsuba llvm_ad_rgb's warm frame (the reference)")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")  # an older checkout's renamed options
    scene = warprt.load_scene(SCENE)
    r = warprt.Renderer(scene)
    frame, result = medians(r.render, args.frames)
    out = {"frame_ms": round(1e3 * frame, 1), "trace_ms": round(1e3 * result.stats.times["trace"], 1)}
    try:
        grad, _ = medians(lambda: r.render(grad=True), args.frames)
        out.update(grad_frame_ms=round(1e3 * grad, 1), grad_over_plain=round(grad / frame, 3))
    except TypeError:  # before Renderer.render(grad=...)
        pass
    if args.mitsuba:
        from reference.mitsuba_whitted import Switches, mitsuba_scene
        from warprt.scene import resolve_effects

        switches = Switches.for_effects(resolve_effects(scene), scene.render)
        ms = mitsuba_scene(scene, switches.smooth)
        seconds, _ = medians(lambda: ms.render(switches), args.frames)
        out.update(mitsuba_ms=round(1e3 * seconds, 1), over_mitsuba=round(frame / seconds, 2))
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
