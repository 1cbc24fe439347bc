"""Small scenes for tests, written as the dicts a TOML scene file parses to: built in memory
(make_scene) or written to a real scene file (write_scene) for what reads files."""

from __future__ import annotations

import copy
import json
import math
import re
from pathlib import Path

import numpy as np

import warprt

# A camera on the +z axis looking at the origin: the image plane is parallel to z = 0.
FRONT_CAMERA = {"eye": [0.0, 0.0, 5.0], "center": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0],
                "fovy": 60.0, "near": 1.0, "width": 64, "height": 48}


def scene_doc(objects, materials=None, lights=(), camera=None, **render) -> dict:
    """The scene-file dict of a test scene: FRONT_CAMERA (fields overridden by ``camera``), no
    ambient light and a black background unless ``render`` says otherwise."""
    return {
        "camera": {**FRONT_CAMERA, **(camera or {})},
        "render": {"ambient": [0.0, 0.0, 0.0], "background": [0.0, 0.0, 0.0], "max_depth": 1, **render},
        "lights": [dict(l) for l in lights],
        "materials": copy.deepcopy(materials or {}),
        "objects": [dict(o) for o in objects],
    }


def make_scene(objects, materials=None, lights=(), camera=None, **render):
    return warprt.load_dict(scene_doc(objects, materials, lights, camera, **render), source="<test>")


# A material that shows only its ambient term: with C_amb = 1 a hit pixel is exactly ka.
MARKER = {"ka": [1.0, 1.0, 1.0], "kd": [0.0, 0.0, 0.0]}


def write_scene(folder, doc: dict, name: str = "scene.toml") -> Path:
    """Write the scene-file dict ``doc`` (as make_scene's or tomllib's) to folder/name as TOML; the path."""
    path = Path(folder) / name
    path.write_text(to_toml(doc))
    return path


_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _key(k) -> str:
    return k if _BARE_KEY.fullmatch(k) else _string(k)


def _string(s: str) -> str:
    # A JSON string is a TOML basic string, but for DEL and surrogate escapes, which TOML forbids.
    return json.dumps(s, ensure_ascii=False).replace("\x7f", "\\u007f")


def _value(v) -> str:
    """One TOML value: booleans, integers, floats (nan and inf too), strings, arrays, inline tables."""
    if isinstance(v, (np.ndarray, np.generic)):
        v = v.tolist()
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) else repr(v)
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + "}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    raise TypeError(f"no TOML value for {type(v).__name__}")


def _is_table_array(v) -> bool:
    return isinstance(v, (list, tuple)) and len(v) > 0 and all(isinstance(x, dict) for x in v)


def _table(path: list[str], table: dict, lines: list[str], header: bool = True):
    """A table's key/value pairs (under its [header], unless it is an array entry whose [[header]]
    is written already), then its sub-tables and arrays of tables."""
    values = {k: v for k, v in table.items() if not isinstance(v, dict) and not _is_table_array(v)}
    children = [k for k in table if k not in values]
    dotted = lambda keys: ".".join(map(_key, keys))
    if header and path and (values or not children):
        lines.append(f"[{dotted(path)}]")
    lines += [f"{_key(k)} = {_value(v)}" for k, v in values.items()]
    for k in children:
        if isinstance(table[k], dict):
            _table(path + [k], table[k], lines)
            continue
        for item in table[k]:
            lines.append(f"[[{dotted(path + [k])}]]")
            _table(path + [k], item, lines, header=False)


def to_toml(doc: dict) -> str:
    """TOML text that tomllib reads back as ``doc`` (tomllib only reads): dicts become tables,
    lists of dicts arrays of tables, everything else a value."""
    lines: list[str] = []
    _table([], doc, lines)
    return "\n".join(lines) + "\n"


def trace_kernel_source(fx) -> str:
    """The C++ Warp generates for the trace kernel of EffectSet ``fx`` (what a variant's switches leave in)."""
    import warp as wp

    from warprt.kernels import init_warp, make_trace_kernel

    init_warp()
    kernel = make_trace_kernel(fx)
    wp.load_module(kernel.module, device="cpu")
    (module_exec,) = kernel.module.execs.values()
    return Path(module_exec.binary_path).with_suffix("").with_suffix(".cpp").read_text()
