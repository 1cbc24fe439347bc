"""The kernel-floor benchmark: its bare kernel renders warprt's image to the bit (so the race is the same
race), the comparison notices a floor that does less work, and its Targets row says met only where it is."""

import json
from pathlib import Path

import pytest

from benchmarks import kernel_floor


@pytest.mark.parametrize("name", ["cornell", "glass_cube"])
def test_the_floor_renders_warprts_image_to_the_bit(name):
    """Two kernels written apart, one bare and one warprt's: mirrors and smooth normals (cornell), the
    ray tree with its stack and Beer's law (glass_cube)."""
    pair = kernel_floor.Pair(kernel_floor.load(name, 64, 48))
    assert pair.difference() == {"identical": True, "pixels_differing": 0, "max_abs_diff": 0.0}


def test_a_floor_that_stops_at_the_first_hit_is_caught():
    """Negative control: the same floor with one ray level instead of the scene's misses the mirrors."""
    pair = kernel_floor.Pair(kernel_floor.load("cornell", 64, 48))
    pair.max_depth = 1
    d = pair.difference()
    assert not d["identical"] and d["pixels_differing"] > 0 and d["max_abs_diff"] > 0.0


def test_the_floor_refuses_a_scene_it_does_not_render():
    with pytest.raises(ValueError, match="texture"):
        kernel_floor.Pair(kernel_floor.load("textured", 32, 24))


def _rows(*rows):
    return {"rows": [{"scene": s, "floor": f, "warprt": w, "identical": same} for s, f, w, same in rows]}


def test_target_met_only_within_the_ratio_and_with_identical_images():
    assert kernel_floor.target_row(_rows(("a", 1.0, 1.05, True), ("b", 2.0, 2.24, True)))[1:] == (
        "1.05x to 1.12x (worst: b); images identical", "met")
    assert kernel_floor.target_row(_rows(("a", 1.0, 1.10, True), ("b", 1.0, 1.2, True)))[2] == "not met"
    assert kernel_floor.target_row(_rows(("a", 1.0, 1.0, True), ("b", 1.0, 1.0, False)))[2] == "not met"


def test_quick_run_writes_its_table(tmp_path):
    kernel_floor.main(["--quick", "--scene", "seed", "-o", str(tmp_path / "kernel_floor.md")])
    (row,) = json.loads((tmp_path / "kernel_floor.json").read_text())["rows"]
    assert row["scene"] == "seed" and row["identical"]
    assert all(row[k] > 0 for k in ("floor", "warprt", "one_launch", "row_major", "render"))
    assert "| seed |" in Path(tmp_path / "kernel_floor.md").read_text()


def test_make_benchmark_targets_carry_the_kernel_floor_row():
    from benchmarks.__main__ import targets

    h2h = {"rows": [{"scene": "a", "width": 64, "height": 48, "warprt_warm": 0.1, "hybrid_warm": 0.1,
                     "mitsuba_llvm_warm": 0.1, "before_warm": 0.1}]}
    cast = {"rows": [{"triangles": 20, "warp_closest_1t": 1.0, "mitsuba_closest_1t": 1.0, "warp_any_1t": 1.0,
                      "mitsuba_any_1t": 1.0}]}
    row = next(l for l in targets(h2h, cast, kernel_floor=_rows(("a", 1.0, 1.3, True))).splitlines()
               if l.startswith("| warprt's kernel within 1.15x of the floor"))
    assert row.endswith("| 1.30x to 1.30x (worst: a); images identical | not met |")
