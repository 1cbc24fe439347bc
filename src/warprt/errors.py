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


class ArgumentError(SceneError):
    """A bad argument to a library function, named as a Python caller wrote it: ``render(): shadows: ...``.
    ``message`` may mention another argument as ``{name}``, written ``name='value'`` from ``values``; a
    front end with its own names for the arguments (cli.py's flags) rewords the error with ``worded``."""

    def __init__(self, function: str, argument: str, message: str, values: dict | None = None):
        self.function, self.argument, self.template = function, argument, message
        self.values = dict(values or {})
        super().__init__(f"{function}()", argument, self._fill(lambda name, v: f"{name}={v!r}"))

    def _fill(self, write) -> str:
        text = self.template
        for name, v in self.values.items():
            text = text.replace("{" + name + "}", write(name, v))
        return text

    def worded(self, source: str, names: dict) -> SceneError:
        """The same error in another vocabulary: ``names`` maps each argument to its name there (a
        flag), another argument's value written as that name, a space and the value; self where the argument has no name there."""
        if self.argument not in names or any(n not in names for n in self.values):
            return self
        return SceneError(source, names[self.argument], self._fill(lambda name, v: f"{names[name]} {v}"))


def one_line(text, empty: str = "") -> str:
    """Text (an exception's message) as one line of an error: its runs of whitespace as single spaces;
    ``empty`` where nothing is left."""
    return " ".join(str(text).split()) or empty


def show(v) -> str:
    """A value as an error message quotes it: its repr, cut to 60 characters."""
    s = repr(v)
    return s if len(s) <= 60 else s[:57] + "..."


class SceneWarning(UserWarning):
    """Input that renders, but not as its author may expect (a missing texture, an open glass mesh, an
    MTL statement that is not read): diagnostics.warn() issues it, the command line prints it as one line."""
