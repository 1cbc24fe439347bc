"""The accuracy check can fail: a warprt image with a real error (its shadows left out, a highlight too
wide, a texture upside down, vertex colours left out) is rejected, and the message names a folder with
both images and the difference."""

import re
from pathlib import Path

import numpy as np
import pytest

import warprt
from accuracy import harness

pytestmark = pytest.mark.accuracy

SEED = harness.ROOT / "scenes" / "seed.toml"


def broken_render(monkeypatch, **extra):
    """warprt.render with an error injected: keyword arguments added to every call."""
    original = warprt.render

    def render(scene, **kw):
        if "scene" in extra:
            scene = extra["scene"](scene)
        return original(scene, **{**kw, **{k: v for k, v in extra.items() if k != "scene"}})

    monkeypatch.setattr(warprt, "render", render)


def failure(tmp_path, monkeypatch, case, scene):
    monkeypatch.setattr(harness, "ARTIFACTS", tmp_path)
    with pytest.raises(AssertionError) as info:
        harness.check(case, scene)
    message = str(info.value)
    folder = Path(re.search(r"images \(warprt, Mitsuba, difference\): (.+)$", message).group(1))
    assert folder == tmp_path / case
    for name in ("warprt.npy", "mitsuba.npy", "warprt.png", "mitsuba.png", "difference.npy",
                 "difference_x10.png", "side_by_side.png"):
        assert (folder / name).is_file(), name
    ours, ref = np.load(folder / "warprt.npy"), np.load(folder / "mitsuba.npy")
    assert np.allclose(np.load(folder / "difference.npy"), np.abs(np.clip(ours, 0, 1) - np.clip(ref, 0, 1)))
    return message


def test_missing_shadows_are_caught(tmp_path, monkeypatch):
    broken_render(monkeypatch, disable=["shadows"])
    message = failure(tmp_path, monkeypatch, "no_shadows", harness.small(SEED))
    assert "pixels off" in message


def test_a_small_error_within_the_thresholds_is_caught_pixel_by_pixel(tmp_path, monkeypatch):
    """The orange ball's highlight slightly wide (shininess 80 -> 77): SSIM, PSNR and the share of
    pixels off stay within their thresholds; the float64 trace of each differing pixel does not."""
    from dataclasses import replace

    def wider_highlight(scene):
        mats = dict(scene.materials)
        mats["orange"] = replace(mats["orange"], shininess=77.0)
        return replace(scene, materials=mats)

    broken_render(monkeypatch, scene=wider_highlight)
    message = failure(tmp_path, monkeypatch, "wide_highlight", harness.small(SEED))
    ssim = float(re.search(r"SSIM ([0-9.]+)", message).group(1))
    psnr = float(re.search(r"PSNR ([0-9.]+) dB", message).group(1))
    off = float(re.search(r"pixels off by > 2/255: ([0-9.]+)%", message).group(1)) / 100
    assert ssim >= harness.SSIM_MIN and psnr >= harness.PSNR_MIN and off <= harness.OFF_MAX
    assert "float64 with Mitsuba's offsets" in message


def test_a_texture_read_upside_down_is_caught(tmp_path, monkeypatch):
    """warprt with the globe's image flipped (v read from the wrong edge, the classic uv slip) against
    Mitsuba and the float64 oracle reading it the right way up."""
    from dataclasses import replace

    from warprt.scene import Texture

    def flipped(scene):
        mats = dict(scene.materials)
        t = mats["globe"].kd_texture
        mats["globe"] = replace(mats["globe"], kd_texture=Texture(np.ascontiguousarray(t.image[::-1]), None,
                                                                  t.uv_transform, t.source))
        return replace(scene, materials=mats)

    broken_render(monkeypatch, scene=flipped)
    message = failure(tmp_path, monkeypatch, "texture_flipped", harness.small(harness.ROOT / "scenes" / "textured.toml"))
    assert "(allowed 0.20%)" in message or "float64 with Mitsuba's offsets" in message


def test_vertex_colours_left_out_are_caught(tmp_path, monkeypatch):
    broken_render(monkeypatch, disable=["vertex_color"])
    message = failure(tmp_path, monkeypatch, "no_vertex_colors", harness.small(harness.ROOT / "scenes" / "vertex_colors.toml"))
    assert "(allowed 0.20%)" in message
