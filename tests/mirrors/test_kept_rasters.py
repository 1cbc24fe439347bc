"""A view's virtual cameras are kept by its Renderer and reused by its next frames: a frame that changes
only lights or colours reuses them; one that changes what they were rasterized for (the camera, the image
size, the samples, the bounces, which materials reflect) builds its own. Every frame is the traced image,
and rasters kept for another eye give wrong answers (the negative control that makes the camera a key)."""

from dataclasses import replace

import numpy as np
import pytest

import warprt
from marks import quick_cases
from warprt.geometry import Geometry
from warprt.image import MirrorFrame
from warprt.scene import resolve_effects

from mirrors.probes import level_counts


def base():
    return warprt.load_scene().with_camera(width=96, height=72, eye=(0.4, 1.4, 5.1))


def frame_after(first, second):
    """``second`` rendered with the mirrors after ``first`` by one Renderer (the same objects: the same Geometry)."""
    r = warprt.Renderer(first, reflection_query="mirrors")
    assert r.render().stats.mirrors["rasters"] == "built"
    r.set_scene(second)
    result = r.render()
    traced = warprt.render(second, reflection_query="bvh")
    assert np.array_equal(result.image, traced.image) and result.stats.rays == traced.stats.rays
    return result.stats


def moved_light(s):
    return replace(s, lights=[replace(s.lights[0], position=(3.0, 7.0, 4.0)), *s.lights[1:]])


def recoloured(s):
    return replace(s, materials={**s.materials, "mirror": replace(s.materials["mirror"], kd=(0.3, 0.1, 0.1),
                                                                  reflectivity=(0.5, 0.6, 0.7))})


@pytest.mark.parametrize("change", [moved_light, recoloured], ids=["light", "colours"])
def test_a_frame_changing_only_lights_or_colours_reuses_the_rasters(change):
    s = base()
    stats = frame_after(s, change(s))
    assert stats.reflection_query == "mirrors" and stats.mirrors["rasters"] == "reused" and stats.mirrors["decided"] > 0


CHANGES = {
    "eye": lambda s: s.with_camera(eye=(0.9, 1.3, 4.8)),
    "center": lambda s: s.with_camera(center=(0.1, 0.7, 0.0)),
    "up": lambda s: s.with_camera(up=(0.1, 1.0, 0.0)),
    "fovy": lambda s: s.with_camera(fovy=40.0),
    "near": lambda s: s.with_camera(near=0.5),
    "size": lambda s: s.with_camera(width=80, height=60),
    "spp": lambda s: s.with_render(spp=4),
    "max_depth": lambda s: s.with_render(max_depth=2),
    "matte floor": lambda s: replace(s, materials={**s.materials, "floor": replace(s.materials["floor"],
                                                                                   reflectivity=(0.0, 0.0, 0.0))}),
}


@pytest.mark.parametrize("name", quick_cases(list(CHANGES), {"eye", "spp", "matte floor"}))
def test_a_frame_changing_the_view_builds_its_own_rasters(name):
    s = base()
    stats = frame_after(s, CHANGES[name](s))
    assert stats.reflection_query == "mirrors" and stats.mirrors["rasters"] == "built"


def test_rasters_of_another_eye_decide_no_ray_wrongly():
    """Rasters built for an eye 0.5 away, asked about this eye's rays (what a key without the eye would
    do): each ray's stray from its sample's ideal line refuses them (no mismatch, few rays decided), and
    without that check they answer rays wrongly (the negative control). The key keeps the rasters useful;
    the per-ray check keeps them exact."""
    s = base()
    moved = s.with_camera(eye=(0.9, 1.3, 4.8))
    geom = Geometry(s)
    data, fx = geom.scene_data(s), resolve_effects(s)
    counts = lambda frame: level_counts(moved, geom, data, frame.mirrors).sum(axis=0)
    own = counts(MirrorFrame(moved, geom, data, fx, 2, 16, "cpu"))
    stale = counts(MirrorFrame(s, geom, data, fx, 2, 16, "cpu"))
    unchecked = counts(MirrorFrame(s, geom, data, fx, 2, 16, "cpu", stray_check=False))
    print("rays, decided, mismatches: own", own, "stale", stale, "stale unchecked", unchecked)
    assert own[2] == 0 and own[1] > 0.9 * own[0]
    assert stale[2] == 0 and stale[1] < 0.1 * own[1]
    assert unchecked[2] > 0


def test_a_renderer_keeps_two_views():
    """A stereo pair alternates without rebuilding; a third view sends the oldest away."""
    s = base()
    left, right, third = (s.with_camera(eye=(x, 1.4, 5.1)) for x in (0.3, 0.5, 0.7))
    r = warprt.Renderer(s, reflection_query="mirrors")

    def rasters(scene):
        r.set_scene(scene)
        return r.render().stats.mirrors["rasters"]

    assert [rasters(v) for v in (left, right, left, right, third, right, left)] == \
        ["built", "built", "reused", "reused", "built", "reused", "built"]
    assert warprt.render(left, reflection_query="mirrors").stats.mirrors["rasters"] == "built"  # nothing kept
