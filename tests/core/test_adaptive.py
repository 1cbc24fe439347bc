"""render.adaptive = t: Whitted's adaptive supersampling (image/adaptive.py). Checked: the image is, to the bit,
the render.spp frame's colour in the pixels refined_pixels picks from the pixel-centre frame and the centre frame's
elsewhere (both rendered plainly here), its ray counts those two frames' share; every pixel a straight edge
crosses (where the spp frame differs from the centres': partial coverage of a flat, ambient-lit quad over black)
is refined, and the control, a threshold above the quad's contrast, refines none and leaves those pixels wrong;
the same image on any number of threads and bands; a gradient frame refused in one line; a bad value named."""

from pathlib import Path

import numpy as np
import pytest

import warprt

SCENES = Path(__file__).resolve().parents[2] / "scenes"


def _frames(scene, t: float, **options):
    """(adaptive, spp, centres) RenderResults of ``scene`` (its render.spp > 1)."""
    out = []
    for s in (scene.with_render(adaptive=t), scene, scene.with_render(spp=1)):
        with warprt.Renderer(s, **options) as r:
            out.append(r.render())
    return out


def test_refined_pixels_are_the_spp_frames_and_the_rest_the_centres():
    scene = warprt.load_scene().with_camera(width=64, height=48).with_render(spp=16)
    adaptive, full, centres = _frames(scene, 0.01)
    picked = warprt.image.refined_pixels(centres.image, 0.01)
    assert 0.02 < len(picked) / (64 * 48) < 0.6  # a part of the image, not none or all
    expected = centres.image.reshape(-1, 3).copy()
    expected[picked] = full.image.reshape(-1, 3)[picked]
    assert np.array_equal(adaptive.image, expected.reshape(adaptive.image.shape))
    assert adaptive.stats.adaptive["refined"] == len(picked) and adaptive.stats.spp == 16
    assert adaptive.stats.rays["primary"] == 64 * 48 + 16 * len(picked)
    assert adaptive.stats.rays["primary"] < 0.7 * full.stats.rays["primary"]


def _quad_scene(spp: int = 16):
    """A flat quad lit by the ambient term alone (its colour a constant 0.3) over a black background: the spp
    frame differs from the centres' exactly where the quad's outline crosses a pixel."""
    return warprt.load_dict({
        "camera": {"eye": [0.0, 0.0, 4.0], "center": [0.0, 0.0, 0.0], "fovy": 40.0, "width": 40, "height": 30},
        "render": {"ambient": [1.0, 1.0, 1.0], "background": [0.0, 0.0, 0.0], "spp": spp, "shadows": False},
        "materials": {"flat": {"ka": [0.3, 0.3, 0.3], "kd": [0.0, 0.0, 0.0], "ks": [0.0, 0.0, 0.0]}},
        "objects": [{"shape": "triangles", "vertices": [[-0.9, -0.6, 0.0], [1.1, -0.8, 0.0], [0.8, 0.9, 0.0],
                                                        [-1.0, 0.7, 0.0]], "faces": [[0, 1, 2], [0, 2, 3]],
                     "material": "flat"}]})


@pytest.mark.parametrize("t, refines", [(0.01, True), (0.5, False)], ids=["below the contrast", "control: above"])
def test_every_pixel_an_edge_crosses_is_refined(t, refines):
    adaptive, full, centres = _frames(_quad_scene(), t)
    crossed = np.abs(full.image - centres.image).max(axis=2) > 0
    assert crossed.sum() > 40  # the outline's pixels
    right = np.abs(adaptive.image - full.image).max(axis=2) == 0
    assert right[crossed].all() == refines
    if not refines:
        assert adaptive.stats.adaptive["refined"] == 0 and np.array_equal(adaptive.image, centres.image)


def test_the_same_image_on_any_threads_and_bands():
    scene = warprt.load_scene().with_camera(width=48, height=36).with_render(spp=4, adaptive=0.02)
    images = []
    for threads, bands in [(1, 1), (2, None), (2, 7)]:
        with warprt.Renderer(scene, threads=threads, bands=bands) as r:
            images.append(r.render().image)
    assert all(np.array_equal(images[0], im) for im in images[1:])


def test_a_gradient_frame_and_bad_values_are_refused_in_one_line():
    scene = warprt.load_scene().with_camera(width=16, height=12).with_render(spp=4, adaptive=0.01)
    with warprt.Renderer(scene) as r, pytest.raises(warprt.SceneError, match="render.adaptive"):  # an ArgumentError
        r.render(grad=True)
    with warprt.Renderer(scene.with_render(adaptive=0.0)) as r:  # off: a gradient frame as before
        r.render(grad=True)
    for bad in (-0.1, float("nan"), "x"):
        with pytest.raises(warprt.SceneError, match="render.adaptive"):
            warprt.Renderer(scene.with_render(adaptive=bad))


@pytest.mark.parametrize("file, estimator", [("cornell_box.xml", "analytic"), ("envmap.xml", "samples")])
def test_spread_lights_refine_as_the_spp_frame_spreads_them(file, estimator):
    """With render.light_spread (each pixel sample its own share of an area light's points, or of an environment's
    directions) the refined pixels are still the spp frame's to the bit: the pixel kernel reads the frame's spread
    table, not the centre frame's (whose one sample takes every point)."""
    scene = warprt.load_scene(SCENES / file).with_camera(width=40, height=40).with_render(
        spp=4, light_samples=16, light_spread=True, area_estimator=estimator)
    adaptive, full, centres = _frames(scene, 0.01)
    picked = warprt.image.refined_pixels(centres.image, 0.01)
    assert len(picked) > 40
    expected = centres.image.reshape(-1, 3).copy()
    expected[picked] = full.image.reshape(-1, 3)[picked]
    assert np.array_equal(adaptive.image, expected.reshape(adaptive.image.shape))
    with pytest.raises(warprt.SceneError, match="render.light_spread"):  # fewer points than samples: refused
        warprt.Renderer(scene.with_render(spp=16, light_samples=4))
