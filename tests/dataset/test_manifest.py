"""The manifest's reading and appending rules, --resume's matching, the progress bar's switch, and
where batch() is found."""

import io

import warprt
from warprt.dataset import Manifest, done, load_job, progress_bar, read_rows

from dataset.jobs import every_line_is_json, write_job


TORN = '{"frame": 0, "key": "a"}\n{"frame": 1, "key": "b"}\n{"frame": 2, "ke'  # killed mid-append


def test_resume_drops_a_line_cut_short_and_the_file_stays_json_lines(tmp_path):
    (tmp_path / "manifest.jsonl").write_text(TORN)
    m = Manifest(tmp_path, resume=True)
    m.append({"frame": 2, "key": "c"})
    m.close()
    assert every_line_is_json(tmp_path / "manifest.jsonl")
    assert [r["frame"] for r in read_rows(tmp_path)] == [0, 1, 2]
    assert [p.name for p in tmp_path.iterdir()] == ["manifest.jsonl"]  # no temporary file left


def test_the_check_fails_on_a_torn_line_kept_as_before(tmp_path):
    """The negative control: the torn line kept and a newline glued to it, as resume used to leave it."""
    (tmp_path / "manifest.jsonl").write_text(TORN + '\n{"frame": 2, "key": "c"}\n')
    assert not every_line_is_json(tmp_path / "manifest.jsonl")
    assert [r["frame"] for r in read_rows(tmp_path)] == [0, 1, 2]  # the reader skips it; pandas and jq do not


def test_resume_rewrites_an_earlier_glued_torn_line_and_leaves_a_whole_file_untouched(tmp_path):
    path = tmp_path / "manifest.jsonl"
    path.write_text(TORN + '\n{"frame": 2, "key": "c"}\n')
    Manifest(tmp_path, resume=True).close()
    assert every_line_is_json(path) and [r["frame"] for r in read_rows(tmp_path)] == [0, 1, 2]
    inode = path.stat().st_ino
    Manifest(tmp_path, resume=True).close()
    assert path.stat().st_ino == inode  # nothing to drop: not rewritten


def test_a_fresh_unsharded_run_replaces_every_manifest_a_shard_only_its_own(tmp_path):
    for name in ("manifest.jsonl", "manifest.shard-0-of-2.jsonl", "manifest.shard-1-of-2.jsonl"):
        (tmp_path / name).write_text('{"frame": 9, "key": "x"}\n')
    Manifest(tmp_path, shard=(0, 2)).close()
    assert [p.name for p in sorted(tmp_path.iterdir()) if p.stat().st_size] == ["manifest.jsonl", "manifest.shard-1-of-2.jsonl"]
    Manifest(tmp_path).close()
    assert [p.name for p in tmp_path.iterdir()] == ["manifest.jsonl"] and read_rows(tmp_path) == []


def test_resume_needs_the_same_key_and_the_files(tmp_path):
    job = load_job(write_job(tmp_path, 'scene = "{scene}"\noutput = "{frame}.png"\n[[cameras]]\nfovy = 30\n'
                                       '[[cameras]]\nfovy = 40\n[[cameras]]\nfovy = 50\n'))
    f0, f1, f2 = job.frames
    rows = [{"frame": f.index, "key": f.key, "outputs": f.outputs} for f in job.frames]
    rows[2]["key"] = "changed"  # the job (or the scene file) changed since
    (tmp_path / "0.png").write_bytes(b"x")
    (tmp_path / "2.png").write_bytes(b"x")  # 1.png missing
    assert set(done(rows, job.frames, tmp_path)) == {0}
    # The key follows the scene file's content:
    (tmp_path / "s.toml").write_text(open(job.scene_path).read())
    other = load_job(write_job(tmp_path, 'scene = "s.toml"\noutput = "{frame}.png"\n[[cameras]]\nfovy = 30\n', name="j2.toml"))
    key = other.frames[0].key
    with open(tmp_path / "s.toml", "a") as f:
        f.write("\n# edited\n")
    assert load_job(tmp_path / "j2.toml").frames[0].key != key


class _TTY(io.StringIO):
    def isatty(self):
        return True


def test_progress_bar_only_on_a_terminal_and_not_quiet(monkeypatch):
    monkeypatch.setattr("sys.stderr", io.StringIO())
    assert progress_bar(3, quiet=False) is None
    tty = _TTY()
    monkeypatch.setattr("sys.stderr", tty)
    assert progress_bar(3, quiet=True) is None
    bar = progress_bar(3, quiet=False)
    bar.update(3)
    bar.close()
    text = tty.getvalue()
    assert "3/3" in text and "frame/s" in text


def test_batch_is_a_function_of_warprt_and_of_warprt_dataset():
    import warprt.dataset

    assert "batch" in warprt.__all__ and callable(warprt.batch)
    assert warprt.batch is warprt.dataset.batch and warprt.batch.__module__ == "warprt.dataset.driver"
