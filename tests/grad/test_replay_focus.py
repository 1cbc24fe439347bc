"""backward() replays only the ray trees a gradient can come from (image/grad.py replay_focus): never a pixel whose
adjoint is 0, and where every name is an object's (its vertices, pose, vertex colours) only the camera rays whose
tree meets that object's faces; the trees kept are replayed as before, in the same order.

Checked: backward()'s gradient the same to the bit as that of the replay of every tree (backward() with a
material's name beside, and the replay launched by hand), on the mirror scene
(tests/grad/test_vertex_gradients.py's: the crate seen directly and in the tilted floor, three ray levels) and the
glass sphere (test_glass_gradients.py's, the ball's own faces through its tree of five levels), for the vertices
and the pose, and with an adjoint of 0 over half the image for a material's colour; each check
keeps a real part of the trees only (what it keeps is asserted, so the equality is not that of two whole replays).
The control: a focus made from the camera rays' own hits alone (level 0) loses the crate seen in the mirror, and
its gradient is off.
"""

from __future__ import annotations

import numpy as np
import pytest
import warp as wp

import warprt
from warprt.scene import resolve_effects

from .test_glass_gradients import sphere
from .test_vertex_gradients import HEIGHT, WIDTH, mirror_scene


def _frame(s):
    r = warprt.Renderer(s)
    r.render(grad=True)
    geom = r.geometry
    hits = warprt.image.record_first_hits(s, geom, geom.scene_data(s), resolve_effects(s), "cpu")
    return r, geom, hits


def _by_hand(s, geom, hits, d, key: str, focus=None, **kinds) -> np.ndarray:
    """The replay's adjoint of its array ``key`` (points, colors, kd...) launched by hand over the trees ``focus``
    keeps (None: every tree)."""
    replay = warprt.image.build_replay(s, geom, hits, "cpu", **kinds)
    replay.focus = focus
    tape = wp.Tape()
    with tape:
        replay.launch()
    d_rays = np.repeat(d.reshape(-1, 3), hits.samples, axis=0) / np.float32(hits.samples)
    tape.backward(grads={replay.colour: wp.array(d_rays, dtype=wp.vec3)})
    out = replay.arrays[key].grad.numpy().astype(np.float64)
    tape.zero()
    return out


def _rows(s, name: str) -> slice:
    i = [o.name for o in s.objects].index(name)
    starts = np.cumsum([0] + [len(o.vertices) for o in s.objects])
    return slice(starts[i], starts[i + 1])


CASES = {"crate": (mirror_scene, "crate"), "glass": (lambda: sphere(max_depth=5), None)}


@pytest.mark.parametrize("case", list(CASES))
def test_an_objects_gradient_replays_only_the_trees_that_meet_it(case):
    make, name = CASES[case]
    s = make()
    name = name or s.objects[0].name
    r, geom, hits = _frame(s)
    d = np.random.default_rng(7).random((HEIGHT, WIDTH, 3)).astype(np.float32)
    wrt = [f"objects.{name}.vertices"]
    focus = warprt.image.replay_focus(s, hits, wrt, d)
    assert 0.05 < focus.mean() < 0.7, focus.mean()  # a real part of the trees, not all of them
    names = wrt + [f"objects.{name}.translation", f"objects.{name}.rotation"]
    got = r.backward(d, wrt=names, edges=False)
    # with a material's name beside (not an object's: every tree replayed, the replay otherwise the same)
    whole = r.backward(d, wrt=names + [f"materials.{s.objects[0].material}.ks"], edges=False)
    for n in names:
        assert np.array_equal(got[n], whole[n]) and np.abs(got[n]).max() > 0, n
    r.close()


def test_a_pixel_whose_adjoint_is_zero_is_not_replayed():
    s = mirror_scene()
    r, geom, hits = _frame(s)
    d = np.random.default_rng(3).random((HEIGHT, WIDTH, 3)).astype(np.float32)
    d[:, : WIDTH // 2] = 0.0
    name = "materials.crate.ks"
    focus = warprt.image.replay_focus(s, hits, [name], d)
    assert 0.4 < focus.mean() < 0.6, focus.mean()
    slot = r.geometry.material_names.index("crate")
    whole = _by_hand(s, geom, hits, d, "ks")[slot]
    got = r.backward(d, wrt=[name], edges=False)[name]
    assert np.array_equal(got, whole) and np.abs(whole).max() > 0
    r.close()


def test_a_focus_on_the_camera_rays_hits_alone_loses_the_reflection():
    """The control: trees kept where the crate is met at level 0 only (not where it is seen in the floor)."""
    s = mirror_scene()
    r, geom, hits = _frame(s)
    d = np.random.default_rng(7).random((HEIGHT, WIDTH, 3)).astype(np.float32)
    wrt = ["objects.crate.vertices"]
    right = warprt.image.replay_focus(s, hits, wrt, d)
    first, count = hits.level(0)
    face = hits.rec.face.numpy()[first:first + count]
    crate = np.arange(len(s.objects[0].faces), len(s.objects[0].faces) + len(s.objects[1].faces))
    direct = np.isin(face, crate)
    assert right.sum() > direct.sum()  # the crate is seen in the mirror where the camera rays miss it
    rows = _rows(s, "crate")
    whole = _by_hand(s, geom, hits, d, "points", vertices=True)[rows]
    wrong = _by_hand(s, geom, hits, d, "points", direct, vertices=True)[rows]
    assert np.abs(wrong - whole).max() > 0.05 * np.abs(whole).max()
    assert np.array_equal(_by_hand(s, geom, hits, d, "points", right, vertices=True)[rows], whole)
    r.close()
