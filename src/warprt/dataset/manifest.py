"""The manifest: one JSON line per finished frame, appended by the driver only (never by a worker),
after the frame's files are complete (renamed into place), and flushed to the disk.

    DIR/manifest.jsonl                  an unsharded run
    DIR/manifest.shard-I-of-N.jsonl     shard I of N (shards may run at once, on other machines:
                                        one file each, so no two processes append to one file)

The job's manifest is the union of DIR/manifest*.jsonl. A line: frame, key (the frame's
fingerprint), camera, sweep, overrides, outputs (relative to DIR), aovs, stats (RenderStats.to_dict()),
worker (host, pid, threads; node on Ray), seconds (scene, render, write on the worker), attempt, run
(the id of the run that rendered it), backend.

A fresh (not resume) unsharded run removes every manifest*.jsonl in DIR; a fresh shard
truncates its own file only. A line cut short by a crash is ignored when read, and a resumed run drops
it from the file it appends to (rewritten whole, then renamed over it), so that the file stays JSON
lines for pandas.read_json(lines=True) and jq; its frame, having no line, is rendered again.
"""

from __future__ import annotations

import glob
import json
import os
from pathlib import Path

NAME = "manifest.jsonl"


def manifest_name(shard) -> str:
    """The file a run appends to: its shard's own, so that shards running at once never share one."""
    return NAME if shard is None else f"manifest.shard-{shard[0]}-of-{shard[1]}.jsonl"


def manifest_files(out_dir) -> list[Path]:
    return sorted(Path(p) for p in glob.glob(os.path.join(glob.escape(str(out_dir)), "manifest*.jsonl")))


def read_rows(out_dir) -> list[dict]:
    """Every line of every manifest*.jsonl in out_dir: the job's manifest, shards included."""
    rows = []
    for p in manifest_files(out_dir):
        with open(p, encoding="utf-8") as f:
            for line in f:
                line = line.strip()
                if not line:
                    continue
                try:
                    row = json.loads(line)
                except json.JSONDecodeError:
                    continue  # a line cut short by a crash
                if isinstance(row, dict) and "frame" in row:
                    rows.append(row)
    return rows


def done(rows: list[dict], frames, out_dir) -> dict:
    """frame index -> row, for frames whose line (same key) and files exist."""
    by_key = {}
    for r in rows:
        by_key[(r.get("frame"), r.get("key"))] = r
    out = {}
    for f in frames:
        r = by_key.get((f.index, f.key))
        if r is not None and all((Path(out_dir) / p).is_file() for p in r.get("outputs", {}).values()):
            out[f.index] = r
    return out


class Manifest:
    """The run's manifest file, opened for appending: emptied first unless resuming (an unsharded run
    removes every manifest*.jsonl, a shard only its own); when resuming, whole lines only."""

    def __init__(self, out_dir, shard=None, resume=False):
        self.out_dir = Path(out_dir)
        self.path = self.out_dir / manifest_name(shard)
        if not resume:
            stale = manifest_files(self.out_dir) if shard is None else [self.path]
            for p in stale:
                p.unlink(missing_ok=True)
        elif self.path.exists():
            keep_whole_lines(self.path)
        self._f = open(self.path, "ab")

    def append(self, row: dict):
        """One line, on the disk when this returns (a crash right after keeps it)."""
        self._f.write((json.dumps(row, sort_keys=True) + "\n").encode())
        self._f.flush()
        os.fsync(self._f.fileno())

    def close(self):
        self._f.close()


def keep_whole_lines(path: Path):
    """Rewrite ``path`` without the lines that are not JSON (a line cut short by a crash mid-append, or
    one an earlier version glued a newline to), if it has any: the lines kept go to a temporary file,
    on the disk before it is renamed over ``path``, so a crash here leaves the old file or the new one."""
    data = path.read_bytes()
    lines = data.split(b"\n")
    keep = [line for line in lines if _is_json(line)]
    if data.endswith(b"\n") and len(keep) == len(lines) - 1:
        return  # every line whole (the empty string after the last newline aside)
    tmp = path.with_name(path.name + ".tmp")  # not manifest*.jsonl: never read as a manifest
    with open(tmp, "wb") as f:
        f.write(b"".join(line + b"\n" for line in keep))
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)
    if hasattr(os, "O_DIRECTORY"):  # the rename itself on the disk (POSIX; Windows has no directory fsync)
        fd = os.open(path.parent, os.O_RDONLY | os.O_DIRECTORY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _is_json(line: bytes) -> bool:
    try:
        return isinstance(json.loads(line), dict)
    except ValueError:  # JSONDecodeError, or bytes that are not UTF-8
        return False
