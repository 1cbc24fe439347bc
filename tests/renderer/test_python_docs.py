"""docs/python.md's example runs as written: its frames are written and read back, and what it prints
about the BVH is what happened."""

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

from warprt.image import read_image

DOC = Path(__file__).resolve().parents[2] / "docs" / "python.md"


def test_the_from_python_example_runs(tmp_path):
    (block,) = re.findall(r"```python\n(.*?)```", DOC.read_text(), re.S)
    r = subprocess.run([sys.executable, "-c", block], cwd=tmp_path, capture_output=True, text=True,
                       env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].startswith("reused") and lines[-1] == "refit"
    frames = [read_image(tmp_path / f"frame{i}.png") for i in range(4)]
    assert all(f.shape == (120, 160, 3) for f in frames)
    assert not np.array_equal(frames[0], frames[3])  # the light moved
    assert (tmp_path / "squashed.png").exists()
