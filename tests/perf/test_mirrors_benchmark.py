"""The mirrors benchmark compares like with like: auto's frames and the traced frames are the same image
with the same rays, auto takes the virtual cameras where they are the cheaper, and the target row reads
the measured ratios (a smoke run: no timing is asserted)."""

from benchmarks import mirrors
from marks import slow


@slow  # five scenes, four frames each at 320x240
def test_a_small_run_renders_the_traced_images_and_reports_each_scene():
    data = mirrors.run(320, 240, repeat=1)
    rows = {r["scene"]: r for r in data["rows"]}
    assert set(rows) == set(mirrors.SCENES)
    assert all(r["identical"] for r in rows.values())
    # 5,158 triangles under 76,800 samples: raster_is_cheaper, so auto's warm frames take the virtual cameras.
    assert rows["default"]["reflection_query"] == "mirrors" and rows["default"]["share"] > 0.9
    (target,) = mirrors.target_rows(data)
    taken = all(r["reflection_query"] == "mirrors" for r in rows.values())
    assert target[2] == ("met" if taken and max(r["ratio"] for r in rows.values()) <= mirrors.TARGET else "not met")
    assert all(f"{name} {r['ratio']:.3f}x" in target[1] for name, r in rows.items())
    assert mirrors.report(data).count("\n| ") == len(rows) + 1


def test_a_ratio_just_over_the_bound_reads_as_over_it():
    """0.853 against the 0.85 bound: the row says 0.853x and not met (at two places it read 0.85x, not met);
    exactly 0.85 on every scene is met."""
    row = lambda scene, ratio: {"scene": scene, "ratio": ratio, "reflection_query": "mirrors"}
    data = {"size": [1024, 768], "rows": [row("default", 0.735), row("mirrors", 0.853)]}
    (target,) = mirrors.target_rows(data)
    assert "mirrors 0.853x" in target[1] and target[2] == "not met"
    data["rows"][1]["ratio"] = mirrors.TARGET
    assert mirrors.target_rows(data)[0][2] == "met"
