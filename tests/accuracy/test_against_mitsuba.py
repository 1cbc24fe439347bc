"""warprt's images against Mitsuba 3's render of the same scene: every scene in scenes/, and each
effect level of the seed's Figure 6; thresholds and the pixel classes they may differ in: harness.py."""

import pytest

import warprt

from accuracy.harness import ROOT, SCENES, check, record, small
from marks import quick_cases

pytestmark = pytest.mark.accuracy

SEED = ROOT / "scenes" / "seed.toml"

# The seed's Figure 6, (a) to (f): the effects kept, and the ray levels.
FIGURE_6 = [
    ("a_ambient", ["ambient", "smooth"], 1),
    ("b_diffuse", ["ambient", "diffuse", "smooth"], 1),
    ("c_specular", ["ambient", "diffuse", "specular", "smooth"], 1),
    ("d_shadows", ["ambient", "diffuse", "specular", "shadows", "smooth"], 1),
    ("e_reflection_1", None, 2),
    ("f_reflection_2", None, 3),
]


def test_scenes_exist():
    assert SCENES, "scenes/*.toml is empty: the suite would check nothing"


@pytest.mark.parametrize("path", quick_cases(SCENES, {"cornell", "tilted"}, [p.stem for p in SCENES]))
def test_scene_matches_mitsuba(path):
    """Each scene as its file describes it (effects, ray levels, spp), at a small size."""
    result = check(f"scene_{path.stem}", small(path))
    print(f"\n{path.stem}: {record(result)}")


@pytest.mark.parametrize("path", quick_cases(SCENES, {"cornell", "tilted"}, [p.stem for p in SCENES]))
def test_hybrid_rendering_matches_mitsuba(path):
    """Primary hits from the Z-buffer, shadows and reflections traced: held to the same thresholds,
    every differing pixel explained by the same float64 oracle."""
    scene = small(path)
    result = check(f"hybrid_{path.stem}", scene, primary_query="zbuffer")
    assert warprt.render(scene, primary_query="zbuffer").stats.primary_query == "zbuffer"
    print(f"\n{path.stem} hybrid: {record(result)}")


@pytest.mark.parametrize("case, effects, max_depth", FIGURE_6, ids=[c for c, _, _ in FIGURE_6])
def test_figure_6_level_matches_mitsuba(case, effects, max_depth):
    result = check(f"figure6_{case}", small(SEED, **{"render.max_depth": max_depth, "render.spp": 1}), effects=effects)
    print(f"\nseed {case}: {record(result)}")


def test_supersampled_matches_mitsuba():
    """2x2 stratified samples at the stratum centres on both sides, box filter."""
    result = check("seed_spp4", small(SEED, **{"render.spp": 4}))
    print(f"\nseed spp 4: {record(result)}")


def test_smooth_objects_rendered_flat_match_mitsuba():
    """With 'smooth' off, Mitsuba's meshes are built without vertex normals: faceted on both sides."""
    path = ROOT / "scenes" / "curved_shadows.toml"
    result = check("curved_shadows_flat", small(path), disable=["smooth"])
    print(f"\ncurved_shadows flat: {record(result)}")
