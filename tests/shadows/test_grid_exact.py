"""The light-space grid answers every shadow ray as Warp's any-hit query does (0 mismatches), on every
shadow ray of every scene and on rays aimed through every vertex and edge midpoint, and the counters
can see a mismatch: the grid built without its float32 margin misses rays. Its lists keep each cell's
triangles nearest the light first; lights with geometry at them, and a grid over its memory budget,
leave the shadow rays to the BVH; and the images are the traced images to the bit, on every scene,
every Z-buffer hard case and random scenes."""

from dataclasses import replace

import numpy as np
import pytest

import warprt
from accuracy.test_random_scenes import random_scene
from shortcuts import IDS, ROOT, SCENE_CASES, SCENES, SEEDS, at_width, same_as_traced
from tests.scenekit import make_scene
from tests.zbuffer.test_agreement import QUICK_CASES
from tests.zbuffer.test_hybrid_exact import case_scene
from warprt.geometry import Geometry, ShadowGridBuild, cells_for
from warprt.scene import Light

from shadows.probes import frame_counts, stress_counts, through_every_vertex_and_edge

def at(path, width):
    """The scene at ``width`` pixels; one with no point lights (glass_slab; sky, lit by its environment alone)
    gets one above its objects, so that every scene has shadow rays the grid answers to check."""
    scene = warprt.load_scene(path)
    if not scene.whitted_lights:
        lo = np.min([o.vertices.min(0) for o in scene.objects], 0)
        hi = np.max([o.vertices.max(0) for o in scene.objects], 0)
        above = (lo + hi) / 2 + [0.3 * (hi - lo).max(), 1.5 * (hi - lo).max(), 0.2 * (hi - lo).max()]
        scene = replace(scene, lights=[*scene.lights, Light(tuple(float(v) for v in above), (1.0, 1.0, 1.0))])
    return at_width(scene, width)


def grid_of(geom, scene, **kw):
    lights = geom.light_positions(scene)
    return ShadowGridBuild(geom.points_np, geom.indices_np, lights, cells_for(geom.triangle_count), **kw), lights


@pytest.mark.parametrize("path", SCENE_CASES)
def test_every_shadow_ray_of_every_scene_gets_the_bvh_answer(path):
    scene = at(path, 160)
    geom = Geometry(scene)
    build, _ = grid_of(geom, scene)
    counts = frame_counts(scene, geom, geom.scene_data(scene, build.grid), scene.render.max_depth)
    print(path, counts, build.stats)
    pixels = scene.camera.width * scene.camera.height
    assert counts["rays"] > pixels // 4 and counts["blocked"] > 0
    assert counts["mismatches"] == 0


@pytest.mark.parametrize("path", SCENE_CASES)
def test_rays_through_every_vertex_and_edge_midpoint_get_the_bvh_answer(path):
    scene = at(path, 16)
    geom = Geometry(scene)
    build, lights = grid_of(geom, scene)
    targets = through_every_vertex_and_edge(geom, np.random.default_rng(1))
    counts = stress_counts(geom, geom.scene_data(scene, build.grid), lights, targets)
    print(path, counts)
    # Three origins behind each target, for each light with a position: none dropped (an origin at a light is).
    placed = int(np.isfinite(lights).all(1).sum())
    assert counts["rays"] >= 0.99 * 3 * len(targets) * placed and counts["blocked"] > 0
    assert counts["mismatches"] == 0


def test_without_its_margin_the_grid_misses_rays():
    """The negative control: the default scene's rays of the test above, the grid built with no float32
    margin (delta = 0, no widening of the projections): the counter must see the rays it then gets
    wrong (measured: 24 of 371,376)."""
    scene = at(None, 16)
    geom = Geometry(scene)
    build, lights = grid_of(geom, scene, delta_eps=0.0, uv_abs=0.0)
    targets = through_every_vertex_and_edge(geom, np.random.default_rng(1))
    assert stress_counts(geom, geom.scene_data(scene, build.grid), lights, targets)["mismatches"] > 0


def test_without_its_margin_the_grid_misses_rays_of_spot_lights():
    """The negative control for spots: the default scene's lights made spots aimed at its centre. Their
    cube maps are the point lights', and the counter sees the margin-less grid's wrong answers there too."""
    scene = at(None, 16)
    centre = np.mean(scene.bounds(), axis=0)
    scene = replace(scene, lights=[replace(light, type="spot", direction=tuple(centre - light.position))
                                   for light in scene.lights])
    geom = Geometry(scene)
    build, lights = grid_of(geom, scene, delta_eps=0.0, uv_abs=0.0)
    targets = through_every_vertex_and_edge(geom, np.random.default_rng(1))
    assert stress_counts(geom, geom.scene_data(scene, build.grid), lights, targets)["mismatches"] > 0


def test_spots_keep_their_cube_maps_and_directional_lights_go_to_the_bvh():
    """A spot's shadow ray runs to its position like a point light's; a directional light's runs to
    infinity, which no cube map around a position holds: its rays are traced."""
    spots = at(ROOT / "scenes" / "spot_lit.toml", 16)
    assert grid_of(Geometry(spots), spots)[0].light_ok.tolist() == [1, 1]
    sun = at(ROOT / "scenes" / "sun.toml", 16)
    assert [light.type for light in sun.lights] == ["directional", "point"]
    assert grid_of(Geometry(sun), sun)[0].light_ok.tolist() == [0, 1]


def test_a_scene_lit_only_by_the_sun_traces_its_shadow_rays():
    """Only directional lights: no grid at all (its reason says why), the traced image to the bit."""
    scene = make_scene([LAMP, FLOOR], {"m": {"kd": [0.7] * 3}},
                       [{"type": "directional", "direction": [0.3, -1.0, 0.2]},
                        {"type": "directional", "direction": [-0.5, -1.0, -0.1], "color": [0.3, 0.2, 0.1]}],
                       camera={"eye": [0.0, 3.0, 6.0], "center": [0.0, 0.5, 0.0]}, ambient=[0.1] * 3)
    build, _ = grid_of(Geometry(scene), scene)
    assert build.grid is None and "directional" in build.reason
    grid = warprt.render(scene, shadow_query="grid")
    traced = warprt.render(scene, shadow_query="bvh")
    assert grid.stats.shadow_query == "bvh" and traced.stats.rays["shadow"] > 0
    assert np.array_equal(grid.image, traced.image) and grid.stats.rays == traced.stats.rays


def test_each_cell_lists_its_triangles_nearest_the_light_first():
    scene = at(None, 16)
    build, _ = grid_of(Geometry(scene), scene)
    start = build.grid.start.numpy()
    dmin = build.grid.entries.numpy()["dmin"]
    first_of_cell = np.zeros(len(dmin), bool)
    first_of_cell[start[:-1][start[:-1] < len(dmin)]] = True
    assert build.entries > 100_000
    assert np.all((np.diff(dmin) >= 0) | first_of_cell[1:])


def _lists(build) -> tuple:
    g = build.grid
    return g.start.numpy().tolist(), g.entries.numpy()["tri"].tolist(), g.entries.numpy()["dmin"].tolist()


def test_threads_taking_the_triangles_in_any_order_build_the_same_lists():
    """On a GPU many threads claim a cell's slots at once, in no set order: launched farthest the light
    first (the worst order), the lists are the nearest-first build's, entry for entry, after the per-cell
    sort; without the sort (the negative control) they are not, and are no longer nearest first."""
    scene = at(None, 16)
    geom = Geometry(scene)
    nearest, _ = grid_of(geom, scene)
    farthest, _ = grid_of(geom, scene, thread_order="farthest")
    assert nearest.entries == farthest.entries > 100_000
    assert _lists(farthest) == _lists(nearest)
    unsorted, _ = grid_of(geom, scene, thread_order="farthest", sort_cells=False)
    start, tris, dmin = _lists(unsorted)
    assert tris != _lists(nearest)[1] and sorted(tris) == sorted(_lists(nearest)[1])
    first_of_cell = np.zeros(len(dmin), bool)
    first_of_cell[[i for i in start[:-1] if i < len(dmin)]] = True
    assert not np.all((np.diff(dmin) >= 0) | first_of_cell[1:])


LAMP = {"shape": "sphere", "radius": 0.2, "subdivisions": 2, "material": "m", "translate": [0.0, 2.0, 0.0]}
FLOOR = {"shape": "plane", "size": [8.0, 8.0], "material": "m"}


def test_a_light_at_geometry_leaves_its_shadow_rays_to_the_bvh():
    """A light on the lamp's surface: the grid's margin would blow up there, so its rays are traced."""
    scene = make_scene([LAMP, FLOOR], {"m": {"kd": [0.7] * 3}}, [{"position": [0.0, 1.8, 0.0]}, {"position": [3, 4, 2]}],
                       camera={"eye": [0.0, 3.0, 6.0], "center": [0.0, 0.5, 0.0]}, ambient=[0.1] * 3)
    build, _ = grid_of(Geometry(scene), scene)
    assert build.light_ok.tolist() == [0, 1]
    _, grid = same_as_traced(scene, "shadow_query", "grid")
    assert grid.stats.shadow_query == "grid" and grid.stats.shadow_grid["lights_on_grid"] == 1


def test_a_grid_over_its_memory_budget_is_not_built():
    scene = at(None, 16)
    geom = Geometry(scene)
    build, _ = grid_of(geom, scene, max_bytes=1 << 20)
    assert build.grid is None and "budget" in build.reason and build.nbytes > 1 << 20


@pytest.mark.parametrize("name", QUICK_CASES)
def test_grid_shadows_give_the_traced_image_on_the_zbuffer_hard_cases(name):
    scene = case_scene(name)
    traced, grid = same_as_traced(scene, "shadow_query", "grid", primary_query="raytrace")
    grid_lights = traced.stats.rays["shadow"] and scene.triangle_count and scene.whitted_lights
    assert grid.stats.shadow_query == ("grid" if grid_lights else "bvh")  # an environment alone: no grid


@pytest.mark.parametrize("path", SCENE_CASES)
def test_grid_shadows_give_the_traced_image_on_every_scene(path):
    scene = at(path, 200).with_render(spp=4)
    traced, grid = same_as_traced(scene, "shadow_query", "grid", primary_query="raytrace", reflection_query="bvh")
    # glass_slab's materials have no diffuse or specular term: no lit term, so no shadow rays at all.
    assert traced.stats.rays["shadow"] > 0 or IDS[SCENES.index(path)] == "glass_slab"
    assert grid.stats.shadow_query == ("grid" if traced.stats.rays["shadow"] else "bvh")
    assert grid.stats.variant.endswith("_gshadow") == (grid.stats.shadow_query == "grid")


@pytest.mark.parametrize("seed", SEEDS)
def test_grid_shadows_give_the_traced_image_on_random_scenes(seed):
    same_as_traced(random_scene(seed), "shadow_query", "grid", primary_query="raytrace")
