"""Bad input, through the real command: each case of the corpus (tests/cli/corpus) gives exactly its
one-line message on stderr, exit status 2, no traceback, and leaves no file behind, not even a
temporary one.

Each case runs in its own copy of the corpus folder, so its paths are relative and the folder can be
compared file by file before and after. The cases run four at a time (each is a fresh process).
"""

import os
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from marks import slow
from warprt.scene import shapes

SHAPE_TABLE = shapes.SHAPES

CORPUS = Path(__file__).parent / "corpus"
SRC = str(Path(__file__).resolve().parents[2] / "src")
EXTS = ".obj, .ply, .stl, .off, .glb, .gltf, .usd, .usda, .usdc, .usdz"
SHAPES = ", ".join(SHAPE_TABLE)  # the shape names the messages list, as the scene reader knows them

# (case, command line, the message after "warprt: error: "). "-o out.png" is added where the case
# names no output.
CASES = [
    # The scene file: syntax, keys, types, lengths, values.
    ("malformed TOML", ["render", "malformed.toml"],
     "malformed.toml: malformed TOML: Expected ']' at the end of a table declaration (at line 2, column 8)"),
    ("not UTF-8", ["render", "latin1.toml"],
     "latin1.toml: not UTF-8 text (byte 0xe9 on line 1); a TOML file must be UTF-8"),
    ("scene file missing", ["render", "nothere.toml"], "nothere.toml: scene file not found"),
    ("unknown section", ["render", "unknown_section.toml"],
     "unknown_section.toml: camra: unknown section (did you mean 'camera'?)"),
    ("unknown camera key", ["render", "unknown_camera_key.toml"],
     "unknown_camera_key.toml: camera.fvoy: unknown key (did you mean 'fovy'?)"),
    ("unknown material key", ["render", "unknown_material_key.toml"],
     "unknown_material_key.toml: materials.red.shinyness: unknown key (did you mean 'shininess'?)"),
    ("unknown object key", ["render", "unknown_object_key.toml"],
     "unknown_object_key.toml: objects[0].tranlsate: unknown key (did you mean 'translate'?)"),
    ("string for a number", ["render", "fovy_string.toml"],
     "fovy_string.toml: camera.fovy: expected a number, got 'wide'"),
    ("vector of 2", ["render", "eye_two_numbers.toml"],
     "eye_two_numbers.toml: camera.eye: expected a list of 3 numbers, got [0.0, 1.0]"),
    ("string in a colour", ["render", "color_not_number.toml"],
     "color_not_number.toml: lights[0].color: expected a list of 3 numbers, got [1.0, 'red', 1.0]"),
    ("negative kd", ["render", "kd_negative.toml"],
     "kd_negative.toml: materials.paint.kd: expected non-negative numbers, got [-0.2, 0.5, 0.5]"),
    ("negative shininess", ["render", "shininess_negative.toml"],
     "shininess_negative.toml: materials.paint.shininess: expected a number >= 0, got -8"),
    ("NaN fovy", ["render", "fovy_nan.toml"], "fovy_nan.toml: camera.fovy: expected a finite number, got nan"),
    ("infinite light position", ["render", "light_position_inf.toml"],
     "light_position_inf.toml: lights[0].position: expected finite numbers, got [inf, 2.0, 3.0]"),
    ("width 0", ["render", "width_zero.toml"],
     "width_zero.toml: camera.width: expected an integer in [1, 16384], got 0"),
    ("height 100000", ["render", "height_huge.toml"],
     "height_huge.toml: camera.height: expected an integer in [1, 16384], got 100000"),
    ("spp not a square", ["render", "spp_not_square.toml"],
     "spp_not_square.toml: render.spp: expected a square number of samples (k*k stratified: 1, 4, 9, 16, ...), got 3"),
    ("max_depth 0", ["render", "max_depth_zero.toml"],
     "max_depth_zero.toml: render.max_depth: expected an integer in [1, 1024], got 0"),
    ("up along the view", ["render", "up_parallel.toml"],
     "up_parallel.toml: camera.up: is parallel to the viewing direction (eye - center)"),
    ("eye at center", ["render", "eye_is_center.toml"],
     "eye_is_center.toml: camera.center: must differ from camera.eye (no viewing direction)"),
    ("material not a table", ["render", "material_not_table.toml"],
     "material_not_table.toml: materials.red: expected a table, got 3"),
    ("lights not tables", ["render", "lights_not_tables.toml"],
     "lights_not_tables.toml: lights: expected an array of tables ([[lights]]), got 3"),
    ("no such material", ["render", "no_such_material.toml"],
     "no_such_material.toml: objects[0].material: no material named 'rde' (did you mean 'red'?)"),
    ("mesh and shape", ["render", "mesh_and_shape.toml"],
     f"mesh_and_shape.toml: objects[0]: expected exactly one of 'mesh' (a file) or 'shape' ({SHAPES})"),
    ("unknown shape", ["render", "unknown_shape.toml"],
     f"unknown_shape.toml: objects[0].shape: unknown shape 'sphre' (did you mean 'sphere'?); expected one of: {SHAPES}"),
    ("face index out of range", ["render", "faces_out_of_range.toml"],
     "faces_out_of_range.toml: objects[0].faces: vertex index out of range [0, 2]"),
    # Textures and shading.
    ("texture file missing", ["render", "missing_texture.toml"],
     "missing_texture.toml: materials.wood.kd_texture: textures/nothere.png: texture file not found"),
    ("texture not an image", ["render", "texture_not_image.toml"],
     "texture_not_image.toml: materials.tiles.kd_texture.image: notes.txt: not an image file read here (PNG, "
     "JPEG, TIFF, BMP, TGA, WebP, ... through Pillow; EXR)"),
    ("environment image missing", ["render", "missing_sky.toml"],
     "missing_sky.toml: lights[0].image: textures/nosky.hdr: texture file not found"),
    ("environment image cut short", ["render", "short_sky.toml"],
     "short_sky.toml: lights[0].image: short.hdr: cannot read HDR image: the pixel data is cut short or damaged"),
    ("checker of one colour", ["render", "bad_checker.toml"],
     "bad_checker.toml: materials.tiles.kd_texture.checker: expected two colours [[r, g, b], [r, g, b]], "
     "got [[1, 1, 1]]"),
    ("smooth not a mode", ["render", "bad_smooth.toml"],
     "bad_smooth.toml: objects[0].smooth: expected true, false, \"auto\" or a crease angle in degrees, got 'yes'"),
    ("up not an axis", ["render", "bad_up.toml"],
     "bad_up.toml: objects[0].up: expected one of 'x', 'y', 'z', '-x', '-y', '-z', got 'w'"),
    ("reflectivity on glass", ["render", "glass_reflectivity.toml"],
     "glass_reflectivity.toml: materials.glass.reflectivity: a dielectric (ior) reflects by its Fresnel term; "
     "reflectivity must be 0"),
    ("transmittance without ior", ["render", "transmittance_without_ior.toml"],
     "transmittance_without_ior.toml: materials.paint.transmittance: only a dielectric has it: give the material an ior"),
    ("ior 0", ["render", "ior_zero.toml"], "ior_zero.toml: materials.glass.ior: expected a number > 0, got 0"),
    ("transmittance over 1", ["render", "transmittance_over_one.toml"],
     "transmittance_over_one.toml: materials.glass.transmittance: expected values in [0, 1], got [1.0, 1.5, 1.0]"),
    ("eye inside nested glass", ["render", "nested_glass.toml"],
     "nested_glass.toml: camera.eye: is inside more than one object with ior ('inner', 'outer'): nested media are "
     "not modelled"),
    ("glass deeper than the stack", ["render", "glass_ok.toml", "--max-depth", "100"],
     "glass_ok.toml: render.max_depth: a scene with refraction traces at most 65 ray levels (up to 2^64 paths per "
     "sample), got 100"),
    # Mesh files named by a scene.
    ("mesh file missing", ["render", "missing_mesh.toml"],
     "missing_mesh.toml: objects[0].mesh: meshes/nothere.obj: mesh file not found"),
    ("mesh is a folder", ["render", "folder_mesh.toml"],
     "folder_mesh.toml: objects[0].mesh: meshes/folder.obj: is a folder, not a mesh file"),
    ("mesh of points only", ["render", "vertices_only.toml"],
     "vertices_only.toml: objects[0].mesh: meshes/vertices_only.obj: the mesh has no triangles"),
    ("mesh file empty", ["render", "empty_file.toml"],
     "empty_file.toml: objects[0].mesh: meshes/empty.ply: the file is empty"),
    ("not a PLY", ["render", "junk_ply.toml"],
     "junk_ply.toml: objects[0].mesh: meshes/junk.ply: not a PLY file (it does not start with 'ply')"),
    ("not an STL", ["render", "junk_stl.toml"],
     "junk_stl.toml: objects[0].mesh: meshes/junk.stl: not an STL file (binary STL of 25 bytes, expected 84 + 50 * triangles)"),
    ("not a USDA", ["render", "junk_usda.toml"],
     "junk_usda.toml: objects[0].mesh: meshes/junk.usda: not a USDA file (it does not start with '#usda')"),
    ("NaN vertex", ["render", "nan_vertex.toml"],
     "nan_vertex.toml: objects[0].mesh: meshes/nan_vertex.obj: vertex coordinates contain NaN or Inf"),
    ("OBJ face past the vertices", ["render", "bad_index.toml"],
     "bad_index.toml: objects[0].mesh: meshes/bad_index.obj: a face refers to a vertex that does not exist "
     "(vertex 9; the file has 3)"),
    ("unknown mesh format", ["render", "unknown_mesh_format.toml"],
     f"unknown_mesh_format.toml: objects[0].mesh: meshes/model.fbx: unknown mesh format '.fbx'; expected one of: {EXTS}"),
    ("negative Kd in the MTL", ["render", "bad_mtl.toml"],
     "bad_mtl.toml: objects[0].mesh: meshes/bad_mtl.mtl: newmtl paint: Kd: expected 3 non-negative numbers, "
     "got [-1.0, 0.5, 0.5]"),
    ("negative Ni in the MTL", ["render", "bad_ni.toml"],
     "bad_ni.toml: objects[0].mesh: meshes/bad_ni.mtl: newmtl glass: Ni: expected a number > 0, got ['-1.5']"),
    # A bare file on the command line.
    ("bare mesh not a PLY", ["render", "meshes/junk.ply"], "meshes/junk.ply: not a PLY file (it does not start with 'ply')"),
    ("unknown file type", ["render", "notes.txt"],
     f"notes.txt: unknown file type '.txt'; expected a scene file (.toml) or a mesh file ({EXTS})"),
    ("scene is a folder", ["render", "meshes"], "meshes: is a folder; expected a scene file (.toml) or a mesh file"),
    ("--set on a mesh beyond camera/render", ["render", "meshes/tri.obj", "--set", "lights[0].color=[1,1,1]"],
     "meshes/tri.obj: lights[0].color: only camera.* and render.* can be set for a mesh file"),
    ("info on a missing file", ["info", "nothere.toml"], "nothere.toml: scene file not found"),
    # Flags.
    ("--width 0", ["render", "ok.toml", "--width", "0"], "command line: --width: expected an integer in [1, 16384], got 0"),
    ("--height 100000", ["render", "ok.toml", "--height", "100000"],
     "command line: --height: expected an integer in [1, 16384], got 100000"),
    ("--spp 5", ["render", "ok.toml", "--spp", "5"],
     "command line: --spp: expected a square number of samples (k*k stratified: 1, 4, 9, 16, ...), got 5"),
    ("--light-samples 10", ["render", "ok.toml", "--light-samples", "10"],
     "command line: --light-samples: expected a square number of samples (k*k stratified: 1, 4, 9, 16, ...), got 10"),
    ("--adaptive -1", ["render", "ok.toml", "--spp", "4", "--adaptive", "-1"],
     "command line: --adaptive: expected a number >= 0 (0: off), got -1.0"),
    ("--max-depth 0", ["render", "ok.toml", "--max-depth", "0"],
     "command line: --max-depth: expected an integer in [1, 1024], got 0"),
    ("--threads 0", ["render", "ok.toml", "--threads", "0"], "command line: --threads: expected an integer >= 1, got 0"),
    ("--width abc", ["render", "ok.toml", "--width", "abc"],
     "command line: argument --width: invalid int value: 'abc' (see 'warprt render --help')"),
    ("unknown flag", ["render", "ok.toml", "--frobnicate"],
     "command line: unrecognized arguments: --frobnicate (see 'warprt --help')"),
    ("--set without =", ["render", "ok.toml", "--set", "camera.fovy"],
     "command line: --set: expected section.key=value, got 'camera.fovy'"),
    ("--set unknown key", ["render", "ok.toml", "--set", "camera.fvoy=30"],
     "ok.toml: camera.fvoy: unknown key (did you mean 'fovy'?)"),
    ("--set negative fovy", ["render", "ok.toml", "--set", "camera.fovy=-30"],
     "ok.toml: camera.fovy: expected a number > 0, got -30"),
    ("--set NaN", ["render", "ok.toml", "--set", "render.ambient=[0.1, nan, 0.1]"],
     "ok.toml: render.ambient: expected finite numbers, got [0.1, nan, 0.1]"),
    ("--set a light that is not there", ["render", "ok.toml", "--set", "lights[7].color=[1,1,1]"],
     "ok.toml: lights[7].color: there is no lights[7]"),
    ("--effects unknown", ["render", "ok.toml", "--effects", "glow"],
     "command line: --effects: unknown effect 'glow'; expected some of: ambient, diffuse, specular, shadows, "
     "reflection, supersampling, smooth, texture, vertex_color, refraction, absorption"),
    ("--aov unknown", ["render", "ok.toml", "--aov", "depth,glow"],
     "command line: --aov: unknown AOV 'glow'; expected some of: depth, normal, albedo, position, uv, object, material, "
     "face, coverage"),
    ("--aov with the Z-buffer", ["render", "ok.toml", "--aov", "depth", "--algorithm", "zbuffer"],
     "command line: --aov: AOVs come from the tracer's camera rays: not with --algorithm zbuffer"),
    ("--aov into .npy", ["render", "ok.toml", "--aov", "depth", "-o", "out.npy"],
     "out.npy: --output: a .npy file holds the colour only; for AOVs write .npz, .exr, or .png (the AOVs beside it "
     "as <stem>.<aov>.exr)"),
    # Output paths: checked before anything renders.
    ("output .jpg", ["render", "ok.toml", "-o", "out.jpg"],
     "out.jpg: --output: unknown image extension '.jpg'; expected one of: .png, .npy, .exr, .npz"),
    ("output without extension", ["render", "ok.toml", "-o", "out"],
     "out: --output: unknown image extension '(none)'; expected one of: .png, .npy, .exr, .npz"),
    ("output folder missing", ["render", "ok.toml", "-o", "nowhere/out.png"],
     "nowhere/out.png: --output: folder does not exist: nowhere"),
    ("output folder is a file", ["render", "ok.toml", "-o", "notes.txt/out.png"],
     "notes.txt/out.png: --output: not a folder: notes.txt"),
    ("output is a folder", ["render", "ok.toml", "-o", "adir.png"], "adir.png: --output: is a folder, not a file"),
    ("output folder unwritable", ["render", "ok.toml", "-o", "/proc/warprt.png"],
     "/proc/warprt.png: --output: cannot write to folder /proc: No such file or directory"),
    ("stats file folder missing", ["render", "ok.toml", "--stats-file", "nowhere/stats.json"],
     "nowhere/stats.json: --stats-file: folder does not exist: nowhere"),
]


def _listing(root: Path) -> dict:
    """Every file and folder under root (hidden ones too) with its size."""
    return {str(p.relative_to(root)): (p.stat().st_size if p.is_file() else -1) for p in root.rglob("*")}


def _run(argv, cwd):
    env = {**os.environ, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")}
    return subprocess.run([sys.executable, "-m", "warprt", *argv], cwd=cwd, env=env, capture_output=True,
                          text=True, stdin=subprocess.DEVNULL, timeout=120)


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory):
    """Run every case once, four processes at a time: {case: (result, files before, files after)}."""

    # The folders are made here, one after another: tmp_path_factory is not thread-safe.
    folders = {name: tmp_path_factory.mktemp("case") / "corpus" for name, _, _ in CASES}
    for work in folders.values():
        shutil.copytree(CORPUS, work)

    def one(case):
        name, argv, _ = case
        work = folders[name]
        argv = list(argv)
        if argv[0] == "render" and "-o" not in argv:
            argv += ["-o", "out.png"]
        before = _listing(work)
        result = _run(argv, work)
        return name, (result, before, _listing(work))

    with ThreadPoolExecutor(max_workers=4) as pool:
        return dict(pool.map(one, CASES))


def test_corpus_is_large_enough():
    assert len(CASES) >= 30
    assert len({name for name, _, _ in CASES}) == len(CASES)


@slow
@pytest.mark.parametrize("name,argv,message", CASES, ids=[c[0] for c in CASES])
def test_bad_input_gives_its_message(outcomes, name, argv, message):
    result, before, after = outcomes[name]
    assert result.stderr == f"warprt: error: {message}\n"
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert result.stdout == ""
    # Nothing written: no image, no statistics, no temporary file.
    assert after == before


@slow
def test_unavailable_device_is_a_bad_input(tmp_path):
    import warp as wp

    from warprt.kernels import init_warp

    init_warp()
    if wp.is_cuda_available():
        pytest.skip("this machine has a CUDA device")
    shutil.copytree(CORPUS, tmp_path / "c")
    before = _listing(tmp_path / "c")
    r = _run(["render", "ok.toml", "--device", "cuda", "-o", "out.png"], tmp_path / "c")
    assert r.stderr == ("warprt: error: command line: --device: 'cuda' is not available on this machine "
                        "(Warp found no CUDA device); use --device cpu\n")
    assert r.returncode == 2
    assert _listing(tmp_path / "c") == before


@slow
def test_debug_shows_the_traceback(tmp_path):
    shutil.copytree(CORPUS, tmp_path / "c")
    for argv in (["render", "--debug", "missing_mesh.toml"], ["--debug", "render", "missing_mesh.toml"]):
        r = _run([*argv, "-o", "out.png"], tmp_path / "c")
        assert r.returncode != 0
        assert "Traceback (most recent call last)" in r.stderr
        assert r.stderr.rstrip().endswith("missing_mesh.toml: objects[0].mesh: meshes/nothere.obj: mesh file not found")


@slow
def test_a_failed_render_keeps_the_earlier_image(tmp_path):
    """The output is replaced only by a complete new image: a bad input leaves the old one intact."""
    shutil.copytree(CORPUS, tmp_path / "c")
    old = tmp_path / "c" / "out.png"
    old.write_bytes(b"an earlier image")
    r = _run(["render", "kd_negative.toml", "-o", "out.png"], tmp_path / "c")
    assert r.returncode == 2
    assert old.read_bytes() == b"an earlier image"
