"""Mitsuba's own ``direct`` integrator on a Mitsuba scene file, through the file's sensor: the independent,
converged answer for a scene lit by area emitters (warprt integrates them with fixed stratified points;
Mitsuba with random emitter and BSDF samples, MIS-weighted).

    image = render_direct("scenes/cornell_box.xml", spp=1024, seed=0)      # the file's film size
    direct = DirectRenderer("scenes/cornell_box.xml", width=240, height=240, sampler="stratified")
    image = direct(4096, seed=0, samples_per_pass=256)                    # warm: the scene is loaded once

The sensor is the file's (to_world, x_fov, clip planes) with a box filter instead of the file's (a pixel's
value is the mean over the pixel, as warprt's stratified samples average it).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .mitsuba_whitted import mitsuba_variant

SAMPLERS = ("independent", "stratified")  # Mitsuba's default, and its jittered k x k strata (spp a square)
# Every sampler the direct integrator is timed with at equal error (benchmarks/equal_error.py): also Kensler's
# correlated multi-jittered and its low-discrepancy (0,2)-sequence sampler (spp a power of two for both)
ALL_SAMPLERS = SAMPLERS + ("multijitter", "ldsampler")
SEEDS_PER_CALL = 1 << 16  # pass k of a call with seed s renders with seed s * SEEDS_PER_CALL + k


class DirectRenderer:
    """Mitsuba's ``direct`` integrator (its defaults: one emitter and one BSDF sample per sample, MIS) on
    the scene file at ``path``, loaded once. ``width`` x ``height`` (default: the file's film) keeps the
    file's horizontal field of view; ``sampler`` one of ALL_SAMPLERS."""

    def __init__(self, path: Path | str, width: int | None = None, height: int | None = None,
                 sampler: str = "independent"):
        if sampler not in ALL_SAMPLERS:
            raise ValueError(f"sampler '{sampler}': expected one of {', '.join(ALL_SAMPLERS)}")
        mitsuba_variant()
        import mitsuba as mi

        self.mi = mi
        self.scene = mi.load_file(str(path))
        sensor = self.scene.sensors()[0]
        p = mi.traverse(sensor)
        file_w, file_h = (int(v) for v in sensor.film().size())
        self.width, self.height = width or file_w, height or file_h
        self.sampler = sampler

        def scalar(key):
            return float(np.ravel(np.array(p[key]))[0])

        self._sensor = {
            "type": "perspective", "fov_axis": "x", "fov": scalar("x_fov"),
            "near_clip": scalar("near_clip"), "far_clip": scalar("far_clip"),
            "to_world": mi.ScalarTransform4f(np.array(p["to_world"].matrix, np.float64).reshape(4, 4)),
            "film": {"type": "hdrfilm", "width": self.width, "height": self.height, "rfilter": {"type": "box"},
                     "pixel_format": "rgb", "component_format": "float32"}}
        self._sensors = {}  # samples per pass -> sensor
        self.integrator = mi.load_dict({"type": "direct"})

    def sensor(self, spp: int):
        if spp not in self._sensors:
            sampler = {"type": self.sampler, "sample_count": spp}
            if self.sampler in ("stratified", "multijitter"):
                sampler["jitter"] = True
            self._sensors[spp] = self.mi.load_dict({**self._sensor, "sampler": sampler})
        return self._sensors[spp]

    def __call__(self, spp: int, seed: int = 0, samples_per_pass: int | None = None) -> np.ndarray:
        """(height, width, 3) float64 linear RGB at ``spp`` samples per pixel. ``samples_per_pass`` splits
        them into passes of that many, each with its own seed (seed * SEEDS_PER_CALL + k, so that calls
        with different seeds share no pass), averaged: the same estimator in bounded memory (one LLVM
        wavefront holds every sample of a pass)."""
        passes = 1
        if samples_per_pass and samples_per_pass < spp:
            if spp % samples_per_pass:
                raise ValueError(f"spp {spp} is not a multiple of samples_per_pass {samples_per_pass}")
            passes = spp // samples_per_pass
        per_pass = spp // passes
        sensor = self.sensor(per_pass)
        total = np.zeros((self.height, self.width, 3))
        for k in range(passes):
            image = self.mi.render(self.scene, sensor=sensor, integrator=self.integrator, spp=per_pass,
                                   seed=seed * SEEDS_PER_CALL + k)
            total += np.array(image, np.float64)[..., :3]
        return total / passes


def render_direct(path: Path | str, spp: int, seed: int = 0, width: int | None = None, height: int | None = None,
                  samples_per_pass: int | None = None, sampler: str = "independent") -> np.ndarray:
    """One DirectRenderer frame: see DirectRenderer and its __call__."""
    return DirectRenderer(path, width, height, sampler)(spp, seed, samples_per_pass)
