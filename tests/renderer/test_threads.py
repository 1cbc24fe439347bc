"""The threads a frame's bands run on belong to a Renderer: kept from frame to frame, stopped by close()
(or the end of a with block), and render() leaves none behind. No pool lives in module state."""

import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
import warp as wp
import warp._src.context as warp_context

import warprt
from bands import BandCounter
from warprt.image import launch_bands


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


# --- Band threads only launch: the module is loaded before the bands start ----------------------------

@wp.kernel
def _fill(first: int, out: wp.array(dtype=int)):
    out[wp.tid() + first] = wp.tid() + first


def _loading_threads(monkeypatch, launch) -> set[str]:
    """The names of the threads on which Warp loaded _fill's module while ``launch`` ran (a module with
    no executable loaded on the CPU at the start)."""
    _fill.module.unload()
    loaders, real = set(), warp_context.Module.load

    def load(module, device, *args, **kwargs):
        if module is _fill.module and not module.execs:
            loaders.add(threading.current_thread().name)
        return real(module, device, *args, **kwargs)

    monkeypatch.setattr(warp_context.Module, "load", load)
    launch()
    return loaders


def test_band_threads_launch_a_module_already_loaded(monkeypatch):
    """launch_bands loads the kernel's module on the calling thread: two bands starting at once would
    both load it, and one load replaces the module the other band runs (a CI worker's segfault)."""
    out = wp.zeros(64, dtype=int, device="cpu")
    loaders = _loading_threads(monkeypatch, lambda: launch_bands(_fill, lambda first: [first, out], 64, 2, 16, "cpu"))
    assert loaders == {threading.current_thread().name}
    assert np.array_equal(out.numpy(), np.arange(64))
    # The control: the same bands launched on a plain pool load the module on the band threads.
    with ThreadPoolExecutor(2, thread_name_prefix="band") as pool:
        plain = lambda: list(pool.map(lambda f: wp.launch(_fill, dim=8, inputs=[f, out], device="cpu"), range(0, 64, 8)))
        loaders = _loading_threads(monkeypatch, plain)
    assert loaders and all(name.startswith("band") for name in loaders)


def test_a_ctrl_c_while_a_band_thread_starts_leaves_no_band_running(monkeypatch):
    """ThreadPoolExecutor records a thread it starts only after Thread.start() returns; a KeyboardInterrupt
    there (start() waits for the new thread: a Ctrl-C can land in it) used to leave a thread shutdown() did
    not join, taking the frame's bands after render() had raised (CI's segfault). Band threads now all start
    with the pool, before any band is queued: the interrupt lands there, no band runs, no thread stays."""
    import time

    real_start, fired = threading.Thread.start, []

    def start(thread):
        real_start(thread)
        if thread.name.startswith("warprt") and not fired:
            fired.append(thread.name)
            raise KeyboardInterrupt

    # Two long bands (about 0.2 s each): one left running would finish after render() has raised.
    scene = warprt.load_scene().with_camera(width=320, height=240).with_render(spp=16)
    warprt.render(scene.with_camera(width=8, height=6), threads=1)  # kernels loaded, outside the patch
    monkeypatch.setattr(threading.Thread, "start", start)
    progress = BandCounter()
    with pytest.raises(KeyboardInterrupt):
        warprt.render(scene, threads=2, bands=2, progress=progress, primary_query="raytrace", shadow_query="bvh")
    at_raise = progress.done
    time.sleep(1.0)
    assert fired and progress.done == at_raise
    deadline = time.monotonic() + 5.0
    while time.monotonic() < deadline and any(t.name.startswith("warprt") for t in threading.enumerate()):
        time.sleep(0.01)
    assert not any(t.name.startswith("warprt") for t in threading.enumerate())
