"""The cold benchmark's mesh scene compares like with like: Mitsuba's own ply and obj plugins read as many
triangles as warprt does, and the benchmark's Mitsuba script renders the image warprt renders."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import warprt
from benchmarks.cold import MITSUBA_FILES, write_mesh_scene
from reference.mitsuba_whitted import mitsuba
from warprt.image import read_image

REPO = Path(__file__).resolve().parents[2]
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO / "src"), str(REPO), os.environ.get("PYTHONPATH", "")])}
# Everything but the terrain's vertex colours, which the benchmark's Mitsuba integrator does not read.
EFFECTS = "ambient,diffuse,specular,shadows,reflection,smooth"


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory):
    return write_mesh_scene(tmp_path_factory.mktemp("meshes"), width=128, height=96)


def test_mitsubas_plugins_read_the_triangles_warprt_reads(scene_file):
    mi, _ = mitsuba()
    files = sorted(p for p in scene_file.parent.iterdir() if p.suffix in (".ply", ".obj"))
    assert len(files) == 5
    theirs = sum(mi.load_dict({"type": p.suffix[1:], "filename": str(p)}).face_count() for p in files)
    ours = warprt.load_scene(scene_file).triangle_count
    assert theirs == ours == 92_672


def _warprt_image(scene: Path, out: Path) -> np.ndarray:
    r = subprocess.run([sys.executable, "-m", "warprt", "render", str(scene), "-o", str(out), "-q", "--effects", EFFECTS],
                       env=ENV, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return read_image(out)


def _share_off(a: np.ndarray, b: np.ndarray) -> float:
    """The share of pixels more than 8 of 255 apart in some channel (sRGB)."""
    return float((np.abs(a - b).max(-1) > 8 / 255).mean())


def test_the_mitsuba_script_renders_the_image_warprt_renders(scene_file, tmp_path):
    r = subprocess.run([sys.executable, "-c", MITSUBA_FILES, str(scene_file), str(tmp_path / "m.png")], env=ENV,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    theirs = read_image(tmp_path / "m.png")
    assert _share_off(_warprt_image(scene_file, tmp_path / "w.png"), theirs) < 0.01
    # The negative control: the knot turned by 30 degrees more is another image by this measure.
    turned = tmp_path / "turned.toml"
    turned.write_text(scene_file.read_text().replace("rotate = [20.0, 0.0, 0.0]", "rotate = [50.0, 0.0, 0.0]")
                      .replace('mesh = "', f'mesh = "{scene_file.parent}/'))
    assert _share_off(_warprt_image(turned, tmp_path / "t.png"), theirs) > 0.01
