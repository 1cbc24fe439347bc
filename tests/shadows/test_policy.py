"""shadow_query="auto" takes the light-space grid where it is the cheaper: at once where its build costs less
than the frame saves, otherwise from the second frame with those lights on;
the grid is kept with the geometry, its memory counted in the stats, and the flag is checked."""

from dataclasses import replace

import warprt
from marks import slow
from shortcuts import assert_unknown_choice_refused, command_stats
from warprt.geometry import Geometry
from warprt.image import LightHistory, shadows_from_grid
from warprt.scene import resolve_effects


def test_auto_takes_the_grid_for_the_default_scene_at_its_own_size():
    stats = warprt.render(warprt.load_scene()).stats
    assert stats.shadow_query == "grid" and "_gshadow" in stats.variant
    assert stats.memory["shadow_grid"] == stats.shadow_grid["bytes"] > 0


def test_a_grid_too_dear_for_one_frame_waits_for_the_second_frame_with_its_lights():
    """20,518 triangles and 2 lights in a 320x240 frame: the build (estimated 52 ms) costs more than the
    frame's shadow rays save (10 ms), less than 20 such frames do: from the second frame with these lights
    on the grid is taken, as the BVH is, and another light set starts again. At 32x24 (0.1 ms a frame) it
    never pays."""
    scene = warprt.load_scene(None, {"objects[1].subdivisions": 5}).with_camera(width=320, height=240)
    geom, fx, history = Geometry(scene), resolve_effects(scene), LightHistory()

    def ask(s, device="cpu", policy="auto", samples=320 * 240):  # a frame: counted, then the policy asked
        lights = geom.light_positions(s)
        return shadows_from_grid(policy, fx, geom, lights, samples, 2, device, history.record(lights))

    assert [ask(scene) for _ in range(3)] == [False, True, True]
    assert not any(ask(scene.with_camera(width=32, height=24), samples=32 * 24) for _ in range(3))
    moved = replace(scene, lights=[replace(scene.lights[0], position=(0.0, 9.0, 0.0)), *scene.lights[1:]])
    assert not ask(moved)
    assert not ask(scene, "cuda") and ask(scene, "cuda", "grid") and not ask(scene, policy="bvh")


def test_asking_the_policy_counts_no_frame():
    """The frames are counted by a LightHistory's record alone (a Renderer's, in its caches): the same
    question asked again gets the same answer, and the history holds what was recorded, nothing more."""
    scene = warprt.load_scene(None, {"objects[1].subdivisions": 5}).with_camera(width=320, height=240)
    geom, fx, history = Geometry(scene), resolve_effects(scene), LightHistory()
    lights = geom.light_positions(scene)
    assert [shadows_from_grid("auto", fx, geom, lights, 320 * 240, 2, "cpu", 1) for _ in range(3)] == [False] * 3
    assert history.frames == {}
    assert history.record(lights) == 1 and history.record(lights) == 2


def test_a_renderer_takes_the_grid_from_the_second_frame_with_its_lights():
    """The same policy through a Renderer's own history: a one-shot render() is always a first frame."""
    scene = warprt.load_scene(None, {"objects[1].subdivisions": 5}).with_camera(width=320, height=240)
    r = warprt.Renderer(scene, primary_query="raytrace", reflection_query="bvh")
    assert [r.render().stats.shadow_query for _ in range(3)] == ["bvh", "grid", "grid"]
    assert warprt.render(scene).stats.shadow_query == "bvh"


def test_the_grid_is_kept_for_the_next_frame_with_the_same_lights():
    scene = warprt.load_scene().with_camera(width=64, height=48)
    r = warprt.Renderer(scene, shadow_query="grid")
    first = r.render().stats.shadow_grid
    r.set_scene(scene.with_camera(fovy=30.0))
    again = r.render().stats.shadow_grid
    assert again["grid"] == "reused" and again["entries"] == first["entries"]


@slow
def test_a_scene_without_shadow_rays_builds_no_grid():
    scene = warprt.load_scene().with_camera(width=64, height=48).with_render(shadows=False)
    stats = warprt.render(scene, shadow_query="grid").stats
    assert stats.shadow_query == "bvh" and stats.shadow_grid == {} and stats.memory["shadow_grid"] == 0


def test_unknown_shadow_query_is_a_scene_error():
    assert_unknown_choice_refused("shadow_query", "photons")


@slow
def test_the_command_line_flag_and_stats(tmp_path):
    stats = command_stats(tmp_path, "--shadow-query", "grid")
    assert stats["shadow_query"] == "grid" and stats["shadow_grid"]["lights_on_grid"] == 2
    assert stats["shadow_grid"]["cells"] == 256 and stats["memory"]["shadow_grid"] > 0
