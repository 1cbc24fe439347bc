"""The one error type a user sees: bad input, named by file and field; and its warning, for input
that renders but not as the user may expect. The CLI prints an error as a single line and exits with
status 2 (everything else is a bug); a warning is one line on stderr, and the render goes on.
"""

from __future__ import annotations

import warnings


class SceneError(ValueError):
    """Invalid input. ``source`` is the file (or 'camera', 'render' for API input), ``field`` the
    dotted key in the file's own vocabulary (``camera.fovy``, ``objects[2].mesh``)."""

    def __init__(self, source: str, field: str | None, message: str):
        self.source = str(source)
        self.field = field
        self.message = message
        where = f"{self.source}: {field}" if field else self.source
        super().__init__(f"{where}: {message}")


def show(v) -> str:
    """A value as an error message quotes it: its repr, cut to 60 characters."""
    s = repr(v)
    return s if len(s) <= 60 else s[:57] + "..."


class SceneWarning(UserWarning):
    """Input that renders, but not as its author may expect (a dielectric mesh that is not closed)."""


def warn(source: str, field: str | None, message: str):
    """Warn about ``field`` of ``source``, worded as SceneError words an error."""
    where = f"{source}: {field}" if field else str(source)
    warnings.warn(SceneWarning(f"{where}: {message}"), stacklevel=3)


def one_line_warning(message, category, filename, lineno, line=None) -> str:
    """warnings.formatwarning for the command line: a SceneWarning as one line, others as Python has them."""
    if issubclass(category, SceneWarning):
        return f"warprt: warning: {' '.join(str(message).split())}\n"
    return _python_format(message, category, filename, lineno, line)


_python_format = warnings.formatwarning
