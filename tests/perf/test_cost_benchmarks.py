"""The cost-growth and accuracy-cost benchmarks: their fits, upscaling and Pareto logic against closed
forms, and a --quick run of each that writes its plots and a report whose image links resolve."""

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from benchmarks import accuracy_cost, equal_error, growth
from marks import slow
from warprt.scene import Camera


def test_fit_recovers_a_logarithmic_law_and_prefers_it_to_a_line():
    n = np.geomspace(100, 1e6, 9)
    t = 2e-3 + 5e-4 * np.log(n)
    f = growth.growth_fits(n, t)
    assert f["log"]["a"] == pytest.approx(2e-3, rel=1e-9)
    assert f["log"]["b"] == pytest.approx(5e-4, rel=1e-9)
    assert f["log"]["rms_rel"] < 1e-12 < f["linear"]["rms_rel"]


def test_fit_recovers_a_linear_law_and_its_log_log_slope_tends_to_one():
    n = np.geomspace(100, 1e6, 9)
    t = 1e-3 + 2e-8 * n
    f = growth.growth_fits(n, t)
    assert f["linear"]["b"] == pytest.approx(2e-8, rel=1e-9)
    assert f["linear"]["rms_rel"] < 1e-12 < f["log"]["rms_rel"]
    # d ln t / d ln n = c n / (a + c n): 0.39 at n = 3e4, 0.95 at 1e6; a fixed cost hides the growth
    # over the whole sweep, and the top of the sweep shows it.
    assert f["slope"] < 0.5 < 0.8 < f["slope_top"] < 0.95


def test_loglog_slope_of_a_power_law_is_its_exponent():
    x = np.array([1.0, 10.0, 100.0, 1000.0])
    assert growth.loglog_slope(x, 3.0 * x**0.5) == pytest.approx(0.5)


def test_upscale_bilinear_reproduces_a_ramp_between_the_outer_pixel_centres():
    w, h, W, H = 8, 6, 32, 24
    # A ramp in output pixel units: source pixel i has its centre at (i + 0.5) * W / w.
    xs = (np.arange(w) + 0.5) * W / w
    src = np.repeat(np.repeat(xs[None, :, None], h, 0), 3, 2).astype(np.float32)
    out = accuracy_cost.upscale_bilinear(src, W, H)
    assert out.shape == (H, W, 3)
    centres = np.arange(W) + 0.5
    inside = (centres >= xs[0]) & (centres <= xs[-1])
    np.testing.assert_allclose(out[0, inside, 0], centres[inside], rtol=0, atol=1e-4)
    np.testing.assert_allclose(out[0, ~inside & (centres < xs[0]), 0], xs[0])  # clamped at the edges
    np.testing.assert_allclose(out[0, ~inside & (centres > xs[-1]), 0], xs[-1])


def test_upscale_bilinear_by_one_is_the_identity():
    img = np.random.default_rng(1).random((5, 7, 3)).astype(np.float32)
    np.testing.assert_allclose(accuracy_cost.upscale_bilinear(img, 7, 5), img, atol=1e-6)


def test_reference_size_keeps_the_aspect_inside_the_box():
    box = (320, 240)
    assert accuracy_cost.reference_size(Camera(width=640, height=480), box) == (320, 240)
    assert accuracy_cost.reference_size(Camera(width=560, height=560), box) == (240, 240)
    assert accuracy_cost.reference_size(Camera(width=640, height=360), box) == (320, 180)
    # A smaller image is enlarged to the box (Mitsuba's Cornell box file has a 64 x 64 film).
    assert accuracy_cost.reference_size(Camera(width=160, height=120), box) == (320, 240)
    assert accuracy_cost.reference_size(Camera(width=64, height=64), box) == (240, 240)


def test_mitsuba_at_recovers_the_spp_of_a_power_law_between_measured_frames():
    """Frames whose error falls as 0.1 / spp, timed 10 ms per spp: SSIM 0.95 is reached at exactly 2 spp and
    20 ms, 0.99 at 10 spp; an SSIM the 1-spp frame already beats costs at most that frame; one beyond
    the last frame measured is not reached."""
    frames = [{"spp": n, "seconds": 0.01 * n, "ssim": 1.0 - 0.1 / n} for n in (1, 4, 16)]
    m = accuracy_cost.mitsuba_at(frames, 0.95)
    assert m["spp"] == pytest.approx(2.0) and m["seconds"] == pytest.approx(0.02) and not m["bound"]
    assert accuracy_cost.mitsuba_at(frames, 0.99)["spp"] == pytest.approx(10.0)
    assert accuracy_cost.mitsuba_at(frames, 0.8) == {"spp": 1, "seconds": 0.01, "bound": True}
    assert accuracy_cost.mitsuba_at(frames, 0.999) is None
    rows = accuracy_cost.equal_error([{"seconds": 0.01, "ssim": 0.95, "rays": 1}],
                                     [{**f, "sampler": "independent"} for f in frames])
    assert rows[0]["mitsuba"]["independent"]["ratio"] == pytest.approx(0.5)


def _p(seconds, ssim, rays=100):
    return {"seconds": seconds, "ssim": ssim, "rays": rays}


def test_pareto_front_keeps_only_points_nothing_beats_on_both_axes():
    pts = [_p(1.0, 0.90), _p(2.0, 0.95), _p(2.5, 0.94), _p(3.0, 0.99), _p(0.5, 0.80), _p(4.0, 0.99)]
    front = accuracy_cost.pareto(pts)
    assert [(p["seconds"], p["ssim"]) for p in front] == [(0.5, 0.80), (1.0, 0.90), (2.0, 0.95), (3.0, 0.99)]


def test_cheapest_breaks_a_timer_tie_by_rays_and_reports_none_when_unreached():
    pts = [_p(1.00, 0.995, rays=500), _p(1.10, 0.995, rays=300), _p(2.0, 0.999, rays=900), _p(0.2, 0.9)]
    assert accuracy_cost.cheapest(pts, 0.99)["rays"] == 300  # 10% slower on the timer, fewer rays: a tie it wins
    assert accuracy_cost.cheapest(pts, 0.999)["seconds"] == 2.0
    assert accuracy_cost.cheapest(pts, 0.9999) is None


def _links_resolve(markdown: Path):
    links = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", markdown.read_text())
    assert links
    for link in links:
        with Image.open(markdown.parent / link) as im:
            assert im.width >= 400 and im.height >= 300, link


@slow
def test_growth_quick_run_writes_plots_and_report(tmp_path):
    growth.main(["--quick", "-o", str(tmp_path / "growth.md")])
    _links_resolve(tmp_path / "growth.md")
    data = json.loads((tmp_path / "growth.json").read_text())
    counts = [r["triangles"] for r in data["triangles"]["runs"]]
    assert counts == sorted(counts) and counts[-1] > 100 * counts[0]
    assert [r["pixels"] for r in data["pixels"]["runs"]] == [128 * 96, 256 * 192, 512 * 384]
    assert "1" in data["pixels"]["fits"]


@slow
def test_accuracy_cost_quick_run_measures_what_each_knob_buys(tmp_path):
    accuracy_cost.main(["--quick", "--scenes", "seed", "-o", str(tmp_path / "accuracy_cost.md")])
    _links_resolve(tmp_path / "accuracy_cost.md")
    (r,) = json.loads((tmp_path / "accuracy_cost.json").read_text())["scenes"]
    pts = {(p["spp"], p["depth"], p["shadows"], p["scale"]): p for p in r["points"]}
    # The seed scene has a mirror: more ray levels, more samples and shadows each bring warprt closer
    # to the converged reference. These are the model's physics, not the timer's.
    assert pts[(1, 1, True, 1)]["ssim"] < pts[(1, 3, True, 1)]["ssim"] < pts[(4, 3, True, 1)]["ssim"]
    assert pts[(1, 3, False, 1)]["ssim"] < pts[(1, 3, True, 1)]["ssim"]
    # At identical settings warprt and Mitsuba render the same image, up to a few edge pixels.
    assert r["agreement"]["ssim"] > 0.999
    assert all(math.isfinite(p["seconds"]) and p["seconds"] > 0 for p in r["points"])


@slow
def test_accuracy_cost_measures_what_light_samples_buy_against_mitsubas_direct_integrator(tmp_path):
    """Mitsuba's Cornell box file, lit by its area emitter: against Mitsuba's converged direct integrator,
    more points on the light bring warprt closer at every spp (the model's physics), warprt agrees with the
    reference's deterministic integrator at the same sample points, Mitsuba's own error falls as its spp
    grow, and the report gives Mitsuba's cost at warprt's error."""
    accuracy_cost.main(["--quick", "--scenes", "cornell_box", "-o", str(tmp_path / "accuracy_cost.md")])
    _links_resolve(tmp_path / "accuracy_cost.md")
    (r,) = json.loads((tmp_path / "accuracy_cost.json").read_text())["scenes"]
    assert r["reference"]["integrator"] == "direct" and r["reference"]["check"]["ssim"] > 0.998
    pts = {(p["spp"], p["light_samples"]): p for p in r["points"] if p["shadows"] and p["scale"] == 1}
    for spp in (1, 4):
        assert pts[(spp, 1)]["ssim"] < pts[(spp, 4)]["ssim"] < pts[(spp, 16)]["ssim"]
    # At a square size the box's corner edges pass through pixel centres, ties either side of which is right:
    # SSIM 0.9966 at 72 x 72 (at 100 x 75, no ties, 1.000000: tests/accuracy/test_area_lights_reference.py).
    assert r["agreement"]["ssim"] > 0.995 and r["agreement"]["light_samples"] == 16
    for sampler in ("independent", "stratified"):
        errs = [1.0 - d["ssim"] for d in r["direct"] if d["sampler"] == sampler]
        assert errs == sorted(errs, reverse=True) and len(errs) == 3
    assert len(r["equal_error"]) == len(r["pareto"])
    assert "What soft shadows cost" in (tmp_path / "accuracy_cost.md").read_text()


@slow
def test_equal_error_quick_run_times_every_method_to_each_target(tmp_path):
    """benchmarks/equal_error.py --quick: per scene (the Cornell box, the environment map) a row per warprt
    estimator (render.adaptive apart) and Mitsuba sampler, a column per target; the physics, not the timer: more
    light samples bring each warprt estimator closer at 1 spp, the analytic estimator is closer than the samples at 1
    light sample, each Mitsuba sampler's error falls with spp, and render.adaptive's frame is within the plain
    frame's reach at its spp."""
    equal_error.main(["--quick", "-o", str(tmp_path / "equal_error.md")])
    data = json.loads((tmp_path / "equal_error.json").read_text())
    text = (tmp_path / "equal_error.md").read_text()
    assert set(data["scenes"]) == {"cornell_box", "envmap"}
    box = data["scenes"]["cornell_box"]
    at = {(p["estimator"], p["spread"], p["spp"], p["light_samples"], p["adaptive"]): p for p in box["warprt"]}
    for estimator in ("samples", "analytic"):
        assert (at[(estimator, False, 1, 1, 0.0)]["rel"] > at[(estimator, False, 1, 4, 0.0)]["rel"]
                > at[(estimator, False, 1, 16, 0.0)]["rel"])
    assert at[("analytic", False, 1, 1, 0.0)]["ssim"] > at[("samples", False, 1, 1, 0.0)]["ssim"]
    assert at[("analytic", False, 4, 16, 0.005)]["ssim"] > at[("analytic", False, 1, 16, 0.0)]["ssim"]
    for scene in data["scenes"].values():
        for sampler in ("independent", "stratified", "multijitter", "ldsampler"):
            errs = [f["rel"] for f in scene["mitsuba"] if f["sampler"] == sampler]
            assert errs == sorted(errs, reverse=True) and len(errs) >= 2
    for row in ("| Mitsuba direct, ldsampler |", "| warprt analytic + light_spread |", "| warprt samples + adaptive |",
                "### scenes/envmap.xml", "SSIM 0.999 | mean rel. error 1% |"):
        assert row in text, row
    rows = equal_error.target_rows(data)  # the report's Targets rows: met only where both ratios are <= 0.5
    assert len(rows) == 2 and all(r[2] in ("met", "not met") and "SSIM 0.998" in r[1] and "SSIM 0.999" in r[1]
                                  for r in rows)


def _targets_row(text: str, start: str) -> list[str]:
    line = next(l for l in text.splitlines() if l.startswith(f"| {start}"))
    return [c.strip() for c in line.strip("|").split("|")]


def test_targets_say_met_exactly_where_the_ratios_allow():
    """Two scenes at 0.5x and 1.25x Mitsuba's warm time (warprt's default) and 0.5x and 0.83x of the frame before
    the shortcuts fail both warm targets on the second; a cold run at 0.8x Mitsuba's meets its target, one at 1.5x
    does not; rays per second at 60% and 40% of Embree's fail on the 40%."""
    from benchmarks.__main__ import targets

    size = {"width": 1024, "height": 768}
    h2h = {"rows": [{"scene": "a", **size, "warprt_warm": 0.04, "hybrid_warm": 0.05, "mitsuba_llvm_warm": 0.1, "before_warm": 0.1},
                    {"scene": "b", **size, "warprt_warm": 0.2, "hybrid_warm": 0.25, "mitsuba_llvm_warm": 0.2, "before_warm": 0.3}]}
    cold = {"default": {"warprt": 0.4, "mitsuba": 0.5, "ratio": 0.8}, "files": {"warprt": 0.9, "mitsuba": 0.6, "ratio": 1.5},
            "size": [1024, 768]}
    cast = {"rows": [{"triangles": 320, "warp_closest_1t": 6.0, "mitsuba_closest_1t": 10.0,
                      "warp_any_1t": 8.0, "mitsuba_any_1t": 10.0},
                     {"triangles": 1280, "warp_closest_1t": 7.0, "mitsuba_closest_1t": 10.0,
                      "warp_any_1t": 4.0, "mitsuba_any_1t": 10.0}]}
    text = targets(h2h, cast, cold=cold)
    assert _targets_row(text, "Warm 1024x768 frame, every scene: <= 0.6x")[1:] == [
        "0.50x to 0.83x (worst: b); against Mitsuba 0.50x to 1.25x", "not met"]
    assert _targets_row(text, "Warm 1024x768 frame, every scene: <= 1.0x")[1:] == [
        "0.50x to 1.25x (every ray traced: 0.40x to 1.00x)", "not met"]
    assert _targets_row(text, "Cold `warprt render` of the default scene")[1:] == ["0.40 s against 0.50 s: 0.80x", "met"]
    assert _targets_row(text, "Cold `warprt render` of five PLY/OBJ files")[1:] == ["0.90 s against 0.60 s: 1.50x", "not met"]
    assert _targets_row(text, "Rays")[1:] == ["closest hit 60% to 70%, any hit 40% to 80% (320 to 1,280 triangles, one thread each)", "not met"]
    h2h["rows"].pop()
    cast["rows"].pop()
    text = targets(h2h, cast)
    assert _targets_row(text, "Warm 1024x768 frame, every scene: <= 0.6x")[-1] == "met"
    assert _targets_row(text, "Warm 1024x768 frame, every scene: <= 1.0x")[-1] == _targets_row(text, "Rays")[-1] == "met"


def test_warm_targets_split_opaque_scenes_from_glass_at_their_own_bounds():
    """Issue 23's warm targets: opaque scenes <= 2.5x Mitsuba, glass scenes < 1.0x. Opaque at 2.4x and 2.6x fail
    on the 2.6x; glass at 0.99x meets its bound and 1.0x does not (strict); the rows list every scene, worst first."""
    from benchmarks.__main__ import targets

    size = {"width": 1024, "height": 768}
    row = lambda name, ratio, glass: {"scene": name, **size, "warprt_warm": ratio, "hybrid_warm": ratio,
                                      "mitsuba_llvm_warm": 1.0, "before_warm": ratio, "glass": glass}
    cast = {"rows": [{"triangles": 320, "warp_closest_1t": 6.0, "mitsuba_closest_1t": 10.0,
                      "warp_any_1t": 8.0, "mitsuba_any_1t": 10.0}]}
    text = targets({"rows": [row("a", 2.4, False), row("b", 2.6, False), row("g", 0.99, True)]}, cast)
    assert _targets_row(text, "Warm 1024x768 frame, every opaque scene")[1:] == ["b 2.60, a 2.40", "not met"]
    assert _targets_row(text, "Warm 1024x768 frame, every glass scene")[1:] == ["g 0.99", "met"]
    text = targets({"rows": [row("a", 2.5, False), row("g", 1.0, True)]}, cast)
    assert _targets_row(text, "Warm 1024x768 frame, every opaque scene")[-1] == "met"
    assert _targets_row(text, "Warm 1024x768 frame, every glass scene")[-1] == "not met"


def test_shadow_ray_diagnostic_casts_the_renderers_own_shadow_rays():
    """benchmarks.shadow_rays rebuilds the shadow rays of every pixel centre's first hit: as many as the
    renderer itself counts with one ray level, and on the Cornell box some, not all, are occluded."""
    import warprt
    from benchmarks import shadow_rays

    path = Path(__file__).resolve().parents[2] / "scenes" / "cornell.toml"
    row = shadow_rays.run(48, 36, repeat=1, scenes=[path])["rows"][0]
    scene = warprt.load_scene(path).with_camera(width=48, height=36)
    stats = warprt.render(scene.with_render(max_depth=1, spp=1)).stats
    assert row["shadow_rays"] == stats.rays["shadow"] > 0
    assert 0 < row["occluded"] < row["shadow_rays"]
    assert "| cornell |" in shadow_rays.report({"width": 48, "height": 36, "repeat": 1, "rows": [row]})


def test_only_replaces_its_section_and_says_so_in_the_header():
    """`python -m benchmarks --only NAME`: the section from its '## ' heading to the next is replaced, the
    others are left as they are, and the header carries one line per section run again (a second run's
    line replaces the first's); a report without the section is refused in one line."""
    from benchmarks.__main__ import replace_section

    report = ("# report\n\nGenerated by `python -m benchmarks` at commit a.\n## One\n\nold one\n\n## Two\n\nold two\n\n"
              "## Three\n\nthree\n")
    note = lambda c: f"Section \"Two\" run again alone by `python -m benchmarks --only two` at commit {c}."  # noqa: E731
    once = replace_section(report, "## Two\n\nnew two\n", "two", note("b"))
    assert "old two" not in once and "new two" in once and "old one" in once and "## Three\n\nthree" in once
    twice = replace_section(once, "## Two\n\nnewer two\n", "two", note("c"))
    assert twice.count("--only two") == 1 and "commit c." in twice and "new two\n" not in twice
    assert twice.index("Generated by") < twice.index("--only two") < twice.index("## One")
    with pytest.raises(SystemExit, match="no section '## Four'"):
        replace_section(report, "## Four\n\nfour\n", "four", "x")


def test_only_adds_a_missing_section_and_replaces_its_target_rows():
    """`--only gradient_cost` on a report without its section adds it before "What was tried" (the header
    saying so), and its Targets rows replace the rows of the same target (up to the first comma or colon)
    or are added at the table's end, the other rows left as they are."""
    from benchmarks.__main__ import add_section, replace_target_rows

    report = ("# report\n\nGenerated by `python -m benchmarks` at commit a.\n## Targets\n\n| target | measured | |\n"
              "|---|---|---|\n| Old target, warm | 1x | met |\n| Backward pass, warm 8x6 | 9x | not met |\n\n"
              "## One\n\none\n\n## What was tried to make warprt fast\n\ntried\n")
    rows = [("Backward pass, warm 16x12", "2x", "met"), ("Gradient frame: against Mitsuba", "1x", "measured")]
    table = replace_target_rows(report, rows)
    assert "| Backward pass, warm 16x12 | 2x | met |" in table and "9x" not in table
    assert "| Old target, warm | 1x | met |" in table
    assert table.index("| Gradient frame: against Mitsuba |") < table.index("## One")
    added = add_section(table, "## Gradients\n\ncost\n", "gradient_cost", "Section \"Gradients\" run again.")
    assert added.index("## One") < added.index("## Gradients") < added.index("## What was tried")
    assert added.index("Generated by") < added.index("Section \"Gradients\" run again.") < added.index("## Targets")
