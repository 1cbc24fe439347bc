"""Reading TOML for scene and job files alike: the file to a dict (read_toml), typed access to one of its
tables (TableReader), and the "did you mean" hint, each error a SceneError naming the file and dotted field."""

from __future__ import annotations

import difflib
import math
import tomllib
from pathlib import Path

import numpy as np

from ..errors import SceneError, show


def did_you_mean(word: str, choices, otherwise: str = "") -> str:
    """`` (did you mean 'x'?)`` for the choice closest to a misspelt ``word``, else ``otherwise``."""
    close = difflib.get_close_matches(word, sorted(choices), n=1)
    return f" (did you mean '{close[0]}'?)" if close else otherwise


def read_toml(path: Path, what: str) -> dict:
    """A TOML file (``what``: "scene file", "job file", as its errors name it) as tomllib's dict."""
    source = str(path)
    try:
        # utf-8-sig: a byte-order mark, which Windows editors write, is not part of the TOML.
        text = Path(path).read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise SceneError(source, None, f"{what} not found") from None
    except IsADirectoryError:
        raise SceneError(source, None, f"is a folder, not a {what}") from None
    except UnicodeDecodeError as e:
        line = e.object[:e.start].count(b"\n") + 1
        raise SceneError(source, None, f"not UTF-8 text (byte 0x{e.object[e.start]:02x} on line {line}); "
                                       "a TOML file must be UTF-8") from None
    except OSError as e:
        raise SceneError(source, None, f"cannot read {what}: {e.strerror or e}") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SceneError(source, None, f"malformed TOML: {e}") from None


def plain(v):
    """A value as tomllib would give it, from what Python callers write: a tuple or a 1-D NumPy array as a
    list, a NumPy scalar as a Python number, a Path as a string; (N, k) arrays stay arrays (rows() reads them)."""
    if isinstance(v, dict):
        return {k: plain(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [plain(x) for x in v]
    if isinstance(v, np.ndarray) and v.ndim <= 1:
        return v.tolist()
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, Path):
        return str(v)
    return v


class TableReader:
    """Typed access to one TOML table, raising SceneError with the file and dotted field (``prefix.key``;
    the key alone where prefix is "", as a Python call's arguments are named)."""

    def __init__(self, source: str, table: dict, prefix: str):
        self.source, self.table, self.prefix = source, table, prefix

    def fail(self, key: str | None, message: str):
        raise SceneError(self.source, ".".join(p for p in (self.prefix, key) if p) or None, message)

    def check_keys(self, allowed, what: str = "key"):
        listed = f" (expected one of: {', '.join(sorted(allowed))})"
        for key in self.table:
            if key not in allowed:
                self.fail(key, f"unknown {what}{did_you_mean(key, allowed, listed)}")

    def number(self, key, default=None, lo=None, hi=None, lo_open=False, hi_open=False, whole=False):
        """A finite number in range; ``whole``: any failure worded "expected a number" (as job files word it)."""
        v = self.table.get(key, default)
        if v is None:
            self.fail(key, "is required")
        if isinstance(v, bool) or not isinstance(v, (int, float)) or (whole and not math.isfinite(v)):
            self.fail(key, f"expected a number, got {show(v)}")
        v = float(v)
        if not math.isfinite(v):
            self.fail(key, f"expected a finite number, got {v}")
        if lo is not None and (v < lo or (lo_open and v == lo)):
            self.fail(key, f"expected a number {'>' if lo_open else '>='} {lo:g}, got {v:g}")
        if hi is not None and (v > hi or (hi_open and v == hi)):
            self.fail(key, f"expected a number {'<' if hi_open else '<='} {hi:g}, got {v:g}")
        return v

    def integer(self, key, default=None, lo=None, hi=None):
        """An integer; with a lower bound only, any failure is worded by that bound ("an integer >= 1")."""
        v = self.table.get(key, default)
        if v is None:
            self.fail(key, "is required")
        bad_type = isinstance(v, bool) or not isinstance(v, int)
        if lo is not None and hi is None:
            if bad_type or v < lo:
                self.fail(key, f"expected an integer >= {lo}, got {show(v)}")
        elif bad_type:
            self.fail(key, f"expected an integer, got {show(v)}")
        elif (lo is not None and v < lo) or (hi is not None and v > hi):
            self.fail(key, f"expected an integer in [{lo}, {hi}], got {v}")
        return int(v)

    def boolean(self, key, default):
        v = self.table.get(key, default)
        if not isinstance(v, bool):
            self.fail(key, f"expected true or false, got {show(v)}")
        return v

    def string(self, key, default=None):
        v = self.table.get(key, default)
        if v is None:
            self.fail(key, "is required")
        if not isinstance(v, str):
            self.fail(key, f"expected a string, got {show(v)}")
        return v

    def choice(self, key, allowed: tuple, default=None) -> str:
        v = self.string(key, default)
        if v not in allowed:
            self.fail(key, f"expected one of {', '.join(map(repr, allowed))}, got {show(v)}")
        return v

    def vector(self, key, default=None, n=3, nonneg=False, allow_scalar=False, whole=False):
        """n finite numbers as a tuple; ``whole``: any failure worded "a list of n finite numbers" (job files)."""
        v = self.table.get(key, default)
        if v is None:
            self.fail(key, "is required")
        if allow_scalar and isinstance(v, (int, float)) and not isinstance(v, bool):
            v = [v] * n
        if whole and not (isinstance(v, (list, tuple)) and len(v) == n and all(
                isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in v)):
            self.fail(key, f"expected a list of {n} finite numbers, got {show(v)}")
        if not isinstance(v, (list, tuple)) or len(v) != n:
            what = f"a number or a list of {n} numbers" if allow_scalar else f"a list of {n} numbers"
            self.fail(key, f"expected {what}, got {show(v)}")
        out = []
        for x in v:
            if isinstance(x, bool) or not isinstance(x, (int, float)):
                self.fail(key, f"expected a list of {n} numbers, got {show(v)}")
            if not math.isfinite(x):
                self.fail(key, f"expected finite numbers, got {show(v)}")
            if nonneg and x < 0:
                self.fail(key, f"expected non-negative numbers, got {show(v)}")
            out.append(float(x))
        return tuple(out)

    def rows(self, key, width: int, what: str, min_rows: int = 1, nonneg: bool = False) -> np.ndarray:
        """A list of rows of ``width`` finite numbers (``what`` says what they are), as float64 (rows, width);
        ``nonneg``: colours, none below 0."""
        v = self.table.get(key)
        try:
            a = np.asarray(v, np.float64)
        except (TypeError, ValueError):
            a = None
        if a is None or a.ndim != 2 or a.shape[1] != width or len(a) < min_rows:
            self.fail(key, f"expected a list of {what}, got {show(v)}")
        if not np.all(np.isfinite(a)):
            self.fail(key, "expected finite numbers, found NaN or Inf")
        if nonneg and (a < 0).any():
            self.fail(key, "expected non-negative colours")
        return a
