"""[[lights]] in the scene file: each field of the shared Light schema read from a real file, the seed's
defaults kept, --set reaching the new fields, and every bad field one SceneError naming the file and
lights[i].field (through the command: one line, exit 2, no image)."""

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

import warprt
from scenekit import scene_doc, write_scene
from warprt.scene import Light

SRC = str(Path(__file__).resolve().parents[2] / "src")
FLOOR = {"shape": "plane", "size": [4.0, 4.0], "material": "m"}
CAMERA = {"eye": [0.0, 3.0, 4.0], "center": [0.0, 0.0, 0.0], "width": 16, "height": 12}


def scene_file(tmp_path, *lights):
    return write_scene(tmp_path, scene_doc([FLOOR], {"m": {"kd": [0.5, 0.5, 0.5]}}, lights, CAMERA))


def test_every_field_is_read_as_the_schema_says(tmp_path):
    path = scene_file(tmp_path,
                      {"type": "spot", "position": [0.0, 2.0, 0.0], "target": [1.0, 0.0, 0.0], "cutoff_angle": 30.0,
                       "beam_width": 12.5, "falloff": "inverse_square", "color": [2.0, 1.0, 0.5]},
                      {"type": "directional", "direction": [0.0, -3.0, 4.0], "color": [0.2, 0.2, 0.2]},
                      {"position": [1.0, 1.0, 1.0]})
    spot, sun, point = warprt.load_scene(path).lights
    assert replace(spot, direction=None) == Light(position=(0.0, 2.0, 0.0), color=(2.0, 1.0, 0.5), type="spot",
                                                  cutoff_angle=30.0, beam_width=12.5, falloff="inverse_square")
    assert spot.direction == pytest.approx((1 / 5**0.5, -2 / 5**0.5, 0.0), rel=1e-15)
    assert sun.position is None and sun.direction == pytest.approx((0.0, -0.6, 0.8)) and sun.falloff == "none"
    assert point == Light(position=(1.0, 1.0, 1.0))
    assert (point.type, point.falloff, point.direction, point.beam_width) == ("point", "none", None, None)
    assert Light(type="spot", position=(0, 0, 0), direction=(0, 0, -1), cutoff_angle=40.0).beam == 30.0


def test_set_reaches_the_new_fields(tmp_path):
    path = scene_file(tmp_path, {"position": [0.0, 2.0, 0.0]})
    scene = warprt.load_scene(path, {"lights[0].type": "spot", "lights[0].direction": [0.0, -1.0, 0.0],
                                     "lights[0].cutoff_angle": 35.0})
    assert scene.lights[0] == Light(position=(0.0, 2.0, 0.0), type="spot", direction=(0.0, -1.0, 0.0),
                                    cutoff_angle=35.0)


# (the light table, the field named, words of the message)
BAD = [
    ({"type": "laser", "position": [0, 2, 0]}, "type", "expected one of 'point', 'spot', 'directional'"),
    ({"position": [0, 2, 0], "falloff": "linear"}, "falloff", "expected one of 'none', 'inverse_square'"),
    ({"type": "spot", "position": [0, 2, 0]}, "direction", "is required"),
    ({"type": "spot", "direction": [0, -1, 0]}, "position", "is required"),
    ({"type": "directional"}, "direction", "is required"),
    ({"type": "directional", "position": [0, 2, 0], "direction": [0, -1, 0]}, "position", "has no position"),
    ({"position": [0, 2, 0], "direction": [0, -1, 0]}, "direction", "a cone is a spot"),
    ({"position": [0, 2, 0], "cutoff_angle": 30.0}, "cutoff_angle", "only a spot light has it"),
    ({"type": "directional", "direction": [0, -1, 0], "beam_width": 5.0}, "beam_width", "only a spot light has it"),
    ({"type": "spot", "position": [0, 2, 0], "direction": [0, -1, 0], "cutoff_angle": 0.0}, "cutoff_angle",
     "expected a number > 0"),
    ({"type": "spot", "position": [0, 2, 0], "direction": [0, -1, 0], "cutoff_angle": 20.0, "beam_width": 25.0},
     "beam_width", "expected a number <= 20"),
    ({"type": "spot", "position": [0, 2, 0], "target": [0, 2, 0]}, "target", "must differ from position"),
    ({"type": "spot", "position": [0, 2, 0], "target": [0, 0, 0], "direction": [0, -1, 0]}, "target", "not both"),
    ({"type": "spot", "position": [0, 2, 0], "direction": [0, 0, 0]}, "direction", "must not be the zero vector"),
    ({"type": "spot", "position": [0, 2, 0], "direction": "down"}, "direction", "expected a list of 3 numbers"),
]


@pytest.mark.parametrize("light, field, words", BAD, ids=[f"{b[1]}-{i}" for i, b in enumerate(BAD)])
def test_a_bad_field_names_the_file_and_the_field(tmp_path, light, field, words):
    path = scene_file(tmp_path, {"position": [1.0, 1.0, 1.0]}, light)
    with pytest.raises(warprt.SceneError) as e:
        warprt.load_scene(path)
    assert e.value.source == str(path) and e.value.field == f"lights[1].{field}" and words in e.value.message


@pytest.mark.parametrize("change, field", [
    (dict(type="spot"), "direction"),
    (dict(type="directional", direction=(0.0, -1.0, 0.0)), "position"),
    (dict(cutoff_angle=30.0), "cutoff_angle"),
    (dict(type="spot", direction=(0.0, -1.0, 0.0), beam_width=30.0), "beam_width"),
    (dict(falloff="quadratic"), "falloff"),
])
def test_a_scene_built_in_python_is_held_to_the_same_rules(tmp_path, change, field):
    scene = warprt.load_scene(scene_file(tmp_path, {"position": [0.0, 2.0, 0.0]}))
    scene.lights = [replace(scene.lights[0], **change)]
    with pytest.raises(warprt.SceneError) as e:
        warprt.render(scene)
    assert e.value.field == f"lights[0].{field}"


def test_the_command_reports_a_bad_light_in_one_line_and_writes_nothing(tmp_path):
    path = scene_file(tmp_path, {"type": "spot", "position": [0, 2, 0], "direction": [0, -1, 0], "beam_width": 30.0})
    out = tmp_path / "out.png"
    run = subprocess.run([sys.executable, "-m", "warprt", "render", str(path), "-o", str(out)], capture_output=True,
                         text=True, env={"PYTHONPATH": SRC, "PATH": "/usr/bin:/bin"})
    assert run.returncode == 2 and not out.exists()
    assert run.stderr.strip().splitlines() == [
        f"warprt: error: {path}: lights[0].beam_width: expected a number <= 20, got 30"]
