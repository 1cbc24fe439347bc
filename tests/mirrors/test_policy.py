"""reflections="mirrors" takes reflection rays off planar mirrors from their virtual cameras; "auto" traces
them (measured here: the rasters cost about what the queries they replace do, benchmarks/ATTEMPTS.md).
The stats give the chains, the rays decided and their share, and the memory; the flag is checked."""

import warprt
from marks import slow
from shortcuts import ROOT, assert_unknown_choice_refused, command_stats


def test_mirrors_decide_most_reflection_rays_of_the_default_scene():
    stats = warprt.render(warprt.load_scene(), reflections="mirrors").stats
    assert stats.reflections == "mirrors" and stats.variant.endswith("_mreflect")
    assert 0.97 < stats.mirrors["share"] <= 1.0 and stats.mirrors["decided"] <= stats.rays["reflection"]
    assert stats.memory["mirrors"] == stats.mirrors["bytes"] > 0


def test_auto_traces_the_reflection_rays():
    scene = warprt.load_scene().with_camera(width=160, height=120)
    for _ in range(2):
        stats = warprt.render(scene).stats
    assert stats.reflections == "bvh" and stats.mirrors == {} and stats.memory["mirrors"] == 0


def test_a_scene_without_planar_mirrors_traces_its_reflections():
    scene = warprt.load_scene(ROOT / "scenes" / "cornell.toml").with_camera(width=64, height=64)
    stats = warprt.render(scene, reflections="mirrors").stats
    assert stats.reflections == "bvh" and stats.mirrors["chains"] == []


def test_unknown_reflection_query_is_a_scene_error():
    assert_unknown_choice_refused("reflections", "portals")


@slow
def test_the_command_line_flag_and_stats(tmp_path):
    stats = command_stats(tmp_path, "--reflection-rays", "mirrors")
    assert stats["reflections"] == "mirrors" and stats["mirrors"]["decided"] > 0
    assert {"groups", "tiles", "triangles"} <= set(stats["mirrors"]["chains"][0])
