"""`warprt render`: the real command writes a real PNG that reads back as the API's image."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import trimesh

import warprt
from marks import slow
from warprt.image import read_image


SRC = str(Path(__file__).resolve().parents[2] / "src")


def run(*args, cwd=None):
    """The real command, from this checkout's sources whatever is installed."""
    env = {**os.environ, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")}
    return subprocess.run([sys.executable, "-m", "warprt", *args], capture_output=True, text=True, cwd=cwd, env=env)


@slow
def test_render_default_scene_png_matches_api(tmp_path):
    out = tmp_path / "default.png"
    r = run("render", "-o", str(out), "--width", "80", "--height", "60")
    assert r.returncode == 0, r.stderr
    png = read_image(out)
    image, _ = warprt.render(warprt.load_scene().with_camera(width=80, height=60))
    assert png.shape == (60, 80, 3)
    # 8-bit sRGB quantisation: at most half a code value, which is < 0.01 in linear units.
    assert np.abs(png - np.clip(image, 0, 1)).max() < 0.01


@slow
def test_render_without_output_writes_warprt_png(tmp_path):
    r = run("render", "--width", "32", "--height", "24", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert read_image(tmp_path / "warprt.png").shape == (24, 32, 3)


@slow
def test_render_a_bare_mesh_frames_it(tmp_path):
    mesh = trimesh.creation.torus(major_radius=30.0, minor_radius=8.0)
    mesh.apply_translation([100.0, -50.0, 20.0])
    mesh.export(tmp_path / "torus.obj")
    out = tmp_path / "torus.png"
    r = run("render", str(tmp_path / "torus.obj"), "-o", str(out), "--width", "64", "--height", "48")
    assert r.returncode == 0, r.stderr
    image = read_image(out)
    lit = image.max(-1) > 0.02
    # The mesh is in view, centred, and not cut by the frame.
    assert 0.1 < lit.mean() < 0.9
    assert not lit[0].any() and not lit[-1].any() and not lit[:, 0].any() and not lit[:, -1].any()
