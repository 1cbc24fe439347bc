"""reflections="auto" takes the mirrors' virtual cameras on the CPU from the second frame of the same
objects, for the chains whose rasters cost less than their rays' queries; the stats give the chains, the rays decided
and their share, and the memory; the flag is checked."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

import warprt

ROOT = Path(__file__).resolve().parents[2]


def test_auto_takes_the_mirrors_from_the_second_frame_of_the_default_scene_at_its_own_size():
    scene = warprt.load_scene()
    assert warprt.render(scene).stats.reflections == "bvh"
    stats = warprt.render(scene.with_camera(fovy=44.0)).stats
    assert stats.reflections == "mirrors" and stats.variant.endswith("_mreflect")
    assert 0.8 < stats.mirrors["share"] <= 1.0  # measured 0.88: auto leaves chains of few rays to the BVH and stats.mirrors["decided"] <= stats.rays["reflection"]
    assert stats.memory["mirrors"] == stats.mirrors["bytes"] > 0


def test_auto_traces_the_reflections_of_a_mirror_that_shows_more_triangles_than_samples():
    """The knot's floor mirrors 524,288 triangles into a 64x48 frame: rasterizing them would cost more
    than tracing 3,072 samples' reflections."""
    scene = warprt.load_scene(ROOT / "scenes" / "knot.toml").with_camera(width=64, height=48)
    warprt.render(scene)
    stats = warprt.render(scene).stats
    assert stats.reflections == "bvh" and stats.memory["mirrors"] == 0


def test_a_scene_without_planar_mirrors_traces_its_reflections():
    scene = warprt.load_scene(ROOT / "scenes" / "cornell.toml").with_camera(width=64, height=64)
    stats = warprt.render(scene, reflections="mirrors").stats
    assert stats.reflections == "bvh" and stats.mirrors["chains"] == []


def test_unknown_reflection_query_is_a_scene_error():
    with pytest.raises(warprt.SceneError, match="--reflection-rays"):
        warprt.render(warprt.load_scene().with_camera(width=8, height=6), reflections="portals")


def test_the_command_line_flag_and_stats(tmp_path):
    r = subprocess.run([sys.executable, "-m", "warprt", "render", "-o", str(tmp_path / "o.png"), "--width", "64",
                        "--height", "48", "--reflection-rays", "mirrors", "--stats"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    stats = json.loads(r.stdout)
    assert stats["reflections"] == "mirrors" and stats["mirrors"]["decided"] > 0
    assert {"groups", "tiles", "triangles"} <= set(stats["mirrors"]["chains"][0])
