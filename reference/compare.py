"""warprt against Mitsuba on the same scene and effect set: SSIM, PSNR and the share of pixels off,
and the side-by-side image (warprt | Mitsuba | |difference| x 10) that shows where they differ.

Metrics are taken on linear RGB clamped to [0, 1] (what a display can show), never on PNGs.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

# A pixel is "off" when any channel differs by more than two 8-bit steps.
OFF_THRESHOLD = 2.0 / 255.0
DIFF_GAIN = 10.0


@dataclass
class CompareResult:
    ssim: float
    psnr: float  # dB; inf for identical images
    frac_off: float  # share of pixels with a channel off by more than OFF_THRESHOLD
    max_abs: float  # largest absolute channel difference
    warprt: np.ndarray  # linear float32 (H, W, 3)
    mitsuba: np.ndarray
    effects: str = ""
    variant: str = ""
    times: dict = field(default_factory=dict)  # seconds: warprt, mitsuba

    @property
    def difference(self) -> np.ndarray:
        return np.abs(_clamped(self.warprt) - _clamped(self.mitsuba))

    @property
    def off_mask(self) -> np.ndarray:
        return (self.difference > OFF_THRESHOLD).any(-1)

    def summary(self) -> str:
        return (f"SSIM {self.ssim:.6f}  PSNR {self.psnr:.2f} dB  pixels off by > 2/255: {100 * self.frac_off:.3f}% "
                f"({int(self.off_mask.sum())} of {self.off_mask.size})  max |diff| {self.max_abs:.4f}")

    def write(self, folder) -> Path:
        """Both images (.npy linear float, .png sRGB), the difference and the side-by-side strip."""
        from warprt.image import write_image

        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        for name, image in (("warprt", self.warprt), ("mitsuba", self.mitsuba)):
            write_image(folder / f"{name}.npy", image)
            write_image(folder / f"{name}.png", image)
        write_image(folder / "difference.npy", self.difference)
        write_image(folder / "difference_x10.png", np.clip(self.difference * DIFF_GAIN, 0.0, 1.0))
        side_by_side(self.warprt, self.mitsuba, folder / "side_by_side.png")
        (folder / "metrics.txt").write_text(f"effects {self.effects}\nmitsuba variant {self.variant}\n{self.summary()}\n")
        return folder


def _clamped(image: np.ndarray) -> np.ndarray:
    return np.clip(np.asarray(image, np.float64), 0.0, 1.0)


def metrics(a: np.ndarray, b: np.ndarray) -> tuple[float, float, float, float]:
    """(SSIM, PSNR dB, share of pixels off, max |diff|) of two linear images clamped to [0, 1]."""
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity

    a, b = _clamped(a), _clamped(b)
    if a.shape != b.shape:
        raise ValueError(f"image shapes differ: {a.shape} vs {b.shape}")
    # SSIM's 7x7 window, narrowed (odd) for images smaller than that; below 3 pixels there is no SSIM.
    side = min(a.shape[:2])
    win = min(7, side if side % 2 else side - 1)
    ssim = float(structural_similarity(a, b, data_range=1.0, channel_axis=-1, win_size=win)) if win >= 3 else math.nan
    diff = np.abs(a - b)
    psnr = float("inf") if not diff.any() else float(peak_signal_noise_ratio(a, b, data_range=1.0))
    return ssim, psnr, float((diff > OFF_THRESHOLD).any(-1).mean()), float(diff.max())


def side_by_side(warprt_image: np.ndarray, mitsuba_image: np.ndarray, path) -> Path:
    """warprt | Mitsuba | |difference| x 10, one PNG, panels separated by a thin grey gap."""
    from warprt.image import write_image

    a, b = _clamped(warprt_image), _clamped(mitsuba_image)
    diff = np.clip(np.abs(a - b) * DIFF_GAIN, 0.0, 1.0)
    gap = np.full((a.shape[0], max(2, a.shape[1] // 100), 3), 0.2)
    return write_image(path, np.concatenate([a, gap, b, gap, diff], axis=1).astype(np.float32))


def compare(scene, *, effects=None, disable=(), threads: int | None = None, output=None, **render_options) -> CompareResult:
    """Render ``scene`` with warprt and with the Mitsuba reference under the same effect set
    (warprt.render's ``effects``/``disable``) and compare; write the side-by-side PNG to ``output``.
    ``render_options`` go to warprt.render as they are (e.g. primary_query="zbuffer")."""
    import warprt
    from warprt.scene import resolve_effects

    from .mitsuba_whitted import Switches, mitsuba_scene, mitsuba_variant, refuse_environment

    refuse_environment(scene)  # before warprt's render: the reference could not match it
    fx = resolve_effects(scene, effects, disable)
    for on, field in ((fx.area_analytic, "render.area_estimator"), (fx.light_spread, "render.light_spread")):
        if on:  # the reference sums the same points as warprt's "samples"; the others are checked against Mitsuba's direct
            raise warprt.SceneError(scene.source, field, "the reference integrates area lights at warprt's own points, "
                                    "as render.area_estimator = 'samples' without render.light_spread does: compare "
                                    "that (this estimator is checked against Mitsuba's direct integrator, "
                                    "tests/accuracy/test_xml_area_lights.py)")
    switches = Switches.for_effects(fx, scene.render)
    t = time.perf_counter()
    ours = warprt.render(scene, threads=threads, effects=effects, disable=disable, **render_options).image
    t_warprt = time.perf_counter() - t
    t = time.perf_counter()
    ref = mitsuba_scene(scene, switches.smooth).render(switches)
    t_mitsuba = time.perf_counter() - t
    ssim, psnr, frac_off, max_abs = metrics(ours, ref)
    result = CompareResult(ssim, psnr, frac_off, max_abs, ours, ref, str(fx), mitsuba_variant(),
                           {"warprt": t_warprt, "mitsuba": t_mitsuba})
    if output is not None:
        side_by_side(ours, ref, output)
    return result
