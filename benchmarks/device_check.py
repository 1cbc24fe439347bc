"""CPU against GPU: the hash list's cases (benchmarks/image_hashes.py) rendered on the CPU and on a CUDA
device, each image held to the tolerance docs/gpu.md states; the gradients of GRAD_SCENES (render(grad=True),
backward) held to GRAD_TOLERANCE; and warm frames timed on the device (and Mitsuba's cuda_ad_rgb running the
reference's integrator where it is installed). On a machine without CUDA, nothing to check.

    python -m benchmarks.device_check                        # make device-check: every case, cuda against cpu
    python -m benchmarks.device_check --device cpu --quick   # make device-check DEVICE=cpu: the script on the CPU
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

import warprt
from benchmarks.image_hashes import PATHS, cases
from benchmarks.output import save

# Not to the bit: NVRTC contracts multiply-adds (fuse_fp), so a hit or shadow test at an edge may go the other way
# and a texel's weights move in their last bits (the bilinear lookup is warprt's own, float-weighted on both devices).
PIXEL_TOLERANCE = 1e-3  # a pixel agrees when each of its channels is within this of the CPU's
MAX_DIFFERING = 1e-3  # an image agrees when at most this share of its pixels do not ...
MIN_SSIM = 0.999  # ... or its SSIM against the CPU's (linear, clipped to [0, 1]) is at least this
MAX_RAYS = 1e-3  # and its total ray count is within this share of the CPU's

QUICK = ("seed", "whitted")  # --quick: these scenes, spp 1, every path, QUICK_SIZE
QUICK_SIZE = (48, 36)
# Gradients on both devices (their parameters' gradients against a fixed d_image): a point-lit mirror scene, a
# supersampled textured one, Mitsuba's area-lit Cornell box. Held as the images are: a shading sum reordered by
# fused multiply-adds, and a hit or visibility gone the other way at an edge, move a gradient by little.
GRAD_SCENES = (("seed", {}), ("textured", {"render.spp": 4}), ("cornell_box.xml", {}))
GRAD_SIZE = (64, 48)
GRAD_TOLERANCE = 1e-2  # |g_device - g_cpu| / max(|g_cpu|) per parameter, its largest entry
TIMED_SIZE = (1024, 768)  # warm frames, as the performance report's head to head


@dataclass
class Comparison:
    case: str
    max_abs: float = 0.0
    differing: float = 0.0  # share of pixels with a channel beyond PIXEL_TOLERANCE
    ssim: float | None = None  # None where scikit-image is not installed
    rays: float = 0.0  # relative difference of the total ray count
    error: str | None = None  # a render that failed on one side (a refusal on both sides agrees)

    @property
    def ok(self) -> bool:
        close = self.differing <= MAX_DIFFERING or (self.ssim is not None and self.ssim >= MIN_SSIM)
        return self.error is None and close and self.rays <= MAX_RAYS

    def __str__(self) -> str:
        if self.error:
            return f"{self.case}: {self.error}  FAIL"
        ssim = "-" if self.ssim is None else f"{self.ssim:.5f}"
        return (f"{self.case}: max |diff| {self.max_abs:.2e}, {100 * self.differing:.3f}% pixels beyond "
                f"{PIXEL_TOLERANCE:g}, SSIM {ssim}, rays {100 * self.rays:+.3f}%  {'ok' if self.ok else 'FAIL'}")


def ssim(a: np.ndarray, b: np.ndarray) -> float | None:
    try:
        from skimage.metrics import structural_similarity
    except ImportError:
        return None
    a, b = (np.clip(x, 0.0, 1.0) for x in (a, b))
    side = min(7, *a.shape[:2])  # the default window, or the largest odd one a tiny image holds
    return float(structural_similarity(a, b, channel_axis=-1, data_range=1.0, win_size=side - 1 + side % 2))


def compare(case: str, cpu, other) -> Comparison:
    """``other`` (a RenderResult) against ``cpu``'s, in the terms of the tolerance above."""
    a, b = (np.asarray(r.image, dtype=np.float64) for r in (cpu, other))
    diff = np.abs(a - b)
    diff[~np.isfinite(diff)] = np.inf  # a NaN on one side differs
    rays = [float(r.stats.rays.get("total", 0)) for r in (cpu, other)]
    return Comparison(case, float(diff.max(initial=0.0)), float(np.mean(diff.max(axis=-1) > PIXEL_TOLERANCE)),
                      ssim(a, b), abs(rays[1] - rays[0]) / max(rays[0], 1.0))


def attempt(scene, device: str, options: dict):
    """The RenderResult, or the refusal's or the failure's message."""
    try:
        return warprt.render(scene, device=device, **options)
    except warprt.SceneError as e:
        return f"refused: {e}"
    except Exception as e:  # a GPU-only failure is what this check is for: report it, check the rest
        return f"{type(e).__name__}: {e}"


def check(device: str, quick: bool = False, only=None) -> list[Comparison]:
    out = []
    for path, size, spp in cases():
        name = "default" if path is None else path.stem
        if (quick and (name not in QUICK or spp != 1)) or (only and name not in only):
            continue
        w, h = QUICK_SIZE if quick else size
        scene = warprt.load_scene(path, {"camera.width": w, "camera.height": h, "render.spp": spp})
        for label, options in PATHS.items():
            case = f"{name} {w}x{h} spp{spp} {label}"
            cpu, other = attempt(scene, "cpu", options), attempt(scene, device, options)
            if isinstance(cpu, str) and isinstance(other, str) and cpu.startswith("refused") and other.startswith("refused"):
                out.append(Comparison(f"{case} (refused on both)"))
            elif isinstance(cpu, str) or isinstance(other, str):
                said = lambda r: r if isinstance(r, str) else "rendered"  # noqa: E731
                out.append(Comparison(case, error=f"cpu: {said(cpu)}; {device}: {said(other)}"))
            else:
                out.append(compare(case, cpu, other))
            print(out[-1], flush=True)
    return out


def gradient_difference(cpu: dict, other: dict) -> tuple[float, str]:
    """The largest |other - cpu| / max |cpu| over the parameters (inf where ``other`` is not finite or lacks
    one), and its parameter's name."""
    worst, where = 0.0, ""
    for key, g in cpu.items():
        g = np.asarray(g, np.float64)
        o = np.asarray(other.get(key, np.full_like(g, np.nan)), np.float64)
        scale = max(float(np.abs(g).max(initial=0.0)), 1e-12)
        rel = float(np.abs(o - g).max(initial=0.0)) / scale if o.shape == g.shape and np.all(np.isfinite(o)) else np.inf
        if rel > worst:
            worst, where = rel, key
    return worst, where


def gradient_check(device: str, quick: bool = False) -> list[dict]:
    """Per GRAD_SCENES scene (the first alone with ``quick``): every parameter's gradient on ``device`` and on
    the CPU for one d_image, and the largest relative difference."""
    SCENES = Path(__file__).resolve().parent.parent / "scenes"
    out = []
    for name, overrides in GRAD_SCENES[:1] if quick else GRAD_SCENES:
        w, h = QUICK_SIZE if quick else GRAD_SIZE
        path = SCENES / (name if "." in name else f"{name}.toml")
        scene = warprt.load_scene(path, {"camera.width": w, "camera.height": h, **overrides})
        # Positive weights: a gradient summed over pixels in another order (atomics on a GPU) cannot cancel
        # down to its rounding.
        d_image = np.random.default_rng(3).random((h, w, 3)).astype(np.float32)
        grads = {}
        try:
            for dev in ("cpu", device):
                with warprt.Renderer(scene, device=dev) as r:
                    r.render(grad=True)
                    grads[dev] = r.backward(d_image, edges=False)
        except Exception as e:  # a GPU-only failure is what this check is for
            out.append({"scene": name, "error": f"{type(e).__name__}: {e}", "ok": False})
            print(f"gradients of {name}: {out[-1]['error']}  FAIL", flush=True)
            continue
        worst, where = gradient_difference(grads["cpu"], grads[device])
        out.append({"scene": name, "parameters": len(grads["cpu"]), "worst": worst, "worst_parameter": where,
                    "ok": worst <= GRAD_TOLERANCE})
        print(f"gradients of {name}: {len(grads['cpu'])} parameters, largest relative difference {worst:.2e} "
              f"({where or '-'})  {'ok' if worst <= GRAD_TOLERANCE else 'FAIL'}", flush=True)
    return out


def warm_times(device: str, quick: bool = False, repeat: int = 3, only=None) -> list[dict]:
    """Warm frames of every scene at TIMED_SIZE (QUICK_SIZE with ``quick``) on ``device``, the median of
    ``repeat`` after one untimed frame; and Mitsuba's cuda_ad_rgb with the reference's integrator where it is
    installed and the device is a GPU (else None)."""
    w, h = QUICK_SIZE if quick else TIMED_SIZE
    mitsuba = device != "cpu" and _mitsuba_cuda()
    out = []
    for path, _, spp in cases():
        name = "default" if path is None else path.stem
        if spp != 1 or (quick and name not in QUICK) or (only and name not in only):
            continue
        scene = warprt.load_scene(path, {"camera.width": w, "camera.height": h})
        row = {"scene": name, "width": w, "height": h, "warprt": None, "mitsuba_cuda": None}
        try:
            with warprt.Renderer(scene, device=device) as r:
                r.render()
                row["warprt"] = _median_time(r.render, repeat)
        except Exception as e:
            row["error"] = f"{type(e).__name__}: {e}"
        if mitsuba:
            try:
                from reference.mitsuba_whitted import Switches, mitsuba_scene

                ms = mitsuba_scene(scene)
                switches = Switches.for_effects(warprt.scene.resolve_effects(scene), scene.render)
                ms.render(switches)
                row["mitsuba_cuda"] = _median_time(lambda: ms.render(switches), repeat)
            except Exception as e:  # the reference refuses some scenes (area lights with glass)
                row["mitsuba_error"] = f"{type(e).__name__}: {e}"
        out.append(row)
        ratio = (f", {row['warprt'] / row['mitsuba_cuda']:.2f}x Mitsuba cuda_ad_rgb"
                 if row["warprt"] and row["mitsuba_cuda"] else "")
        print(f"warm {name} {w}x{h} on {device}: "
              + (f"{row['warprt'] * 1000:.1f} ms{ratio}" if row["warprt"] else row.get("error", "-")), flush=True)
    return out


def _median_time(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return float(np.median(times))


def _mitsuba_cuda() -> bool:
    """Whether Mitsuba's cuda_ad_rgb variant is installed and can run here: then the reference runs on it."""
    try:
        import mitsuba

        if "cuda_ad_rgb" not in mitsuba.variants():
            return False
        os.environ["WARPRT_MITSUBA_VARIANT"] = "cuda_ad_rgb"
        from reference import mitsuba_variant

        return mitsuba_variant() == "cuda_ad_rgb"
    except Exception:
        return False


def report_section(summary: str, results, grads, times) -> str:
    """The REPORT.md section of a device run."""
    lines = ["## On a GPU: `make device-check`", "", summary, "",
             "| scene | size | warprt warm | Mitsuba `cuda_ad_rgb` warm | ratio |", "|---|---|---:|---:|---:|"]
    for t in times:
        ratio = f"{t['warprt'] / t['mitsuba_cuda']:.2f}x" if t.get("warprt") and t.get("mitsuba_cuda") else "-"
        ms = lambda v: f"{v * 1000:.1f} ms" if v else "-"  # noqa: E731
        lines.append(f"| {t['scene']} | {t['width']}x{t['height']} | {ms(t.get('warprt'))} | {ms(t.get('mitsuba_cuda'))} | {ratio} |")
    lines += ["", "Gradients against the CPU's: " + "; ".join(
        f"{g['scene']} {g.get('worst', float('nan')):.1e} ({'ok' if g['ok'] else 'FAIL'})" for g in grads) + ".", "",
        f"Images beyond the tolerance: {sum(not r.ok for r in results)} of {len(results)} (results/device.md).", ""]
    return "\n".join(lines)


def cuda_count() -> int:
    from warprt.kernels import init_warp, wp  # warprt's own start: quiet, its settings

    init_warp()
    return wp.get_cuda_device_count()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--device", default="cuda", help="the device held to the CPU: cuda (default), cuda:1, or cpu")
    ap.add_argument("--quick", action="store_true", help=f"scenes {', '.join(QUICK)} at {QUICK_SIZE[0]}x{QUICK_SIZE[1]}, spp 1")
    ap.add_argument("--only", nargs="+", metavar="SCENE", help="these scenes alone (stems, or 'default')")
    ap.add_argument("--out", type=Path, help="write the results here (Markdown, and JSON beside it)")
    ap.add_argument("--report", type=Path, help="replace (or add) the REPORT.md section 'On a GPU' in this file")
    args = ap.parse_args(argv)
    if args.device != "cpu" and cuda_count() == 0:
        print("no CUDA device: nothing to check")
        return 0
    start = time.perf_counter()
    results = check(args.device, args.quick, set(args.only or ()))
    grads = gradient_check(args.device, args.quick)
    times = warm_times(args.device, args.quick, repeat=1 if args.quick else 3, only=set(args.only or ()))
    failed = [r for r in results if not r.ok]
    failed_grads = [g for g in grads if not g["ok"]]
    summary = (f"{len(results)} images on {args.device} against the CPU in {time.perf_counter() - start:.0f} s: "
               f"{len(failed)} beyond the tolerance of docs/gpu.md; gradients of {len(grads)} scenes: "
               f"{len(failed_grads)} beyond {GRAD_TOLERANCE:g}")
    print(summary)
    if args.out:
        save(args.out, {"device": args.device, "results": [asdict(r) | {"ok": r.ok} for r in results],
                        "gradients": grads, "warm": times},
             "\n".join([f"# {summary}", "", *(f"- {r}" for r in results)]))
    if args.report:
        from benchmarks.__main__ import commit, replace_section

        section = report_section(summary, results, grads, times)
        tag = "`python -m benchmarks.device_check --report`"
        note = f"Section \"On a GPU\" written by {tag} on {args.device} at commit {commit() or 'unknown'}."
        text = args.report.read_text()
        if section.splitlines()[0] + "\n" not in text:  # the first GPU run: the section goes last
            text = text.rstrip("\n") + "\n\n" + section.splitlines()[0] + "\n"
        args.report.write_text(replace_section(text, section, "device_check", note, tag=tag))
    return 1 if failed or failed_grads else 0


if __name__ == "__main__":
    sys.exit(main())
