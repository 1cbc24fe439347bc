"""Head to head on every scene, measured in one run: warprt's tracer and Z-buffer against Mitsuba 3
llvm_ad_rgb and scalar_rgb running the same Whitted integrator (reference/).

Cold: process start to image file, every compiled-kernel cache warm (each command is run once
before it is timed). Warm: a frame after two in the same process (the first builds the BVH, the second
what auto keeps from the second frame on: the shadow grid, the mirrors' virtual cameras). Ratios are
to Mitsuba llvm_ad_rgb; "before" is warprt's default before the exact shadow and mirror structures
(first hits as now, every shadow and reflection ray traced), the target's "today's".

    python -m benchmarks.head_to_head [--width 1024 --height 768]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks.output import save
from warprt.scene import load_scene

ROOT = Path(__file__).resolve().parent
REPO = ROOT.parent
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO / "src"), str(REPO), os.environ.get("PYTHONPATH", "")]),
       "DRJIT_LIBLLVM_PATH": os.environ.get("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")}

# Cold Mitsuba: what a user of Mitsuba's Python API runs from process start to image file.
MITSUBA_COLD = """
import sys, warprt
from reference.mitsuba_whitted import mi, mitsuba, render_mitsuba
size = {"camera.width": int(sys.argv[3]), "camera.height": int(sys.argv[4])} if len(sys.argv) > 3 else None
scene = warprt.load_scene(sys.argv[1] or None, size)
image = render_mitsuba(scene)
mitsuba()[0].util.write_bitmap(sys.argv[2], image)  # an sRGB PNG, as warprt writes
"""

# Warm frames: each engine renders the scene twice in one process; the second frame is timed.
WARM = """
import json, sys, time, warprt
scene = warprt.load_scene(sys.argv[1], {"camera.width": int(sys.argv[2]), "camera.height": int(sys.argv[3])})
engine, repeat = sys.argv[4], int(sys.argv[5])
if engine.startswith("mitsuba"):
    from reference.mitsuba_whitted import Switches, mitsuba_scene
    from warprt.scene import resolve_effects
    switches = Switches.for_effects(resolve_effects(scene), scene.render)
    ms = mitsuba_scene(scene, switches.smooth)
    frame = lambda: ms.render(switches)
else:
    algorithm = "zbuffer" if engine == "zbuffer" else "raytrace"
    # hybrid: the default; before: the default with every shadow and reflection ray traced; warprt: every ray
    options = {"hybrid": {}, "before": {"shadow_query": "bvh", "reflection_query": "bvh"}}.get(
        engine, {"primary_query": "raytrace", "shadow_query": "bvh", "reflection_query": "bvh"})
    frame = warprt.Renderer(scene, algorithm=algorithm, **options).render  # warm frames keep the BVH and caches
frame()
frame()
times = []
for _ in range(repeat):
    t = time.perf_counter()
    result = frame()
    times.append(time.perf_counter() - t)
rays = result.stats.rays["total"] if hasattr(result, "stats") else None
print("RESULT " + json.dumps({"times": times, "rays": rays}))
"""


def _run(cmd: list[str], env=None) -> float:
    t = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True, env=env or ENV, cwd=REPO)
    elapsed = time.perf_counter() - t
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{r.stderr[-2000:]}")
    return elapsed


def cold(engine: str, scene: Path | None, width: int | None, height: int | None, repeat: int) -> float:
    """Median seconds from process start to PNG file, after one untimed run fills every cache.
    scene None is the built-in default scene; width None keeps the scene's own size."""
    out = Path(tempfile.mkdtemp()) / "out.png"
    size = [] if width is None else [str(width), str(height)]
    if engine in ("warprt", "zbuffer"):
        cmd = [sys.executable, "-m", "warprt", "render", *([str(scene)] if scene else []), "-o", str(out), "-q",
               *(["--width", size[0], "--height", size[1]] if size else [])] + (["--algorithm", "zbuffer"] if engine == "zbuffer" else [])
        env = ENV
    else:
        cmd = [sys.executable, "-c", MITSUBA_COLD, str(scene or ""), str(out), *size]
        env = {**ENV, "WARPRT_MITSUBA_VARIANT": "scalar_rgb" if engine == "mitsuba_scalar" else "llvm_ad_rgb"}
    _run(cmd, env)
    return statistics.median(_run(cmd, env) for _ in range(repeat))


def warm(engine: str, scene: Path, width: int, height: int, repeat: int) -> tuple[float, int | None]:
    env = {**ENV, "WARPRT_MITSUBA_VARIANT": "scalar_rgb" if engine == "mitsuba_scalar" else "llvm_ad_rgb"}
    r = subprocess.run([sys.executable, "-c", WARM, str(scene), str(width), str(height), engine, str(repeat)],
                       capture_output=True, text=True, env=env, cwd=REPO)
    if r.returncode != 0:
        raise RuntimeError(f"warm {engine} {scene} failed:\n{r.stderr[-2000:]}")
    # Mitsuba's log may share the line (its colour codes end without a newline).
    (line,) = [l for l in r.stdout.splitlines() if "RESULT " in l]
    data = json.loads(line.split("RESULT ", 1)[1])
    return statistics.median(data["times"]), data["rays"]


def scenes() -> list[Path]:
    return sorted((REPO / "scenes").glob("*.toml"))


def run(width=1024, height=768, scalar_width=128, scalar_height=96, repeat=3, only=None) -> dict:
    # The cold targets (the default scene, a scene of mesh files) are benchmarks/cold.py's.
    rows = []
    for scene in scenes():
        if only and scene.stem not in only:
            continue
        row = {"scene": scene.stem, "width": width, "height": height}
        for engine in ("mitsuba_llvm", "warprt", "before", "hybrid", "zbuffer"):
            if engine not in ("hybrid", "before"):
                row[f"{engine}_cold"] = cold(engine, scene, width, height, repeat)
            row[f"{engine}_warm"], rays = warm(engine, scene, width, height, repeat)
            if engine == "warprt":
                row["rays"] = rays
        # scalar_rgb calls Python per ray: measured at a small size, against llvm_ad_rgb at that size.
        row["scalar_size"] = [scalar_width, scalar_height]
        # The reference's ray tree (glass) runs on a JIT variant only: no scalar_rgb time for those scenes.
        glass = any(m.dielectric for m in load_scene(scene).materials.values())
        row["glass"] = glass
        row["mitsuba_scalar_warm"] = None if glass else warm("mitsuba_scalar", scene, scalar_width, scalar_height, 1)[0]
        row["mitsuba_llvm_warm_small"], _ = warm("mitsuba_llvm", scene, scalar_width, scalar_height, repeat)
        row["warprt_warm_small"], _ = warm("warprt", scene, scalar_width, scalar_height, repeat)
        rows.append(row)
        print(f"{scene.stem:<16} warm warprt/mitsuba {row['warprt_warm'] / row['mitsuba_llvm_warm']:.2f}  "
              f"cold {row['warprt_cold'] / row['mitsuba_llvm_cold']:.2f}", flush=True)
    return {"rows": rows}


def report(data: dict) -> str:
    rows = data["rows"]
    if not rows:
        return ""
    w, h = rows[0]["width"], rows[0]["height"]
    sw, sh = rows[0]["scalar_size"]
    lines = [
        "## Head to head: warprt against Mitsuba 3 on every scene",
        "",
        f"{w}x{h}, each scene's own settings (spp, ray levels, lights). Seconds, median of the repeats; the ratio is "
        "time / Mitsuba `llvm_ad_rgb` time measured in the same run (below 1 = warprt is faster). Cold = process start "
        "to image file with every kernel cache warm; warm = a second frame in the same process (the scene converted "
        "and its BVH built once, on both sides). The Z-buffer renders without shadows and reflections, so its image "
        "is not the same image: it is listed for its cost. warprt default = `primary_query=\"auto\"`, what `warprt render` "
        "does: first hits from the Z-buffer where it is the cheaper (one triangle per ten samples or fewer) and certain, "
        "shadow rays from the light-space grid and reflections off planar mirrors from their virtual cameras (from a view's "
        "second frame on) where those are the cheaper, the rest traced, the image the traced one to the bit; before = that default before the grid and "
        "the mirrors (`shadows=\"bvh\", reflections=\"bvh\"`); traced = every ray traced. warprt "
        "cold is `warprt render`, so the default. Rays per second use warprt's exact ray count and the traced time.",
        "",
        "| scene | rays | Mitsuba llvm warm | warprt default warm | ratio | / before | warprt before warm | warprt traced warm | ratio | Z-buffer warm | ratio | Mitsuba llvm cold | warprt cold | ratio | Z-buffer cold | traced Mrays/s |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        m = r["mitsuba_llvm_warm"]
        mc = r["mitsuba_llvm_cold"]
        lines.append(f"| {r['scene']} | {r['rays']:,} | {m:.3f} | {r['hybrid_warm']:.3f} | {r['hybrid_warm'] / m:.2f} "
                     f"| {r['hybrid_warm'] / r['before_warm']:.2f} | {r['before_warm']:.3f} | {r['warprt_warm']:.3f} | {r['warprt_warm'] / m:.2f} | {r['zbuffer_warm']:.3f} | {r['zbuffer_warm'] / m:.2f} | {mc:.2f} | {r['warprt_cold']:.2f} "
                     f"| {r['warprt_cold'] / mc:.2f} | {r['zbuffer_cold']:.2f} | {r['rays'] / r['warprt_warm'] / 1e6:.1f} |")
    lines += ["", f"Mitsuba `scalar_rgb` runs the Python integrator per ray, so it is measured at {sw}x{sh} (warm frame):", "",
              "| scene | scalar_rgb | llvm_ad_rgb | warprt | scalar / llvm | warprt / llvm |", "|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        s = r["mitsuba_scalar_warm"]
        scalar, ratio = (f"{s:.2f}", f"{s / r['mitsuba_llvm_warm_small']:.0f}") if s is not None else ("- (glass: JIT only)", "-")
        lines.append(f"| {r['scene']} | {scalar} | {r['mitsuba_llvm_warm_small']:.4f} | "
                     f"{r['warprt_warm_small']:.4f} | {ratio} | "
                     f"{r['warprt_warm_small'] / r['mitsuba_llvm_warm_small']:.2f} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--height", type=int, default=768)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--scene", action="append", help="only these scenes (stems)")
    ap.add_argument("-o", "--output", default=str(ROOT / "results" / "head_to_head.md"))
    args = ap.parse_args()
    data = run(args.width, args.height, repeat=args.repeat, only=args.scene)
    save(args.output, data, report(data))
    print(report(data))


if __name__ == "__main__":
    main()
