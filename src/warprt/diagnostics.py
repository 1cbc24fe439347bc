"""Warnings: one line each, the render goes on. A reader that meets something it does not use (a missing
texture, an MTL statement it ignores, an open glass mesh) says so through warn(), as a SceneWarning:
Python callers can filter or catch it; the command line prints it as one line and -q silences it.
"""

from __future__ import annotations

import warnings

from .errors import SceneWarning


def warn(source, field, message):
    """A SceneWarning worded as a SceneError is: ``source: field: message``. Python shows each distinct
    one once (its default filter), so a statement repeated a thousand times warns once."""
    where = f"{source}: {field}" if field else str(source)
    warnings.warn(SceneWarning(" ".join(f"{where}: {message}".split())), stacklevel=2)


def set_quiet(quiet: bool = True):
    """Silence (or restore) warprt's warnings: the command line's -q."""
    warnings.filterwarnings("ignore" if quiet else "default", category=SceneWarning)


def one_line_warning(message, category, filename, lineno, line=None) -> str:
    """warnings.formatwarning for the command line: a SceneWarning as one line, others as Python has them."""
    if issubclass(category, SceneWarning):
        return f"warprt: warning: {message}\n"
    return _python_format(message, category, filename, lineno, line)


_python_format = warnings.formatwarning
