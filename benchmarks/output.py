"""Writing a benchmark's results: its numbers as JSON beside its Markdown report."""

from __future__ import annotations

import json
import os
from pathlib import Path


def link(plot: str, relative_to) -> str:
    """A plot's path as the Markdown written to ``relative_to`` should link it."""
    return os.path.relpath(plot, relative_to) if relative_to is not None else plot


def save(out: Path | str, data: dict, markdown: str) -> Path:
    """Write ``markdown`` to ``out`` and ``data`` to the .json beside it; returns ``out``."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps(data, indent=1, default=str) + "\n")
    out.write_text(markdown + "\n")
    return out
