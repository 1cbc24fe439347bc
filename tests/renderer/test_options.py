"""One schema for the options: RenderOptions says each option once, the command line's flags are made from
it, the first release's spellings still work with one warning, and an option the algorithm cannot honour
is refused rather than dropped."""

import argparse
import subprocess
import sys
import warnings

import numpy as np
import pytest

import warprt
from warprt.cli import build_parser
from warprt.options import RENAMED, RenderOptions


def small():
    return warprt.load_scene().with_camera(width=24, height=18)


def render_flags() -> dict:
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    return {a.dest: a for a in sub.choices["render"]._actions if a.help != argparse.SUPPRESS}


def test_every_option_the_command_line_offers_is_a_flag_with_the_schemas_choices_and_help():
    flags = render_flags()
    offered = [o for o in RenderOptions.schema() if o["cli"]]
    assert {"threads", "device", "effects", "algorithm", "primary_query", "shadow_query", "reflection_query",
            "aovs"} == {o["name"] for o in offered}
    for o in offered:
        action = flags[o["name"]]
        assert action.help.startswith(o["help"])
        assert (action.choices and list(action.choices)) == (o["choices"] and list(o["choices"]))
        if o["choices"]:
            assert action.default == o["default"]
    assert all(o["help"] for o in RenderOptions.schema())


def test_a_planted_option_becomes_a_flag(monkeypatch):
    """The negative control: a field added to the schema shows up in the parser without touching cli.py."""
    import warprt.cli as cli

    planted = {"name": "photons", "default": None, "help": "planted", "choices": None, "metavar": "N", "cli": True,
               "listed": False, "cli_name": None, "check_choices": True, "type": int}
    monkeypatch.setattr(cli, "RENDER_OPTIONS", cli.RENDER_OPTIONS + [planted])
    assert "photons" in render_flags()


@pytest.mark.parametrize("old", sorted(set(RENAMED) - {"tile"}))
def test_an_old_spelling_warns_once_and_renders_the_same(old):
    new = RENAMED[old]
    value = {"primary_query": "raytrace", "shadow_query": "bvh", "reflection_query": "bvh"}[new]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        by_old = warprt.render(small(), **{old: value})
    deprecations = [w for w in caught if issubclass(w.category, DeprecationWarning)]
    assert len(deprecations) == 1 and f"'{old}' is now '{new}'" in str(deprecations[0].message)
    assert deprecations[0].filename == __file__  # it points at the caller's line
    by_new = warprt.render(small(), **{new: value})
    assert np.array_equal(by_old.image, by_new.image)


def test_both_spellings_at_once_is_an_error():
    with pytest.raises(TypeError, match="both 'shadows' and its new name 'shadow_query'"):
        warprt.render(small(), shadows="bvh", shadow_query="grid")


def test_an_unknown_option_is_a_type_error_naming_it():
    with pytest.raises(TypeError, match="unexpected keyword argument 'shadow_quer'"):
        warprt.Renderer(small(), shadow_quer="bvh")


@pytest.mark.parametrize("option", [{"report_truncated": True}, {"pixel_tile": (4, 4)}, {"aovs": ["depth"]}])
def test_the_zbuffer_refuses_what_only_the_tracer_honours(option):
    name = next(iter(option))
    with pytest.raises(warprt.SceneError, match=rf"render\(\): {name}: .* not with algorithm='zbuffer'"):
        warprt.render(small(), algorithm="zbuffer", **option)


def test_the_zbuffers_raster_tile_is_its_own_option():
    from warprt.image import render_zbuffer

    scene = small()
    a = warprt.render(scene, algorithm="zbuffer", raster_tile=8)
    with pytest.warns(DeprecationWarning, match="'tile' is now 'raster_tile'"):
        b = render_zbuffer(scene, tile=8)
    assert np.array_equal(a.image, b.image) and np.array_equal(a.image, warprt.render(scene, algorithm="zbuffer").image)


def test_an_old_flag_warns_in_one_line_and_renders(tmp_path):
    out = tmp_path / "o.png"
    r = subprocess.run([sys.executable, "-m", "warprt", "render", "-o", str(out), "--width", "24", "--height", "18",
                        "--shadow-rays", "bvh", "--stats"], capture_output=True, text=True)
    assert r.returncode == 0 and out.exists()
    assert r.stderr.strip() == ("warprt: warning: command line: --shadow-rays: is now --shadow-query "
                                "(--shadow-rays goes in the next release)")
    assert '"shadow_query": "bvh"' in r.stdout
