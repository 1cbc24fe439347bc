"""What batch() returns: a BatchResult whose rows and counts are what the manifest on disk says (read
back here as JSON lines, not through warprt), the summary line the command prints from it, and the
deprecated summary dict, which warns once."""

import dataclasses
import json
import re
import warnings

import pytest

from warprt.dataset import batch

from dataset.jobs import write_job

JOB = 'scene = "{scene}"\noutput = "f/{frame}.png"\n[orbit]\nframes = 3\n'


def manifest_lines(path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines()]


def disagreements(result, lines: list[dict]) -> list[str]:
    """The fields of ``result`` that say otherwise than the manifest's ``lines``: none when they agree."""
    mine = [x for x in lines if x["run"] == result.run]
    said = {"rows": sorted(lines, key=lambda x: x["frame"]), "frames": len(lines), "rendered": len(mine),
            "skipped": len(lines) - len(mine)}
    told = {"rows": list(result.rows), "frames": result.frames, "rendered": result.rendered, "skipped": result.skipped}
    problems = [name for name in said if said[name] != told[name]]
    if any(x["backend"] != result.backend for x in mine):
        problems.append("backend")
    if len({x["worker"]["pid"] for x in mine}) > (result.workers or 0):
        problems.append("workers")
    return problems


@pytest.fixture(scope="module")
def first(tmp_path_factory):
    """A 3-frame job rendered by one worker: (job, output folder, result, the warnings it raised)."""
    d = tmp_path_factory.mktemp("result")
    job = write_job(d, JOB)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = batch(job, d / "out", workers=1)
    return job, d / "out", result, caught


def test_the_result_is_what_the_manifest_says(first):
    _, out, result, _ = first
    assert result.manifest == out / "manifest.jsonl"
    lines = manifest_lines(result.manifest)
    assert disagreements(result, lines) == [] and (result.rendered, result.skipped) == (3, 0)
    # The negative control: a count one off is seen.
    assert disagreements(dataclasses.replace(result, rendered=2), lines) == ["rendered", "skipped"]


def test_a_resumed_runs_result_is_what_the_manifest_then_says(first, tmp_path):
    job, out, earlier, _ = first
    lines = manifest_lines(earlier.manifest)
    again = tmp_path / "out"
    (again / "f").mkdir(parents=True)
    for x in lines:
        (again / x["outputs"]["color"]).write_bytes((out / x["outputs"]["color"]).read_bytes())
    (again / "manifest.jsonl").write_text("".join(json.dumps(x) + "\n" for x in lines[:2]))  # the last one lost

    result = batch(job, again, workers=1, resume=True)
    now = manifest_lines(result.manifest)
    assert disagreements(result, now) == [] and (result.rendered, result.skipped) == (1, 2)
    assert disagreements(earlier, now) == ["rows", "rendered", "skipped"]  # the negative control: another run's


def test_the_result_reads_as_its_rows(first):
    """As batch() returned the rows' list before the result: iterated, indexed, measured."""
    result = first[2]
    assert list(result) == list(result.rows) and result[-1] is result.rows[-1] and len(result) == result.frames == 3


def test_the_command_prints_what_the_manifest_says(tmp_path, capsys):
    from warprt.cli import main

    job = write_job(tmp_path, JOB)
    assert main(["batch", str(job), "-o", str(tmp_path / "out"), "--workers", "1"]) == 0
    line = capsys.readouterr().err.strip()
    lines = manifest_lines(tmp_path / "out" / "manifest.jsonl")
    m = re.fullmatch(r"warprt batch: (\d+) frames rendered, (\d+) already done, of (\d+) on 1 local workers x \d+ "
                     r"threads in [\d.]+ s, [\d.]+ frames/s", line)
    assert m, line
    assert [int(g) for g in m.groups()] == [len(lines), 0, len(lines)] == [3, 0, 3]


def test_no_summary_no_warning(first):
    assert not [w for w in first[3] if issubclass(w.category, DeprecationWarning) and "summary" in str(w.message)]


def test_the_deprecated_summary_dict_warns_once_and_holds_the_results_values(tmp_path):
    job = write_job(tmp_path, JOB)
    summary = {}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = batch(job, tmp_path / "out", workers=1, summary=summary)
    said = [w for w in caught if issubclass(w.category, DeprecationWarning) and "summary" in str(w.message)]
    assert len(said) == 1 and "\n" not in str(said[0].message) and said[0].filename == __file__  # the caller's line
    r = result
    assert summary == {"frames": 3, "skipped": 0, "rendered": 3, "backend": "local", "workers": 1,
                       "threads": r.threads, "seconds": r.seconds, "check_seconds": r.check_seconds,
                       "frame_check_seconds": r.frame_check_seconds, "render_seconds": r.render_seconds,
                       "boot_seconds": list(r.boot_seconds)}
    assert len(r.boot_seconds) == 1 and r.render_seconds > 0 and r.seconds > r.render_seconds
