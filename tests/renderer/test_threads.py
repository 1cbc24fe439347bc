"""The threads a frame's bands run on belong to a Renderer: kept from frame to frame, stopped by close()
(or the end of a with block), and render() leaves none behind. No pool lives in module state."""

import threading

import numpy as np

import warprt


def band_threads() -> set[int]:
    return {t.ident for t in threading.enumerate() if t.name.startswith("warprt")}


def small():
    return warprt.load_scene().with_camera(width=48, height=36)


def test_render_leaves_no_band_threads_behind():
    before = band_threads()
    warprt.render(small(), threads=2)
    assert band_threads() == before


def test_a_renderers_frames_share_its_threads_until_close():
    before = band_threads()
    r = warprt.Renderer(small(), threads=2)
    first = r.render().image
    mine = band_threads() - before
    assert len(mine) == 2  # two threads, started by the first frame
    again = r.render().image
    assert band_threads() - before == mine and np.array_equal(first, again)
    r.close()
    assert band_threads() == before
    # a frame after close() starts threads again and renders the same image
    assert np.array_equal(r.render().image, first)
    assert len(band_threads() - before) == 2
    r.close()


def test_a_with_block_closes_and_one_thread_starts_none():
    before = band_threads()
    with warprt.Renderer(small(), threads=2) as r:
        r.render()
        assert len(band_threads() - before) == 2
    assert band_threads() == before
    with warprt.Renderer(small(), threads=1) as r:
        r.render()
        assert band_threads() == before
