"""The Ray backend on a real local Ray instance, started as `warprt batch --ray` starts it (one for the
module): frames bit-identical to direct renders, an actor's process killed mid-job, bad input met on a
worker. Ray missing is a failure, not a skip (pip install -e '.[test,ray]')."""

import json
import os
import signal

import numpy as np
import pytest

import warprt
from marks import slow
from warprt import SceneError
from warprt.dataset import RAY_MESSAGES, batch, connect_ray, read_rows
from warprt.image import read_aovs, read_image

from dataset.jobs import SCENE, require_ray, write_job

AOVS = '["depth", "normal", "object"]'  # the local tests' set: the same compiled kernels


@pytest.fixture(scope="module")
def ray():
    ray = require_ray()
    if ray.is_initialized():
        ray.shutdown()
    assert connect_ray(None)  # what `warprt batch --ray` does
    assert {n["NodeManagerAddress"] for n in ray.nodes()} == {"127.0.0.1"}  # loopback only
    yield ray
    ray.shutdown()


@slow
def test_ray_frames_match_direct_renders(ray, tmp_path):
    job = write_job(tmp_path, f'scene = "{{scene}}"\noutput = "f/{{frame}}_{{render.spp}}.npz"\naovs = {AOVS}\n'
                              '[orbit]\nframes = 3\n[sweep]\n"render.spp" = [1, 4]\n')
    result = batch(job, tmp_path / "out", ray="local")
    rows = result.rows
    assert [r["frame"] for r in rows] == list(range(6)) and {r["backend"] for r in rows} == {"ray"}
    assert result.workers == len(os.sched_getaffinity(0))  # default: one actor per core
    assert ray.is_initialized()  # it was running before: batch leaves it running
    for r in rows:
        direct = warprt.render(warprt.load_scene(SCENE, overrides=r["overrides"]), aovs=r["aovs"])
        path = tmp_path / "out" / r["outputs"]["color"]
        assert np.array_equal(read_image(path), direct.image)
        assert all(np.array_equal(a, direct.aovs[n]) for n, a in read_aovs(path).items())


@slow
def test_killed_actor_leaves_every_frame_once(ray, tmp_path, capfd):
    n = 12
    job = write_job(tmp_path, 'scene = "{scene}"\noutput = "f/{frame:02d}.npz"\n'
                              f'[set]\n"camera.width" = 64\n"camera.height" = 48\n"render.spp" = 4\n[orbit]\nframes = {n}\n')
    killed = []

    def on_frame(row):
        if not killed:  # this actor has its next frame in hand (two in flight per actor)
            killed.append(row["worker"]["pid"])
            os.kill(killed[0], signal.SIGKILL)

    rows = batch(job, tmp_path / "out", ray="local", workers=2, on_frame=on_frame).rows
    lines = [json.loads(x) for x in (tmp_path / "out" / "manifest.jsonl").read_text().splitlines()]
    assert sorted(x["frame"] for x in lines) == list(range(n))  # one line per frame, none twice
    pids = {r["worker"]["pid"] for r in rows}
    assert killed[0] in pids and len(pids) >= 3  # two actors, and the killed one restarted
    assert any(r["attempt"] >= 2 for r in rows) or len(pids) >= 3
    assert sorted(p.name for p in (tmp_path / "out" / "f").iterdir()) == [f"{k:02d}.npz" for k in range(n)]
    for r in rows:
        assert read_image(tmp_path / "out" / r["outputs"]["color"]).shape == (48, 64, 3)
    out, err = capfd.readouterr()
    assert "(raylet)" not in out + err  # Ray's "a worker died ... will be retried" kept off the terminal


@slow
def test_bad_frame_on_a_ray_worker_fails_the_job_naming_it(ray, tmp_path):
    job = write_job(tmp_path, 'scene = "{scene}"\noutput = "f/{frame}.npz"\n'
                              '[[cameras]]\neye = [0.0, 1.5, 5.0]\n[[cameras]]\neye = [0.0, 0.6, 0.0]\n')
    with pytest.raises(SceneError) as e:  # check=False: the driver leaves the frames to the workers
        batch(job, tmp_path / "out", ray="local", workers=1, check=False)
    assert e.value.source == str(job) and e.value.field == "frame 1 (cameras[1])"
    assert "camera.center: must differ from camera.eye" in e.value.message
    assert 1 not in {r["frame"] for r in read_rows(tmp_path / "out")}
