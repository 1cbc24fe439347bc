"""The tests' scene-file writer (scenekit.write_scene): the TOML it writes reads back, through tomllib,
as the dict it was given, and through load_scene as the scene make_scene builds from that dict."""

import math
import tomllib

import numpy as np
import pytest

import warprt
from scenekit import make_scene, scene_doc, to_toml, write_scene

DOC = {
    "camera": {"eye": [0.0, 1.5, 5.0], "center": [0, 0, 0], "fovy": 45.0, "width": 32, "height": 24},
    "render": {"ambient": [0.1, 0.2, 0.3], "max_depth": 3, "shadows": False, "effects": ["ambient", "diffuse"]},
    "lights": [{"position": [4.0, 6.0, 4.0]}, {"position": [-1.0, 2.0, 3.0], "color": [0.5, 0.5, 0.5]}],
    "materials": {"red": {"kd": [0.7, 0.1, 0.1], "ks": [0.5] * 3, "shininess": 32.0, "reflectivity": 0.25},
                  "thing/odd name": {"kd": [0.1, 0.2, 0.3]}},
    "objects": [{"shape": "sphere", "subdivisions": 2, "material": "red", "smooth": True, "translate": [1e-300, -2.5e7, 0.1]},
                {"shape": "box", "size": [1.0, 2.0, 3.0], "material": "thing/odd name", "name": 'a "quoted" \\ name é'}],
}


def test_the_toml_reads_back_as_the_dict():
    assert tomllib.loads(to_toml(DOC)) == DOC


def test_nested_tables_empty_tables_and_top_level_values_read_back():
    doc = {"title": "x", "lights": [], "materials": {}, "objects": [{"shape": "box", "extra": {"a": 1, "b": [{"c": 2}]}}, {}]}
    assert tomllib.loads(to_toml(doc)) == doc


def test_nan_inf_and_numpy_values_are_written_as_toml():
    doc = {"camera": {"eye": [math.nan, math.inf, -math.inf], "width": np.int64(7), "center": np.array([0.5, 1.0, 2.0])}}
    back = tomllib.loads(to_toml(doc))["camera"]
    assert math.isnan(back["eye"][0]) and back["eye"][1:] == [math.inf, -math.inf]
    assert back["width"] == 7 and back["center"] == [0.5, 1.0, 2.0]


def test_a_value_toml_cannot_hold_is_refused():
    with pytest.raises(TypeError):
        to_toml({"camera": {"eye": object()}})


def test_the_written_file_loads_as_make_scene_builds_it(tmp_path):
    objects, materials = DOC["objects"], DOC["materials"]
    path = write_scene(tmp_path, scene_doc(objects, materials, DOC["lights"], DOC["camera"], **DOC["render"]), "s.toml")
    assert path == tmp_path / "s.toml"
    loaded, built = warprt.load_scene(path), make_scene(objects, materials, DOC["lights"], DOC["camera"], **DOC["render"])
    assert (loaded.camera, loaded.render, loaded.lights, loaded.materials) == (built.camera, built.render, built.lights,
                                                                               built.materials)
    assert [o.name for o in loaded.objects] == [o.name for o in built.objects]
    for a, b in zip(loaded.objects, built.objects):
        assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)
        assert (a.material, a.smooth) == (b.material, b.smooth)
