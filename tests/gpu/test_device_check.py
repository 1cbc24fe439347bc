"""make device-check: on a machine without CUDA it says so and succeeds; its comparison holds a device's
image to the CPU's within the stated tolerance and no further; on the CPU it runs end to end."""

import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from benchmarks import device_check
from benchmarks.device_check import MAX_DIFFERING, PIXEL_TOLERANCE, compare, cuda_count

ROOT = Path(__file__).resolve().parents[2]


def result(image, rays=1000):
    return SimpleNamespace(image=image, stats=SimpleNamespace(rays={"total": rays}))


def cpu_image(shape=(100, 100, 3)):
    return np.random.default_rng(7).random(shape, dtype=np.float32)


def test_without_cuda_make_device_check_says_so_and_succeeds():
    if cuda_count():
        pytest.skip("a CUDA device is here: make device-check would run the whole check")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), str(ROOT)])}
    run = subprocess.run(["make", "-s", "device-check", f"PYTHON={sys.executable}"], cwd=ROOT, env=env,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "no CUDA device: nothing to check"


def test_low_bit_differences_everywhere_agree():
    a = cpu_image()
    assert compare("c", result(a), result(a + PIXEL_TOLERANCE / 2)).ok


def test_a_few_flipped_edge_pixels_agree():
    a, b = cpu_image(), cpu_image().copy()
    b.reshape(-1, 3)[: int(MAX_DIFFERING * 100 * 100)] += 0.5  # ten of 10,000 pixels: a hit gone the other way
    c = compare("c", result(a), result(b))
    assert c.ok and c.max_abs == pytest.approx(0.5)


def test_more_differing_pixels_than_the_tolerance_fail():
    """The negative control: the share over MAX_DIFFERING, far off in value, so that SSIM cannot pass it either."""
    a, b = cpu_image(), cpu_image().copy()
    b[:5] = 1.0 - b[:5]  # five rows of 100: 5% of the pixels
    c = compare("c", result(a), result(b))
    assert not c.ok and c.differing > 0.04 and "FAIL" in str(c)


def test_a_nan_on_the_device_fails():
    a, b = cpu_image(), cpu_image().copy()
    b[: 50] = np.nan
    c = compare("c", result(a), result(b))
    assert not c.ok and c.max_abs == np.inf


def test_a_different_ray_count_fails():
    a = cpu_image()
    assert not compare("c", result(a, rays=1000), result(a, rays=1010)).ok


def test_on_the_cpu_the_check_runs_every_path_and_agrees(capsys):
    assert device_check.main(["--device", "cpu", "--quick", "--only", "seed"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len([ln for ln in lines if ln.endswith("  ok")]) == len(device_check.PATHS)
    assert lines[-1].startswith(f"{len(device_check.PATHS)} images on cpu against the CPU")


def test_a_device_that_cannot_render_fails_each_case_with_its_error(capsys):
    results = device_check.check("cuda:7", quick=True, only={"seed"})
    assert len(results) == len(device_check.PATHS) and not any(r.ok for r in results)
    assert all("cuda:7: ValueError" in r.error for r in results)
