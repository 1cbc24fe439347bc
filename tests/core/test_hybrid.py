"""Hybrid rendering: the first hits rasterized by the Z-buffer, the rest traced. Same model, same
closed forms, same determinism; tests/accuracy holds it to Mitsuba on every scene."""

import numpy as np
import pytest

import warprt
from marks import slow
from warprt.image import raster_is_cheaper
from core.test_shading import wall_scene, wall_terms


def test_hybrid_gives_the_closed_form_phong_terms():
    scene = wall_scene(shadows=False)
    image, stats = warprt.render(scene, primary_query="zbuffer")
    assert stats.primary_query == "zbuffer" and stats.variant.endswith("_zprimary")
    expect = sum(wall_terms(scene).values())
    np.testing.assert_allclose(image, expect, rtol=2e-4, atol=2e-6)


@slow
def test_hybrid_is_bit_identical_across_threads_and_bands():
    scene = warprt.load_scene().with_camera(width=96, height=72).with_render(spp=4)
    first, stats = warprt.render(scene, primary_query="zbuffer", threads=2)
    assert stats.rays["primary"] == 96 * 72 * 4 and stats.rays["reflection"] > 0
    for threads, bands in [(1, 1), (3, 5), (2, 97)]:
        image, s = warprt.render(scene, primary_query="zbuffer", threads=threads, bands=bands)
        assert np.array_equal(image, first) and s.rays == stats.rays


def test_auto_rasterizes_only_where_it_is_cheaper():
    sparse = warprt.load_scene().with_camera(width=320, height=240)   # 5,158 triangles, 76,800 samples
    assert warprt.render(sparse, primary_query="auto").stats.primary_query == "zbuffer"
    dense = warprt.load_scene().with_camera(width=32, height=24)      # more triangles than samples
    assert warprt.render(dense, primary_query="auto").stats.primary_query == "raytrace"
    assert raster_is_cheaper(1000, 10_000) and not raster_is_cheaper(1001, 10_000) and not raster_is_cheaper(0, 10)
    assert not raster_is_cheaper(10, 10_000, device="cuda")


@slow
def test_auto_traces_a_frame_whose_raster_buffers_would_be_large():
    """28 bytes per sample: 1920x1080 at 9 spp (18.7 M samples, 522 MB) still rasterizes, 16 spp (33 M,
    929 MB) is traced; the memory stats count the buffers when they exist."""
    assert raster_is_cheaper(5000, 1920 * 1080 * 9) and not raster_is_cheaper(5000, 1920 * 1080 * 16)
    scene = warprt.load_scene().with_camera(width=320, height=240)
    stats = warprt.render(scene, primary_query="auto").stats
    assert stats.primary_query == "zbuffer" and stats.memory["raster"] == 320 * 240 * 28
    assert warprt.render(scene, primary_query="raytrace").stats.memory["raster"] == 0


def test_unknown_primary_is_a_scene_error():
    with pytest.raises(warprt.SceneError, match=r"render\(\): primary_query: unknown primary query 'photon'"):
        warprt.render(warprt.load_scene().with_camera(width=8, height=6), primary_query="photon")
