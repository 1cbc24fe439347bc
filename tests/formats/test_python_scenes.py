"""Scenes built in Python are the scenes their files describe: warprt.load_dict of a scene file's dict,
Scene's defaults and SceneObject's constructors each equal, field by field and array by array, what
load_scene reads from the same scene written as a real file (scenekit.write_scene); bad input is the
file's SceneError. The expected side is always the file reader's."""

import copy
import dataclasses
import tomllib
from pathlib import Path

import numpy as np
import pytest

import warprt
from warprt.scene import DEFAULT_MATERIAL, validate_scene
from scenekit import write_scene

ROOT = Path(__file__).resolve().parents[2]
FIELDS = ("camera", "render", "lights", "materials", "objects")


def differences(a, b, where="scene") -> list[str]:
    """Where two scene values differ: dataclasses field by field (a Texture too, though it compares by
    identity), arrays by np.array_equal, dicts in their order; [] when equal."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        same = isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and np.array_equal(a, b)
        return [] if same else [where]
    if dataclasses.is_dataclass(a) and type(a) is type(b):
        return [d for f in dataclasses.fields(a) for d in differences(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")]
    if isinstance(a, dict) and isinstance(b, dict):
        if list(a) != list(b):
            return [f"{where} keys"]
        return [d for k in a for d in differences(a[k], b[k], f"{where}[{k!r}]")]
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)) and type(a) is type(b):
        if len(a) != len(b):
            return [f"{where} length"]
        return [d for i, (x, y) in enumerate(zip(a, b)) for d in differences(x, y, f"{where}[{i}]")]
    return [] if type(a) is type(b) and a == b else [where]


def scene_differences(a, b) -> list[str]:
    return [d for name in FIELDS for d in differences(getattr(a, name), getattr(b, name), name)]


def from_file(folder, doc, name="scene.toml"):
    """What load_scene reads from ``doc`` written as a TOML file in ``folder``."""
    return warprt.load_scene(write_scene(folder, doc, name))


def write_ply(path, vertices, faces, normals):
    """An ASCII PLY of float vertices with per-vertex normals."""
    lines = ["ply", "format ascii 1.0", f"element vertex {len(vertices)}",
             *(f"property float {c}" for c in ("x", "y", "z", "nx", "ny", "nz")),
             f"element face {len(faces)}", "property list uchar int vertex_indices", "end_header"]
    lines += [" ".join(repr(float(x)) for x in (*v, *n)) for v, n in zip(vertices, normals)]
    lines += ["3 " + " ".join(str(int(i)) for i in f) for f in faces]
    Path(path).write_text("\n".join(lines) + "\n")


# A square pyramid with its own (deliberately not geometric) normals; values exact in float32, as PLY stores them.
PYRAMID_V = np.array([[-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [1.0, 0.0, 1.0], [-1.0, 0.0, 1.0], [0.0, 1.5, 0.0]])
PYRAMID_F = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [0, 2, 1], [0, 3, 2]])
PYRAMID_N = np.array([[-0.5, 0.25, -0.5], [0.5, 0.25, -0.5], [0.5, 0.25, 0.5], [-0.5, 0.25, 0.5], [0.0, 1.0, 0.0]])


def write_checker_png(path):
    from PIL import Image

    pixels = np.zeros((4, 4, 3), np.uint8)
    pixels[::2, ::2] = pixels[1::2, 1::2] = 255
    Image.fromarray(pixels).save(path)


DOCS = {
    "shapes and placement": {
        "camera": {"eye": [0.0, 2.0, 6.0], "center": [0.0, 0.5, 0.0], "fovy": 50.0, "width": 40, "height": 30},
        "render": {"ambient": [0.05, 0.05, 0.1], "max_depth": 4, "spp": 4, "effects": ["ambient", "diffuse", "shadows"]},
        "lights": [{"position": [4.0, 6.0, 4.0]}, {"type": "spot", "position": [0.0, 4.0, 0.0], "target": [0.0, 0.0, 0.0],
                                                   "cutoff_angle": 30.0, "falloff": "inverse_square"},
                   {"type": "directional", "direction": [0.0, -1.0, -1.0], "color": [0.2, 0.2, 0.2]}],
        "materials": {"red": {"kd": [0.8, 0.1, 0.1], "ks": [0.3, 0.3, 0.3], "reflectivity": 0.25},
                      "glass": {"ior": 1.5, "ka": [0, 0, 0], "kd": [0, 0, 0], "absorption": [0.0, 0.1, 0.2]}},
        "objects": [{"shape": "sphere", "subdivisions": 2, "smooth": True, "material": "red", "translate": [1.0, 0.5, 0.0]},
                    {"shape": "box", "size": [1.0, 2.0, 0.5], "rotate": [10.0, 20.0, 30.0], "scale": [1.0, -1.0, 2.0]},
                    {"shape": "cylinder", "sections": 12, "smooth": 40, "material": "glass", "up": "z"},
                    {"shape": "triangles", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "faces": [[0, 1, 2]],
                     "colors": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "name": "tri"}],
    },
    "textures": {
        "materials": {"wood": {"kd_texture": "checker.png"},
                      "checks": {"kd_texture": {"checker": [[0.9, 0.9, 0.9], [0.1, 0.1, 0.1]], "scale": 4}, "ks": [0.5, 0.5, 0.5]}},
        "objects": [{"shape": "plane", "size": [4.0, 4.0], "material": "wood"},
                    {"shape": "uv_sphere", "segments": [8, 16], "material": "checks", "smooth": True}],
    },
    "a mesh file with normals": {
        "materials": {"red": {"kd": [0.8, 0.1, 0.1]}},
        "objects": [{"mesh": "pyramid.ply", "smooth": "auto", "material": "red", "scale": [1.0, -2.0, 0.5],
                     "rotate": [0.0, 45.0, 0.0], "translate": [0.0, 1.0, 0.0], "up": "-x"}],
    },
}


def write_assets(folder):
    write_ply(Path(folder) / "pyramid.ply", PYRAMID_V, PYRAMID_F, PYRAMID_N)
    write_checker_png(Path(folder) / "checker.png")


# --- load_dict --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", DOCS)
def test_load_dict_is_load_scene_of_the_same_file(tmp_path, name):
    write_assets(tmp_path)
    expected = from_file(tmp_path, DOCS[name])
    assert scene_differences(warprt.load_dict(copy.deepcopy(DOCS[name]), base=tmp_path), expected) == []


def test_a_changed_value_is_a_difference(tmp_path):
    """The negative control of the comparison: one translate moved by one ulp is found."""
    write_assets(tmp_path)
    doc = copy.deepcopy(DOCS["shapes and placement"])
    expected = from_file(tmp_path, doc)
    doc["objects"][0]["translate"][0] = np.nextafter(1.0, 2.0)
    assert scene_differences(warprt.load_dict(doc, base=tmp_path), expected) == ["objects[0].vertices"]


@pytest.mark.parametrize("path", sorted((ROOT / "scenes").glob("*.toml")), ids=lambda p: p.name)
def test_each_scene_of_the_repository_loads_from_its_dict(path):
    doc = tomllib.loads(path.read_text())
    assert scene_differences(warprt.load_dict(doc, base=path.parent), warprt.load_scene(path)) == []


def test_load_dict_takes_python_values_as_the_file_has_them(tmp_path):
    """Tuples, NumPy vectors and numbers, as a notebook writes them, read as a file's lists and numbers."""
    doc = DOCS["shapes and placement"]
    python = copy.deepcopy(doc)
    python["camera"].update(eye=np.array([0.0, 2.0, 6.0]), fovy=np.float32(50.0), width=np.int64(40))
    python["lights"][0]["position"] = (4.0, 6.0, 4.0)
    python["objects"][0]["translate"] = np.array([1.0, 0.5, 0.0])
    python["objects"][3]["vertices"] = np.array(doc["objects"][3]["vertices"], np.float32)
    assert scene_differences(warprt.load_dict(python), from_file(tmp_path, doc)) == []


def test_load_dict_leaves_its_dict_as_it_was():
    doc = copy.deepcopy(DOCS["shapes and placement"])
    warprt.load_dict(doc)
    assert doc == DOCS["shapes and placement"]


BAD = [
    ({"camera": {"fovy": 0.0}}, "camera.fovy"),
    ({"camera": {"fvoy": 30.0}}, "camera.fvoy"),
    ({"lights": [{"position": [1.0, 2.0]}]}, "lights[0].position"),
    ({"materials": {"red": {"kd": [0.5, -0.1, 0.5]}}}, "materials.red.kd"),
    ({"objects": [{"shape": "sphere", "radius": -1.0}]}, "objects[0].radius"),
    ({"objects": [{"shape": "box", "material": "rde"}], "materials": {"red": {}}}, "objects[0].material"),
    ({"objects": [{"shape": "box", "scale": [1.0, 0.0, 1.0]}]}, "objects[0].scale"),
    ({"objects": [{"shape": "triangles", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "faces": [[0, 1, 3]]}]},
     "objects[0].faces"),
    ({"camra": {}}, "camra"),
]


@pytest.mark.parametrize("doc, field", BAD, ids=[f for _, f in BAD])
def test_bad_input_is_the_files_error_naming_the_field(tmp_path, doc, field):
    path = write_scene(tmp_path, doc)
    with pytest.raises(warprt.SceneError) as from_dict:
        warprt.load_dict(doc)
    with pytest.raises(warprt.SceneError) as from_path:
        warprt.load_scene(path)
    assert (from_dict.value.source, from_dict.value.field) == ("<dict>", field)
    assert (from_dict.value.field, from_dict.value.message) == (from_path.value.field, from_path.value.message)


def test_a_given_source_names_the_error():
    with pytest.raises(warprt.SceneError, match=r"^notebook cell 3: camera.fovy: "):
        warprt.load_dict({"camera": {"fovy": 200.0}}, source="notebook cell 3")


def test_good_input_raises_nothing():
    """The negative control of the bad inputs: the same tables with good values load."""
    warprt.load_dict({"camera": {"fovy": 30.0}, "lights": [{"position": [1.0, 2.0, 3.0]}],
                      "materials": {"red": {"kd": [0.5, 0.1, 0.5]}},
                      "objects": [{"shape": "box", "material": "red", "scale": [1.0, 2.0, 1.0]}]})


# --- Scene's defaults -------------------------------------------------------------------------------------


def test_an_empty_scene_is_an_empty_file(tmp_path):
    assert scene_differences(warprt.Scene(), from_file(tmp_path, {})) == []


def test_a_scene_of_objects_alone_is_a_file_of_objects_alone(tmp_path):
    doc = {"objects": [{"shape": "sphere", "subdivisions": 1}, {"shape": "plane", "translate": [0.0, -1.0, 0.0]}]}
    scene = warprt.Scene(objects=[warprt.SceneObject.from_shape("sphere", subdivisions=1),
                                  warprt.SceneObject.from_shape("plane", translate=[0.0, -1.0, 0.0])])
    assert scene_differences(scene, from_file(tmp_path, doc)) == []


def test_an_object_on_the_default_material_gets_it_beside_the_scenes_own(tmp_path):
    doc = {"materials": {"red": {"kd": [0.8, 0.1, 0.1]}}, "objects": [{"shape": "box"}, {"shape": "sphere", "material": "red"}]}
    red = warprt.Material(kd=(0.8, 0.1, 0.1))
    scene = warprt.Scene(materials={"red": red}, objects=[warprt.SceneObject.from_shape("box"),
                                                          warprt.SceneObject.from_shape("sphere", material="red")])
    assert scene_differences(scene, from_file(tmp_path, doc)) == []
    assert scene.materials["default"] is DEFAULT_MATERIAL


def test_a_material_no_object_defines_is_an_error_at_validation():
    scene = warprt.Scene(objects=[warprt.SceneObject.from_shape("box", material="red")])
    with pytest.raises(warprt.SceneError) as e:
        validate_scene(scene)
    assert (e.value.field, e.value.message) == ("objects[0].material", "no material named 'red'")


def test_a_defined_material_validates():
    """The negative control: the same scene with the material defined."""
    validate_scene(warprt.Scene(materials={"red": warprt.Material()},
                                objects=[warprt.SceneObject.from_shape("box", material="red")]))


def test_positional_fields_keep_their_order():
    camera, render = warprt.Camera(fovy=30.0), warprt.RenderSettings(spp=4)
    scene = warprt.Scene(camera, render, [], {"default": DEFAULT_MATERIAL}, [])
    assert (scene.camera, scene.render, scene.lights, scene.objects) == (camera, render, [], [])


# --- SceneObject's constructors ---------------------------------------------------------------------------

SO = warprt.SceneObject
TRIANGLE = {"vertices": [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            "faces": [[0, 1, 2], [0, 2, 3], [0, 3, 1]]}

# (the [[objects]] table, the same object written as a Python call, the materials the file needs)
SHAPE_CASES = {
    "sphere placed": ({"shape": "sphere", "radius": 0.5, "subdivisions": 2, "smooth": True, "translate": [0.0, 1.0, 0.0],
                       "rotate": [15.0, 0.0, 5.0]},
                      lambda: SO.from_shape("sphere", radius=0.5, subdivisions=2, smooth=True, translate=(0.0, 1.0, 0.0),
                                            rotate=np.array([15.0, 0.0, 5.0]))),
    "box mirrored": ({"shape": "box", "size": [1.0, 2.0, 3.0], "scale": [-1.0, 1.0, 1.0], "name": "crate"},
                     lambda: SO.from_shape("box", "crate", size=[1.0, 2.0, 3.0], scale=(-1.0, 1.0, 1.0))),
    "box textured": ({"shape": "box", "material": "checks", "up": "z"},
                     lambda: SO.from_shape("box", material="checks", textured=True, up="z")),
    "uv sphere textured": ({"shape": "uv_sphere", "segments": [6, 12], "material": "checks", "smooth": 60},
                           lambda: SO.from_shape("uv_sphere", material="checks", textured=True, segments=(6, 12), smooth=60)),
    "cylinder": ({"shape": "cylinder", "radius": 0.25, "height": 2.0, "sections": 9, "scale": 2.0},
                 lambda: SO.from_shape("cylinder", radius=0.25, height=2.0, sections=9, scale=2.0)),
    "torus knot": ({"shape": "torus_knot", "p": 3, "q": 5, "segments": [64, 8], "smooth": True},
                   lambda: SO.from_shape("torus_knot", p=3, q=5, segments=[64, 8], smooth=True)),
    "arrays": ({"shape": "triangles", **TRIANGLE, "name": "tet", "scale": [1.0, 1.0, -3.0], "rotate": [0.0, 90.0, 0.0],
                "translate": [1.0, 2.0, 3.0], "up": "-y", "smooth": 30,
                "uv": [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]], "colors": [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]]},
               lambda: SO.from_arrays("tet", np.array(TRIANGLE["vertices"], np.float32), np.array(TRIANGLE["faces"], np.uint32),
                                      uv=np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]),
                                      colors=[[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], smooth=30,
                                      scale=[1.0, 1.0, -3.0], rotate=[0.0, 90.0, 0.0], translate=[1.0, 2.0, 3.0], up="-y")),
}
CHECKS = {"checks": {"kd_texture": {"checker": [[0.9, 0.9, 0.9], [0.1, 0.1, 0.1]]}}}


@pytest.mark.parametrize("case", SHAPE_CASES)
def test_a_constructed_object_is_the_files_object(tmp_path, case):
    table, build = SHAPE_CASES[case]
    (expected,) = from_file(tmp_path, {"materials": CHECKS, "objects": [table]}).objects
    assert differences(build(), expected, "object") == []


def test_an_object_from_arrays_with_normals_is_the_mesh_files_object(tmp_path):
    write_assets(tmp_path)
    table = DOCS["a mesh file with normals"]["objects"][0]
    (expected,) = from_file(tmp_path, {"materials": {"red": {}}, "objects": [{**table, "name": "pyramid"}]}).objects
    built = SO.from_arrays("pyramid", PYRAMID_V, PYRAMID_F, "red", normals=PYRAMID_N, scale=table["scale"],
                           rotate=table["rotate"], translate=table["translate"], up=table["up"])
    assert expected.normals is not None  # the file's own normals, placed: what the comparison is about
    assert differences(built, expected, "object") == []


def test_a_changed_argument_makes_another_object(tmp_path):
    """The negative control of the constructors: one placement value changed is found."""
    table, _ = SHAPE_CASES["sphere placed"]
    (expected,) = from_file(tmp_path, {"objects": [table]}).objects
    built = SO.from_shape("sphere", radius=0.5, subdivisions=2, smooth=True, translate=(0.0, 1.0, 0.0), rotate=(15.0, 0.0, 6.0))
    assert differences(built, expected, "object") == ["object.vertices"]


def test_a_scene_built_in_python_renders_as_its_file(tmp_path):
    doc = {"camera": {"width": 32, "height": 24}, "lights": [{"position": [4.0, 6.0, 4.0]}],
           "materials": {"red": {"kd": [0.8, 0.1, 0.1], "ks": [0.4, 0.4, 0.4]}},
           "objects": [{"shape": "sphere", "subdivisions": 2, "smooth": True, "material": "red"},
                       {"shape": "triangles", **TRIANGLE, "translate": [0.0, -1.0, 0.0]}]}
    scene = warprt.Scene(camera=warprt.Camera(width=32, height=24), lights=[warprt.Light(position=(4.0, 6.0, 4.0))],
                         materials={"red": warprt.Material(kd=(0.8, 0.1, 0.1), ks=(0.4, 0.4, 0.4))},
                         objects=[SO.from_shape("sphere", material="red", subdivisions=2, smooth=True),
                                  SO.from_arrays("triangles", TRIANGLE["vertices"], TRIANGLE["faces"], translate=(0.0, -1.0, 0.0))])
    image, _ = warprt.render(scene)
    expected, _ = warprt.render(from_file(tmp_path, doc))
    assert np.array_equal(image, expected) and image.max() > 0


BAD_ARGUMENTS = [
    (lambda: SO.from_shape("sphere", radius=-1.0), "SceneObject.from_shape()", "radius", "expected a number > 0, got -1"),
    (lambda: SO.from_shape("sphre"), "SceneObject.from_shape()", "shape", "unknown shape 'sphre' (did you mean 'sphere'?)"),
    (lambda: SO.from_shape("box", radius=1.0), "SceneObject.from_shape()", "radius", "unknown key"),
    (lambda: SO.from_shape("sphere", textured=True), "SceneObject.from_shape()", "textured", "no texture coordinates"),
    (lambda: SO.from_shape("box", scale=[1.0, 0.0, 1.0]), "SceneObject.from_shape()", "scale", "non-zero"),
    (lambda: SO.from_shape("box", up="w"), "SceneObject.from_shape()", "up", "expected one of"),
    (lambda: SO.from_arrays("t", TRIANGLE["vertices"], [[0, 1, 4]]), "SceneObject.from_arrays()", "faces", "out of range"),
    (lambda: SO.from_arrays("t", TRIANGLE["vertices"], TRIANGLE["faces"], normals=[[0.0, 1.0, 0.0]]),
     "SceneObject.from_arrays()", "normals", "expected one per vertex (4), got 1"),
    (lambda: SO.from_arrays("t", [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], [[0, 1, 2]]), "SceneObject.from_arrays()",
     "vertices", "expected a list of [x, y, z] points"),
    (lambda: SO.from_arrays("t", TRIANGLE["vertices"], TRIANGLE["faces"], material=3), "SceneObject.from_arrays()",
     "material", "expected a string"),
    (lambda: SO.from_arrays("t", TRIANGLE["vertices"], TRIANGLE["faces"], scale=1e308),
     "SceneObject.from_arrays()", "scale", "beyond the range of float64"),
]


@pytest.mark.parametrize("build, source, field, message", BAD_ARGUMENTS, ids=[f"{s}{f}" for _, s, f, _ in BAD_ARGUMENTS])
def test_a_bad_argument_is_a_scene_error_naming_it(build, source, field, message):
    with pytest.raises(warprt.SceneError) as e:
        build()
    assert (e.value.source, e.value.field) == (source, field) and message in e.value.message
