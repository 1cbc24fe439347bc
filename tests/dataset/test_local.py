"""The local backend (worker processes): every frame and its AOVs bit-identical to `warprt render` of that
frame, a killed worker, --resume after the whole run is killed, and shards whose union is the run."""

import json
import multiprocessing as mp
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import warprt
from marks import slow
from warprt.dataset import batch, read_rows
from warprt.image import read_aovs, read_image

from dataset.jobs import ROOT, SCENE, cli, every_line_is_json, write_job

ORBIT = """
scene = "{scene}"
output = "frames/{frame:03d}_spp{render.spp}.npz"
aovs = ["depth", "normal", "object"]
[orbit]
frames = 3
[sweep]
"render.spp" = [1, 4]
"""


def same_rows(a, b):
    keep = ("frame", "key", "camera", "sweep", "overrides", "outputs")
    return [{k: r[k] for k in keep} for r in a] == [{k: r[k] for k in keep} for r in b]


@pytest.fixture(scope="module")
def orbit_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("orbit")
    job = write_job(d, ORBIT)
    return job, d / "out", batch(job, d / "out", workers=2)


def test_frames_and_aovs_are_bit_identical_to_direct_renders(orbit_run):
    job, out, result = orbit_run
    assert [r["frame"] for r in result.rows] == list(range(6)) and result.rendered == 6 and result.workers == 2
    for r in result.rows:
        direct = warprt.render(warprt.load_scene(SCENE, overrides=r["overrides"]), aovs=r["aovs"])
        path = out / r["outputs"]["color"]
        assert np.array_equal(read_image(path), direct.image), r["frame"]
        aovs = read_aovs(path)
        assert aovs.keys() == direct.aovs.keys() and all(np.array_equal(aovs[n], direct.aovs[n]) for n in aovs)
        assert r["stats"]["rays"] == direct.stats.rays and r["stats"]["spp"] == r["sweep"]["render.spp"]


@slow
def test_png_and_exr_frames_are_the_files_warprt_render_writes(tmp_path):
    """The same bytes as the command writes with --set for the frame's overrides: PNG, its AOV files, EXR."""
    for ext in ("png", "exr"):
        job = write_job(tmp_path, f'scene = "{{scene}}"\noutput = "f/{{frame}}.{ext}"\naovs = ["depth", "normal", "object"]\n'
                                  '[[cameras]]\neye = [1.0, 1.2, 4.5]\nfovy = 38.5\n[[cameras]]\ncenter = [0.2, 0.5, 0.0]\n',
                        name=f"job_{ext}.toml")
        rows = batch(job, tmp_path / ext, workers=1).rows
        assert [r["frame"] for r in rows] == [0, 1]
        r = rows[1]
        ref = tmp_path / f"ref.{ext}"
        sets = [f"--set={k}={json.dumps(v)}" for k, v in r["overrides"].items()]
        p = cli("render", SCENE, "-o", ref, "-q", "--aov", "depth,normal,object", *sets)
        assert p.returncode == 0, p.stderr
        names = {"color": ref} if ext == "exr" else \
            {"color": ref, **{n: ref.with_name(f"ref.{n}.exr") for n in ("depth", "normal", "object")}}
        assert r["outputs"].keys() == names.keys()
        for name, path in names.items():
            assert (tmp_path / ext / r["outputs"][name]).read_bytes() == path.read_bytes(), (ext, name)


@slow
def test_killed_worker_leaves_every_frame_once(tmp_path):
    job = write_job(tmp_path, 'scene = "{scene}"\noutput = "f/{frame:02d}.png"\naovs = ["depth", "normal", "object"]\n'
                              '[set]\n"camera.width" = 64\n"camera.height" = 48\n"render.spp" = 4\n[orbit]\nframes = 12\n')
    killed = []

    def on_frame(row):
        if not killed:  # the other worker has a frame in hand: kill it
            others = [p for p in mp.active_children() if p.name == "warprt-batch-worker" and p.pid != row["worker"]["pid"]]
            os.kill(others[0].pid, signal.SIGKILL)
            killed.append(others[0].pid)

    rows = batch(job, tmp_path / "out", workers=2, on_frame=on_frame).rows
    lines = [json.loads(x) for x in (tmp_path / "out" / "manifest.jsonl").read_text().splitlines()]
    assert killed and sorted(x["frame"] for x in lines) == list(range(12))  # one line per frame, none twice
    assert [r["frame"] for r in rows] == list(range(12))
    assert any(r["attempt"] == 2 for r in rows)  # the killed worker's frame, rendered again
    files = sorted(p.name for p in (tmp_path / "out" / "f").iterdir())
    assert files == sorted(f"{k:02d}{x}" for k in range(12) for x in (".png", ".depth.exr", ".normal.exr", ".object.exr"))
    for r in rows:  # no temporary leftovers (above), every file whole
        assert read_image(tmp_path / "out" / r["outputs"]["color"]).shape == (48, 64, 3)
        assert read_aovs(tmp_path / "out" / r["outputs"]["color"])["depth"].shape == (48, 64)


@slow
def test_resume_after_an_interrupt_renders_only_what_is_missing(tmp_path):
    n = 16
    job = write_job(tmp_path, 'scene = "{scene}"\noutput = "f/{frame:02d}.png"\n'
                              f'[set]\n"camera.width" = 64\n"camera.height" = 48\n"render.spp" = 4\n[orbit]\nframes = {n}\n')
    out = tmp_path / "out"
    manifest = out / "manifest.jsonl"
    p = subprocess.Popen([sys.executable, "-m", "warprt", "batch", str(job), "-o", str(out), "--workers", "1", "-q"],
                         cwd=ROOT, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.time() + 120
    while time.time() < deadline and p.poll() is None:
        if manifest.exists() and manifest.read_text().count("\n") >= 3:
            break
        time.sleep(0.005)
    os.killpg(p.pid, signal.SIGKILL)  # the driver and its worker, as a lost node would
    p.wait()
    text = manifest.read_bytes()
    if text.endswith(b"\n"):  # the kill fell between two appends: cut the last line as one mid-append does
        last = text[:-1].rfind(b"\n") + 1
        manifest.write_bytes(text[:last + (len(text) - last) // 2])
    assert not every_line_is_json(manifest)
    first = read_rows(out)
    assert 2 <= len(first) < n, "the interrupt came too late to test anything"
    mtimes = {r["frame"]: (out / r["outputs"]["color"]).stat().st_mtime_ns for r in first}

    result = batch(job, out, workers=1, resume=True)
    assert result.skipped == len(first) and result.rendered == n - len(first)
    rows = result.rows
    resumed = {r["run"] for r in rows if r["frame"] not in mtimes}
    assert len(resumed) == 1 and {r["frame"] for r in rows if r["run"] in resumed} == set(range(n)) - set(mtimes)
    assert all((out / r["outputs"]["color"]).stat().st_mtime_ns == mtimes[r["frame"]] for r in first)
    assert sorted(r["frame"] for r in read_rows(out)) == list(range(n))  # one line each, no duplicates
    assert every_line_is_json(manifest)  # the torn line dropped, its frame rendered again
    assert sorted(x.name for x in (out / "f").iterdir()) == [f"{k:02d}.png" for k in range(n)]

    again = batch(job, out, resume=True)  # nothing left: no worker starts
    assert again.rendered == 0 and again.skipped == n and again.workers is None


def test_union_of_shards_is_the_unsharded_run(orbit_run, tmp_path):
    job, out, result = orbit_run
    shards = [batch(job, tmp_path, workers=1, shard=f"{i}/2").rows for i in range(2)]
    assert [r["frame"] for r in shards[0]] == [0, 2, 4] and [r["frame"] for r in shards[1]] == [1, 3, 5]
    assert sorted(p.name for p in tmp_path.glob("manifest*.jsonl")) == ["manifest.shard-0-of-2.jsonl",
                                                                       "manifest.shard-1-of-2.jsonl"]
    union = sorted(read_rows(tmp_path), key=lambda r: r["frame"])
    assert same_rows(union, result.rows)
    for r in union:
        assert (tmp_path / r["outputs"]["color"]).read_bytes() == (out / r["outputs"]["color"]).read_bytes()


def test_workers_fork_from_a_driver_that_has_not_rendered_and_not_from_one_that_has(tmp_path):
    """fork: a worker starts with warprt imported. Never from a process holding warprt's thread pool and
    Warp's runtime (the child's first threaded frame would hang): that one starts a fork server."""
    job = write_job(tmp_path, 'scene = "{scene}"\noutput = "f/{frame}.png"\n[orbit]\nframes = 2\n')
    script = textwrap.dedent(f"""
        import sys
        import warprt
        from warprt.dataset import batch, default_start_method
        if __name__ == "__main__":
            before = default_start_method()
            batch({str(job)!r}, {str(tmp_path / "a")!r}, workers=1)
            warprt.render(warprt.load_scene({str(SCENE)!r}), threads=2)
            after = default_start_method()
            rows = batch({str(job)!r}, {str(tmp_path / "b")!r}, workers=1).rows
            print(before, after, len(rows))
    """)
    (tmp_path / "driver.py").write_text(script)
    p = subprocess.run([sys.executable, str(tmp_path / "driver.py")], capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert p.returncode == 0, p.stderr
    assert p.stdout.split() == ["fork", "forkserver", "2"]
    for name in ("0.png", "1.png"):
        assert (tmp_path / "a" / "f" / name).read_bytes() == (tmp_path / "b" / "f" / name).read_bytes()
