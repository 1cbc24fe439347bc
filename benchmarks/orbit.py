"""A camera orbit: 20 frames around a 327,680-triangle mesh, each from a new eye, against the static warm
frame (the same scene rendered again from its first eye). With the BVH reused across eyes (the frame
origin is the objects' centre for every eye of the orbit), a frame of the orbit should cost about what a
static frame costs.

    python -m benchmarks.orbit [--width 1024 --height 768] [--frames 20] [--subdivisions 7]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

import warprt
from benchmarks.output import save
from benchmarks.timing import growth_scene

ROOT = Path(__file__).resolve().parent


def orbit_eyes(scene, frames: int) -> list[tuple]:
    """``frames`` eyes on the horizontal circle through the eye around the camera's center."""
    eye, center = np.asarray(scene.camera.eye, float), np.asarray(scene.camera.center, float)
    x, z = eye[0] - center[0], eye[2] - center[2]
    eyes = []
    for a in np.linspace(0.0, 2.0 * np.pi, frames, endpoint=False):
        eyes.append(tuple(float(v) for v in center + [x * np.cos(a) + z * np.sin(a), eye[1] - center[1],
                                                       -x * np.sin(a) + z * np.cos(a)]))
    return eyes


def run(width: int = 1024, height: int = 768, frames: int = 20, subdivisions: int = 7, repeat: int = 3) -> dict:
    """The orbit from a cold geometry (its first frame builds the BVH), per frame; the static warm frame,
    the median of ``repeat`` after two warm-up frames."""
    scene = growth_scene(subdivisions, width, height)
    orbit = []
    geometry = []
    t_all = time.perf_counter()
    renderer = None
    for eye in orbit_eyes(scene, frames):
        t = time.perf_counter()
        if renderer is None:
            renderer = warprt.Renderer(scene.with_camera(eye=eye))
        else:
            renderer.set_scene(scene.with_camera(eye=eye))
        result = renderer.render()
        orbit.append(time.perf_counter() - t)
        geometry.append(result.stats.geometry["bvh"])
    total = time.perf_counter() - t_all
    renderer.set_scene(scene)
    renderer.render()
    static = []
    for _ in range(repeat):
        t = time.perf_counter()
        result = renderer.render()
        static.append(time.perf_counter() - t)
    return {"width": width, "height": height, "frames": frames, "triangles": result.stats.triangles,
            "orbit_frames": orbit, "orbit_per_frame": total / frames, "bvh": geometry,
            "static_warm": statistics.median(static), "variant": result.stats.variant}


def report(data: dict) -> str:
    built = sum(1 for b in data["bvh"] if b == "built")
    ratio = data["orbit_per_frame"] / data["static_warm"]
    return "\n".join([
        "## A camera orbit", "",
        f"{data['frames']} frames at {data['width']}x{data['height']} around scenes/seed.toml with its sphere an icosphere of "
        f"{data['triangles']:,} triangles in all, each frame from a new eye on the circle through the first, the geometry "
        f"cold at the first frame; against the static warm frame (median of repeats). Regenerate: `python -m benchmarks.orbit`.", "",
        "| per orbit frame (s) | static warm frame (s) | ratio | BVH builds | first frame (s) | slowest later frame (s) |",
        "|---:|---:|---:|---:|---:|---:|",
        f"| {data['orbit_per_frame']:.3f} | {data['static_warm']:.3f} | {ratio:.2f} | {built} of {data['frames']} | "
        f"{data['orbit_frames'][0]:.3f} | {max(data['orbit_frames'][1:], default=0.0):.3f} |",
    ])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--height", type=int, default=768)
    ap.add_argument("--frames", type=int, default=20)
    ap.add_argument("--subdivisions", type=int, default=7, help="icosphere subdivisions: 20 * 4^s triangles")
    ap.add_argument("-o", "--output", default=str(ROOT / "results" / "orbit.md"))
    args = ap.parse_args(argv)
    data = run(args.width, args.height, args.frames, args.subdivisions)
    print(report(data))
    print(f"wrote {save(args.output, data, report(data))}")


if __name__ == "__main__":
    main()
