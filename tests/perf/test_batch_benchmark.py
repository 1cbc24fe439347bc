"""The many-frames benchmark's report: its two ratios and the Targets rows from known runs (its runs
themselves are smoke-tested with `python -m benchmarks.batch --quick`: they start Ray twice)."""

from benchmarks import batch
from benchmarks.__main__ import targets


def runs(seconds: dict) -> dict:
    """A benchmark result of 48 frames per run with the given seconds per configuration (lists: repeats)."""
    results = []
    for config, times in seconds.items():
        for s in times:
            r = {"config": config, "seconds": s, "frames": 48, "workers": 2, "threads": 1,
                 "frame_ms": {"bvh": 20.0, "trace": 100.0, "total": 130.0}}
            if config.startswith(("ray", "cluster")):
                r["ray_start_seconds"] = 6.0
            results.append(r)
    return {"frames": 48, "width": 320, "height": 240, "repeat": 2, "scene": "scenes/seed.toml", "cores": 2,
            "results": results}


DATA = runs({"loop": [12.0, 10.0], "loop_reload": [14.0, 13.0], "local_1": [9.0, 9.5], "local_2": [6.0, 5.0],
             "ray_1": [9.0, 9.0], "ray_2": [6.5, 7.0], "cluster_2": [8.0, 8.0]})


def test_ratios_take_each_configurations_best_run():
    q = batch.ratios(DATA)
    assert q["local_over_loop"] == (48 / 5.0) / (48 / 10.0)  # 2.0
    assert q["ray_over_local"] == 6.5 / 5.0


def test_report_lists_every_configuration_and_the_targets_their_verdicts():
    text = batch.report(DATA)
    for config in batch.CONFIGS:
        assert batch.LABELS[config] in text
    assert "| 9.60 |" in text  # local_2's best: 48 frames in 5.0 s
    table = targets({"rows": [{"scene": "s", "width": 320, "height": 240, "warprt_warm": 1, "mitsuba_llvm_warm": 1,
                               "hybrid_warm": 1, "before_warm": 1}],
                     "default_cold": {"warprt_cold": 1, "mitsuba_llvm_cold": 1}},
                    {"rows": [{"warp_closest_1t": 1, "mitsuba_closest_1t": 1, "warp_any_1t": 1, "mitsuba_any_1t": 1,
                               "triangles": 1}]}, many=DATA)
    local = next(line for line in table.splitlines() if "Python loop" in line)
    ray = next(line for line in table.splitlines() if "--ray" in line)
    assert "2.00x" in local and local.endswith("| met |")
    assert "1.30x" in ray and ray.endswith("| not met |")
