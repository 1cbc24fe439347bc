"""Inputs from the wild, one class at a time: output paths (symlinks, an output that is an input or
another output, a full device), pipes and environments (a reader that goes away, an unwritable home),
library messages (NumPy, USD, glTF, a byte-order mark), memory, and the Python API as a notebook
uses it (lists for vectors, Ctrl-C). Each test states the exit status, the exact stderr and the files
left behind; where a process-level effect is the point (a signal, a limit, an environment) the real
command runs in a subprocess, otherwise warprt.cli.main runs in-process, with fd 2 captured.
"""

import json
import os
import re
import resource
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import warprt
from bands import BandCounter
from marks import slow
from scenekit import to_toml, write_scene
from warprt import Camera, Light, Material, RenderSettings, Scene, SceneError, SceneObject
from warprt.cli import main
from warprt.image import read_image

SRC = str(Path(__file__).resolve().parents[2] / "src")
ENV = {**os.environ, "PYTHONPATH": SRC + os.pathsep + os.environ.get("PYTHONPATH", "")}

OK = {"camera": {"eye": [0.0, 1.0, 5.0], "center": [0.0, 0.0, 0.0], "width": 16, "height": 12},
      "lights": [{"position": [3.0, 5.0, 4.0]}],
      "materials": {"red": {"kd": [0.8, 0.1, 0.1]}},
      "objects": [{"shape": "sphere", "subdivisions": 2, "material": "red"}]}


def ok_with(**sphere) -> dict:
    """OK with its sphere's fields changed or added."""
    return {**OK, "objects": [{**OK["objects"][0], **sphere}]}


@pytest.fixture
def work(tmp_path, monkeypatch):
    """A folder holding a valid scene (ok.toml) and a triangle (tri.obj), and the current folder."""
    write_scene(tmp_path, OK, "ok.toml")
    (tmp_path / "tri.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def listing(root: Path) -> dict:
    """Every entry under root, hidden ones too: a file's bytes, a link's target, a folder's None."""
    out = {}
    for p in sorted(root.rglob("*")):
        rel = str(p.relative_to(root))
        out[rel] = ("->", os.readlink(p)) if p.is_symlink() else (p.read_bytes() if p.is_file() else None)
    return out


def cli(capfd, *argv):
    """warprt.cli.main in this process: (exit status, stdout, stderr lines), fd 1 and fd 2 captured."""
    capfd.readouterr()
    code = main(list(argv))
    out, err = capfd.readouterr()
    return code, out, err.splitlines()


def run(argv, cwd, env=None, preexec_fn=None, stdout=subprocess.PIPE):
    return subprocess.run([sys.executable, "-m", "warprt", *argv], cwd=cwd, env={**ENV, **(env or {})},
                          stdin=subprocess.DEVNULL, stdout=stdout, stderr=subprocess.PIPE, text=True,
                          timeout=300, preexec_fn=preexec_fn)


def assert_png(path: Path, width=16, height=12):
    image = read_image(path)
    assert image.shape == (height, width, 3) and image.max() > 0


# --- Output paths -------------------------------------------------------------------------------------


def test_an_output_symlink_is_written_through(work, capfd):
    """As cp, convert and a shell's '>' do: the file the link leads to gets the image, the link stays."""
    (work / "renders").mkdir()
    (work / "renders" / "final.png").write_bytes(b"an earlier image")
    (work / "out.png").symlink_to("renders/final.png")
    code, _, err = cli(capfd, "render", "ok.toml", "-o", "out.png", "-q")
    assert (code, err) == (0, [])
    assert os.readlink(work / "out.png") == "renders/final.png"
    assert_png(work / "renders" / "final.png")
    assert sorted(p.name for p in (work / "renders").iterdir()) == ["final.png"]  # no temporary file left


def test_a_dangling_output_symlink_gets_its_target_made(work, capfd):
    (work / "out.png").symlink_to("made.png")
    code, _, err = cli(capfd, "render", "ok.toml", "-o", "out.png", "-q")
    assert (code, err) == (0, [])
    assert (work / "out.png").is_symlink()
    assert_png(work / "made.png")


def test_stats_file_naming_the_image_is_refused_before_rendering(work, capfd):
    (work / "x.png").write_bytes(b"an earlier image")
    before = listing(work)
    code, out, err = cli(capfd, "render", "ok.toml", "-o", "x.png", "--stats-file", "x.png")
    assert code == 2 and out == ""
    assert err == ["warprt: error: x.png: --stats-file: is also the --output file (x.png); each output needs a file of its own"]
    assert listing(work) == before


def test_stats_file_reaching_the_image_through_a_link_is_refused(work, capfd):
    (work / "s.json").symlink_to("x.png")
    before = listing(work)
    code, _, err = cli(capfd, "render", "ok.toml", "-o", "x.png", "--stats-file", "s.json")
    assert code == 2
    assert err == ["warprt: error: s.json: --stats-file: is also the --output file (x.png); each output needs a file of its own"]
    assert listing(work) == before


@pytest.mark.parametrize("scene,what", [("ok.toml", "scene file"), ("tri.obj", "mesh file")])
def test_an_output_naming_an_input_is_refused(work, capfd, scene, what):
    before = listing(work)
    code, _, err = cli(capfd, "render", scene, "-o", "x.png", "--stats-file", scene)
    assert code == 2
    assert err == [f"warprt: error: {scene}: --stats-file: is the {what} this command reads ({scene}); "
                   "writing there would destroy it"]
    assert listing(work) == before


def test_an_output_naming_a_mesh_of_the_scene_is_refused(work, capfd):
    write_scene(work, {**OK, "objects": [{"mesh": "tri.obj", "material": "red"}]}, "m.toml")
    before = listing(work)
    code, _, err = cli(capfd, "render", "m.toml", "-o", "x.png", "--stats-file", "tri.obj")
    assert code == 2
    assert err == ["warprt: error: tri.obj: --stats-file: is the mesh file this command reads (tri.obj); "
                   "writing there would destroy it"]
    assert listing(work) == before


def test_a_link_to_a_full_device_is_an_error(work, capfd):
    """/dev/full fails every write with ENOSPC: the command must say so, not report success."""
    (work / "out.png").symlink_to("/dev/full")
    before = listing(work)
    code, _, err = cli(capfd, "render", "ok.toml", "-o", "out.png", "-q")
    assert code == 2
    assert err == ["warprt: error: out.png: --output: cannot write: No space left on device "
                   "(writing /dev/full, where the link leads)"]
    assert listing(work) == before


def _file_size_limit(nbytes):
    return lambda: resource.setrlimit(resource.RLIMIT_FSIZE, (nbytes, resource.RLIM_INFINITY))


@slow
@pytest.mark.parametrize("ext", [".png", ".npy", ".exr"])
def test_a_write_cut_short_keeps_the_earlier_file(work, ext):
    """A file-size limit stops the write part way (EFBIG), as a full disk does: one line, exit 2, the
    earlier file as it was, no temporary file. (Python ignores SIGXFSZ, so the write fails instead.)"""
    argv = ["render", "ok.toml", "-o", f"out{ext}", "--width", "256", "--height", "192", "-q"]
    assert run(argv, work).returncode == 0  # the kernels compiled and cached outside the limit
    (work / f"out{ext}").write_bytes(b"an earlier image")
    before = listing(work)
    r = run(argv, work, preexec_fn=_file_size_limit(4096))
    assert r.returncode == 2
    assert r.stderr == f"warprt: error: out{ext}: --output: cannot write: File too large\n"
    assert listing(work) == before


@slow
def test_a_full_disk_keeps_the_earlier_file(work):
    """A real full file system: a tmpfs of 8 KiB (skipped where this user may not mount one)."""
    disk = work / "disk"
    disk.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=8k", "tmpfs", str(disk)], capture_output=True).returncode:
        pytest.skip("cannot mount a tmpfs here")
    try:
        (disk / "out.exr").write_bytes(b"an earlier image")
        before = listing(disk)
        r = run(["render", "ok.toml", "-o", "disk/out.exr", "--width", "256", "--height", "192", "-q"], work)
        assert r.returncode == 2
        assert r.stderr == "warprt: error: disk/out.exr: --output: cannot write: No space left on device\n"
        assert listing(disk) == before
    finally:
        subprocess.run(["umount", str(disk)], check=True)


# --- Pipes and environment ----------------------------------------------------------------------------


def test_a_reader_that_has_gone_ends_the_command_as_it_ends_cat(work):
    """`warprt info s.toml | head -1`: stdout's reader gone before the first write. Like cat and git,
    warprt dies of SIGPIPE (a shell shows 141), silently."""
    p = subprocess.Popen([sys.executable, "-m", "warprt", "info", "ok.toml"], cwd=work, env=ENV,
                         stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    p.stdout.close()  # the reader is gone before warprt writes anything
    err = p.stderr.read().decode()
    p.wait(timeout=120)
    assert err == ""
    assert p.returncode == -signal.SIGPIPE


@slow
def test_stats_on_a_gone_reader_still_writes_the_files(work):
    p = subprocess.Popen([sys.executable, "-m", "warprt", "render", "ok.toml", "-o", "x.png", "--stats",
                          "--stats-file", "s.json"], cwd=work, env=ENV, stdin=subprocess.DEVNULL,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    p.stdout.close()
    err = p.stderr.read().decode()
    p.wait(timeout=120)
    assert (p.returncode, err) == (-signal.SIGPIPE, "")
    assert_png(work / "x.png")
    assert json.loads((work / "s.json").read_text())["width"] == 16


@slow
def test_an_unwritable_home_renders_with_a_temporary_kernel_cache(work):
    """A read-only container: Warp's cache folder cannot be made (here HOME is a file). The render
    goes on with kernels cached in a private temporary folder, one warning, and that folder removed."""
    (work / "home").write_text("not a folder")
    tmp = work / "tmp"
    tmp.mkdir()
    env = {k: v for k, v in ENV.items() if k not in ("XDG_CACHE_HOME", "WARP_CACHE_PATH")}
    r = subprocess.run([sys.executable, "-m", "warprt", "render", "ok.toml", "-o", "x.png"], cwd=work,
                       env={**env, "HOME": str(work / "home"), "TMPDIR": str(tmp)}, stdin=subprocess.DEVNULL,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    lines = r.stderr.splitlines()
    assert len(lines) == 2 and lines[1].startswith("wrote x.png (16x12")
    assert re.fullmatch(rf"warprt: warning: Warp's kernel cache {re.escape(str(work))}/home/\.cache/warp/\S+ is not "
                        rf"writable \(Not a directory\); caching kernels in {re.escape(str(tmp))}/warprt-kernels-\S+ "
                        r"for this run \(set WARP_CACHE_PATH to a writable folder to keep them\)", lines[0]), lines[0]
    assert_png(work / "x.png")
    # The temporary cache went with the process (Warp's compiler leaves its own wp_pch_* folders anyway).
    assert [p.name for p in tmp.iterdir() if p.name.startswith("warprt-kernels-")] == []


def _interrupted_render(work, width: int) -> tuple[int, bool, bytes, str]:
    """A render of cornell at ``width`` x 3/4 ``width``, 16 spp, with stderr on a pseudo-terminal, sent
    SIGINT once its progress line shows the trace has begun: (exit status, whether it was sent, stderr, the
    child's signal masks from /proc when it was sent)."""
    import pty
    import select
    import time

    scene = Path(__file__).parents[2] / "scenes" / "cornell.toml"
    master, slave = pty.openpty()
    # `python -m warprt render ...`, with SIGINT as a terminal's shell gives it (Python's handler, unblocked), not as
    # the test worker may have left it: a full make test twice had the render ignore its SIGINT to the end (exit
    # 0 after 55 s at 4096 x 3072) where the test alone never did, a disposition inherited through exec
    start = ("import runpy, signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
             "signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT}); sys.argv[0] = 'warprt'; "
             "runpy.run_module('warprt', run_name='__main__', alter_sys=True)")
    p = subprocess.Popen([sys.executable, "-c", start, "render", str(scene), "-o", "out.png", "--width", str(width),
                          "--height", str(width * 3 // 4), "--spp", "16", "--primary-query", "raytrace"], cwd=work,
                         env={**ENV, "WARPRT_PROGRESS_AFTER": "0"}, stdin=subprocess.DEVNULL,
                         stdout=subprocess.DEVNULL, stderr=slave)
    os.close(slave)
    seen, sent, deadline, disposition = b"", False, time.monotonic() + 300, ""
    while time.monotonic() < deadline:
        if select.select([master], [], [], 1.0)[0]:
            try:
                chunk = os.read(master, 65536)
            except OSError:
                break
            if not chunk:
                break
            seen += chunk
            if not sent and b"tiles" in seen:
                status = Path(f"/proc/{p.pid}/status")
                signals = [l for l in status.read_text().splitlines() if l.startswith("Sig")] if status.exists() else []
                p.send_signal(signal.SIGINT)
                sent = True
                disposition = " ".join(signals)  # the child's at the signal: shown if the test fails
        elif p.poll() is not None:
            break
    os.close(master)
    return p.wait(timeout=120), sent, seen, disposition


@slow
def test_ctrl_c_exits_130_and_writes_nothing(work):
    """SIGINT once the progress line shows the trace has begun (stderr on a pseudo-terminal): exit 130,
    'warprt: interrupted' as the last line, no image and no temporary file. On a loaded machine this test
    may see the line so late that the render finishes first (exit 0, the image written): then the signal
    proved nothing and the render is tried again, twice as wide; a render that ignores SIGINT finishes
    every time and fails."""
    for width in (1024, 2048, 4096):
        code, sent, seen, disposition = _interrupted_render(work, width)
        if code != 0:
            break
        (work / "out.png").unlink()
    assert code == 130 and sent, (code, sent, seen[-400:], disposition)  # what it printed, its signals, if it fails
    assert seen.decode().replace("\r\x1b[K", "\n").splitlines()[-1] == "warprt: interrupted"
    assert sorted(os.listdir(work)) == ["ok.toml", "tri.obj"]


# --- Messages -----------------------------------------------------------------------------------------


def test_a_scene_file_with_a_byte_order_mark_loads(work, capfd):
    (work / "bom.toml").write_bytes(b"\xef\xbb\xbf" + to_toml(OK).encode())
    assert cli(capfd, "render", "bom.toml", "-o", "bom.npy", "-q")[::2] == (0, [])
    assert cli(capfd, "render", "ok.toml", "-o", "ok.npy", "-q")[::2] == (0, [])
    assert np.array_equal(np.load(work / "bom.npy"), np.load(work / "ok.npy"))


@slow
def test_an_absurd_scale_is_one_line_without_numpy_warnings(work):
    """In a subprocess: pytest would catch NumPy's RuntimeWarning before it reached stderr."""
    write_scene(work, ok_with(scale=1e300), "huge.toml")
    r = run(["render", "huge.toml", "-o", "x.png"], work)
    assert r.returncode == 2
    assert r.stderr == ("warprt: error: huge.toml: objects[0]: 'sphere' reaches more than 1e+12 from camera.eye; "
                        "float32 ray tests cannot reach it\n")


def test_a_scale_beyond_float64_names_the_scale(work, capfd):
    write_scene(work, ok_with(scale=1e308, translate=[1.7e308, 0.0, 0.0]), "inf.toml")
    code, _, err = cli(capfd, "render", "inf.toml", "-o", "x.png")
    assert code == 2
    assert err == ["warprt: error: inf.toml: objects[0].scale: scale [1e+308, 1e+308, 1e+308], rotate and "
                   "translate take the mesh beyond the range of float64"]


def test_junk_in_a_gltf_names_the_file_and_says_what_it_is_not(work, capfd):
    (work / "junk.gltf").write_bytes(b"\x00\x01binary junk{")
    code, _, err = cli(capfd, "render", "junk.gltf", "-o", "x.png")
    assert code == 2
    assert err == ["warprt: error: junk.gltf: not a glTF file (not JSON: Expecting value at line 1, column 1)"]


def test_a_gltf_missing_its_buffer_names_the_buffer(work, capfd):
    (work / "nobuf.gltf").write_text(json.dumps({"asset": {"version": "2.0"}, "buffers": [{"uri": "gone.bin", "byteLength": 36}]}))
    code, _, err = cli(capfd, "render", "nobuf.gltf", "-o", "x.png")
    assert code == 2
    assert err == ["warprt: error: nobuf.gltf: buffer file not found: gone.bin"]


BROKEN_REFERENCE_USDA = """#usda 1.0
def Mesh "m" (references = @missing.usda@)
{
    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
}
"""


def test_usd_diagnostics_become_one_warning_line(work, capfd):
    (work / "ref.usda").write_text(BROKEN_REFERENCE_USDA)
    code, _, err = cli(capfd, "render", "ref.usda", "-o", "x.png", "--width", "16", "--height", "12")
    assert code == 0
    assert err[0] == ("warprt: warning: ref.usda: USD: In </m>: Could not open asset @missing.usda@ for reference "
                      "introduced by @ref.usda@</m>.")
    assert len(err) == 2 and err[1].startswith("wrote x.png (16x12")
    assert cli(capfd, "render", "ref.usda", "-o", "x.png", "-q", "--width", "16", "--height", "12")[::2] == (0, [])


TEXTURED_PLY = """ply
format ascii 1.0
comment TextureFile missing.png
element vertex 3
property float x
property float y
property float z
element face 1
property list uchar int vertex_indices
end_header
0 0 0
1 0 0
0 1 0
3 0 1 2
"""


@slow
def test_a_missing_ply_texture_is_one_warning_line(work):
    """warprt reads PLY itself: a missing texture is its own one warning, not trimesh's log as well."""
    (work / "tex.ply").write_text(TEXTURED_PLY)
    r = run(["render", "tex.ply", "-o", "x.png", "--width", "16", "--height", "12"], work)
    assert r.returncode == 0
    lines = r.stderr.splitlines()
    assert lines[0].startswith("warprt: warning: tex.ply: comment TextureFile: ") and "missing.png" in lines[0]
    assert len(lines) == 2 and lines[1].startswith("wrote x.png (16x12")
    assert run(["render", "tex.ply", "-o", "x.png", "-q"], work).stderr == ""


LOG_WITH_TRACEBACK = textwrap.dedent("""\
    import logging
    from warprt.diagnostics import collecting
    with collecting("m.stl"):
        try:
            raise FileNotFoundError("missing.png")
        except FileNotFoundError:
            logging.getLogger("trimesh.exchange").warning("unable to load image!", exc_info=True)
    """)


def test_a_trimesh_log_warning_with_its_traceback_is_one_line(work):
    """trimesh (STL, OFF) logs some failures with their traceback, which logging's last resort would
    print whole (in a subprocess: pytest's own log capture would hide it)."""
    r = subprocess.run([sys.executable, "-c", LOG_WITH_TRACEBACK], capture_output=True, text=True, env=ENV, cwd=work)
    assert r.returncode == 0
    assert r.stderr.splitlines() == ["warprt: warning: m.stl: trimesh: unable to load image! (FileNotFoundError: missing.png)"]


def test_a_failing_usd_file_is_its_error_line_alone(work, capfd):
    """The diagnostics of a load that fails are dropped: the error says what went wrong, in one line."""
    (work / "empty_ref.usda").write_text('#usda 1.0\ndef Xform "x" (references = @missing.usda@)\n{\n}\n')
    code, _, err = cli(capfd, "render", "empty_ref.usda", "-o", "x.png")
    assert code == 2
    assert err == ["warprt: error: empty_ref.usda: the mesh has no triangles"]


# --- Memory -------------------------------------------------------------------------------------------

GiB = 2**30
HUGE = ["render", "ok.toml", "--width", "16384", "--height", "16384", "-o", "x.png", "--threads", "2", "-q"]


@slow
def test_a_frame_bigger_than_the_memory_limit_is_refused_before_allocating(work):
    """Under a 4 GiB address-space limit a 16384x16384 frame (10 GiB of buffers) is refused with one
    line naming both numbers, and nothing is written; a small frame still renders under that limit."""
    limit = lambda: resource.setrlimit(resource.RLIMIT_AS, (4 * GiB, resource.RLIM_INFINITY))
    small = run(["render", "ok.toml", "-o", "small.png", "--threads", "2", "-q"], work, preexec_fn=limit)
    assert (small.returncode, small.stderr) == (0, "")
    before = listing(work)
    r = run(HUGE, work, preexec_fn=limit)
    assert r.returncode == 2
    m = re.fullmatch(r"warprt: error: ok\.toml: camera\.width, camera\.height: a 16384x16384 frame needs about "
                     r"10\.0 GiB of memory \(image buffers 10\.0 GiB, geometry and BVH [\d.]+ KiB\), more than the "
                     r"([\d.]+) (GiB|MiB) (left of the address space limit of 4\.0 GiB \(RLIMIT_AS\)|"
                     r"available memory \(MemAvailable\))\n", r.stderr)
    assert m, r.stderr
    assert float(m[1]) * (GiB if m[2] == "GiB" else 2**20) < 4 * GiB
    assert listing(work) == before


def _frame_memory(work, size, primary):
    """The stats' memory record of a size x size frame rendered by the command in a process of its own."""
    r = run(["render", "ok.toml", "--width", str(size), "--height", str(size), "--primary-query", primary, "-o", "m.npy",
             "--stats", "-q", "--threads", "2"], work)
    assert r.returncode == 0, r.stderr
    stats = json.loads(r.stdout)
    assert stats["primary_query"] == primary
    return stats["memory"]


@slow
@pytest.mark.parametrize("primary", ["raytrace", "zbuffer"])
def test_the_estimate_bounds_the_growth_of_a_frame(work, primary):
    """What --stats estimates a frame adds, between a 512x512 and a 2048x2048 frame, against what the
    frame really takes. Load-proof: the buffers the renderer allocates (its own count: the image, ray
    counts and Z-buffer) are at most the estimate, and the estimate at most twice them (a host copy
    and the writer's share come on top); the process's peak RSS grows by at most 1.25 x the estimate,
    since another process's load can only take resident pages away, never add them."""
    _frame_memory(work, 16, primary)  # a first compile of the kernels peaks higher than a frame
    small, big = _frame_memory(work, 512, primary), _frame_memory(work, 2048, primary)
    estimated = big["estimate"]["total"] - small["estimate"]["total"]
    allocated = (big["image"] + big["raster"]) - (small["image"] + small["raster"])
    measured = big["peak_rss"] - small["peak_rss"]
    assert allocated <= estimated <= 2 * allocated, (allocated, estimated)
    assert measured <= 1.25 * estimated, (measured, estimated)


# --- The Python API as a notebook uses it ------------------------------------------------------------


def _scene(vec, rows):
    """The same scene with its vectors made by ``vec`` and its mesh rows by ``rows``."""
    camera = Camera(eye=vec([0.0, 1.0, 5.0]), center=vec([0.0, 0.0, 0.0]), up=vec([0.0, 1.0, 0.0]), width=16, height=12)
    materials = {"red": Material(kd=vec([0.8, 0.1, 0.1]), ks=vec([0.3, 0.3, 0.3]), reflectivity=0.25)}
    tri = SceneObject("tri", rows([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), rows([[0, 1, 2]]), "red")
    return Scene(camera, RenderSettings(ambient=vec([0.1, 0.1, 0.1]), background=vec([0.0, 0.0, 0.2])),
                 [Light(position=vec([3.0, 5.0, 4.0]), color=vec([1.0, 1.0, 1.0]))], materials, [tri])


@pytest.mark.parametrize("kind", ["lists", "numpy arrays"])
def test_vectors_given_as_lists_or_arrays_render_as_tuples_do(kind):
    vec = list if kind == "lists" else np.array
    rows = list if kind == "lists" else np.array
    as_tuples = _scene(tuple, lambda r: np.asarray(r))
    image, _ = warprt.render(_scene(vec, rows))
    expected, _ = warprt.render(as_tuples)
    assert np.array_equal(image, expected)
    scene = _scene(vec, rows)
    assert scene.camera == as_tuples.camera and scene.materials == as_tuples.materials
    assert scene.lights == as_tuples.lights and scene.render == as_tuples.render


@pytest.mark.parametrize("make,field", [
    (lambda: Camera(eye="0 1 5"), "eye"),
    (lambda: Light(position=[3.0, "up", 4.0]), "position"),
    (lambda: Material(kd={"r": 1}), "kd"),
    (lambda: RenderSettings(ambient=[[0.1, 0.1, 0.1]]), "ambient"),
    (lambda: SceneObject("x", "vertices", [[0, 1, 2]], "red"), "vertices"),
])
def test_what_is_not_numbers_is_a_scene_error_naming_the_field(make, field):
    with pytest.raises(SceneError) as e:
        make()
    assert e.value.field == field


def _interrupted(progress):
    scene = warprt.load_scene(Path(__file__).parents[2] / "scenes" / "cornell.toml")
    scene = scene.with_camera(width=96, height=72).with_render(spp=16)
    warprt.render(scene.with_camera(width=8, height=6), threads=2, primary_query="raytrace")  # kernels loaded
    with pytest.raises(KeyboardInterrupt):
        warprt.render(scene, threads=2, bands=16, progress=progress, primary_query="raytrace")
    finished_at_raise = progress.done
    # The next render runs on the same pool of two workers: it gets them only once the old bands are done.
    image, _ = warprt.render(scene.with_camera(width=8, height=6), threads=2, primary_query="raytrace")
    assert image.shape == (6, 8, 3)
    return finished_at_raise, progress.done


def test_keyboard_interrupt_from_a_band_stops_the_render_s_bands():
    """Ctrl-C as a progress callback meets it (on a worker, after the second band): the bands not yet
    started are cancelled and the running one waited for, so no band of the interrupted render
    finishes after render() has raised, and at most the one running beside the interrupting band does."""

    def interrupt(n):
        if n == 2:
            raise KeyboardInterrupt

    at_raise, later = _interrupted(BandCounter(interrupt))
    assert later == at_raise
    assert at_raise <= 3


def test_a_sigint_during_a_render_stops_its_bands():
    """Ctrl-C as a terminal or a notebook's kernel sends it: SIGINT to the main thread, here sent at the
    first band's end. The bands that end meanwhile wait until the main thread has taken the signal (its
    handler is Python's own plus a note that it ran), so how soon the main thread runs does not count."""
    main_thread = threading.main_thread().ident
    taken = threading.Event()

    def handler(signum, frame):
        # Python drops an exception raised inside a __del__ ("Exception ignored in"): a signal that lands while
        # the main thread frees an array there is sent again a moment later, not lost (a user's Ctrl-C would be
        # lost there too, by Python, not by warprt: the next one stops the render; measured on a loaded run)
        while frame is not None and frame.f_code.co_name != "__del__":
            frame = frame.f_back
        if frame is not None:
            threading.Timer(0.01, signal.pthread_kill, (main_thread, signal.SIGINT)).start()
            return
        taken.set()
        raise KeyboardInterrupt

    def interrupt(n):
        if n == 1:
            signal.pthread_kill(main_thread, signal.SIGINT)
        assert taken.wait(60), "the main thread never took the SIGINT"

    previous = signal.signal(signal.SIGINT, handler)
    try:
        at_raise, later = _interrupted(BandCounter(interrupt))
    finally:
        signal.signal(signal.SIGINT, previous)
    assert later == at_raise
    assert at_raise <= 3


def test_a_ctrl_c_that_python_dropped_is_raised_again_by_the_band_loop():
    """The command line's SIGINT handler notes the signal before it raises (warprt/interrupt.py); where Python
    drops that raise (inside a __del__: what a loaded full run met, the render then going on to its end), the
    band loop raises it at its next poll. Here the note alone, made at the first band's end with no signal
    sent, stops the render as a delivered SIGINT does; the control, the same render without it, finishes."""
    pending = warprt.cli.interrupt.PENDING

    def note(n):  # the bands that end meanwhile wait until the loop has taken the note, as the SIGINT test's
        if n == 1:
            pending.set()
        deadline = time.monotonic() + 60
        while pending.is_set() and time.monotonic() < deadline:
            time.sleep(0.001)
        assert not pending.is_set(), "the band loop never took the note"

    try:
        at_raise, later = _interrupted(BandCounter(note))
    finally:
        pending.clear()
    assert later == at_raise and at_raise <= 3
    counter = BandCounter()
    scene = warprt.load_scene(Path(__file__).parents[2] / "scenes" / "cornell.toml").with_camera(width=96, height=72)
    warprt.render(scene, threads=2, bands=16, progress=counter, primary_query="raytrace")
    assert counter.done == 16


# --- What the fuzzing found (tests/cli/test_fuzz.py), each as its smallest file -------------------------


def _box_gltf(**material) -> bytes:
    import trimesh
    from trimesh.exchange.gltf import export_gltf

    box = trimesh.creation.box()
    box.visual = trimesh.visual.TextureVisuals(material=trimesh.visual.material.PBRMaterial(
        name="clay", baseColorFactor=[0.5, 0.4, 0.3, 1.0]))
    doc = json.loads(export_gltf(trimesh.Scene(box), embed_buffers=True)["model.gltf"])
    doc["materials"][0].update(material)
    return json.dumps(doc).encode()


def _crate_with_token_count(folder: Path, count: int) -> bytes:
    """A real binary USD file (pxr's own), with the element count of its TOKENS section replaced."""
    import struct

    from pxr import Usd

    (folder / "seed.usda").write_text(BROKEN_REFERENCE_USDA.replace(" (references = @missing.usda@)", ""))
    Usd.Stage.Open(str(folder / "seed.usda")).Export(str(folder / "seed.usdc"))
    data = bytearray((folder / "seed.usdc").read_bytes())
    toc = struct.unpack("<q", data[16:24])[0]
    for i in range(struct.unpack("<Q", data[toc:toc + 8])[0]):
        entry = data[toc + 8 + 32 * i:toc + 40 + 32 * i]
        if entry[:16].rstrip(b"\0") == b"TOKENS":
            start, length = struct.unpack("<qq", entry[16:])
            data[start:start + 8] = struct.pack("<Q", count)
            return bytes(data), length
    raise AssertionError("no TOKENS section")


def test_obj_vertices_of_two_coordinates_are_refused(work, capfd):
    (work / "two.obj").write_text("v 0 0\nv 1 0\nv 0 1\nf 1 2 3\n")
    assert cli(capfd, "render", "two.obj", "-o", "x.png")[::2] == (
        2, ["warprt: error: two.obj: a vertex (v) has fewer than 3 coordinates"])


def test_an_mtl_illum_of_inf_is_refused(work, capfd):
    (work / "m.obj").write_text("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl p\nf 1 2 3\n")
    (work / "m.mtl").write_text("newmtl p\nKd 0.5 0.5 0.5\nillum inf\n")
    assert cli(capfd, "render", "m.obj", "-o", "x.png")[::2] == (
        2, ["warprt: error: m.mtl: newmtl p: illum: expected a number, got 'inf'"])


def test_a_gltf_material_named_by_a_list_still_renders(work, capfd):
    (work / "box.gltf").write_bytes(_box_gltf(name=[]))
    code, _, err = cli(capfd, "render", "box.gltf", "-o", "x.png", "--width", "16", "--height", "12")
    assert code == 0 and len(err) == 1 and err[0].startswith("wrote x.png (16x12")
    assert_png(work / "x.png")


def test_bytes_that_are_not_utf8_in_a_usda_are_one_line(work, capfd):
    (work / "bad.usda").write_bytes(b'#usda 1.0\ndef Mesh "m\xdb\xff" {\n}\n')
    assert cli(capfd, "render", "bad.usda", "-o", "x.png")[::2] == (
        2, ["warprt: error: bad.usda: cannot open USD stage: the file holds bytes that are not UTF-8 text where USD "
            "expects text"])


def test_a_crate_file_claiming_a_billion_tokens_is_refused_before_usd_reads_it(work, capfd):
    """USD would reserve memory for them first (55 s and 14 GB for the fuzzed file)."""
    data, length = _crate_with_token_count(work, 1_761_607_723)
    (work / "bad.usdc").write_bytes(data)
    assert cli(capfd, "render", "bad.usdc", "-o", "x.png")[::2] == (
        2, [f"warprt: error: bad.usdc: not a valid USD crate file (its TOKENS section claims 1761607723 entries in "
            f"{length} bytes)"])


def test_the_crate_check_passes_the_untouched_file(work, capfd):
    """The negative control: the same file with its own token count renders."""
    _crate_with_token_count(work, 0)  # writes seed.usdc, untouched
    code, _, err = cli(capfd, "render", "seed.usdc", "-o", "x.png", "--width", "16", "--height", "12")
    assert code == 0, err


def test_a_bare_mesh_too_far_out_to_frame_says_so(work, capfd):
    (work / "far.obj").write_text("v 0 0 0\nv 1e14 0 0\nv 0 1e14 0\nf 1 2 3\n")
    assert cli(capfd, "render", "far.obj", "-o", "x.png")[::2] == (
        2, ["warprt: error: far.obj: cannot frame the mesh, which spans [0.0, 0.0, 0.0] .. [100000000000000.0, "
            "100000000000000.0, 0.0]: the framing's lights[0].position is more than 1e+12 from camera.eye; float32 ray "
            "tests cannot reach it"])
