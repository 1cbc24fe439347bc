"""What accuracy costs in time: warprt's image error (SSIM, PSNR) against a converged Mitsuba reference,
against warm render time, for each knob that buys accuracy, with the Pareto front of the two.

    python -m benchmarks.accuracy_cost [--quick] [--scenes seed,bunny] [-o benchmarks/results/accuracy_cost.md]

Reference: reference/mitsuba_whitted.py, the same Whitted model on Mitsuba's own tracer, at the
reference size (each scene's image shrunk to fit 320x240), 256 spp (16x16 stratum centres) and 64
ray levels: the limit of every knob swept here. Its convergence is measured, not assumed: the report
gives the reference at a quarter of its samples and half its levels against itself, and says where a
threshold lies beyond what that resolves.

Knobs (warprt.render on the scene, everything else as the scene file says):
  samples per pixel 1, 4, 16, 64 x ray levels (max_depth) 1, 2, 3, 4, 8, shadows on: the combined grid,
  with every level 1..8 at 1 spp; a row stops at the first level that traces no reflection ray (no deeper
  level can change a pixel then); shadows off at each spp (the scene's ray levels);
  resolution: a half- and a quarter-size image at 1, 4, 16 spp, upscaled to the reference size by
  bilinear interpolation in linear RGB (pixel centres aligned, edges clamped); the upscale is timed too;
  render.adaptive 0.005 and 0.02 at 4, 16, 64 spp (Whitted's adaptive supersampling: the spp samples only in
  pixels whose 3x3 neighbourhood of centres differs by more than that).
Error: SSIM (7x7 window, channels averaged) and PSNR of linear RGB clamped to [0, 1] (reference/compare.py).

Scenes lit by area lights (a Mitsuba file: scenes/cornell_box.xml) are measured against Mitsuba's own
``direct`` integrator on the file, converged (4096 independent samples per pixel, box filter), with one more
knob: light samples 1, 4, 16, 64, 256 (k x k points per light, one shadow ray each) at every spp, up to
1024 shadow rays per pixel and light. Mitsuba's ``direct`` integrator itself is timed at 1..1024 spp with its
independent and its stratified sampler: the Mitsuba frame that reaches the same error as warprt's.
"""

from __future__ import annotations

import argparse
import math
import os
import time
from pathlib import Path

import numpy as np
import warp

import warprt
from benchmarks.output import link, save
from benchmarks.timing import SCENES, cpu_name, ms, once
from reference.compare import metrics
from reference.mitsuba_direct import SAMPLERS, DirectRenderer
from reference.mitsuba_whitted import Switches, mitsuba_scene, mitsuba_variant
from warprt.scene import resolve_effects
from warprt.geometry import Geometry
from warprt.image import default_threads
from warprt.kernels import init_warp

ROOT = Path(__file__).resolve().parent
RESULTS = ROOT / "results"
THRESHOLDS = (0.99, 0.999)

FULL = {"box": (320, 240), "ref_spp": 256, "ref_depth": 64, "spps": [1, 4, 16, 64], "grid_depths": [1, 2, 3, 4, 8],
        "depths": list(range(1, 9)), "scales": [2, 4], "scale_spps": [1, 4, 16], "repeat": 3,
        "light_samples": [1, 4, 16, 64, 256], "max_light_rays": 1024, "direct_ref_spp": 4096,
        "direct_spps": [1, 4, 16, 64, 256, 1024], "adaptive": [0.005, 0.02]}
QUICK = {"box": (96, 72), "ref_spp": 16, "ref_depth": 16, "spps": [1, 4], "grid_depths": [1, 2, 3],
         "depths": [1, 2, 3], "scales": [2], "scale_spps": [1], "repeat": 1,
         "light_samples": [1, 4, 16], "max_light_rays": 64, "direct_ref_spp": 1024, "direct_spps": [1, 16, 64],
         "adaptive": [0.02]}
DIRECT_PASS = 256  # Mitsuba's direct integrator renders its reference in passes of this many samples per pixel
CHEAP = 0.3  # seconds: frames faster than this are timed as the median of `repeat` renders, others once
NOISE = 0.15  # relative: times closer than this are a tie, broken by the number of rays traced


def reference_size(camera, box) -> tuple[int, int]:
    """The scene's image scaled to fit ``box``, aspect kept, both sides multiples of 4 (so the half-
    and quarter-size images have the same aspect and pixel grid): shrunk, or enlarged where the file's
    image is smaller than the box (a Mitsuba file's 64 x 64 film)."""
    s = min(box[0] / camera.width, box[1] / camera.height)
    return max(4, round(camera.width * s / 4) * 4), max(4, round(camera.height * s / 4) * 4)


def upscale_bilinear(image: np.ndarray, width: int, height: int) -> np.ndarray:
    """Bilinear interpolation of a linear-RGB image to width x height: output pixel centre x + 0.5 maps
    to source position (x + 0.5) * w / width - 0.5, clamped to the outer pixel centres."""
    h, w = image.shape[:2]

    def taps(n_out, n_in):
        u = np.clip((np.arange(n_out) + 0.5) * n_in / n_out - 0.5, 0.0, n_in - 1)
        i0 = np.floor(u).astype(int)
        return i0, np.minimum(i0 + 1, n_in - 1), (u - i0).astype(np.float32)

    y0, y1, fy = taps(height, h)
    x0, x1, fx = taps(width, w)
    fx, fy = fx[None, :, None], fy[:, None, None]
    rows0, rows1 = image[y0], image[y1]
    top = rows0[:, x0] * (1 - fx) + rows0[:, x1] * fx
    bottom = rows1[:, x0] * (1 - fx) + rows1[:, x1] * fx
    return top * (1 - fy) + bottom * fy


def describe(p: dict) -> str:
    """A setting in words: '16 spp, 3 ray levels, shadows, 160x120 upscaled' (', 16 light samples' where
    the scene has area lights)."""
    levels = f"{p['depth']} ray level{'s' * (p['depth'] > 1)}"
    size = f", {p['width']}x{p['height']} upscaled" if p["scale"] > 1 else ""
    lights = f", {p['light_samples']} light sample{'s' * (p['light_samples'] > 1)}" if p.get("light_samples") else ""
    adaptive = f", adaptive {p['adaptive']:g}" if p.get("adaptive") else ""
    return f"{p['spp']} spp{adaptive}, {levels}{lights}, {'shadows' if p['shadows'] else 'no shadows'}{size}"


def measure(scene, geometry, p: dict, ref: np.ndarray, repeat: int) -> tuple[dict, np.ndarray]:
    """Warm render time of one setting (upscale included), its error against the reference, the
    reflection rays it traced, and the image."""
    W, H = ref.shape[1], ref.shape[0]
    w, h = W // p["scale"], H // p["scale"]
    s = scene.with_camera(width=w, height=h).with_render(spp=p["spp"], max_depth=p["depth"], shadows=True)
    if p.get("light_samples"):
        s = s.with_render(light_samples=p["light_samples"])
    if p.get("adaptive"):
        s = s.with_render(adaptive=p["adaptive"])
    # Warmed up at full size (a small warm-up may not compile the kernels the frame takes: at 8 x 6 the
    # tracer finds every first hit, at full size the Z-buffer may); the warm-up's time says whether the frame
    # is cheap enough to be timed as the median of ``repeat``.
    with warprt.Renderer(s, geometry=geometry, disable=[] if p["shadows"] else ["shadows"]) as renderer:
        warm_up = once(renderer.render)[1]
        timed = [once(renderer.render) for _ in range(repeat if warm_up < CHEAP else 1)]
    result, t = timed[-1][0], float(np.median([seconds for _, seconds in timed]))
    image = result.image
    if p["scale"] > 1:
        image, t_up = once(lambda: upscale_bilinear(result.image, W, H))
        t += t_up
    ssim, psnr, frac_off, _ = metrics(image, ref)
    return {**p, "width": w, "height": h, "seconds": t, "ssim": ssim, "psnr": psnr, "frac_off": frac_off,
            "rays": result.stats.rays["total"], "reflection_rays": result.stats.rays["reflection"]}, image


def sweep(scene, geometry, ref, cfg) -> tuple[list[dict], dict, dict, int, bool]:
    """Measure every setting once: the spp x ray-level grid with shadows (ray levels 1..8 at the
    lowest spp), shadows off and the smaller images at the scene's own ray levels; with area lights, the
    spp x light-samples grid (up to cfg["max_light_rays"] shadow rays per pixel and light), the others at
    the scene's own light samples. A grid row stops where a level traced no reflection ray (its count
    equals the level before's): no deeper level can change a pixel then. Returns the points, the point
    and image for the agreement check, the rows that stopped early ({spp: last level}), the baseline ray
    levels, and whether ray levels matter at all."""
    reflective = resolve_effects(scene.with_render(max_depth=max(cfg["depths"]))).reflection
    base_depth = scene.render.max_depth if reflective else 1
    base_ls = scene.render.light_samples if scene.area_lights else None
    points, images = {}, {}

    def point(spp, depth, shadows=True, scale=1, ls=base_ls, adaptive=0.0):
        key = (spp, depth, shadows, scale, ls, adaptive)
        if key not in points:
            points[key], images[key] = measure(scene, geometry, dict(zip(("spp", "depth", "shadows", "scale",
                                                                           "light_samples", "adaptive"), key)),
                                               ref, cfg["repeat"])
            m = points[key]
            print(f"    {describe(m):<66} {ms(m['seconds']):>9}  SSIM {m['ssim']:.5f}  PSNR {m['psnr']:6.2f} dB", flush=True)
        return points[key]

    last, stopped = {}, {}  # spp -> deepest ray level measured in its grid row; rows that stopped early
    for spp in cfg["spps"]:
        rays = None
        # Every row includes the scene's own ray levels: the spp sweep at those levels reads from the grid.
        levels = sorted({*(cfg["depths"] if spp == cfg["spps"][0] else cfg["grid_depths"]), base_depth}) if reflective else [1]
        for d in levels:
            m = point(spp, d)
            last[spp] = d
            if rays is not None and m["reflection_rays"] == rays:
                if d < levels[-1]:
                    stopped[spp] = d
                break
            rays = m["reflection_rays"]
    if base_ls:
        for spp in cfg["spps"]:
            for ls in sorted({*cfg["light_samples"], base_ls}):
                if spp * ls <= cfg["max_light_rays"]:
                    point(spp, base_depth, ls=ls)
    for spp in cfg["spps"]:
        point(spp, base_depth, shadows=False)
    for scale in cfg["scales"]:
        for spp in cfg["scale_spps"]:
            point(spp, base_depth, scale=scale)
    for spp in cfg["spps"][1:]:  # render.adaptive: the spp samples where the pixels' centres differ
        for t in cfg["adaptive"]:
            point(spp, base_depth, adaptive=t)
    same = (cfg["spps"][-2], last[cfg["spps"][-2]], True, 1, base_ls, 0.0)  # warprt against Mitsuba at these settings
    return list(points.values()), {"point": points[same], "image": images[same]}, stopped, base_depth, reflective


def direct_sweep(direct: dict, ref: np.ndarray, cfg: dict) -> list[dict]:
    """Mitsuba's direct integrator at each of cfg["direct_spps"] with each sampler (``direct``: sampler ->
    DirectRenderer): warm time (a first, untimed frame at that spp; the median of ``repeat`` for cheap
    frames) and error against the reference, each frame with its own seeds (none the reference's)."""
    out = []
    for sampler, render in direct.items():
        for spp in cfg["direct_spps"]:
            kw = {"samples_per_pass": DIRECT_PASS}
            render(spp, seed=1000, **kw)  # compiles the kernels of this wavefront size
            seed = iter(range(1001, 2000))
            image, t = once(lambda: render(spp, seed=next(seed), **kw))
            if t < CHEAP and cfg["repeat"] > 1:
                times = [t] + [once(lambda: render(spp, seed=next(seed), **kw))[1] for _ in range(cfg["repeat"] - 1)]
                t = float(np.median(times))
            ssim, psnr, _, _ = metrics(image, ref)
            out.append({"sampler": sampler, "spp": spp, "seconds": t, "ssim": ssim, "psnr": psnr})
            print(f"    Mitsuba direct, {sampler} sampler, {spp} spp{'':<22} {ms(t):>9}  SSIM {ssim:.5f}  PSNR {psnr:6.2f} dB",
                  flush=True)
    return out


def mitsuba_at(direct: list[dict], ssim: float) -> dict | None:
    """Mitsuba's cost to reach ``ssim`` with one sampler's frames ``direct`` (ascending spp): between the two
    measured frames whose errors bracket it, spp and time interpolated on log(1 - SSIM) (Monte Carlo error
    falls as a power of spp: a line there); at most the 1-spp frame where that already does better
    ("bound": True); None where no frame measured reaches it."""
    err = lambda d: max(1.0 - d["ssim"], 1e-9)  # noqa: E731
    e = max(1.0 - ssim, 1e-9)
    if err(direct[0]) <= e:
        return {"spp": direct[0]["spp"], "seconds": direct[0]["seconds"], "bound": True}
    for a, b in zip(direct, direct[1:]):
        if err(b) <= e:
            f = (math.log(err(a)) - math.log(e)) / max(math.log(err(a)) - math.log(err(b)), 1e-12)
            lerp = lambda x, y: math.exp(math.log(x) + f * (math.log(y) - math.log(x)))  # noqa: E731
            return {"spp": lerp(a["spp"], b["spp"]), "seconds": lerp(a["seconds"], b["seconds"]), "bound": False}
    return None


def equal_error(points: list[dict], direct: list[dict]) -> list[dict]:
    """For each of warprt's Pareto points and each Mitsuba sampler: Mitsuba's spp and time at the same
    SSIM (mitsuba_at) and warprt's time over Mitsuba's (None where Mitsuba's frames do not reach it)."""
    rows = []
    for p in pareto(points):
        row = {"point": points.index(p), "mitsuba": {}}
        for sampler in dict.fromkeys(d["sampler"] for d in direct):
            m = mitsuba_at([d for d in direct if d["sampler"] == sampler], p["ssim"])
            row["mitsuba"][sampler] = None if m is None else {**m, "ratio": p["seconds"] / m["seconds"]}
        rows.append(row)
    return rows


def at_depth(points, spp: int, depth: int, shadows=True, scale=1, light_samples=None) -> dict:
    """The point for (spp, depth): the deepest measured level up to ``depth`` (a grid row that stopped
    early stands for every deeper level, which renders the same image); at ``light_samples`` where the
    scene has area lights."""
    row = [p for p in points if p["spp"] == spp and p["shadows"] == shadows and p["scale"] == scale and p["depth"] <= depth
           and p.get("light_samples") == light_samples and not p.get("adaptive")]
    return max(row, key=lambda p: p["depth"])


def pareto(points: list[dict]) -> list[dict]:
    """The points no other point beats on both time and SSIM, fastest first."""
    front, best = [], -math.inf
    for p in sorted(points, key=lambda p: (p["seconds"], -p["ssim"])):
        if p["ssim"] > best:
            front.append(p)
            best = p["ssim"]
    return front


def cheapest(points: list[dict], threshold: float) -> dict | None:
    """The fastest point with SSIM >= threshold; among those within NOISE of its time (a tie on a
    timer), the one that traced the fewest rays (deterministic), so that e.g. 6 ray levels that render
    the same image as 3 cannot win by timer noise."""
    ok = [p for p in points if p["ssim"] >= threshold]
    if not ok:
        return None
    fastest = min(p["seconds"] for p in ok)
    return min((p for p in ok if p["seconds"] <= fastest * (1 + NOISE)), key=lambda p: (p["rays"], p["seconds"]))


def scene_run(path: Path, cfg: dict) -> dict:
    scene = warprt.load_scene(path)
    W, H = reference_size(scene.camera, cfg["box"])
    scene = scene.with_camera(width=W, height=H)
    name = path.stem
    print(f"  {name}: {scene.triangle_count:,} triangles, {W}x{H}", flush=True)

    area = bool(scene.area_lights)
    if area:
        # Area lights: Mitsuba's own direct integrator on the file, converged, is the reference (the Whitted
        # reference integrates the lights at warprt's own sample points: the agreement check below).
        fx = resolve_effects(scene)
        if path.suffix.lower() != ".xml" or fx.reflection or fx.refraction:
            raise SystemExit(f"accuracy_cost: {path}: a scene with area lights is measured against Mitsuba's direct "
                             "integrator on a Mitsuba file without mirrors or glass")
        direct = {sampler: DirectRenderer(path, W, H, sampler) for sampler in SAMPLERS}
        spp = cfg["direct_ref_spp"]
        ref, t_ref = once(lambda: direct["independent"](spp, seed=0, samples_per_pass=DIRECT_PASS))
        coarse = direct["independent"](spp // 4, seed=1, samples_per_pass=DIRECT_PASS)
        reference = {"integrator": "direct", "sampler": "independent", "spp": spp, "seconds": t_ref}
        check = {"spp": spp // 4}
    else:
        mi_scene = mitsuba_scene(scene)
        ref, t_ref = once(lambda: mi_scene.render(Switches(max_depth=cfg["ref_depth"], spp=cfg["ref_spp"])))
        # The reference's own error: a quarter of its samples and half its ray levels against it.
        coarse = mi_scene.render(Switches(max_depth=cfg["ref_depth"] // 2, spp=cfg["ref_spp"] // 4))
        reference = {"integrator": "whitted", "spp": cfg["ref_spp"], "depth": cfg["ref_depth"], "seconds": t_ref}
        check = {"spp": cfg["ref_spp"] // 4, "depth": cfg["ref_depth"] // 2}
    ref_check = metrics(coarse, ref)
    reference["check"] = {**check, "ssim": ref_check[0], "psnr": ref_check[1]}
    print(f"    reference {describe_reference(reference)}: {t_ref:.1f} s; its self-check "
          f"SSIM {ref_check[0]:.5f}, PSNR {ref_check[1]:.1f} dB", flush=True)

    geometry, t_geometry = once(lambda: Geometry(scene))
    measured, same, stopped, base_depth, reflective = sweep(scene, geometry, ref, cfg)
    # Where warprt and Mitsuba disagree at identical settings: error no knob can remove (with area lights:
    # the Whitted reference integrates them at warprt's own sample points).
    sp = same["point"]
    same_scene = scene.with_render(light_samples=sp["light_samples"]) if area else scene
    agree = metrics(same["image"], mitsuba_scene(same_scene).render(Switches(max_depth=sp["depth"], spp=sp["spp"])))
    front = pareto(measured)
    out = {
        "scene": f"scenes/{path.name}", "name": name, "triangles": scene.triangle_count, "size": [W, H],
        "base_depth": base_depth, "reflective": reflective, "rows_stopped": {str(k): v for k, v in stopped.items()},
        "base_light_samples": scene.render.light_samples if area else None,
        "geometry_seconds": t_geometry,
        "reference": reference,
        "agreement": {"spp": sp["spp"], "depth": sp["depth"], "light_samples": sp.get("light_samples"),
                      "ssim": agree[0], "psnr": agree[1]},
        "points": measured,
        "pareto": [measured.index(p) for p in front],
        "cheapest": {str(t): (measured.index(c) if (c := cheapest(measured, t)) else None) for t in THRESHOLDS},
    }
    if area:
        out["direct"] = direct_sweep(direct, ref, cfg)
        out["equal_error"] = equal_error(measured, out["direct"])
    return out


def describe_reference(ref: dict) -> str:
    if ref["integrator"] == "direct":
        return (f"Mitsuba's direct integrator, {ref['spp']} spp ({ref['sampler']} sampler); self-check: "
                f"{ref['check']['spp']} spp, other seeds")
    return (f"Whitted, {ref['spp']} spp, {ref['depth']} levels; self-check: {ref['check']['spp']} spp, "
            f"{ref['check']['depth']} levels")


def scene_paths(only=None) -> list[Path]:
    """The scenes measured: scenes/ (or those named in ``only``) less those lit by an environment, whose light the
    Whitted reference does not have (reference/mitsuba_whitted.py refuse_environment); their error against time is
    the equal-error section's (benchmarks/equal_error.py, against Mitsuba's direct integrator)."""
    paths = sorted([*SCENES.glob("*.toml"), *SCENES.glob("*.xml")], key=lambda p: p.stem)
    if only:
        wanted = set(only)
        paths = [p for p in paths if p.stem in wanted]
        missing = wanted - {p.stem for p in paths}
        if missing:
            raise SystemExit(f"accuracy_cost: no scene named {', '.join(sorted(missing))} in {SCENES}")
    lit = [p.stem for p in paths if warprt.load_scene(p).environment is not None]
    if only and lit:
        raise SystemExit(f"accuracy_cost: {', '.join(lit)}: lit by an environment, measured by benchmarks.equal_error")
    return [p for p in paths if p.stem not in lit]


def run(quick: bool = False, scenes=None, out: Path | str = RESULTS, ref_spp: int | None = None,
        box: tuple[int, int] | None = None) -> dict:
    """Every scene in scenes/ (or those named in ``scenes``): reference, sweep, Pareto front, plots
    in ``out``. The returned dict is JSON-ready."""
    init_warp()
    t0 = time.perf_counter()
    cfg = dict(QUICK if quick else FULL)
    if ref_spp:
        if math.isqrt(ref_spp) ** 2 != ref_spp or ref_spp < 4:
            raise SystemExit(f"accuracy_cost: --ref-spp must be a square >= 4 (k x k stratum centres), got {ref_spp}")
        cfg["ref_spp"] = ref_spp
    if box:
        cfg["box"] = tuple(box)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    print("accuracy against time", flush=True)
    results = [scene_run(path, cfg) for path in scene_paths(scenes)]
    data = {"quick": quick, "config": cfg, "machine": f"{cpu_name()}, {os.cpu_count()} CPU threads",
            "threads": default_threads(), "warp": warp.__version__, "mitsuba_variant": mitsuba_variant(),
            "scenes": results}
    data["plots"] = {r["name"]: str(plot_scene(r, out / f"accuracy_cost_{r['name']}.png")) for r in results}
    data["plots"]["fronts"] = str(plot_fronts(results, out / "accuracy_cost_fronts.png"))
    data["seconds"] = time.perf_counter() - t0
    return data


# --- plots -----------------------------------------------------------------------------------------

def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def families(r: dict) -> list[tuple[str, list[dict], str]]:
    """The one-knob sweeps through the measured points: (label, points in knob order, marker)."""
    pts, d0 = [p for p in r["points"] if not p.get("adaptive")], r["base_depth"]
    spp1 = min(p["spp"] for p in pts)
    spps = sorted({p["spp"] for p in pts if p["scale"] == 1})
    ls0 = r.get("base_light_samples")
    out = [(f"samples per pixel ({d0} level{'s' * (d0 > 1)}" + (f", {ls0} light samples)" if ls0 else ")"),
            [at_depth(pts, spp, d0, light_samples=ls0) for spp in spps], "o")]
    if ls0:
        for spp in spps:
            row = sorted([p for p in pts if p["spp"] == spp and p["shadows"] and p["scale"] == 1], key=lambda p: p["light_samples"])
            if len(row) > 1:
                out.append((f"light samples ({spp} spp)", row, "D"))
    if r["reflective"]:
        out.append((f"ray levels 1..8 ({spp1} spp)", sorted([p for p in pts if p["spp"] == spp1 and p["shadows"]
                                                             and p["scale"] == 1], key=lambda p: p["depth"]), "^"))
    out.append(("shadows off", sorted([p for p in pts if not p["shadows"]], key=lambda p: p["spp"]), "x"))
    for s in sorted({p["scale"] for p in pts if p["scale"] > 1}):
        out.append((f"1/{s} size, upscaled", sorted([p for p in pts if p["scale"] == s], key=lambda p: p["spp"]), "s"))
    for t in sorted({p["adaptive"] for p in r["points"] if p.get("adaptive")}):
        out.append((f"adaptive {t:g}", sorted([p for p in r["points"] if p.get("adaptive") == t], key=lambda p: p["spp"]), "v"))
    return out


def _ms_ticks(ax):
    """Time axis labelled in plain milliseconds (5, 20, 100, 2000), minor ticks at 2 and 5 only."""
    import matplotlib.ticker

    ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda x, _: f"{x:g}"))
    ax.xaxis.set_minor_formatter(matplotlib.ticker.FuncFormatter(lambda x, _: f"{x:g}" if f"{x:.0e}"[0] in "25" else ""))


def _err(p) -> float:
    return max(1.0 - p["ssim"], 1e-6)


def plot_scene(r: dict, path: Path) -> Path:
    plt = _pyplot()
    pts = r["points"]
    fig, axes = plt.subplots(1, 2, figsize=(13, 5))
    t = lambda ps: [p["seconds"] * 1000 for p in ps]
    for ax, value in zip(axes, (_err, lambda p: p["psnr"])):
        ax.plot(t(pts), [value(p) for p in pts], ".", color="lightgrey", label="every measured setting", zorder=1)
        for label, ps, marker in families(r):
            ax.plot(t(ps), [value(p) for p in ps], marker + "-", ms=5, lw=1, label=label, zorder=2)
        front = [pts[i] for i in r["pareto"]]
        ax.step(t(front), [value(p) for p in front], where="post", color="black", lw=1.2, alpha=0.7,
                label="Pareto front", zorder=3)
        for sampler, style in (("independent", "--"), ("stratified", ":")):
            ds = [d for d in r.get("direct", []) if d["sampler"] == sampler]
            if ds:
                ax.plot(t(ds), [value(d) for d in ds], "v" + style, color="dimgrey", ms=4, lw=1, zorder=2,
                        label=f"Mitsuba direct, {sampler} sampler ({ds[0]['spp']}..{ds[-1]['spp']} spp)")
        ax.set_xscale("log")
        ax.set_xlabel("warm render time (ms)")
        ax.grid(True, which="both", alpha=0.3)
        _ms_ticks(ax)
    axes[0].set_yscale("log")
    axes[0].set_ylabel("1 - SSIM against the reference")
    for th in THRESHOLDS:
        axes[0].axhline(1 - th, color="grey", ls=":", lw=1)
        axes[0].text(0.01, 1 - th, f"SSIM {th}", transform=axes[0].get_yaxis_transform(), fontsize=7, va="bottom")
        c = r["cheapest"][str(th)]
        if c is not None:
            p = pts[c]
            axes[0].annotate(f"SSIM {th}: {describe(p)}", (p["seconds"] * 1000, _err(p)), fontsize=7,
                             xytext=(6, 6), textcoords="offset points")
    axes[1].set_ylabel("PSNR against the reference (dB)")
    axes[0].legend(fontsize=7)
    w, h = r["size"]
    ref = r["reference"]
    what = (f"Mitsuba's direct integrator ({ref['spp']} spp)" if ref.get("integrator") == "direct"
            else f"Mitsuba ({ref['spp']} spp, {ref['depth']} levels)")
    fig.suptitle(f"{r['scene']} ({r['triangles']:,} triangles) at {w}x{h}: error against {what} and the time")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def plot_fronts(results: list[dict], path: Path) -> Path:
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8, 5.5))
    for r in results:
        front = [r["points"][i] for i in r["pareto"]]
        ax.step([p["seconds"] * 1000 for p in front], [_err(p) for p in front], "o-", where="post", ms=3,
                label=f"{r['name']} ({r['size'][0]}x{r['size'][1]})")
    ax.set_xscale("log")
    ax.set_yscale("log")
    for th in THRESHOLDS:
        ax.axhline(1 - th, color="grey", ls=":", lw=1)
        ax.text(0.01, 1 - th, f"SSIM {th}", transform=ax.get_yaxis_transform(), fontsize=7, va="bottom")
    _ms_ticks(ax)
    ax.set_xlabel("warm render time (ms)")
    ax.set_ylabel("1 - SSIM against the reference")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("The fastest way to each error level, every scene (Pareto fronts)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


# --- the report ------------------------------------------------------------------------------------

def report(data: dict, relative_to: Path | str | None = ROOT) -> str:
    """Markdown for the performance report; image links relative to ``relative_to`` (the folder the
    Markdown is written to: benchmarks/ for `python -m benchmarks`)."""
    cfg = data["config"]
    lines = [
        "## What accuracy costs in time",
        "",
        f"warprt's image error against a converged reference, against its warm render time (kernels compiled, BVH built; "
        f"{data['threads']} threads, median of {cfg['repeat']} for frames under {CHEAP * 1000:.0f} ms), on {data['machine']}, "
        f"Warp {data['warp']}. Regenerate alone: `python -m benchmarks.accuracy_cost`"
        + (" (this was a --quick run: tiny images, few settings; not for quoting)" if data["quick"] else "") + ".",
        "",
        f"- Reference: Mitsuba 3 `{data['mitsuba_variant']}` with the same Whitted integrator (reference/mitsuba_whitted.py) "
        f"at {cfg['ref_spp']} spp (stratum centres) and {cfg['ref_depth']} ray levels, each scene's image shrunk to fit "
        f"{cfg['box'][0]}x{cfg['box'][1]}. Self-check: the reference at a quarter of its samples and half its ray levels "
        "against itself. Its own error is smaller than that (an edge pixel's error with k x k stratum centres falls "
        "as 1/k), but a threshold above the self-check's SSIM is beyond what this reference can resolve: the table "
        "says so where that happens.",
        f"- Scenes lit by area lights (a Mitsuba file): the reference is Mitsuba's own `direct` integrator on the file at "
        f"{cfg['direct_ref_spp']} spp (independent sampler, box filter, in passes of {DIRECT_PASS}), each image scaled to "
        f"fit the same box; self-check: {cfg['direct_ref_spp'] // 4} spp at other seeds against it (its error is about "
        "half the self-check's: the two errors add). One more knob: light samples "
        f"{', '.join(map(str, cfg['light_samples']))} (k x k points per light, a shadow ray each) at every spp, up to "
        f"{cfg['max_light_rays']} shadow rays per pixel and light; the other sweeps at the scene's own light samples.",
        "- Error: SSIM (7x7 window) and PSNR of linear RGB clamped to [0, 1].",
        f"- Knobs: spp {', '.join(map(str, cfg['spps']))} x ray levels {', '.join(map(str, cfg['grid_depths']))} with shadows "
        f"(the grid; ray levels {cfg['depths'][0]}..{cfg['depths'][-1]} at {cfg['spps'][0]} spp; a row stops at the first "
        "level that traces no reflection ray, since no deeper level can change a pixel); shadows off at each spp; "
        f"resolution 1/{', 1/'.join(map(str, cfg['scales']))} at {', '.join(map(str, cfg['scale_spps']))} spp, upscaled to "
        "the reference size by bilinear interpolation (linear RGB, pixel centres aligned; the upscale is timed). "
        "The one-knob sweeps hold the other knobs at the scene file's values (1 spp, its ray levels, shadows).",
        "- Agreement: warprt against Mitsuba at identical settings; the error no knob removes.",
        f"- Cheapest: the fastest setting that reaches the SSIM; settings within {NOISE * 100:.0f}% of its time are a tie "
        "(timer noise), won by the one that traces the fewest rays.",
        "",
        f"![Pareto fronts]({link(data['plots']['fronts'], relative_to)})",
        "",
        "| scene | triangles | size | cheapest to SSIM 0.99 | cheapest to SSIM 0.999 | best measured | agreement | "
        "reference self-check |",
        "|---|---:|---|---|---|---|---|---|",
    ]
    for r in data["scenes"]:
        pts = r["points"]
        a, chk = r["agreement"], r["reference"]["check"]

        def cell(th):
            c = r["cheapest"][str(th)]
            if c is None:
                return "not reached"
            p = pts[c]
            return f"{describe(p)}: {ms(p['seconds'])} (SSIM {p['ssim']:.4f})" + (
                "" if chk["ssim"] >= th else "; the reference's self-check is below this threshold too")

        best = max(pts, key=lambda p: p["ssim"])
        lines.append(f"| {r['name']} | {r['triangles']:,} | {r['size'][0]}x{r['size'][1]} | {cell(0.99)} | {cell(0.999)} | "
                     f"{describe(best)}: SSIM {best['ssim']:.4f}, {best['psnr']:.1f} dB, {ms(best['seconds'])} | "
                     f"SSIM {a['ssim']:.5f} ({a['spp']} spp, {a['depth']} level{'s' * (a['depth'] > 1)}"
                     + (f", {a['light_samples']} light samples" if a.get("light_samples") else "") + f") | SSIM {chk['ssim']:.5f} |")
    lines.append("")
    for r in data["scenes"]:
        lines += [f"### {r['scene']}", "",
                  f"![{r['name']}: error against time]({link(data['plots'][r['name']], relative_to)})", ""]
        if not r["reflective"]:
            lines += ["No reflective material: ray levels change nothing, so only 1 level is measured.", ""]
        elif r["rows_stopped"]:
            lines += ["Grid rows that stopped at a ray level that traced no reflection ray (every deeper level renders "
                      "the same image): " + ", ".join(f"{spp} spp at {d} levels" for spp, d in r["rows_stopped"].items())
                      + ".", ""]
        front = [r["points"][i] for i in r["pareto"]]
        lines += ["Pareto front: " + "; ".join(f"{describe(p)} {ms(p['seconds'])} SSIM {p['ssim']:.4f}" for p in front)
                  + ".", ""]
        if "direct" in r:
            lines += soft_shadows(r)
    return "\n".join(lines)


def soft_shadows(r: dict) -> list[str]:
    """The light-samples rows of an area-lit scene: SSIM and time per (spp, light samples), and Mitsuba's
    direct integrator at the spp that reaches the same error."""
    pts = [p for p in r["points"] if p["shadows"] and p["scale"] == 1 and not p.get("adaptive")]
    spps = sorted({p["spp"] for p in pts})
    counts = sorted({p["light_samples"] for p in pts})
    at = {(p["spp"], p["light_samples"]): p for p in pts}
    ref = r["reference"]
    lines = [f"What soft shadows cost: SSIM against {describe_reference(ref)} (self-check SSIM "
             f"{ref['check']['ssim']:.5f}) and warm time, per light samples (rows) and spp (columns); "
             "k x k light samples trace k x k shadow rays per pixel sample and light.", "",
             "| light samples | " + " | ".join(f"{s} spp" for s in spps) + " |",
             "|---:|" + "---|" * len(spps)]
    for ls in counts:
        cells = [f"{at[(s, ls)]['ssim']:.4f}, {ms(at[(s, ls)]['seconds'])}" if (s, ls) in at else "-" for s in spps]
        lines.append(f"| {ls} | " + " | ".join(cells) + " |")
    direct = r["direct"]
    lines += ["", "Mitsuba's `direct` integrator on the same file (one emitter and one BSDF sample per sample, MIS), warm:", "",
              "| sampler | " + " | ".join(f"{d['spp']} spp" for d in direct if d["sampler"] == direct[0]["sampler"]) + " |",
              "|---|" + "---|" * sum(d["sampler"] == direct[0]["sampler"] for d in direct)]
    for sampler in dict.fromkeys(d["sampler"] for d in direct):
        lines.append(f"| {sampler} | " + " | ".join(f"{d['ssim']:.4f}, {ms(d['seconds'])}" for d in direct
                                                    if d["sampler"] == sampler) + " |")
    samplers = list(dict.fromkeys(d["sampler"] for d in direct))
    lines += ["", "At the same error: each point of warprt's Pareto front, and the spp and warm time at which Mitsuba's "
              "`direct` integrator reaches its SSIM (interpolated between the two measured frames around it on a "
              "log scale of 1 - SSIM; the ratio is warprt's time over Mitsuba's, below 1 warprt is faster):", "",
              "| warprt | SSIM | time | " + " | ".join(f"Mitsuba, {s} sampler | ratio" for s in samplers) + " |",
              "|---|---:|---:|" + "---|---:|" * len(samplers)]
    for row in r["equal_error"]:
        p = r["points"][row["point"]]
        cells = []
        for s in samplers:
            m = row["mitsuba"][s]
            if m is None:
                cells += [f"not reached at {max(d['spp'] for d in direct if d['sampler'] == s)} spp", "-"]
            elif m["bound"]:
                cells += [f"1 spp does better: {ms(m['seconds'])}", f">= {m['ratio']:.2f}x"]
            else:
                cells += [f"{m['spp']:.0f} spp, {ms(m['seconds'])}", f"{m['ratio']:.2f}x"]
        lines.append(f"| {describe(p)} | {p['ssim']:.4f} | {ms(p['seconds'])} | " + " | ".join(cells) + " |")
    return lines + [""]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="tiny images, few settings, a 16-spp reference: a smoke run")
    ap.add_argument("--scenes", default=None, help="comma-separated scene names from scenes/ (default: all)")
    ap.add_argument("--ref-spp", type=int, default=None, help="the reference's samples per pixel, a square (default 256; 16 with --quick)")
    ap.add_argument("--size", default=None, metavar="WxH", help="the box each scene's image is shrunk to fit (default 320x240; 96x72 with --quick)")
    ap.add_argument("-o", "--output", default=str(RESULTS / "accuracy_cost.md"), help="Markdown report; plots and JSON beside it")
    args = ap.parse_args(argv)
    box = None
    if args.size:
        try:
            box = tuple(int(v) for v in args.size.lower().split("x"))
            assert len(box) == 2 and min(box) >= 16
        except (ValueError, AssertionError):
            ap.error(f"--size: expected WxH with both sides >= 16, e.g. 320x240; got '{args.size}'")
    out = Path(args.output)
    data = run(quick=args.quick, scenes=args.scenes.split(",") if args.scenes else None, out=out.parent,
               ref_spp=args.ref_spp, box=box)
    save(out, data, report(data, relative_to=out.parent))
    print(f"wrote {out} and its plots in {data['seconds']:.0f} s", flush=True)


if __name__ == "__main__":
    main()
