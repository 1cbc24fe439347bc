"""The many-frames benchmark's report: its ratios per job length and the Targets rows from known runs (its
runs themselves are smoke-tested with `python -m benchmarks.batch --quick`: they start Ray twice)."""

from benchmarks import batch
from benchmarks.__main__ import targets


def runs(by_length: dict) -> dict:
    """A benchmark result: job length -> configuration -> (seconds, CPU use) per run."""
    results = []
    for frames, configs in by_length.items():
        for config, times in configs.items():
            for seconds, cpu_use in times:
                r = {"config": config, "seconds": seconds, "frames": frames, "workers": 2, "threads": 1,
                     "cpu_use": cpu_use, "first_frame_seconds": 0.5, "frame_ms": {"bvh": 20.0, "trace": 100.0, "total": 130.0}}
                if config.startswith("local"):
                    r["boot_seconds"] = [0.3, 0.4]
                if config.startswith(("ray", "cluster")):
                    r["ray_start_seconds"] = 6.0
                results.append(r)
    return {"lengths": list(by_length), "width": 320, "height": 240, "repeat": 2, "scene": "scenes/seed.toml",
            "cores": 2, "results": results}


DATA = runs({48: {"loop": [(12.0, 0.6), (10.0, 0.6)], "loop_reload": [(14.0, 0.5), (13.0, 0.5)],
                  "local": [(6.0, 0.9), (5.0, 0.95)], "local_1": [(9.0, 0.6), (9.5, 0.6)], "local_2": [(6.0, 0.9), (5.0, 0.95)],
                  "ray_1": [(9.0, 0.5), (9.0, 0.5)], "ray_2": [(6.5, 0.8), (7.0, 0.8)], "cluster_2": [(8.0, 0.7), (8.0, 0.7)],
                  "mitsuba_loop": [(4.5, 0.9), (4.0, 0.9)]},
             480: {"loop": [(100.0, 0.6), (90.0, 0.6)], "local": [(80.0, 0.99), (75.0, 0.85)], "ray_2": [(80.0, 0.9)]}})


def test_ratios_take_each_configurations_best_run_at_each_length():
    q = batch.ratios(DATA)
    assert q["local_over_loop"] == {48: 10.0 / 5.0, 480: 90.0 / 75.0}
    assert q["cpu_use"] == {48: 0.95, 480: 0.85}  # the best run's, not the highest
    # At 48 frames against local_2's best; at 480, where only the default ran, against it (2 workers x 1 thread).
    assert q["ray_over_local"] == {48: 6.5 / 5.0, 480: 80.0 / 75.0}
    assert q["local_over_mitsuba"] == {48: 4.0 / 5.0}  # where the Mitsuba script ran: its best over local's best


def test_report_lists_every_configuration_and_the_targets_their_verdicts():
    text = batch.report(DATA)
    for config in batch.CONFIGS:
        assert batch.LABELS[config] in text
    assert "| 48 | local backend, its default workers x threads | 9.60 |" in text  # 48 frames in 5.0 s
    assert "| 480 | local backend, its default workers x threads | 6.40 |" in text  # 480 frames in 75 s
    table = targets({"rows": [{"scene": "s", "width": 320, "height": 240, "warprt_warm": 1, "mitsuba_llvm_warm": 1,
                               "hybrid_warm": 1, "before_warm": 1}],
                     "default_cold": {"warprt_cold": 1, "mitsuba_llvm_cold": 1}},
                    {"rows": [{"warp_closest_1t": 1, "mitsuba_closest_1t": 1, "warp_any_1t": 1, "mitsuba_any_1t": 1,
                               "triangles": 1}]}, many=DATA)
    at48 = next(line for line in table.splitlines() if ">= 1.0x" in line and "48 frames" in line)
    at480 = next(line for line in table.splitlines() if ">= 1.3x" in line and "480 frames" in line)
    cpu = next(line for line in table.splitlines() if "CPU use" in line)
    ray = next(line for line in table.splitlines() if "--ray" in line and "48 frames" in line)
    ray480 = next(line for line in table.splitlines() if "--ray" in line and "480 frames" in line)
    mitsuba = next(line for line in table.splitlines() if "Mitsuba script" in line)
    assert "0.80x" in mitsuba and mitsuba.endswith("| not met |")
    assert "2.00x" in at48 and at48.endswith("| met |")
    assert "1.20x" in at480 and at480.endswith("| not met |")
    assert "95% at 48 frames, 85% at 480 frames" in cpu and cpu.endswith("| not met |")
    assert "1.30x" in ray and ray.endswith("| not met |")
    assert "1.07x" in ray480 and ray480.endswith("| met |")
