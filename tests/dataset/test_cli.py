"""`warprt batch` on the command line: bad input is one line on stderr naming the job file and the
field or frame, exit status 2, no traceback, nothing rendered."""

import json

import pytest

from marks import slow

from dataset.jobs import SCENE, cli, require_ray, write_job

BAD = [
    # a bad job key
    ('scene = "{scene}"\noutputs = "f/{frame}.png"\n', "outputs: unknown key (did you mean 'output'?)"),
    # a bad sweep field: the scene's reader names it
    ('scene = "{scene}"\n[sweep]\n"render.sppp" = [1, 4]\n', "sweep.render.sppp[0]: "),
    # an unknown AOV
    ('scene = "{scene}"\naovs = ["depth", "zdepth"]\n', "aovs: unknown AOV 'zdepth'"),
    # a missing scene
    ('scene = "missing.toml"\n', "scene: scene file not found"),
    # a frame whose overrides are invalid: caught before any frame renders
    ('scene = "{scene}"\noutput = "f/{frame}.png"\n[[cameras]]\neye = [0.0, 1.5, 5.0]\n'
     '[[cameras]]\neye = [0.0, 0.6, 0.0]\n', f"frame 1 (cameras[1]): {SCENE}: camera.center: must differ from camera.eye"),
]


def _main(argv, capsys):
    """warprt.cli.main, as the command runs it: (exit status, stdout, stderr)."""
    from warprt.cli import main

    try:
        code = main([str(a) for a in argv])
    except SystemExit as e:  # argparse's usage errors
        code = e.code
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.mark.parametrize("body, expected", BAD)
def test_bad_input_is_one_line_exit_2(tmp_path, capsys, body, expected):
    job = write_job(tmp_path, body)
    code, out, err = _main(["batch", job, "-o", tmp_path / "out", "-q"], capsys)
    assert code == 2, err
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"warprt: error: {job}: ") and expected in lines[0], lines[0]
    assert "Traceback" not in err and out == ""
    assert not list((tmp_path / "out").rglob("*.png"))
    manifest = tmp_path / "out" / "manifest.jsonl"
    assert not manifest.exists() or manifest.read_text() == ""


@slow
def test_the_command_exits_2_with_the_one_line(tmp_path):
    job = write_job(tmp_path, BAD[-1][0])
    r = cli("batch", job, "-o", tmp_path / "out", "-q")
    lines = r.stderr.splitlines()
    assert (r.returncode, r.stdout, len(lines)) == (2, "", 1) and lines[0].startswith(f"warprt: error: {job}: {BAD[-1][1]}")


@pytest.mark.parametrize("args, expected", [
    (["--shard", "3/2"], "command line: --shard: expected 0 <= I < N, got 3/2"),
    (["--workers", "0"], "command line: --workers: expected an integer >= 1"),
    (["--bogus"], "command line: unrecognized arguments: --bogus"),
    (["--ray", "127.0.0.1:1"], "command line: --ray: cannot reach a Ray cluster at 127.0.0.1:1"),  # not a 5-min hang
])
def test_bad_options_are_one_line_exit_2(tmp_path, capsys, args, expected):
    if "--ray" in args:
        require_ray()
    job = write_job(tmp_path, 'scene = "{scene}"\n')
    code, _, err = _main(["batch", job, "-q", "-o", tmp_path / "out", *args], capsys)
    assert code == 2 and len(err.splitlines()) == 1 and expected in err, err


@slow
def test_cli_run_writes_frames_and_manifest(tmp_path):
    job = write_job(tmp_path, 'scene = "{scene}"\noutput = "f/{frame:02d}.png"\n[orbit]\nframes = 3\n')
    r = cli("batch", job, "--workers", "1", "-q")  # default output folder: the job file's
    assert r.returncode == 0 and r.stderr == "" and r.stdout == "", r.stderr
    rows = [json.loads(line) for line in (tmp_path / "manifest.jsonl").read_text().splitlines()]
    assert sorted(r["frame"] for r in rows) == [0, 1, 2]
    assert all((tmp_path / r["outputs"]["color"]).is_file() for r in rows)


def _orbit(tmp_path, frames=2):
    return write_job(tmp_path, f'scene = "{{scene}}"\noutput = "f/{{frame}}.png"\n'
                               f'[set]\n"camera.width" = 16\n"camera.height" = 12\n[orbit]\nframes = {frames}\n')


def test_device_cpu_renders_the_frames_and_the_manifest_names_the_device(tmp_path, capsys):
    job = _orbit(tmp_path)
    code, out, err = _main(["batch", job, "-o", tmp_path / "out", "-q", "--device", "cpu"], capsys)
    assert code == 0, err
    rows = [json.loads(line) for line in (tmp_path / "out" / "manifest.jsonl").read_text().splitlines()]
    assert len(rows) == 2 and all(r["worker"]["device"] == "cpu" and r["stats"]["device"] == "cpu" for r in rows)


@pytest.mark.parametrize("flags, expected", [
    (["--device", "cuda"], "command line: --device: 'cuda' is not available on this machine"),
    (["--device", "tpu"], "command line: argument --device: invalid choice: 'tpu'"),
], ids=["cuda without a GPU", "unknown device"])
def test_a_device_this_machine_lacks_is_one_line_exit_2(tmp_path, capsys, flags, expected):
    import warp as wp

    wp.init()
    if flags[1] == "cuda" and wp.is_cuda_available():
        pytest.skip("this machine has CUDA: the refusal is for machines without")
    job = _orbit(tmp_path)
    code, out, err = _main(["batch", job, "-o", tmp_path / "out", "-q", *flags], capsys)
    assert code == 2 and len(err.splitlines()) == 1 and expected in err, err
    assert not (tmp_path / "out").exists() or not list((tmp_path / "out").rglob("*.png"))


def test_batch_refuses_a_device_before_any_worker_starts(tmp_path):
    """Python callers: the device is checked first, and a GPU with Ray is refused (not built)."""
    import warprt.dataset as dataset
    from warprt import SceneError

    job = _orbit(tmp_path)
    with pytest.raises(SceneError, match=r"batch\(\): device: 'cuda' with Ray is not supported"):
        dataset.batch(job, tmp_path / "out", device="cuda", ray=True)
    with pytest.raises(SceneError, match=r"batch\(\): device: expected a Warp device name"):
        dataset.batch(job, tmp_path / "out", device="")
    assert not (tmp_path / "out").exists() or not list((tmp_path / "out").rglob("*.png"))
