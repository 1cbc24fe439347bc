"""`import warprt` never imports torch (issue 38): only `import warprt.torch` does, for those who ask for it."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def torch_imported_by(statement: str) -> bool:
    """Whether ``statement``, run in a fresh interpreter, leaves torch in sys.modules."""
    code = f"import sys\n{statement}\nprint('torch' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT,
                         env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})  # this checkout's warprt
    return out.stdout.split()[-1] == "True"


@pytest.mark.parametrize("statement", ["import warprt", "import warprt; warprt.Renderer; warprt.image"])
def test_warprt_does_not_import_torch(statement):
    assert not torch_imported_by(statement)


def test_warprt_torch_imports_torch():
    """The negative control: the same check sees torch once warprt.torch is asked for."""
    assert torch_imported_by("import warprt.torch")
