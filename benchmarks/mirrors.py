"""The planar mirrors' virtual cameras: warm frames as `reflection_query="auto"` renders them (the rasters kept
from a view's second frame) against the same frames with every reflection ray traced, in turn in one process.

    python -m benchmarks.mirrors [--width 1024 --height 768] [--repeat 7]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

import warprt
from benchmarks.output import save

ROOT = Path(__file__).resolve().parent
SCENES = ("default", "mirrors", "seed", "bunny", "tilted")  # the scenes with planar mirrors the issue names
TARGET = 0.85  # >= 15% off the warm frame


def timed_render(renderer):
    t = time.perf_counter()
    result = renderer.render()
    return time.perf_counter() - t, result


def run(width: int = 1024, height: int = 768, repeat: int = 7) -> dict:
    """Per scene: auto and traced reflections in turn, frame after frame of two Renderers; auto's
    second frame builds the rasters (its time against the traced frame beside it is the build frame's
    ratio), the medians of ``repeat`` frames after two are the warm frames."""
    rows = []
    for name in SCENES:
        path = None if name == "default" else ROOT.parent / "scenes" / f"{name}.toml"
        scene = warprt.load_scene(path, {"camera.width": width, "camera.height": height})
        pairs, identical, build = [], True, None
        auto_r, traced_r = warprt.Renderer(scene), warprt.Renderer(scene, reflection_query="bvh")
        for i in range(repeat + 2):
            t_auto, auto = timed_render(auto_r)
            t_bvh, traced = timed_render(traced_r)
            identical &= np.array_equal(auto.image, traced.image) and auto.stats.rays == traced.stats.rays
            if i == 1:
                build = t_auto / t_bvh
            if i >= 2:
                pairs.append((t_auto, t_bvh))
        mirrors = auto.stats.mirrors
        rows.append({"scene": name, "auto": statistics.median(p[0] for p in pairs),
                     "traced": statistics.median(p[1] for p in pairs),
                     "ratio": statistics.median(p[0] / p[1] for p in pairs), "build_ratio": build,
                     "reflection_query": auto.stats.reflection_query, "share": mirrors.get("share", 0.0),
                     "chains": len(mirrors.get("chains", [])), "identical": bool(identical), "pairs": pairs})
        print(f"{name:<10} auto/traced reflections {rows[-1]['ratio']:.2f} (build frame {build:.2f}), "
              f"{auto.stats.reflection_query}", flush=True)
    return {"rows": rows, "size": [width, height], "repeat": repeat}


def target_rows(data: dict) -> list[tuple[str, str, str]]:
    """The Targets table's row: auto takes the virtual cameras and they take >= 15% off every scene's warm frame."""
    rows = data["rows"]
    w, h = data["size"]
    taken = all(r["reflection_query"] == "mirrors" for r in rows)
    worst = max(rows, key=lambda r: r["ratio"])
    return [(f"Warm {w}x{h} frame with planar mirrors ({', '.join(r['scene'] for r in rows)}): `auto` takes the "
             "virtual cameras and the frame is <= 0.85x the same frame with every reflection ray traced",
             # three places: a ratio a hair over the bound must not print as the bound itself
             ", ".join(f"{r['scene']} {r['ratio']:.3f}x" for r in rows) + f" (worst: {worst['scene']}; auto took them on "
             f"{sum(r['reflection_query'] == 'mirrors' for r in rows)} of {len(rows)})",
             "met" if taken and worst["ratio"] <= TARGET else "not met")]


def report(data: dict) -> str:
    w, h = data["size"]
    lines = ["## Planar mirrors' virtual cameras", "",
             f"Warm {w}x{h} frames, `warprt.render(scene)` (auto: the rasters built on the view's second frame and kept) "
             "against `reflection_query=\"bvh\"` (every reflection ray traced; first hits and shadows auto in both), the two in "
             f"turn in one process: seconds are medians of {data['repeat']} frames after two, the ratio the median of the "
             "pairs' ratios; the build frame is auto's second frame against the traced frame beside it (the first scene's "
             "also loads the virtual cameras' kernels). Share: the reflection "
             "rays the virtual cameras decided. Regenerate: `python -m benchmarks.mirrors`.", "",
             "| scene | auto | traced reflections | ratio | build frame | chains | share decided | same image |",
             "|---|---:|---:|---:|---:|---:|---:|---|"]
    for r in data["rows"]:
        lines.append(f"| {r['scene']} | {r['auto']:.3f} | {r['traced']:.3f} | {r['ratio']:.2f} | {r['build_ratio']:.2f} "
                     f"| {r['chains']} | {r['share']:.1%} | {'yes' if r['identical'] else 'NO'} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--height", type=int, default=768)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("-o", "--output", default=str(ROOT / "results" / "mirrors.md"))
    args = ap.parse_args()
    data = run(args.width, args.height, args.repeat)
    save(args.output, data, report(data))
    print(report(data))


if __name__ == "__main__":
    main()
