"""`warprt render --algorithm zbuffer`: the real command writes the API's Z-buffer image."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import warprt
from marks import slow
from warprt.image import read_image

SRC = str(Path(__file__).resolve().parents[2] / "src")


def run(*args):
    """The real command, from this checkout's sources whatever is installed."""
    env = {**os.environ, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")}
    return subprocess.run([sys.executable, "-m", "warprt", *args], capture_output=True, text=True, env=env)


@slow
def test_render_zbuffer_npy_matches_api(tmp_path):
    out, stats_file = tmp_path / "zb.npy", tmp_path / "stats.json"
    r = run("render", "--algorithm", "zbuffer", "-o", str(out), "--width", "80", "--height", "60",
            "--stats-file", str(stats_file))
    assert r.returncode == 0, r.stderr
    assert "triangles rasterized" in r.stderr
    image, _ = warprt.render(warprt.load_scene().with_camera(width=80, height=60), algorithm="zbuffer")
    assert np.array_equal(read_image(out), image)
    stats = json.loads(stats_file.read_text())
    assert stats["algorithm"] == "zbuffer" and stats["rays"]["total"] == 0
    assert "shadows" not in stats["effects"].split(",") and "reflection" not in stats["effects"].split(",")


def test_unknown_algorithm_exits_2_without_output(tmp_path):
    r = run("render", "--algorithm", "scanline", "-o", str(tmp_path / "x.png"))
    assert r.returncode == 2
    assert "invalid choice: 'scanline'" in r.stderr
    assert not (tmp_path / "x.png").exists()


def test_unknown_algorithm_in_the_api_names_the_option():
    with pytest.raises(warprt.SceneError, match=r"render\(\): algorithm: unknown algorithm"):
        warprt.render(warprt.load_scene(), algorithm="scanline")
