"""The command as users meet it: the flags pbrt and Mitsuba users expect, --help with examples,
`warprt info`, statistics as JSON with memory, and the progress line on a real pseudo-terminal."""

import json
import os
import pty
import re
import select
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from marks import slow
from scenekit import write_scene
from warprt.image import read_image

SRC = str(Path(__file__).resolve().parents[2] / "src")
ENV = {**os.environ, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")}


def run(*args, cwd=None, env=None):
    return subprocess.run([sys.executable, "-m", "warprt", *args], cwd=cwd, env={**ENV, **(env or {})},
                          capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=300)


def run_on_terminal(*args, cwd=None, env=None, timeout=300):
    """The command with its stderr on a pseudo-terminal (stdout a pipe): what a user at a terminal sees."""
    master, slave = pty.openpty()
    p = subprocess.Popen([sys.executable, "-m", "warprt", *args], cwd=cwd, env={**ENV, **(env or {})},
                         stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=slave)
    os.close(slave)
    seen, deadline = [], time.monotonic() + timeout
    while time.monotonic() < deadline:
        ready, _, _ = select.select([master], [], [], 1.0)
        if ready:
            try:
                data = os.read(master, 65536)
            except OSError:  # the child closed the terminal
                break
            if not data:
                break
            seen.append(data)
        elif p.poll() is not None:
            break
    os.close(master)
    out = p.stdout.read().decode()
    p.stdout.close()
    p.wait(timeout=30)
    return p.returncode, b"".join(seen).decode(errors="replace"), out


FLAGS = ["-o", "--output", "--spp", "--width", "--height", "--max-depth", "--light-samples", "--adaptive", "--no-shadows", "--threads",
         "--device", "--set", "--stats", "--stats-file", "-q", "--quiet", "--debug"]


def test_help_lists_the_flags_with_examples():
    r = run("render", "--help")
    assert r.returncode == 0
    for flag in FLAGS:
        assert re.search(rf"(^|[\s,]){re.escape(flag)}\b", r.stdout), flag
    assert "{cpu,cuda}" in r.stdout
    assert "examples:" in r.stdout and "warprt render" in r.stdout and "--set camera.fovy=30" in r.stdout
    top = run("--help")
    assert top.returncode == 0 and "--version" in top.stdout and "render" in top.stdout and "info" in top.stdout


def test_version():
    import warprt

    r = run("--version")
    assert r.returncode == 0 and r.stdout.strip() == f"warprt {warprt.__version__}"


SCENE = {
    "camera": {"eye": [0.0, 0.0, 6.0], "center": [0.0, 0.0, 0.0], "width": 48, "height": 32},
    "render": {"max_depth": 2},
    "lights": [{"position": [3.0, 4.0, 5.0]}],
    "materials": {"red": {"kd": [0.8, 0.1, 0.1], "reflectivity": 0.3}},
    "objects": [{"shape": "sphere", "subdivisions": 2, "material": "red"},
                {"shape": "box", "size": [1.0, 1.0, 1.0], "translate": [2.5, 0.0, -1.0]}],
}


@pytest.fixture
def scene_file(tmp_path):
    return write_scene(tmp_path, SCENE, "s.toml")


@slow
def test_flags_reach_the_render(scene_file, tmp_path):
    out = tmp_path / "o.npy"
    r = run("render", str(scene_file), "-o", str(out), "--width", "20", "--height", "10", "--spp", "4",
            "--max-depth", "1", "--no-shadows", "--threads", "1", "--set", "camera.fovy=30", "--stats")
    assert r.returncode == 0, r.stderr
    stats = json.loads(r.stdout)
    assert (stats["width"], stats["height"], stats["spp"], stats["max_depth"], stats["threads"]) == (20, 10, 4, 1, 1)
    assert "shadows" not in stats["effects"].split(",") and "reflection" not in stats["effects"].split(",")
    # spp 4: exactly 4 primary rays per pixel; no shadow or reflection rays.
    assert stats["rays"] == {"primary": 20 * 10 * 4, "shadow": 0, "reflection": 0, "refraction": 0, "total": 800}
    assert np.load(out).shape == (10, 20, 3)


@slow
def test_stats_file_matches_stats_and_reports_memory(scene_file, tmp_path):
    r = run("render", str(scene_file), "-o", str(tmp_path / "o.png"), "--stats", "--stats-file", str(tmp_path / "s.json"))
    assert r.returncode == 0, r.stderr
    printed, written = json.loads(r.stdout), json.loads((tmp_path / "s.json").read_text())
    assert printed.keys() == written.keys()
    assert written["triangles"] == 20 * 4**2 + 12
    mem = written["memory"]
    geo = mem["geometry"]
    # The index array is 3 int32 per triangle; the per-triangle tables are 2 int32 per triangle.
    assert geo["indices"] == 12 * written["triangles"] and geo["per_triangle"] == 8 * written["triangles"]
    assert geo["total"] == sum(v for k, v in geo.items() if k != "total")
    assert mem["image"] == 48 * 32 * (12 + 12)  # float32 RGB and three int32 ray counts per pixel
    assert mem["peak_rss"] > geo["total"]
    assert read_image(tmp_path / "o.png").shape == (32, 48, 3)


@slow
def test_info_summarises_the_scene(scene_file):
    r = run("info", str(scene_file))
    assert r.returncode == 0, r.stderr
    lines = dict(line.split(None, 1) for line in r.stdout.splitlines() if line and not line.startswith(" "))
    assert lines["triangles"] == f"{20 * 16 + 12:,}"
    assert lines["objects"] == "2" and lines["lights"] == "1"
    assert set(lines["materials"].split(", ")) == {"red", "default"}
    lo, hi = (np.array(json.loads(s)) for s in lines["bounds"].split(" .. "))
    np.testing.assert_allclose(lo, [-1.0, -1.0, -1.5])
    np.testing.assert_allclose(hi, [3.0, 1.0, 1.0])
    assert lines["effects"] == "ambient,diffuse,specular,shadows,reflection"
    assert re.match(r"[\d.]+ (B|KiB|MiB) geometry: vertices .*, indices .*, bvh .*; peak RSS [\d.]+ MiB", lines["memory"])


@slow
def test_mesh_file_renders_with_stats_file_and_quiet(tmp_path):
    """A bare mesh, framed automatically; -q prints nothing at all."""
    (tmp_path / "t.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    r = run("render", "t.obj", "-o", "t.exr", "--width", "24", "--height", "16", "-q", "--stats-file", "st.json",
            cwd=tmp_path)
    assert r.returncode == 0 and r.stdout == "" and r.stderr == ""
    assert json.loads((tmp_path / "st.json").read_text())["triangles"] == 1
    assert read_image(tmp_path / "t.exr").shape == (16, 24, 3)


# --- the progress line ------------------------------------------------------------------------------

LONG = ["--width", "640", "--height", "480", "--spp", "9", "--threads", "1"]  # ~10 M rays: seconds on one core


@slow
def test_progress_line_on_a_terminal(tmp_path):
    code, err, out = run_on_terminal("render", "-o", str(tmp_path / "p.png"), *LONG)
    assert code == 0, err
    frames = [f for f in re.split(r"[\r\n]", err) if "tiles" in f]
    assert frames, err
    last = frames[-1]
    m = re.search(r"\[[#.]{24}\] (\d+)/(\d+) tiles  ([\d.]+ [kMG]?)rays/s  [\d.:]+ s? ?elapsed, ([\d.:]+ s?|--) ?left", last)
    assert m, last
    assert 0 <= int(m[1]) <= int(m[2]) == 16
    assert "\x1b[K" in err  # each redraw clears the rest of the line
    assert err.rstrip().splitlines()[-1].split("\x1b[K")[-1].startswith("wrote ")  # the bar is cleared at the end


@slow
def test_no_progress_for_a_short_render_on_a_terminal(tmp_path):
    code, err, _ = run_on_terminal("render", "-o", str(tmp_path / "p.png"), "--width", "16", "--height", "12")
    assert code == 0
    assert "tiles" not in err and err.startswith("wrote ")


@slow
@pytest.mark.parametrize("where", ["pipe", "quiet"])
def test_progress_silent_off_terminal_and_with_quiet(tmp_path, where):
    """Even with the line due at once (WARPRT_PROGRESS_AFTER=0): a pipe gets none, -q gets nothing."""
    env = {"WARPRT_PROGRESS_AFTER": "0"}
    args = ["render", "-o", str(tmp_path / "p.png"), "--width", "64", "--height", "48"]
    if where == "pipe":
        r = run(*args, env=env)
        assert r.returncode == 0 and "tiles" not in r.stderr and r.stderr.startswith("wrote ")
    else:
        code, err, _ = run_on_terminal(*args, "-q", env=env)
        assert code == 0 and err == ""
    # The same render on a terminal does show it: the two cases above are silent for their reason.
    code, err, _ = run_on_terminal(*args, env=env)
    assert code == 0 and "tiles" in err


@slow
def test_an_open_glass_mesh_is_one_warning_line_and_the_render_goes_on(tmp_path):
    """A dielectric must be closed for its inside to be known; an open one still renders (each crossing
    switches the medium by the winding), with one line on stderr saying so."""
    write_scene(tmp_path, {"camera": {"eye": [0.0, 1.0, 5.0], "center": [0.0, 0.0, 0.0], "width": 16, "height": 12},
                           "render": {"max_depth": 3}, "materials": {"glass": {"ior": 1.5}},
                           "objects": [{"name": "pane", "shape": "plane", "material": "glass"}]}, "s.toml")
    r = run("render", "s.toml", "-o", "out.png", "--stats", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stderr == ("warprt: warning: s.toml: objects[0]: 'pane' has ior but is not closed (4 open or "
                        "inconsistently wound edges): rays leaving through them stay inside\n")
    assert (tmp_path / "out.png").exists()
    rays = json.loads(r.stdout)["rays"]
    assert rays["refraction"] > 0 and rays["total"] == sum(v for k, v in rays.items() if k != "total")
