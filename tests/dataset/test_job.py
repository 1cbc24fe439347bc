"""Job files: expansion into frames, and every bad input as a SceneError naming the job file and field.
No rendering here (check_scene loads scenes, which is cheap)."""

import math

import numpy as np
import pytest

from warprt import SceneError
from warprt.dataset import check_scene, load_job, orbit_eye, parse_shard, select_shard

from dataset.jobs import SCENE, write_job
from oracle import axis_rotation


@pytest.fixture
def job_dir(tmp_path):
    return tmp_path


def test_orbit_eyes_rotate_about_up_through_center(job_dir):
    job = load_job(write_job(job_dir, """
        scene = "{scene}"
        [orbit]
        frames = 4
    """))
    base = check_scene(job)
    eye, center = base.camera.eye, base.camera.center
    assert [f.index for f in job.frames] == [0, 1, 2, 3]
    assert job.frames[0].overrides["camera.eye"] == list(eye)  # k = 0 is the scene's eye, exactly
    r = math.dist((eye[0], eye[2]), (center[0], center[2]))
    for f in job.frames:
        e = f.overrides["camera.eye"]
        assert set(f.overrides) == {"camera.eye"}  # center and up unchanged
        assert e[1] == pytest.approx(eye[1])  # about the up axis: height kept
        assert math.dist((e[0], e[2]), (center[0], center[2])) == pytest.approx(r)
    # 90 degrees right-handed about +y: +z (towards the viewer) goes to +x.
    e1 = job.frames[1].overrides["camera.eye"]
    assert e1[0] - center[0] == pytest.approx(eye[2] - center[2]) and e1[2] == pytest.approx(center[2])


def test_orbit_eye_about_any_axis_is_rodrigues_rotation():
    rng = np.random.default_rng(7)
    for _ in range(20):
        eye, center, up = rng.normal(size=(3, 3)) * 3.0
        degrees = float(rng.uniform(-400.0, 400.0))
        axis = up / np.linalg.norm(up)
        expected = center + axis_rotation(axis, degrees) @ (eye - center)
        np.testing.assert_allclose(orbit_eye(eye, center, up, degrees), expected, rtol=0, atol=1e-12)


def test_sweep_product_frame_order_and_output_names(job_dir):
    job = load_job(write_job(job_dir, """
        scene = "{scene}"
        output = "out/{frame:02d}_c{camera}_spp{render.spp}_d{render.max_depth}.npz"
        [[cameras]]
        eye = [0.0, 1.5, 5.0]
        [[cameras]]
        eye = [1.0, 1.5, 5.0]
        fovy = 30
        [sweep]
        "render.spp" = [1, 4]
        render.max_depth = [1, 2, 3]      # a nested table is the same field
    """))
    assert len(job.frames) == 2 * 2 * 3
    f = job.frames[7]  # s = 3 (spp 4, max_depth 1), c = 1
    assert (f.sweep_index, f.camera_index) == (3, 1)
    assert f.overrides == {"camera.eye": [1.0, 1.5, 5.0], "camera.fovy": 30.0, "render.spp": 4, "render.max_depth": 1}
    assert f.outputs == {"color": "out/07_c1_spp4_d1.npz"}  # the AOVs, if any, inside
    assert f.label == "frame 7 (cameras[1], render.spp=4, render.max_depth=1)"
    assert len({f.key for f in job.frames}) == len(job.frames)


def test_path_keyframes_interpolate_linearly(job_dir):
    job = load_job(write_job(job_dir, """
        scene = "{scene}"
        [path]
        frames = 5
        keyframes = [
          {frame = 0, eye = [0.0, 1.0, 5.0], fovy = 40.0},
          {frame = 2, eye = [2.0, 1.0, 5.0], fovy = 50.0},
          {frame = 4, eye = [2.0, 3.0, 1.0], fovy = 30.0},
        ]
    """))
    eyes = [f.overrides["camera.eye"] for f in job.frames]
    assert eyes == [[0.0, 1.0, 5.0], [1.0, 1.0, 5.0], [2.0, 1.0, 5.0], [2.0, 2.0, 3.0], [2.0, 3.0, 1.0]]
    assert [f.overrides["camera.fovy"] for f in job.frames] == [40.0, 45.0, 50.0, 40.0, 30.0]


def test_a_png_frame_lists_its_aov_files(job_dir):
    job = load_job(write_job(job_dir, 'scene = "{scene}"\noutput = "f/{frame:02d}.png"\naovs = ["normal", "depth"]\n'))
    assert job.aovs == ("depth", "normal")
    assert job.frames[0].outputs == {"color": "f/00.png", "depth": "f/00.depth.exr", "normal": "f/00.normal.exr"}


def test_shards_partition_the_frames(job_dir):
    job = load_job(write_job(job_dir, 'scene = "{scene}"\noutput = "{frame}.png"\n[sweep]\n"render.spp" = [1, 4, 9, 16, 25]\n'))
    parts = [select_shard(job.frames, (i, 3)) for i in range(3)]
    assert sorted(f.index for p in parts for f in p) == list(range(5))
    assert [f.index for f in parts[1]] == [1, 4]


def test_frame_count_and_worker_spec_are_known_before_an_orbit_is_expanded(job_dir):
    """The workers start before check_scene(): what they are given must not need it."""
    job = load_job(write_job(job_dir, 'scene = "{scene}"\noutput = "{frame}_{render.spp}_{sweep}.png"\n[orbit]\nframes = 5\n'
                                      '[sweep]\n"render.spp" = [1, 4]\n"lights[0].color" = [[1, 1, 1], [0.5, 0.5, 0.5]]\n'))
    counts = [job.frame_count(s) for s in (None, (0, 3), (1, 3), (2, 3))]
    spec = job.spec()
    check_scene(job)  # expands the orbit: 2 x 2 sweep combinations x 5 eyes
    assert counts == [len(job.frames)] + [len(select_shard(job.frames, (i, 3))) for i in range(3)] == [20, 7, 7, 6]
    first_of_each = {}
    for f in job.frames:  # per render.* setting, its first frame, the orbit's eye aside
        first_of_each.setdefault(f.overrides["render.spp"], {k: v for k, v in f.overrides.items() if k != "camera.eye"})
    assert spec["warmup"] == list(first_of_each.values())


@pytest.mark.parametrize("text, env, expected", [
    ("1/4", {}, (1, 4)),
    ("auto", {"SLURM_ARRAY_TASK_ID": "5", "SLURM_ARRAY_TASK_MIN": "4", "SLURM_ARRAY_TASK_COUNT": "3"}, (1, 3)),
    ("auto", {"SLURM_ARRAY_TASK_ID": "2", "SLURM_ARRAY_TASK_COUNT": "3"}, (2, 3)),
    ("auto/8", {"JOB_COMPLETION_INDEX": "7"}, (7, 8)),
    ("auto", {"JOB_COMPLETION_INDEX": "0", "WARPRT_SHARD_COUNT": "2"}, (0, 2)),
    ("auto", {"WARPRT_SHARD_INDEX": "1", "WARPRT_SHARD_COUNT": "2"}, (1, 2)),
])
def test_parse_shard(text, env, expected):
    assert parse_shard(text, env) == expected


@pytest.mark.parametrize("text, env, message", [
    ("2/2", {}, "expected 0 <= I < N"),
    ("1", {}, "expected I/N"),
    ("a/2", {}, "not an integer"),
    ("auto", {}, "no shard index"),
    ("auto", {"JOB_COMPLETION_INDEX": "3"}, "no count"),
    ("auto/4", {"SLURM_ARRAY_TASK_ID": "1", "SLURM_ARRAY_TASK_COUNT": "3"}, "disagrees"),
])
def test_parse_shard_errors(text, env, message):
    with pytest.raises(SceneError, match=message) as e:
        parse_shard(text, env)
    assert e.value.field == "shard"


BAD_JOBS = [
    ('scene = "{scene}"\nframes = 3\n', "frames", "unknown key"),
    ('output = "a.png"\n', "scene", "is required"),
    ('scene = "nope/missing.toml"\n', "scene", "scene file not found"),
    ('scene = "{scene}"\noutput = "f/{frame}.jpg"\n', "output", "unknown image extension"),
    ('scene = "{scene}"\noutput = "f/{frame}_{spp}.png"\n[orbit]\nframes = 2\n', "output", "unknown placeholder {spp}"),
    ('scene = "{scene}"\noutput = "f/one.png"\n[orbit]\nframes = 2\n', "output", "would both write"),
    ('scene = "{scene}"\n[orbit]\nframes = 0\n', "orbit.frames", "expected an integer >= 1"),
    ('scene = "{scene}"\n[orbit]\nframes = 2\nradius = 3\n', "orbit.radius", "unknown key"),
    ('scene = "{scene}"\n[orbit]\nframes = 2\n[[cameras]]\neye = [0, 1, 5]\n', "cameras", "one camera sequence"),
    ('scene = "{scene}"\n[[cameras]]\neye = [0, 1]\n', "cameras[0].eye", "3 finite numbers"),
    ('scene = "{scene}"\n[[cameras]]\nnear = 2.0\n', "cameras[0].near", "unknown camera field"),
    ('scene = "{scene}"\n[sweep]\n"render.spp" = 4\n', "sweep.render.spp", "non-empty list"),
    ('scene = "{scene}"\n[orbit]\nframes = 2\n[sweep]\n"camera.eye" = [[0, 1, 5]]\n', "sweep.camera.eye", "set by the job"),
    ('scene = "{scene}"\n[path]\nkeyframes = [{frame = 0, eye = [0, 1, 5]}, {frame = 3, fovy = 30}]\n',
     "path.keyframes[1]", "the same camera fields"),
    ('scene = "{scene}"\n[path]\nkeyframes = [{frame = 1, eye = [0, 1, 5]}, {frame = 3, eye = [1, 1, 5]}]\n',
     "path.keyframes[0].frame", "must be frame 0"),
    ('scene = "{scene}"\naovs = "depth"\n', "aovs", "expected a list of AOV names"),
    ('scene = "{scene}"\naovs = ["depth", "zdepth"]\n', "aovs", "unknown AOV 'zdepth'"),
    ('scene = "{scene}"\n[sweep\n', None, "malformed TOML"),
]


@pytest.mark.parametrize("body, field, message", BAD_JOBS)
def test_bad_job_files(job_dir, body, field, message):
    path = write_job(job_dir, body)
    with pytest.raises(SceneError) as e:
        check_scene(load_job(path))
    assert e.value.source == str(path) and e.value.field == field
    assert message in e.value.message


@pytest.mark.parametrize("body, field, message", [
    ('scene = "{scene}"\n[sweep]\n"render.sppp" = [1]\n', "sweep.render.sppp[0]", "unknown key (did you mean 'spp'?)"),
    ('scene = "{scene}"\n[sweep]\n"render.spp" = [1, 3]\n', "sweep.render.spp[1]", "render.spp: expected a square"),
    ('scene = "{scene}"\n[set]\n"camera.width" = -1\n', "set.camera.width", "expected an integer in"),
    ('scene = "{scene}"\n[sweep]\n"lights[5].color" = [[1, 1, 1]]\n', "sweep.lights[5].color[0]", "there is no lights[5]"),
])
def test_bad_sweep_and_set_fields_name_the_job_and_the_scene(job_dir, body, field, message):
    path = write_job(job_dir, body)
    with pytest.raises(SceneError) as e:
        check_scene(load_job(path))
    assert (e.value.source, e.value.field) == (str(path), field)
    assert message in e.value.message and str(SCENE) in e.value.message


def test_a_job_file_reads_as_a_scene_file_does(job_dir):
    """One TOML reader: a byte-order mark (as Windows editors write) is skipped in a job file too, and a
    byte that is not UTF-8 is named with its line, in the scene file's words."""
    path = write_job(job_dir, 'scene = "{scene}"\n[orbit]\nframes = 2\n')
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    assert load_job(path).n_cameras == 2
    path.write_bytes(b'scene = "{scene}"\n# caf\xe9\n')
    with pytest.raises(SceneError) as e:
        load_job(path)
    assert (e.value.field, e.value.message) == (None, "not UTF-8 text (byte 0xe9 on line 2); a TOML file must be UTF-8")
