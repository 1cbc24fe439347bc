"""Job files, the `warprt batch` command and Ray for the batch tests: frames are tiny (tiny.toml, 32x24)."""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

SCENE = Path(__file__).resolve().parent / "data" / "tiny.toml"
ROOT = Path(__file__).resolve().parents[2]


def write_job(folder: Path, body: str, name: str = "job.toml", scene: Path = SCENE) -> Path:
    """A job file in ``folder``; ``{scene}`` in the body is the test scene's path."""
    folder.mkdir(parents=True, exist_ok=True)
    p = folder / name
    p.write_text(textwrap.dedent(body).replace("{scene}", str(scene).replace("\\", "/")))
    return p


def cli(*args, timeout=180, **kw):
    """The real command: python -m warprt ARGS."""
    return subprocess.run([sys.executable, "-m", "warprt", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, cwd=ROOT, **kw)


def require_ray():
    """Ray, or a failure saying how to get it: CI must run these tests on a real Ray, never skip them."""
    try:
        import ray
    except ImportError:
        pytest.fail("the Ray tests need Ray: pip install -e '.[test,ray]' (make test installs it)", pytrace=False)
    return ray


def every_line_is_json(path) -> bool:
    """What pandas.read_json(lines=True) and jq need of a manifest: each line one JSON value."""
    try:
        for line in Path(path).read_text().splitlines():
            json.loads(line)
    except json.JSONDecodeError:
        return False
    return True
