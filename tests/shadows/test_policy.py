"""shadows="auto" takes the light-space grid where it is the cheaper: at once where its build costs less
than the frame saves, otherwise once the frames with those lights have paid for it, and from then on;
the grid is kept with the geometry, its memory counted in the stats, and the flag is checked."""

import json
import subprocess
import sys

import pytest

import warprt
from warprt.geometry import Geometry
from warprt.image import shadows_from_grid
from warprt.scene import resolve_effects


def test_auto_takes_the_grid_for_the_default_scene_at_its_own_size():
    stats = warprt.render(warprt.load_scene()).stats
    assert stats.shadows == "grid" and "_gshadow" in stats.variant
    assert stats.memory["shadow_grid"] == stats.shadow_grid["bytes"] > 0


def test_a_grid_too_dear_for_one_frame_is_built_once_frames_have_paid_for_it():
    """20,518 triangles and 2 lights in a 160x120 frame: the build (estimated 52 ms) is worth some 20
    frames of the shadow rays it saves (2.5 ms each); the policy counts the frames with these lights."""
    scene = warprt.load_scene(None, {"objects[1].subdivisions": 5}).with_camera(width=160, height=120)
    geom, fx = Geometry(scene), resolve_effects(scene)
    choices = [shadows_from_grid("auto", geom, scene, fx, 160 * 120, 2, "cpu") for _ in range(40)]
    assert 10 < choices.index(True) < 30
    assert not choices[0] and choices[-1]
    first = choices.index(True)
    assert all(choices[first:])
    assert not shadows_from_grid("auto", geom, scene, fx, 160 * 120, 2, "cuda")
    assert shadows_from_grid("grid", geom, scene, fx, 160 * 120, 2, "cuda")
    assert not shadows_from_grid("bvh", geom, scene, fx, 10**9, 2, "cpu")


def test_the_grid_is_kept_for_the_next_frame_with_the_same_lights():
    scene = warprt.load_scene().with_camera(width=64, height=48)
    first = warprt.render(scene, shadows="grid").stats.shadow_grid
    again = warprt.render(scene.with_camera(fovy=30.0), shadows="grid").stats.shadow_grid
    assert again["grid"] == "reused" and again["entries"] == first["entries"]


def test_a_scene_without_shadow_rays_builds_no_grid():
    scene = warprt.load_scene().with_camera(width=64, height=48).with_render(shadows=False)
    stats = warprt.render(scene, shadows="grid").stats
    assert stats.shadows == "bvh" and stats.shadow_grid == {} and stats.memory["shadow_grid"] == 0


def test_unknown_shadow_query_is_a_scene_error():
    with pytest.raises(warprt.SceneError, match="--shadow-rays"):
        warprt.render(warprt.load_scene().with_camera(width=8, height=6), shadows="photons")


def test_the_command_line_flag_and_stats(tmp_path):
    r = subprocess.run([sys.executable, "-m", "warprt", "render", "-o", str(tmp_path / "o.png"), "--width", "64",
                        "--height", "48", "--shadow-rays", "grid", "--stats"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    stats = json.loads(r.stdout)
    assert stats["shadows"] == "grid" and stats["shadow_grid"]["lights_on_grid"] == 2
    assert stats["shadow_grid"]["cells"] == 256 and stats["memory"]["shadow_grid"] > 0
