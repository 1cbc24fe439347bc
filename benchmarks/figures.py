"""The seed's three experiments as figures, timed: Figure 6 (effect progression, with a refraction
level), Figure 7 (Z-buffer against ray tracing, three views), Figure 8 (gallery of scenes/, Whitted's
classic scene among them, with ray counts), and the cost growth of both algorithms from 10^2 to 10^6
triangles.

    python -m benchmarks.figures [--repeat 5] [--quick] [-o DIR]   -> benchmarks/figures/*.png and README.md

Times are warm wall-clock medians of --repeat renders (kernels compiled, scene geometry and BVH
prepared once per scene, as an interactive viewer would), on all cores of this machine.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np
import warp
from PIL import Image, ImageDraw, ImageFont

import warprt
from benchmarks.effects import FIG6, FIG6_REFRACTION, glass_sphere
from benchmarks.timing import NO_SHADOWS_OR_REFLECTIONS, TRACED, cpu_name, growth_runs, ms, timed, timed_result
from warprt.image import to_srgb8
from warprt.geometry import Geometry

ROOT = Path(__file__).resolve().parent
SCENES = ROOT.parent / "scenes"
OUT = ROOT / "figures"


# --- image grids with labels -----------------------------------------------------------------------

def font(size: int):
    """DejaVu Sans, which matplotlib ships, so labels look the same on every machine."""
    from matplotlib import font_manager

    return ImageFont.truetype(font_manager.findfont("DejaVu Sans"), size)


def grid(cells, cols: int, path: Path, header=None, row_labels=None, col_labels=None, text_lines: int = 1):
    """cells: [(linear image, [caption lines])]; images share one size. Writes a labelled PNG."""
    h, w = cells[0][0].shape[:2]
    f, fb = font(15), font(18)
    line = 20
    cap = 8 + line * text_lines
    top = (34 if header else 0) + (26 if col_labels else 0)
    left = 70 if row_labels else 0
    rows = -(-len(cells) // cols)
    canvas = Image.new("RGB", (left + cols * (w + 8) + 8, top + rows * (h + cap) + 8), "white")
    draw = ImageDraw.Draw(canvas)
    if header:
        draw.text((8, 8), header, fill="black", font=fb)
    for c, label in enumerate(col_labels or []):
        draw.text((left + 8 + c * (w + 8) + w // 2, top - 14), label, fill="black", font=f, anchor="mm")
    for r, label in enumerate(row_labels or []):
        draw.text((left // 2, top + r * (h + cap) + h // 2), label, fill="black", font=f, anchor="mm")
    for i, (image, captions) in enumerate(cells):
        r, c = divmod(i, cols)
        x, y = left + 8 + c * (w + 8), top + r * (h + cap)
        canvas.paste(Image.fromarray(to_srgb8(image)), (x, y))
        for j, text in enumerate(captions):
            draw.text((x + w // 2, y + h + 4 + j * line), text, fill="black", font=f, anchor="ma")
    path.parent.mkdir(parents=True, exist_ok=True)
    canvas.save(path, optimize=True)
    return path


# --- Figure 6: effect progression ------------------------------------------------------------------

def figure6(out: Path, repeat: int, width: int, height: int) -> dict:
    scene = warprt.load_scene(SCENES / "seed.toml").with_camera(width=width, height=height)
    geometry = Geometry(scene)
    cells, rows = [], []
    for label, effects, depth in FIG6:
        image, t = timed(scene.with_render(max_depth=depth), geometry, repeat, effects=effects)
        cells.append((image, [label, ms(t)]))
        rows.append({"label": label, "seconds": t})
    label, effects, depth = FIG6_REFRACTION
    glass = glass_sphere(scene).with_render(max_depth=depth)
    result, t = timed_result(glass, Geometry(glass), repeat, effects=effects)
    cells.append((result.image, [label, f"{ms(t)}, {result.stats.rays['refraction']:,} refracted rays"]))
    rows.append({"label": label, "seconds": t, "rays": result.stats.rays})
    grid(cells, 3, out / "fig6_effects.png", header="Figure 6: ray tracing, one effect at a time (scenes/seed.toml)",
         text_lines=2)
    return {"scene": "scenes/seed.toml", "size": [width, height], "panels": rows}


# --- Figure 7: Z-buffer against ray tracing, three views -------------------------------------------

VIEWS = [  # (eye, center): the scene's own camera, then from the left and above, then low from the right
    None,
    ([-4.5, 3.6, 4.2], [0.2, 0.7, 0.0]),
    ([4.2, 0.7, 3.6], [-0.4, 1.0, -0.6]),
]


def figure7(out: Path, repeat: int, width: int, height: int) -> dict:
    base = warprt.load_scene(SCENES / "seed.toml").with_camera(width=width, height=height)
    cells, rows = [], []
    for view in VIEWS:
        scene = base if view is None else base.with_camera(eye=tuple(view[0]), center=tuple(view[1]))
        geometry = Geometry(scene)
        zb, t_zb = timed(scene, geometry, repeat, algorithm="zbuffer")
        rt, t_rt = timed(scene, geometry, repeat, disable=NO_SHADOWS_OR_REFLECTIONS, primary_query=TRACED)
        full, t_full = timed(scene.with_render(max_depth=2), geometry, repeat, primary_query=TRACED)
        cells += [(zb, [ms(t_zb)]), (rt, [ms(t_rt)]), (full, [ms(t_full)])]
        rows.append({"view": "scene camera" if view is None else {"eye": view[0], "center": view[1]},
                     "zbuffer": t_zb, "raytrace_local": t_rt, "raytrace_full_2_levels": t_full})
    grid(cells, 3, out / "fig7_zbuffer_vs_raytracing.png",
         header=f"Figure 7: three views of scenes/seed.toml, {geometry.triangle_count:,} triangles; warm render time under each",
         row_labels=["view 1", "view 2", "view 3"],
         col_labels=["Z-buffer", "ray tracing, no shadows or reflections", "ray tracing, shadows, 2 ray levels"])
    return {"scene": "scenes/seed.toml", "size": [width, height], "views": rows}


# --- Figure 8: gallery -----------------------------------------------------------------------------

GALLERY_FIRST = ["seed", "whitted", "cornell", "mirrors", "bunny", "knot"]
# The last row: files rendered bare, as `warprt render file` frames them, with their own textures,
# vertex colours and normals (written by scenes/assets.py).
GALLERY_MODELS = ["meshes/tile.glb", "meshes/painted.ply", "meshes/cube_flat.usda"]


def figure8(out: Path, repeat: int, width: int, height: int) -> dict:
    paths = sorted(SCENES.glob("*.toml"), key=lambda p: (GALLERY_FIRST.index(p.stem) if p.stem in GALLERY_FIRST
                                                         else len(GALLERY_FIRST), p.stem))
    cells, rows = [], []
    for path in paths:
        scene = warprt.load_scene(path)
        # Keep each scene's aspect ratio inside a width x height cell: wide scenes get letterboxed.
        scale = min(width / scene.camera.width, height / scene.camera.height)
        scene = scene.with_camera(width=max(1, round(scene.camera.width * scale)),
                                  height=max(1, round(scene.camera.height * scale)))
        geometry = Geometry(scene)
        result, t = timed_result(scene, geometry, max(1, repeat // 2))
        image, rays = result.image, result.stats.rays
        cell = np.ones((height, width, 3), np.float32)
        y0, x0 = (height - image.shape[0]) // 2, (width - image.shape[1]) // 2
        cell[y0:y0 + image.shape[0], x0:x0 + image.shape[1]] = image
        kinds = [f"{count(rays[k])} {label}" for k, label in (("shadow", "shadow"), ("reflection", "reflected"),
                                                                   ("refraction", "refracted")) if rays[k]]
        cells.append((cell, [f"{path.name}: {geometry.triangle_count:,} triangles",
                             f"max_depth {scene.render.max_depth}, {ms(t)}, {rays['total']:,} rays", ", ".join(kinds)]))
        rows.append({"scene": f"scenes/{path.name}", "triangles": geometry.triangle_count, "seconds": t, "rays": rays})
    cols = 3
    cells += [(np.ones((height, width, 3), np.float32), [])] * (-len(cells) % cols)  # the models start a row
    for name in GALLERY_MODELS:
        scene = warprt.load_scene(SCENES / name, {"camera.width": width, "camera.height": height})
        geometry = Geometry(scene)
        result, t = timed_result(scene, geometry, max(1, repeat // 2))
        cells.append((result.image, [f"{Path(name).name} (bare): {geometry.triangle_count:,} triangles",
                                     f"{ms(t)}, {result.stats.rays['total']:,} rays"]))
        rows.append({"scene": f"scenes/{name}", "triangles": geometry.triangle_count, "seconds": t,
                     "rays": result.stats.rays})
    grid(cells, cols, out / "fig8_gallery.png",
         header="Figure 8: scenes/, full ray tracing (shadows, every reflection and refraction level the scene asks "
                "for); last row: textured and vertex-coloured files rendered bare", text_lines=3)
    return {"size": [width, height], "scenes": rows}


def count(n: int) -> str:
    """A ray count short enough for a caption: 950, 77k, 1.2M."""
    return f"{n / 1e6:.1f}M" if n >= 999_500 else f"{n / 1e3:.0f}k" if n >= 1000 else str(n)


# --- Cost growth -----------------------------------------------------------------------------------

def cost_growth(out: Path, repeat: int, sizes, subdivisions) -> dict:
    runs = growth_runs(repeat, sizes, subdivisions, log=lambda line: print(line, flush=True))
    plot_growth(runs, out / "cost_growth.png")
    return {"runs": runs, "crossover": crossovers(runs)}


def crossovers(runs) -> dict:
    """Per image size: the triangle count where the Z-buffer's per-frame time first exceeds the tracer's
    (log-interpolated between measured counts), for frames alone and with scene preparation."""
    out = {}
    for (w, h) in sorted({(r["width"], r["height"]) for r in runs}):
        rs = [r for r in runs if (r["width"], r["height"]) == (w, h)]
        n = np.array([r["triangles"] for r in rs], float)
        frame = np.log(np.array([r["zbuffer"] / r["raytrace"] for r in rs]))
        total = np.log(np.array([(r["zbuffer"] + r["prepare_flat"]) / (r["raytrace"] + r["prepare_bvh"]) for r in rs]))
        out[f"{w}x{h}"] = {"frame": _first_crossing(n, frame), "with_preparation": _first_crossing(n, total)}
    return out


def _first_crossing(n, log_ratio):
    """The count from which on the Z-buffer stays the slower (log(Z-buffer / ray tracing) >= 0 up to
    the largest count), log-interpolated; 0 if it is the slower at every count, None if it is the
    faster at the largest. Timing noise can flip small-count ratios; the large counts decide."""
    if log_ratio[-1] < 0:
        return None
    i = len(n) - 1
    while i > 0 and log_ratio[i - 1] >= 0:
        i -= 1
    if i == 0:
        return 0.0
    f = -log_ratio[i - 1] / (log_ratio[i] - log_ratio[i - 1])
    return float(np.exp(np.log(n[i - 1]) + f * (np.log(n[i]) - np.log(n[i - 1]))))


def plot_growth(runs, path: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8), sharey=True)
    sizes = sorted({(r["width"], r["height"]) for r in runs}, key=lambda s: s[0] * s[1])
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, with_prep in zip(axes, (False, True)):
        for k, (w, h) in enumerate(sizes):
            rs = sorted((r for r in runs if (r["width"], r["height"]) == (w, h)), key=lambda r: r["triangles"])
            n = [r["triangles"] for r in rs]
            zb = [(r["zbuffer"] + (r["prepare_flat"] if with_prep else 0)) * 1000 for r in rs]
            rt = [(r["raytrace"] + (r["prepare_bvh"] if with_prep else 0)) * 1000 for r in rs]
            c = colors[k % len(colors)]
            ax.loglog(n, zb, "o-", color=c, label=f"Z-buffer, {w}x{h}")
            ax.loglog(n, rt, "s--", color=c, label=f"ray tracing, {w}x{h}")
        for k, (size, c) in enumerate(crossovers(runs).items()):
            n_cross = c["with_preparation" if with_prep else "frame"]
            if n_cross:
                ax.axvline(n_cross, color=colors[k % len(colors)], alpha=0.4, lw=1)
                ax.annotate(f"crossover {size}\n~{n_cross:,.0f}", (n_cross, 0.02), xycoords=("data", "axes fraction"),
                            fontsize=7, rotation=90, ha="right", va="bottom", color=colors[k % len(colors)])
        ax.set_xlabel("triangles")
        # Label 1, 2 and 5 times each power of ten; labelling every minor tick makes them collide.
        plain = matplotlib.ticker.FuncFormatter(
            lambda y, _: f"{y:g}" if y > 0 and round(y / 10 ** np.floor(np.log10(y)), 6) in (1, 2, 5) else "")
        ax.yaxis.set_major_formatter(plain)
        ax.yaxis.set_minor_formatter(plain)
        ax.grid(True, which="both", alpha=0.3)
        ax.set_title("per frame (geometry and BVH ready)" if not with_prep else
                     "per frame + scene preparation (flatten; flatten + BVH build)")
    axes[0].set_ylabel("time (ms)")
    axes[0].legend(fontsize=8)
    axes[1].legend(fontsize=8)
    fig.suptitle("Cost growth: scenes/seed.toml, sphere subdivided; same image, no shadows or reflections, "
                 f"{os.cpu_count()} CPU threads")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# --- the report ------------------------------------------------------------------------------------

def write_readme(out: Path, results: dict, seconds: float):
    f6, f7, f8, g = results["fig6"], results["fig7"], results["fig8"], results["growth"]
    lines = [
        "# Figures",
        "",
        "Written by `python -m benchmarks.figures` (about "
        f"{seconds / 60:.1f} minutes here). Times are warm wall-clock medians (kernels compiled, geometry and BVH "
        f"prepared once per scene) on {cpu_name()}, {os.cpu_count()} CPU threads, Warp {results['warp']}; "
        "a busy machine makes them noisy, so compare ratios within one run.",
        "Regenerate: `python -m benchmarks.figures` from the repository root (`--quick` for a smoke test, `-o DIR` "
        "to write elsewhere). Numbers: figures.json.",
        "",
        "## Figure 6: effect progression (scenes/seed.toml)",
        "",
        "![Figure 6](fig6_effects.png)",
        "",
        "| panel | time |",
        "|---|---:|",
        *[f"| {p['label']} | {ms(p['seconds'])} |" for p in f6["panels"]],
        "",
        "## Figure 7: Z-buffer against ray tracing, three views (scenes/seed.toml)",
        "",
        "![Figure 7](fig7_zbuffer_vs_raytracing.png)",
        "",
        "| view | Z-buffer | ray tracing, no shadows/reflections | ray tracing, shadows, 2 ray levels |",
        "|---|---:|---:|---:|",
        *[f"| {i + 1} | {ms(v['zbuffer'])} | {ms(v['raytrace_local'])} | {ms(v['raytrace_full_2_levels'])} |"
          for i, v in enumerate(f7["views"])],
        "",
        "## Figure 8: gallery (scenes/)",
        "",
        "![Figure 8](fig8_gallery.png)",
        "",
        "| scene | triangles | time | rays (primary, shadow, reflection, refraction) |",
        "|---|---:|---:|---:|",
        *[f"| {s['scene']} | {s['triangles']:,} | {ms(s['seconds'])} | {s['rays']['total']:,} ({s['rays']['primary']:,}, "
          f"{s['rays']['shadow']:,}, {s['rays']['reflection']:,}, {s['rays']['refraction']:,}) |" for s in f8["scenes"]],
        "",
        "## Cost growth: Z-buffer and ray tracing from 10^2 to 10^6 triangles",
        "",
        "![Cost growth](cost_growth.png)",
        "",
        "| image | triangles | Z-buffer | ray tracing | flatten | flatten + BVH |",
        "|---|---:|---:|---:|---:|---:|",
        *[f"| {r['width']}x{r['height']} | {r['triangles']:,} | {ms(r['zbuffer'])} | {ms(r['raytrace'])} | "
          f"{ms(r['prepare_flat'])} | {ms(r['prepare_bvh'])} |" for r in g["runs"]],
        "",
        "Crossover (the triangle count from which on the Z-buffer is the slower of the two; Z-buffer work grows with the "
        "triangle count, ray tracing with the pixel count times the BVH depth, so the crossover moves up with the image "
        "size; counting the BVH build, which grows with the triangle count too, moves it further):",
        "",
        *[f"- {size}: per frame {_n(c['frame'])}; with scene preparation {_n(c['with_preparation'])}"
          for size, c in g["crossover"].items()],
        "",
    ]
    (out / "README.md").write_text("\n".join(lines))


def _n(x):
    if x is None:
        return "none: the Z-buffer is still the faster at the largest count"
    if x == 0:
        return "none: the Z-buffer is the slower at every count"
    return f"about {x:,.0f} triangles"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=5, help="timed renders per image (median)")
    ap.add_argument("--quick", action="store_true", help="small images and fewer sizes, for a smoke test")
    ap.add_argument("-o", "--output", default=str(OUT), help="folder for the PNGs, figures.json and README.md")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    w, h = (160, 120) if args.quick else (400, 300)
    subdivisions = [0, 2, 4, 6] if args.quick else list(range(0, 9))
    sizes = [(160, 120)] if args.quick else [(160, 120), (320, 240), (640, 480)]
    out = Path(args.output)
    results = {"warp": warp.__version__}
    print("Figure 6", flush=True)
    results["fig6"] = figure6(out, args.repeat, w, h)
    print("Figure 7", flush=True)
    results["fig7"] = figure7(out, args.repeat, w, h)
    print("Figure 8", flush=True)
    results["fig8"] = figure8(out, args.repeat, w, h)
    print("Cost growth", flush=True)
    results["growth"] = cost_growth(out, args.repeat, sizes, subdivisions)
    seconds = time.perf_counter() - t0
    results["seconds"] = seconds
    (out / "figures.json").write_text(json.dumps(results, indent=1) + "\n")
    write_readme(out, results, seconds)
    print(f"wrote {out} in {seconds:.0f} s", flush=True)


if __name__ == "__main__":
    main()
