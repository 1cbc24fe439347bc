"""The same scene gives bit-identical images across runs, thread counts and band splits."""

import numpy as np

import warprt
from marks import slow


@slow
def test_bit_identical_across_runs_threads_and_bands():
    scene = warprt.load_scene().with_camera(width=96, height=72).with_render(spp=4)
    first, stats = warprt.render(scene, threads=2)
    assert stats.rays["shadow"] > 0 and stats.rays["reflection"] > 0  # every effect is exercised
    for threads, bands in [(2, None), (1, 1), (1, 7), (3, 5), (2, 96 * 72)]:
        image, s = warprt.render(scene, threads=threads, bands=bands)
        assert np.array_equal(image, first), (threads, bands)
        assert s.rays == stats.rays
