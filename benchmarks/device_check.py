"""CPU against GPU: the hash list's cases (benchmarks/image_hashes.py) rendered on the CPU and on a CUDA
device, each image held to the tolerance docs/gpu.md states; on a machine without CUDA, nothing to check.

    python -m benchmarks.device_check                        # make device-check: every case, cuda against cpu
    python -m benchmarks.device_check --device cpu --quick   # make device-check DEVICE=cpu: the script on the CPU
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

import warprt
from benchmarks.image_hashes import PATHS, cases
from benchmarks.output import save

# Not to the bit: NVRTC contracts multiply-adds (fuse_fp) and CUDA's bilinear filter weighs texels in 8 bits,
# so a hit or shadow test at an edge may go the other way and a texture lookup move by 1/256 of a texel step.
PIXEL_TOLERANCE = 1e-3  # a pixel agrees when each of its channels is within this of the CPU's
MAX_DIFFERING = 1e-3  # an image agrees when at most this share of its pixels do not ...
MIN_SSIM = 0.999  # ... or its SSIM against the CPU's (linear, clipped to [0, 1]) is at least this
MAX_RAYS = 1e-3  # and its total ray count is within this share of the CPU's

QUICK = ("seed", "whitted")  # --quick: these scenes, spp 1, every path, QUICK_SIZE
QUICK_SIZE = (48, 36)


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
    args = ap.parse_args(argv)
    if args.device != "cpu" and cuda_count() == 0:
        print("no CUDA device: nothing to check")
        return 0
    start = time.perf_counter()
    results = check(args.device, args.quick, set(args.only or ()))
    failed = [r for r in results if not r.ok]
    summary = (f"{len(results)} images on {args.device} against the CPU in {time.perf_counter() - start:.0f} s: "
               f"{len(failed)} beyond the tolerance of docs/gpu.md")
    print(summary)
    if args.out:
        save(args.out, {"device": args.device, "results": [asdict(r) | {"ok": r.ok} for r in results]},
             "\n".join([f"# {summary}", "", *(f"- {r}" for r in results)]))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
