"""`python -m benchmarks.figures` regenerates every figure: a quick run into a temporary folder."""

import json

from PIL import Image

from benchmarks import figures
from marks import slow


@slow
def test_quick_run_writes_every_figure(tmp_path):
    figures.main(["--quick", "--repeat", "1", "-o", str(tmp_path)])
    for name in ("fig6_effects.png", "fig7_zbuffer_vs_raytracing.png", "fig8_gallery.png", "cost_growth.png"):
        with Image.open(tmp_path / name) as im:
            assert im.width >= 300 and im.height >= 200, name
    results = json.loads((tmp_path / "figures.json").read_text())
    assert [p["label"][:3] for p in results["fig6"]["panels"]] == ["(a)", "(b)", "(c)", "(d)", "(e)", "(f)", "(g)"]
    assert results["fig6"]["panels"][-1]["rays"]["refraction"] > 0
    assert len(results["fig7"]["views"]) >= 3
    gallery = {s["scene"]: s["triangles"] for s in results["fig8"]["scenes"]}
    for scene in ("scenes/seed.toml", "scenes/whitted.toml", "scenes/cornell.toml", "scenes/mirrors.toml",
                  "scenes/bunny.toml", "scenes/knot.toml"):
        assert scene in gallery
    whitted = next(s for s in results["fig8"]["scenes"] if s["scene"] == "scenes/whitted.toml")
    assert whitted["rays"]["refraction"] > 0 and whitted["rays"]["reflection"] > 0
    assert gallery["scenes/knot.toml"] >= 100_000
    counts = [r["triangles"] for r in results["growth"]["runs"]]
    assert min(counts) < 1000 and max(counts) > 50_000
    assert "![Figure 7](fig7_zbuffer_vs_raytracing.png)" in (tmp_path / "README.md").read_text()
