"""What the exact shortcuts' suites share (shadows, mirrors, zbuffer, geometry): every scene at a
small size, a shortcut's render held to the traced one, the command's stats, and the probes' cameras."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import warprt
from marks import quick_cases
from warprt.kernels import CameraData, camera_data, camera_ray, sample_offset, wp
from warprt.scene import camera_basis, resolve_effects

ROOT = Path(__file__).resolve().parents[1]
SCENES = [None] + sorted((ROOT / "scenes").glob("*.toml"))  # None: the default scene
IDS = ["default"] + [p.stem for p in SCENES[1:]]
SCENE_CASES = quick_cases(SCENES, {"cornell", "tilted"}, IDS)  # the quick loop's two cheap scenes
SEEDS = quick_cases(range(12), {0, 2})  # random scenes (accuracy.test_random_scenes): two in the quick loop


def at_width(scene, width: int):
    """``scene`` ``width`` pixels across, its aspect kept, at least 8 pixels high."""
    return scene.with_camera(width=width, height=max(8, round(width * scene.camera.height / scene.camera.width)))


def same_as_traced(scene, option: str, shortcut: str, **choices):
    """render(scene) with ``option`` = "bvh" and with ``option`` = ``shortcut`` (``choices`` for both):
    the two results, once the shortcut's image is the traced image to the bit with the same ray counts."""
    traced = warprt.render(scene, **{option: "bvh"}, **choices)
    fast = warprt.render(scene, **{option: shortcut}, **choices)
    assert np.array_equal(fast.image, traced.image) and fast.stats.rays == traced.stats.rays
    return traced, fast


def assert_unknown_choice_refused(option: str, value: str):
    """render(``option``=``value``) for a value render() does not know: a SceneError naming the argument."""
    with pytest.raises(warprt.SceneError, match=rf"render\(\): {option}: unknown"):
        warprt.render(warprt.load_scene().with_camera(width=8, height=6), **{option: value})


def command_stats(tmp_path, *flags) -> dict:
    """The statistics `warprt render` prints for the default scene at 64x48 with ``flags``, in a process of its own."""
    r = subprocess.run([sys.executable, "-m", "warprt", "render", "-o", str(tmp_path / "o.png"), "--width", "64",
                        "--height", "48", *flags, "--stats"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def probe_camera(scene, geom):
    """The camera a probe kernel spawns its rays from, as render() makes it for ``geom``'s frame origin."""
    return camera_data(camera_basis(scene.camera), geom.eye_offset(scene.camera.eye))


@wp.func
def probe_ray(c: CameraData, x: int, row: int, sample: int, samples: int, k: int):
    """The direction of a pixel's sample as the tracer takes it: the centre without supersampling."""
    offset = wp.vec2(0.5, 0.5)
    if samples > 1:
        offset = sample_offset(sample, k)
    return camera_ray(c, x, row, offset[0], offset[1])


def probe_samples(scene) -> tuple[int, int]:
    """(k, samples per pixel) as the tracer takes them: k*k with supersampling, else the pixel centre."""
    k = math.isqrt(scene.render.spp)
    return k, k * k if resolve_effects(scene).supersampling else 1
