"""AOV files, written by `warprt render --aov` and read back: .npz holds the arrays as render() returns
them, .exr one multi-channel file (layer.channel names, IDs as UINT), .png the PNG unchanged plus one
EXR per AOV beside it; every file written through a temporary one, none left over."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import warprt
from marks import slow
from scenekit import write_scene
from warprt.image import AOVS, read_aovs, read_image

SRC = str(Path(__file__).resolve().parents[2] / "src")
SCENE = {
    "camera": {"eye": [0.0, 1.0, 5.0], "center": [0.0, 0.5, 0.0], "fovy": 50.0, "width": 24, "height": 16},
    "render": {"spp": 4},
    "lights": [{"position": [2.0, 4.0, 3.0]}],
    "materials": {"red": {"kd": [0.8, 0.1, 0.1]}},
    "objects": [{"shape": "plane", "size": [4.0, 4.0]}, {"shape": "sphere", "radius": 0.6, "subdivisions": 2,
                                                         "translate": [0.0, 0.6, 0.0], "material": "red", "smooth": True}],
}
CHANNELS = {"R", "G", "B", "depth.Z", "normal.X", "normal.Y", "normal.Z", "albedo.R", "albedo.G", "albedo.B",
            "position.X", "position.Y", "position.Z", "uv.U", "uv.V", "object.id", "material.id", "face.id", "coverage.A"}


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """One render's files in each format, and the render itself (as warprt.render gives it)."""
    folder = tmp_path_factory.mktemp("aovs")
    scene_path = write_scene(folder, SCENE, "s.toml")
    env = {**os.environ, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")}
    for out, extra in (("all.npz", ["--aov", ",".join(AOVS)]), ("all.exr", ["--aov", ",".join(AOVS)]),
                       ("all.png", ["--aov", "depth,object,normal"]), ("plain.png", [])):
        r = subprocess.run([sys.executable, "-m", "warprt", "render", "s.toml", "-o", out, "-q", *extra],
                           cwd=folder, env=env, capture_output=True, text=True, timeout=300)
        assert r.returncode == 0 and r.stderr == "", r.stderr
    return folder, warprt.render(warprt.load_scene(scene_path), aovs=list(AOVS))


@slow
def test_npz_holds_the_colour_and_every_aov_exactly(written):
    folder, result = written
    with np.load(folder / "all.npz") as z:
        assert set(z.files) == {"color", *AOVS}
        assert np.array_equal(z["color"], result.image)
        for name in AOVS:
            assert z[name].dtype == result.aovs[name].dtype and np.array_equal(z[name], result.aovs[name]), name


@slow
def test_exr_is_one_file_of_named_channels(written):
    import OpenEXR

    folder, result = written
    with OpenEXR.File(str(folder / "all.exr"), separate_channels=True) as f:
        channels = f.channels()
        assert set(channels) == CHANNELS
        assert {n for n, c in channels.items() if c.pixels.dtype == np.uint32} == {"object.id", "material.id", "face.id"}
        assert np.array_equal(channels["depth.Z"].pixels, result.aovs["depth"])  # +inf where nothing is hit
        assert np.isinf(channels["depth.Z"].pixels).any()
        assert np.array_equal(channels["normal.Y"].pixels, result.aovs["normal"][..., 1])
        # IDs keep their int32 bits: -1 (no hit) is 4294967295.
        assert np.array_equal(channels["object.id"].pixels.view(np.int32), result.aovs["object"])
        assert (channels["object.id"].pixels == 2**32 - 1).any()
    aovs = read_aovs(folder / "all.exr")
    assert np.array_equal(read_image(folder / "all.exr"), result.image)
    for name in AOVS:
        expected = result.aovs[name].astype(np.float32) if name == "position" else result.aovs[name]
        assert np.array_equal(aovs[name], expected), name


@slow
def test_png_is_unchanged_and_each_aov_is_an_exr_beside_it(written):
    import OpenEXR

    folder, result = written
    assert (folder / "all.png").read_bytes() == (folder / "plain.png").read_bytes()
    beside = sorted(p.name for p in folder.glob("all.*.exr"))
    assert beside == ["all.depth.exr", "all.normal.exr", "all.object.exr"]
    with OpenEXR.File(str(folder / "all.normal.exr"), separate_channels=True) as f:
        assert set(f.channels()) == {"normal.X", "normal.Y", "normal.Z"}
    aovs = read_aovs(folder / "all.png")
    assert aovs.keys() == {"depth", "object", "normal"}
    assert all(np.array_equal(aovs[n], result.aovs[n]) for n in aovs)


@slow
def test_no_temporary_file_is_left(written):
    folder, _ = written
    assert sorted(p.name for p in folder.iterdir() if p.name.startswith(".")) == []


def test_the_aovs_of_a_file_are_those_asked_for(tmp_path):
    result = warprt.render(warprt.load_scene(write_scene(tmp_path, SCENE, "s.toml")), aovs=["coverage", "uv"])
    from warprt.image import write_image

    write_image(tmp_path / "f.npz", result.image, aovs=result.aovs)
    with np.load(tmp_path / "f.npz") as z:
        assert set(z.files) == {"color", "coverage", "uv"}
    assert 0.0 < result.aovs["coverage"].mean() < 1.0
