"""One place where warprt and the libraries it calls speak to the user. warprt's own warnings (a missing
texture, an MTL statement it ignores, an open glass mesh: warn()) are SceneWarnings; within collecting()
they, Python warnings (NumPy's floating-point ones, trimesh's, PIL's), trimesh's log and native diagnostics
written to fd 2 (USD's, Warp's) become warprt's one-line warnings on stderr, or nothing with quiet().
Outside it (a Scene built in Python) a SceneWarning is an ordinary Python warning, to filter or catch.

Warnings met while a step runs are held (collecting()) and printed when it succeeds; when it fails they
are dropped, since its one-line error says what went wrong and a failed command prints that line only.
"""

from __future__ import annotations

import logging
import os
import re
import sys
import tempfile
import warnings
from contextlib import contextmanager
from pathlib import Path

from .errors import SceneWarning, one_line

_quiet = False
_collectors: list[list[str]] = []  # the open collecting() blocks, innermost last


def warn(source, field, message):
    """A SceneWarning worded as a SceneError is: ``source: field: message``."""
    where = f"{source}: {field}" if field else str(source)
    warnings.warn(SceneWarning(one_line(f"{where}: {message}")), stacklevel=2)


def emit(message: str):
    """A warning line: held by the innermost collecting() block, else printed at once."""
    line = one_line(message)
    if _collectors:
        if line not in _collectors[-1]:
            _collectors[-1].append(line)
    elif not _quiet:
        print(f"warprt: warning: {line}", file=sys.stderr)


@contextmanager
def quiet(on: bool = True):
    """No warnings printed within the block (the command line's -q)."""
    global _quiet
    saved, _quiet = _quiet, bool(on)
    try:
        yield
    finally:
        _quiet = saved


class _LogToWarnings(logging.Handler):
    def __init__(self, source: str):
        super().__init__(logging.WARNING)
        self.source = source

    def emit(self, record):
        # A record with exc_info would print a whole traceback: its last line is what it says.
        why = f" ({record.exc_info[0].__name__}: {one_line(record.exc_info[1])})" if record.exc_info and record.exc_info[1] else ""
        emit(f"{self.source}: {record.name.split('.')[0]}: {record.getMessage()}{why}")


# Libraries whose log records at WARNING and above would reach stderr through logging's last-resort
# handler as bare, possibly multi-line text.
_LOGGERS = ("trimesh",)


@contextmanager
def collecting(source: str, hold: bool = True):
    """Run a step with its library warnings turned into warprt's, each named by ``source`` and the
    library that gave it, each distinct one once. hold: printed if the step succeeds, dropped if it
    raises; else printed as they come."""
    held: list[str] = []
    seen: set[str] = set()
    if hold:
        _collectors.append(held)

    def show(message, category, filename, lineno, file=None, line=None):
        # warprt's own say where they are; a library's, the step and the library it came from.
        text = str(message) if issubclass(category, SceneWarning) else f"{source}: {_library(filename)}: {message}"
        if text not in seen:
            seen.add(text)
            emit(text)

    handler = _LogToWarnings(source)
    loggers = [logging.getLogger(name) for name in _LOGGERS]
    saved = [(lg.propagate, lg.level) for lg in loggers]
    for lg in loggers:
        lg.addHandler(handler)
        lg.propagate = False
        if lg.level == logging.NOTSET or lg.level > logging.WARNING:
            lg.setLevel(logging.WARNING)
    failed = True
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("always")
            warnings.showwarning = show
            yield
        failed = False
    finally:
        for lg, (propagate, level) in zip(loggers, saved):
            lg.removeHandler(handler)
            lg.propagate, lg.level = propagate, level
        if hold:
            _collectors.pop()
            if not failed:
                for line in held:
                    emit(line)


def _library(filename: str) -> str:
    """The top-level package a warning came from (numpy, trimesh, PIL), from its file's path."""
    parts = Path(filename).parts
    if "site-packages" in parts:
        i = parts.index("site-packages")
        if i + 1 < len(parts):
            return Path(parts[i + 1]).stem
    if "warprt" in parts:
        return "warprt"
    return Path(filename).stem


class Captured:
    """What native code wrote to fd 2 within native_stderr(): ``text``, once the block has ended."""

    text = ""


@contextmanager
def native_stderr():
    """Capture what native code (C++ libraries writing to fd 2 directly, past sys.stderr) writes within
    the block, so that it can be turned into one-line warnings instead of reaching the terminal."""
    got = Captured()
    sys.stderr.flush()
    try:
        saved = os.dup(2)
    except OSError:  # no fd 2 at all (a daemon): nothing can reach the user there anyway
        yield got
        return
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 2)
        try:
            yield got
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            got.text = sink.read().decode(errors="replace")


# USD's diagnostics (TfDiagnosticMgr's default output): a header naming the kind, the function, the
# line and the C++ file, the message after ' -- ' (warnings) or quoted after ' : ' (errors), sometimes
# over several lines, and for composition errors the stage's address in memory.
_USD_HEADER = re.compile(r"^(Warning|Error|Coding Error|Runtime Error|Fatal Error|Status|Secure Error)\b", re.M)
_USD_NOISE = (re.compile(r"pxrInternal_[A-Za-z0-9_]*::"), re.compile(r"\s*\((?:instantiating|recomposing) stage on stage [^)]*\)"),
              re.compile(r"\s*<0x[0-9a-fA-F]+>"))  # object addresses: noise, and never the same twice


def usd_messages(text: str) -> list[str]:
    """USD's diagnostic blocks in ``text``, each one line: its kind unless a warning, then its message
    without the C++ function, file and line."""
    starts = [m.start() for m in _USD_HEADER.finditer(text)] or ([0] if text.strip() else [])
    out = []
    for a, b in zip(starts, starts[1:] + [len(text)]):
        block = one_line(text[a:b])
        kind = _USD_HEADER.match(block)
        if " -- " in block:
            body = block.split(" -- ", 1)[1]
        else:
            quoted = re.match(r".*? at line \d+ (?:in file|of) \S+ : '(.*)'$", block)
            body = quoted[1] if quoted else block
        for noise in _USD_NOISE:
            body = noise.sub("", body)
        out.append(body if kind is None or kind[1] == "Warning" else f"{kind[1].lower()}: {body}")
    return out
