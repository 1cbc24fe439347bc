"""Image files out, chosen by extension and read back: .exr and .npy hold the linear float image
exactly (values above 1 too), .png holds its sRGB encoding in 8 bits; a failed write leaves nothing."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from marks import slow
from scenekit import write_scene
from warprt.image import read_image, to_srgb8, write_image

SRC = str(Path(__file__).resolve().parents[2] / "src")

# Two squares seen face-on, shown by their ambient term only (C_amb = 2): the left one's pixels are
# 2 * ka, above 1 in red, the right one's are small enough for the sRGB curve's linear segment.
SCENE = {
    "camera": {"eye": [0.0, 0.0, 5.0], "center": [0.0, 0.0, 0.0], "fovy": 60.0, "width": 40, "height": 20},
    "render": {"ambient": [2.0, 2.0, 2.0], "background": [0.25, 0.5, 0.75]},
    "materials": {"hot": {"ka": [0.9, 0.3, 0.05], "kd": [0.0, 0.0, 0.0]},
                  "dim": {"ka": [0.001, 0.0015, 0.2], "kd": [0.0, 0.0, 0.0]}},
    "objects": [{"shape": "plane", "size": [1.0, 1.0], "rotate": [90.0, 0.0, 0.0], "translate": [-1.5, 0.0, 0.0],
                 "material": "hot"},
                {"shape": "plane", "size": [1.0, 1.0], "rotate": [90.0, 0.0, 0.0], "translate": [1.5, 0.0, 0.0],
                 "material": "dim"}],
}


def srgb8(linear):
    """IEC 61966-2-1, written out here: the test's own encoder."""
    x = np.clip(np.asarray(linear, np.float64), 0.0, 1.0)
    y = np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)
    return np.round(y * 255.0).astype(np.int64)


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("images")
    write_scene(folder, SCENE, "s.toml")
    env = {**os.environ, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")}
    for ext in ("npy", "exr", "png"):
        r = subprocess.run([sys.executable, "-m", "warprt", "render", "s.toml", "-o", f"out.{ext}", "-q"],
                           cwd=folder, env=env, capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        assert r.stderr == ""  # -q
    return folder


@slow
def test_npy_is_the_linear_image(outputs):
    image = np.load(outputs / "out.npy")
    assert image.dtype == np.float32 and image.shape == (20, 40, 3)
    # Closed form: a square's pixel is C_amb * ka; a pixel off the squares is the background.
    # The squares' centres, x = -1.5 and 1.5 on a plane 2 * 5 tan(30 deg) * 2 wide, fall in columns 14.8 and 25.2.
    np.testing.assert_allclose(image[10, 15], [1.8, 0.6, 0.1], rtol=1e-6)
    np.testing.assert_allclose(image[10, 25], [0.002, 0.003, 0.4], rtol=1e-6)
    np.testing.assert_allclose(image[0, 0], [0.25, 0.5, 0.75], rtol=1e-6)


@slow
def test_exr_is_linear_float_and_exact(outputs):
    import OpenEXR

    with OpenEXR.File(str(outputs / "out.exr")) as f:
        # The File's dicts are emptied when it closes: read everything inside.
        (x0, y0), (x1, y1) = f.header()["dataWindow"]
        channels = f.channels()
        rgb = np.array(channels["RGB"].pixels if "RGB" in channels else
                       np.stack([channels[c].pixels for c in "RGB"], -1))
    assert rgb.dtype == np.float32  # full float, not half
    assert (x1 - x0 + 1, y1 - y0 + 1) == (40, 20)
    np.testing.assert_array_equal(rgb, np.load(outputs / "out.npy"))
    assert rgb[10, 15, 0] == pytest.approx(1.8)  # above 1: not clamped
    np.testing.assert_array_equal(read_image(outputs / "out.exr"), rgb)


@slow
def test_png_is_srgb_8bit(outputs):
    from PIL import Image

    png = Image.open(outputs / "out.png")
    assert png.mode == "RGB" and png.size == (40, 20)
    np.testing.assert_array_equal(np.asarray(png, np.int64), srgb8(np.load(outputs / "out.npy")))


@pytest.mark.parametrize("height,width", [(1, 1), (7, 37), (64, 300)])
def test_png_decodes_to_the_formula_for_noise_at_any_size(tmp_path, height, width):
    """Noise over the whole range (every neighbour difference wraps somewhere), out-of-range values,
    odd sizes: PIL's decoder reads back the test's own sRGB encoding of the image, byte for byte."""
    from PIL import Image

    rng = np.random.default_rng(height * width)
    image = rng.uniform(-0.1, 1.1, (height, width, 3)).astype(np.float32)
    write_image(tmp_path / "n.png", image)
    png = Image.open(tmp_path / "n.png")
    assert png.mode == "RGB" and png.size == (width, height)
    np.testing.assert_array_equal(np.asarray(png, np.int64), srgb8(image))


def test_failed_write_leaves_no_file(tmp_path):
    """An image the encoder rejects: no output and no temporary file remain."""
    with pytest.raises(Exception):
        write_image(tmp_path / "bad.png", np.zeros((4, 4, 5), np.float32))
    with pytest.raises(Exception):
        write_image(tmp_path / "bad.exr", np.zeros((4, 4), np.float32))
    assert list(tmp_path.iterdir()) == []


def test_written_image_has_the_usual_mode(tmp_path):
    write_image(tmp_path / "a.png", np.zeros((2, 2, 3), np.float32))
    umask = os.umask(0)
    os.umask(umask)
    assert (tmp_path / "a.png").stat().st_mode & 0o777 == 0o666 & ~umask


def test_srgb8_of_float32_is_the_formula_at_every_step():
    """to_srgb8 reads a float32 image through tables (the code per run of 2^16 float32 values, and
    where the next code starts): it must give the float64 formula's code at every value where a
    code could change (each run's ends, each step and the value before it) and elsewhere."""
    runs = np.concatenate([np.arange(0x3F81, dtype=np.uint32) << 16, (np.arange(0x3F80, dtype=np.uint32) << 16) + 0xFFFF])
    x = runs.view(np.float32)  # the first and last float32 of every run in [0, 1]
    rng = np.random.default_rng(3)
    values = np.concatenate([x, rng.uniform(-0.5, 1.5, 200_000).astype(np.float32),
                             (10.0 ** rng.uniform(-10, 0, 200_000)).astype(np.float32)])
    np.testing.assert_array_equal(to_srgb8(values).astype(np.int64), srgb8(values))
    # the values where a code starts, and their predecessors, by bisection between run starts
    ends = np.nonzero(np.diff(srgb8(x[: 0x3F81])))[0]
    lo, hi = runs[ends], runs[ends + 1]
    while np.any(hi - lo > 1):
        mid = lo + (hi - lo) // 2
        up = srgb8(mid.view(np.float32)) > srgb8(lo.view(np.float32))
        hi, lo = np.where(up, mid, hi), np.where(up, lo, mid)
    edges = np.concatenate([lo, hi]).view(np.float32)
    np.testing.assert_array_equal(to_srgb8(edges).astype(np.int64), srgb8(edges))
