"""What every accuracy case does: render warprt and the Mitsuba reference, check the thresholds, and
trace each pixel where they differ in float64 to show why; on failure, keep the images for a human.

Where the two renderers legitimately differ (each pixel class is checked, not assumed):
- ray-origin offsets: warprt pushes a secondary ray off its surface by a float32 error bound
  (about 1e-6 of the coordinates), Mitsuba by (1 + max|p|) * 1500 * 2^-24 (about 1e-4). A shadow or
  reflection ray that passes an edge closer than that, a grazing shadow ray near a smooth object's
  terminator, or a point that close to another surface (a concave corner) is decided differently.
  Such a pixel must be reproduced by the float64 oracle with Mitsuba's offsets for Mitsuba's value,
  and with some offset between 2^-34 and 2^-14 of the coordinates (OFFSET_SWEEP) for warprt's value.
- ties: a ray that passes within float32 rounding of a triangle edge (grazing rays included: what
  counts is how far the ray must move sideways, not the distance in the triangle's plane), two
  surfaces hit at the same distance (a concave corner seen exactly edge-on, a symmetric scene whose
  edges land on pixel centres), or a point lit at n.L = 0. Float32 rounding in Warp's and Embree's
  ray-triangle tests decides these (Embree's even by which rays share its packet: mi.render and a
  direct call of the integrator on the same rays disagree on 2 bunny pixels at 640x480); the
  oracle reports such a decision margin below TIE_MARGIN.
With glass, the oracle walks the whole ray tree (both branches at each dielectric), so the same two
classes cover the refracted and the Fresnel-reflected rays, and a failing pixel is described ray by
ray (path, object hit, contribution, margin).
Any other differing pixel fails the case, however good its SSIM and PSNR.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

import warprt
from reference import compare
from reference.compare import OFF_THRESHOLD
from reference.mitsuba_whitted import Switches
from warprt.scene import resolve_effects

from oracle import OFFSET_SWEEP, Whitted

ROOT = Path(__file__).resolve().parents[2]
# Every scene file but those with an environment light, which the Whitted reference has not (sky.toml: against
# Mitsuba's direct integrator, test_environment_against_mitsuba.py).
SCENES = sorted(p for p in (ROOT / "scenes").glob("*.toml") if 'type = "environment"' not in p.read_text())
ARTIFACTS = ROOT / "tests" / "_artifacts" / "accuracy"
TEST_WIDTH = 160  # small images keep the suite quick; every scene keeps its own aspect ratio

# Thresholds over every case. The floor is SSIM >= 0.995 and PSNR >= 35 dB; these are
# tightened to what the two renderers allow. At TEST_WIDTH every case measured SSIM >= 0.99995,
# PSNR >= 57.7 dB and at most 0.047% of pixels off; the same 15 cases at widths 120..240 (where
# other pixel centres happen to fall on edges: how much luck moves these numbers) gave at worst
# SSIM 0.99923, PSNR 47.9 dB (the Cornell box at 200 px: 5 concave-corner pixels) and 0.086% off.
# The margin below that worst case absorbs another machine's Embree/LLVM rounding; every pixel
# that does differ must still be explained by the oracle.
SSIM_MIN = 0.999
PSNR_MIN = 45.0
OFF_MAX = 0.002  # share of pixels with a channel off by more than 2/255
# A decision closer than this is float32's to make: distance to an edge or between two hits,
# relative to the coordinates (1 + max|p|), or |n.L|. Mitsuba's offsets are 25 times larger.
TIE_MARGIN = 2.0**-18
MAX_TRACED = 400  # more differing pixels than this is a failure without tracing them


def small(path, width: int = TEST_WIDTH, **overrides):
    """The scene at ``width`` pixels across, its aspect ratio kept (at least 7 pixels high for SSIM)."""
    scene = warprt.load_scene(path)
    cam = scene.camera
    height = max(7, round(width * cam.height / cam.width))
    return warprt.load_scene(path, {"camera.width": width, "camera.height": height, **overrides})


def unexplained(scene, switches, result) -> list[str]:
    """The differing pixels the float64 oracle cannot account for, described one per line."""
    off = np.argwhere(result.off_mask)
    if len(off) > MAX_TRACED:
        return [f"{len(off)} pixels differ (more than {MAX_TRACED}: not traced)"]
    oracle = Whitted(scene, switches)
    same = lambda a, b: np.abs(np.clip(a, 0.0, 1.0) - np.clip(b, 0.0, 1.0)).max() <= OFF_THRESHOLD
    bad = []
    for row, x in off:
        ours, ref = result.warprt[row, x], result.mitsuba[row, x]
        m = oracle.pixel(x, row, "mitsuba")
        if m.margin < TIE_MARGIN:
            continue
        if same(m.color, ref):
            sweep = (oracle.pixel(x, row, s) for s in OFFSET_SWEEP)
            if any(t.margin < TIE_MARGIN or same(t.color, ours) for t in sweep):
                continue
        bad.append(f"pixel (row {row}, col {x}): warprt {np.round(ours, 4)}, Mitsuba {np.round(ref, 4)}; "
                   f"float64 with Mitsuba's offsets {np.round(m.color, 4)} (decision margin {m.margin:.1e}), "
                   f"with none of the offsets tried equal to warprt's value; its largest rays: {m.explain(3)}")
    return bad


def check(case: str, scene, effects=None, disable=(), **render_options):
    """Compare, assert the thresholds and that every differing pixel is explained; on failure
    write both images and the difference to tests/_artifacts/accuracy/<case>/ and name it."""
    result = compare(scene, effects=effects, disable=disable, **render_options)
    switches = Switches.for_effects(resolve_effects(scene, effects, disable), scene.render)
    problems = []
    if not result.ssim >= SSIM_MIN:
        problems.append(f"SSIM {result.ssim:.6f} < {SSIM_MIN}")
    if not result.psnr >= PSNR_MIN:
        problems.append(f"PSNR {result.psnr:.2f} dB < {PSNR_MIN}")
    if not result.frac_off <= OFF_MAX:
        problems.append(f"{100 * result.frac_off:.3f}% of pixels off by > 2/255 (allowed {100 * OFF_MAX:.2f}%)")
    problems += unexplained(scene, switches, result)
    if problems:
        folder = result.write(ARTIFACTS / case)
        raise AssertionError(f"{case} ({result.effects}, max_depth {switches.max_depth}, spp {switches.spp}): "
                             f"{result.summary()}\n  " + "\n  ".join(problems[:20])
                             + f"\nimages (warprt, Mitsuba, difference): {folder}")
    return result


def record(result) -> str:
    """One line for the suite's report (pytest -s)."""
    psnr = "inf" if math.isinf(result.psnr) else f"{result.psnr:.2f}"
    return f"SSIM {result.ssim:.6f} PSNR {psnr} dB off {100 * result.frac_off:.3f}%"
