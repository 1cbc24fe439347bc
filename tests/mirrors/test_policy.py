"""reflection_query="mirrors" takes reflection rays off planar mirrors from their virtual cameras; "auto" takes
them from a view's second frame, which builds the rasters that the view's next frames reuse
(benchmarks/ATTEMPTS.md). The stats give the chains, the rays decided and their share, and the memory;
the flag is checked."""

import numpy as np

import warprt
import warprt.image
from marks import slow
from shortcuts import ROOT, assert_unknown_choice_refused, command_stats


def test_mirrors_decide_most_reflection_rays_of_the_default_scene():
    stats = warprt.render(warprt.load_scene(), reflection_query="mirrors").stats
    assert stats.reflection_query == "mirrors" and stats.variant.endswith("_mreflect")
    assert 0.97 < stats.mirrors["share"] <= 1.0 and stats.mirrors["decided"] <= stats.rays["reflection"]
    assert stats.memory["mirrors"] == stats.mirrors["bytes"] > 0


def test_auto_takes_the_virtual_cameras_from_a_views_second_frame():
    """The first frame of a view is traced; the second builds the rasters, the third reuses them; every
    frame is the traced image. (At 320x240 the default scene's 5,158 triangles are few enough to rasterize.)"""
    scene = warprt.load_scene().with_camera(width=320, height=240, eye=(0.3, 1.6, 5.2))
    traced = warprt.render(scene, reflection_query="bvh")
    seen, r = [], warprt.Renderer(scene)
    for _ in range(3):
        result = r.render()
        assert np.array_equal(result.image, traced.image) and result.stats.rays == traced.stats.rays
        seen.append((result.stats.reflection_query, result.stats.mirrors.get("rasters")))
    assert seen == [("bvh", None), ("mirrors", "built"), ("mirrors", "reused")]
    assert result.stats.memory["mirrors"] == result.stats.mirrors["bytes"] > 0


def test_auto_traces_a_moving_cameras_reflections():
    """Each view seen once: no frame pays for rasters it would not reuse."""
    scene = warprt.load_scene().with_camera(width=320, height=240)
    r = warprt.Renderer(scene)
    for x in (0.0, 0.1, 0.2, 0.3):
        r.set_scene(scene.with_camera(eye=(x, 1.5, 5.0)))
        stats = r.render().stats
        assert stats.reflection_query == "bvh" and stats.mirrors == {} and stats.memory["mirrors"] == 0


def test_auto_traces_where_rasterizing_is_not_the_cheaper():
    """Below ten samples a triangle (raster_is_cheaper), the rasters would cost more than the queries."""
    scene = warprt.load_scene().with_camera(width=16, height=12)
    assert not warprt.image.raster_is_cheaper(scene.triangle_count, 16 * 12)
    r = warprt.Renderer(scene)
    for _ in range(3):
        assert r.render().stats.reflection_query == "bvh"


def test_a_scene_without_planar_mirrors_traces_its_reflections():
    scene = warprt.load_scene(ROOT / "scenes" / "cornell.toml").with_camera(width=64, height=64)
    stats = warprt.render(scene, reflection_query="mirrors").stats
    assert stats.reflection_query == "bvh" and stats.mirrors["chains"] == []


def test_unknown_reflection_query_is_a_scene_error():
    assert_unknown_choice_refused("reflection_query", "portals")


@slow
def test_the_command_line_flag_and_stats(tmp_path):
    stats = command_stats(tmp_path, "--reflection-query", "mirrors")
    assert stats["reflection_query"] == "mirrors" and stats["mirrors"]["decided"] > 0
    assert {"groups", "tiles", "triangles"} <= set(stats["mirrors"]["chains"][0])
