"""`warprt compare SCENE`: the numbers it prints are the metrics of the two renders, and its image is
warprt | Mitsuba | |difference| x 10; bad input is one line and exit status 2."""

import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from skimage.metrics import peak_signal_noise_ratio, structural_similarity

import warprt
from reference.mitsuba_whitted import render_mitsuba
from warprt.cli import main
from warprt.image import to_srgb8

pytestmark = pytest.mark.accuracy

SEED = Path(__file__).resolve().parents[2] / "scenes" / "seed.toml"
SIZE = {"camera.width": 48, "camera.height": 36}


def run(capsys, *argv):
    code = main(["compare", *map(str, argv)])
    out, err = capsys.readouterr()
    return code, out, err


def test_prints_the_metrics_of_the_two_renders_and_writes_the_strip(tmp_path, capsys):
    out_png = tmp_path / "cmp.png"
    code, out, err = run(capsys, SEED, "--width", 48, "--height", 36, "-o", out_png)
    assert code == 0, err
    scene = warprt.load_scene(SEED, SIZE)
    ours = np.clip(warprt.render(scene).image, 0, 1).astype(np.float64)
    ref = np.clip(render_mitsuba(scene), 0, 1).astype(np.float64)
    ssim = structural_similarity(ours, ref, data_range=1.0, channel_axis=-1)
    printed_ssim = float(re.search(r"SSIM\s+([0-9.]+)", out).group(1))
    assert abs(printed_ssim - ssim) < 1e-6
    if np.any(ours != ref):
        printed_psnr = float(re.search(r"PSNR\s+([0-9.]+) dB", out).group(1))
        assert abs(printed_psnr - peak_signal_noise_ratio(ours, ref, data_range=1.0)) < 0.01
    off = (np.abs(ours - ref) > 2 / 255).any(-1)
    assert f"({int(off.sum())} of {off.size})" in out

    strip = np.asarray(Image.open(out_png).convert("RGB"))
    h, w = ours.shape[:2]
    gap = (strip.shape[1] - 3 * w) // 2
    assert strip.shape == (h, 3 * w + 2 * gap, 3) and gap > 0
    panels = [strip[:, i * (w + gap): i * (w + gap) + w] for i in range(3)]
    assert np.array_equal(panels[0], to_srgb8(ours))
    assert np.array_equal(panels[1], to_srgb8(ref))
    assert np.array_equal(panels[2], to_srgb8(np.clip(np.abs(ours - ref) * 10, 0, 1)))


def test_effects_apply_to_both_renderers(tmp_path, capsys):
    code, out, err = run(capsys, SEED, "--width", 48, "--height", 36, "--effects", "ambient", "-o", tmp_path / "a.png")
    assert code == 0, err
    assert "effects ambient" in out
    # Ambient only: both images are C_amb ka on hits and the background on misses, so they agree exactly.
    assert float(re.search(r"SSIM\s+([0-9.]+)", out).group(1)) == 1.0


def test_missing_scene_is_one_line_and_exit_2(tmp_path, capsys):
    out_png = tmp_path / "cmp.png"
    code, out, err = run(capsys, tmp_path / "missing.toml", "-o", out_png)
    assert code == 2
    assert err.count("\n") == 1 and "missing.toml" in err and "not found" in err
    assert not out_png.exists()


def test_bad_output_extension_fails_before_rendering(tmp_path, capsys):
    code, out, err = run(capsys, SEED, "-o", tmp_path / "cmp.txt")
    assert code == 2 and err.count("\n") == 1 and ".txt" in err
    assert out == "" and not any(tmp_path.iterdir())
