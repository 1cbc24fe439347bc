"""The one error type a user sees: bad input, named by file and field.

The CLI prints it as a single line and exits with status 2; everything else is a bug.
"""

from __future__ import annotations


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
    """Input that renders, but not as its author may expect (a missing texture, an open glass mesh, an
    MTL statement that is not read): diagnostics.warn() issues it, the command line prints it as one line."""
