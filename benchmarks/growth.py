"""How warprt's cost grows: warm frame time against the triangle count (the Z-buffer beside the
tracer, scene preparation and BVH build timed apart), against the pixel count, and against threads.

    python -m benchmarks.growth [--quick] [--repeat 3] [-o benchmarks/results/growth.md]

Triangles: scenes/seed.toml with its sphere an icosphere of 20 * 4^s triangles, s = 0..8 (138 to 1.3
million triangles in the scene), same camera, same pixels (benchmarks/timing.py, shared with the
figures). Pixels and threads: scenes/seed.toml as written (shadows, 3 ray levels, 1 spp) from 128x96
to 2048x1536, on 1, 2, ... threads. Times are warm: kernels compiled, geometry and BVH built once.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np
import warp

import warprt
from benchmarks.output import link, save
from benchmarks.timing import SCENES, TRACED, cpu_name, growth_runs, ms, timed
from warprt.geometry import Geometry
from warprt.image import default_threads
from warprt.kernels import init_warp

ROOT = Path(__file__).resolve().parent
RESULTS = ROOT / "results"
PIXEL_SIZES = [(128, 96), (256, 192), (512, 384), (1024, 768), (2048, 1536)]
TRIANGLE_IMAGE = (640, 480)


def thread_counts() -> list[int]:
    """1, 2, 4, ... up to the cores this process may use, and that number itself."""
    n = default_threads()
    counts = [1]
    while counts[-1] * 2 <= n:
        counts.append(counts[-1] * 2)
    return sorted(set(counts + [n]))


# --- fits ------------------------------------------------------------------------------------------

def fit(x, y, basis) -> dict:
    """y ~ a + b basis(x), least squares on relative residuals (the points span decades, and an
    ordinary fit would serve only the largest). Returns a, b and the rms relative residual."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    A = np.stack([np.ones_like(x), basis(x)], 1) / y[:, None]
    (a, b), *_ = np.linalg.lstsq(A, np.ones_like(y), rcond=None)
    rel = (a + b * basis(x)) / y - 1.0
    return {"a": float(a), "b": float(b), "rms_rel": float(np.sqrt(np.mean(rel**2)))}


def loglog_slope(x, y) -> float:
    """d ln y / d ln x of the least-squares line through the points: 0 flat, 1 proportional."""
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(np.asarray(y, float)), 1)[0])


def growth_fits(n, t) -> dict:
    """Both models for one renderer's time against the triangle count, and the log-log slopes over
    the whole sweep and over its last two steps (where a constant per-frame cost no longer hides the growth)."""
    return {"log": fit(n, t, np.log), "linear": fit(n, t, lambda v: v),
            "slope": loglog_slope(n, t), "slope_top": loglog_slope(n[-3:], t[-3:]) if len(n) >= 3 else None}


# --- measurements ----------------------------------------------------------------------------------

def triangle_sweep(repeat: int, subdivisions, size) -> dict:
    runs = growth_runs(repeat, [size], subdivisions, full=True, log=lambda line: print(line, flush=True))
    n = np.array([r["triangles"] for r in runs], float)
    for r in runs:  # the BVH build alone: Geometry with it, less Geometry without it
        r["bvh_build"] = max(r["prepare_bvh"] - r["prepare_flat"], 0.0)
    fits = {k: growth_fits(n, np.array([r[k] for r in runs])) for k in ("raytrace", "raytrace_full", "zbuffer")}
    big = n >= 1e4  # below that the build is a fixed cost of a few hundred microseconds
    fits["bvh_build"] = {"slope": loglog_slope(n[big], [r["bvh_build"] for r, b in zip(runs, big) if b])
                         if big.sum() >= 2 else None}
    return {"size": list(size), "subdivisions": list(subdivisions), "threads": default_threads(), "runs": runs,
            "fits": fits}


def pixel_sweep(repeat: int, sizes, threads) -> dict:
    scene = warprt.load_scene(SCENES / "seed.toml")
    geometry = Geometry(scene)  # one eye, one BVH: only the image size changes
    runs = []
    for width, height in sizes:
        row = {"width": width, "height": height, "pixels": width * height, "seconds": {}}
        for n in threads:
            row["seconds"][str(n)] = timed(scene.with_camera(width=width, height=height), geometry, repeat, threads=n,
                                           primary_query=TRACED)[1]
        runs.append(row)
        print(f"  {width}x{height}: " + ", ".join(f"{n} thread{'s' * (n > 1)} {ms(row['seconds'][str(n)])}"
                                                  for n in threads), flush=True)
    p = np.array([r["pixels"] for r in runs], float)
    fits = {}
    for n in threads:
        t = np.array([r["seconds"][str(n)] for r in runs])
        fits[str(n)] = {"linear": fit(p, t, lambda v: v), "slope": loglog_slope(p, t),
                        "slope_top": loglog_slope(p[-3:], t[-3:]) if len(p) >= 3 else None}
    speedup = {str(n): [r["seconds"]["1"] / r["seconds"][str(n)] for r in runs] for n in threads if n > 1}
    return {"scene": "scenes/seed.toml", "max_depth": scene.render.max_depth, "threads": list(threads),
            "runs": runs, "fits": fits, "speedup": speedup}


def run(quick: bool = False, repeat: int | None = None, out: Path | str = RESULTS) -> dict:
    """Measure all three sweeps, write the plots to ``out``; the returned dict is JSON-ready."""
    init_warp()
    t0 = time.perf_counter()
    repeat = repeat or (1 if quick else 3)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    print("cost growth: triangles", flush=True)
    tri = triangle_sweep(repeat, [0, 2, 4, 6] if quick else list(range(9)), (160, 120) if quick else TRIANGLE_IMAGE)
    print("cost growth: pixels and threads", flush=True)
    pix = pixel_sweep(repeat, PIXEL_SIZES[:3] if quick else PIXEL_SIZES, thread_counts())
    data = {"quick": quick, "repeat": repeat, "machine": f"{cpu_name()}, {os.cpu_count()} CPU threads",
            "warp": warp.__version__, "triangles": tri, "pixels": pix}
    data["plots"] = {"triangles": str(plot_triangles(tri, out / "growth_triangles.png")),
                     "pixels": str(plot_pixels(pix, out / "growth_pixels.png"))}
    data["seconds"] = time.perf_counter() - t0
    return data


# --- plots -----------------------------------------------------------------------------------------

def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _plain_ticks(ax):
    """Log-axis labels as plain numbers (0.5, 20, 300), minor ticks labelled at 2 and 5 only."""
    import matplotlib.ticker

    ax.yaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda y, _: f"{y:g}"))
    ax.yaxis.set_minor_formatter(matplotlib.ticker.FuncFormatter(
        lambda y, _: f"{y:g}" if f"{y:.0e}"[0] in "25" else ""))


def plot_triangles(tri: dict, path: Path) -> Path:
    plt = _pyplot()
    runs, fits = tri["runs"], tri["fits"]
    n = np.array([r["triangles"] for r in runs], float)
    dense = np.geomspace(n.min(), n.max(), 200)
    series = [("raytrace", "ray tracing, local shading (the Z-buffer's image)", "s"),
              ("raytrace_full", "ray tracing, shadows + 3 ray levels", "^"),
              ("zbuffer", "Z-buffer", "o")]
    fig, axes = plt.subplots(1, 3, figsize=(17, 5))
    for key, label, marker in series:
        t = np.array([r[key] for r in runs]) * 1000
        f = fits[key]
        model = "log" if key != "zbuffer" else "linear"
        basis = np.log if model == "log" else (lambda v: v)
        line, = axes[0].loglog(n, t, marker, label=f"{label} (slope {f['slope']:.2f})")
        c = line.get_color()
        axes[0].loglog(dense, 1000 * (f[model]["a"] + f[model]["b"] * basis(dense)), "--", color=c, lw=1, alpha=0.7)
        if key != "zbuffer":
            axes[1].semilogx(n, t, marker, color=c, label=label)
            axes[1].semilogx(dense, 1000 * (f["log"]["a"] + f["log"]["b"] * np.log(dense)), "--", color=c, lw=1,
                             label=f"a + b ln N, rms {100 * f['log']['rms_rel']:.0f}%")
    axes[0].set_title("warm frame time (dashed: fitted a + b ln N for the tracer, a + cN for the Z-buffer)", fontsize=9)
    axes[1].set_title("tracer time on a log-N axis: a straight line is logarithmic growth", fontsize=9)
    axes[1].set_ylim(bottom=0)
    build = np.array([r["bvh_build"] for r in runs]) * 1000
    flat = np.array([r["prepare_flat"] for r in runs]) * 1000
    axes[2].loglog(n, flat, "o-", label="flatten (Z-buffer's preparation)")
    shown = build > 0  # at the smallest counts the build is within the timing noise of the flatten step
    axes[2].loglog(n[shown], build[shown], "s-", label="BVH build (added for the tracer)")
    axes[2].loglog(dense, build[-1] * dense / n[-1], ":", color="grey", label="proportional to N")
    axes[2].set_title("scene preparation, once per scene", fontsize=9)
    for ax in axes:
        ax.set_xlabel("triangles in the scene")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
        _plain_ticks(ax)
    axes[0].set_ylabel("time (ms)")
    w, h = tri["size"]
    fig.suptitle(f"Cost against triangles: scenes/seed.toml, sphere subdivided; {w}x{h}, 1 spp, "
                 f"{tri['threads']} threads")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def plot_pixels(pix: dict, path: Path) -> Path:
    plt = _pyplot()
    import matplotlib.ticker

    runs = pix["runs"]
    p = np.array([r["pixels"] for r in runs], float)
    dense = np.geomspace(p.min(), p.max(), 200)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    for n in pix["threads"]:
        t = np.array([r["seconds"][str(n)] for r in runs]) * 1000
        f = pix["fits"][str(n)]
        line, = axes[0].loglog(p, t, "o", label=f"{n} thread{'s' * (n > 1)} (slope {f['slope']:.2f})")
        axes[0].loglog(dense, 1000 * (f["linear"]["a"] + f["linear"]["b"] * dense), "--", color=line.get_color(),
                       lw=1, label=f"{f['linear']['b'] * 1e9:.0f} ns/pixel + {f['linear']['a'] * 1000:.1f} ms")
    for n, s in pix["speedup"].items():
        axes[1].semilogx(p, s, "o-", label=f"{n} threads against 1")
        axes[1].axhline(int(n), color="grey", ls=":", lw=1)
    axes[0].set_title("warm frame time (dashed: fitted a + c pixels)", fontsize=9)
    axes[0].set_ylabel("time (ms)")
    axes[1].set_title("speed-up (dotted: ideal)", fontsize=9)
    axes[1].set_ylabel("time with 1 thread / time with N")
    axes[1].set_ylim(bottom=0)
    for ax in axes:
        ax.set_xlabel("pixels (image size)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        ax.set_xticks(p, [f"{r['width']}x{r['height']}" for r in runs], fontsize=8)
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    _plain_ticks(axes[0])
    fig.suptitle(f"Cost against pixels and threads: {pix['scene']} (shadows, {pix['max_depth']} ray levels, 1 spp)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


# --- the report ------------------------------------------------------------------------------------

def report(data: dict, relative_to: Path | str | None = ROOT) -> str:
    """Markdown for the performance report; image links relative to ``relative_to`` (the folder the
    Markdown is written to: benchmarks/ for `python -m benchmarks`)."""
    tri, pix = data["triangles"], data["pixels"]
    f = tri["fits"]
    w, h = tri["size"]
    n0, n1 = tri["runs"][0]["triangles"], tri["runs"][-1]["triangles"]
    grow = lambda k: tri["runs"][-1][k] / tri["runs"][0][k]

    def model_line(key, name):
        g = f[key]
        return (f"- {name}: {ms(tri['runs'][0][key])} at {n0:,} triangles, {ms(tri['runs'][-1][key])} at {n1:,} "
                f"({grow(key):.1f}x for {n1 / n0:,.0f}x the triangles); log-log slope {g['slope']:.2f} over the sweep, "
                f"{g['slope_top']:.2f} over its last two steps. Fitted a + b ln N: a = {ms(g['log']['a'])}, "
                f"b = {ms(g['log']['b'] * np.log(10))} per decade, rms error {100 * g['log']['rms_rel']:.0f}%; "
                f"a + cN: c = {g['linear']['b'] * 1e9:.2f} ns per triangle, rms error {100 * g['linear']['rms_rel']:.0f}%.")

    lines = [
        "## How cost grows",
        "",
        f"Warm frame times (kernels compiled, geometry and BVH prepared once), median of {data['repeat']} "
        f"renders, on {data['machine']}, Warp {data['warp']}. Regenerate alone: `python -m benchmarks.growth`"
        + (" (this was a --quick run: small sizes, one repeat; not for quoting)" if data["quick"] else "") + ".",
        "",
        "### Against triangles",
        "",
        f"scenes/seed.toml with its sphere an icosphere of 20 x 4^s flat triangles, s = {', '.join(map(str, tri['subdivisions']))}; "
        f"the same camera and {w}x{h} pixels, 1 spp, {tri['threads']} threads. The Z-buffer and the tracer with local "
        "shading make the same image; the full tracer adds the scene's shadows and 3 ray levels.",
        "",
        f"![Cost against triangles]({link(data['plots']['triangles'], relative_to)})",
        "",
        "| triangles | Z-buffer | ray tracing, local | ray tracing, full | flatten | BVH build |",
        "|---:|---:|---:|---:|---:|---:|",
        *[f"| {r['triangles']:,} | {ms(r['zbuffer'])} | {ms(r['raytrace'])} | {ms(r['raytrace_full'])} | "
          f"{ms(r['prepare_flat'])} | {ms(r['bvh_build'])} |" for r in tri["runs"]],
        "",
        "Growth (time ~ a + b ln N is logarithmic, slope 0 on log-log axes; ~ a + cN is linear, slope tending to 1):",
        "",
        model_line("raytrace", "Ray tracing, local shading"),
        model_line("raytrace_full", "Ray tracing, full"),
        model_line("zbuffer", "Z-buffer"),
        *([f"- BVH build (once per scene, not per frame): log-log slope {f['bvh_build']['slope']:.2f} from 10^4 "
           "triangles up (1 is proportional to N; a SAH build is N log N)."] if f["bvh_build"]["slope"] is not None else []),
        "",
        _verdict(f),
        "",
        "### Against pixels and threads",
        "",
        f"{pix['scene']} as written (shadows, {pix['max_depth']} ray levels, 1 spp), same camera, image sizes from "
        f"{pix['runs'][0]['width']}x{pix['runs'][0]['height']} to {pix['runs'][-1]['width']}x{pix['runs'][-1]['height']}; "
        "`warprt.render(scene, threads=N)`.",
        "",
        f"![Cost against pixels and threads]({link(data['plots']['pixels'], relative_to)})",
        "",
        "| image | pixels | " + " | ".join(f"{n} thread{'s' * (n > 1)}" for n in pix["threads"]) + " | "
        + " | ".join(f"speed-up {n}/1" for n in pix["speedup"]) + " |",
        "|---|---:|" + "---:|" * (len(pix["threads"]) + len(pix["speedup"])),
        *[f"| {r['width']}x{r['height']} | {r['pixels']:,} | " + " | ".join(ms(r["seconds"][str(n)]) for n in pix["threads"])
          + " | " + " | ".join(f"{pix['speedup'][n][i]:.2f}x" for n in pix["speedup"]) + " |"
          for i, r in enumerate(pix["runs"])],
        "",
        *[f"- {n} thread{'s' * (int(n) > 1)}: time = {g['linear']['b'] * 1e9:.0f} ns per pixel + {ms(g['linear']['a'])} "
          f"(rms error {100 * g['linear']['rms_rel']:.0f}%); log-log slope {g['slope']:.2f} over the sweep, "
          f"{g['slope_top']:.2f} over its last two steps (1 is linear in pixels)." for n, g in pix["fits"].items()],
        *[f"- Speed-up with {n} threads: {min(s):.2f}x to {max(s):.2f}x, {s[-1]:.2f}x on the largest image "
          f"({100 * s[-1] / int(n):.0f}% parallel efficiency)." for n, s in pix["speedup"].items()],
        "",
    ]
    return "\n".join(lines)


def _verdict(f: dict) -> str:
    """One sentence per renderer: which of the two models the measurements follow better."""
    out = []
    for key, name in (("raytrace", "the tracer (local shading)"), ("raytrace_full", "the full tracer"),
                      ("zbuffer", "the Z-buffer")):
        log_err, lin_err = f[key]["log"]["rms_rel"], f[key]["linear"]["rms_rel"]
        better = "logarithmic (a + b ln N)" if log_err < lin_err else "linear (a + cN)"
        out.append(f"{name} fits {better} better ({100 * min(log_err, lin_err):.0f}% against "
                   f"{100 * max(log_err, lin_err):.0f}% rms)")
    return "Measured: " + "; ".join(out) + "."


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="small images, fewer sizes, one repeat: a smoke run")
    ap.add_argument("--repeat", type=int, default=None, help="timed renders per point, median (default 3; 1 with --quick)")
    ap.add_argument("-o", "--output", default=str(RESULTS / "growth.md"), help="Markdown report; plots and JSON beside it")
    args = ap.parse_args(argv)
    out = Path(args.output)
    data = run(quick=args.quick, repeat=args.repeat, out=out.parent)
    save(out, data, report(data, relative_to=out.parent))
    print(f"wrote {out} and its plots in {data['seconds']:.0f} s", flush=True)


if __name__ == "__main__":
    main()
