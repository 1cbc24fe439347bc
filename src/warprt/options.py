"""How a frame is rendered, as data: RenderOptions says each option's type, choices, default and help
once, so render(), Renderer and the command line (cli.py builds its flags from it) cannot drift. No Warp
here: the command line reads it before it knows whether anything will render."""

from __future__ import annotations

import os
import sys
import warnings
from dataclasses import MISSING, dataclass, field, fields, replace

from .errors import ArgumentError, SceneError, show
from .scene.effects import EFFECTS

ALGORITHMS = ("raytrace", "zbuffer")
PRIMARY_QUERIES = ("auto", "raytrace", "zbuffer")
SHADOW_QUERIES = ("auto", "bvh", "grid")
REFLECTION_QUERIES = ("auto", "bvh", "mirrors")
DEVICES = ("cpu", "cuda")  # what the command line offers; Python callers may name any Warp device ("cuda:1")
RASTER_TILE = 16  # the Z-buffer's raster tiles, pixels a side: each raster thread owns one tile
# The AOVs of the camera rays' first hits (image/aovs.py says what each holds).
AOVS = ("depth", "normal", "albedo", "position", "uv", "object", "material", "face", "coverage")

# Spellings of the first release, kept for one more with a warning: ``shadows`` also names the scene's
# effect (render.shadows, disable=["shadows"]) and ``tile`` the Z-buffer's raster tile.
RENAMED = {"primary": "primary_query", "shadows": "shadow_query", "reflections": "reflection_query",
           "tile": "pixel_tile"}


def option(default, help: str, *, choices: tuple | None = None, metavar: str | None = None, cli: bool = True,
           listed: bool = False, cli_name: str | None = None, check_choices: bool = True, type=None):
    """A RenderOptions field: its default and help, the ``choices`` it takes, and how the command line
    offers it (``cli``: as a flag named after the field, or ``cli_name``; ``listed``: a comma-separated
    list; ``metavar``: the value's name in the usage text)."""
    meta = {"help": help, "choices": choices, "metavar": metavar, "cli": cli, "listed": listed,
            "cli_name": cli_name, "check_choices": check_choices, "type": type}
    return field(default=default, metadata=meta)


@dataclass(frozen=True)
class RenderOptions:
    """How a scene is rendered, checked once, when made. Each field is an argument of render() and
    Renderer() of the same name; the image never depends on the three queries, only its cost does."""

    threads: int | None = option(None, "worker threads (default: all cores)", metavar="N", type=int)
    device: str = option("cpu", "Warp device (default: cpu)", choices=DEVICES, check_choices=False)
    effects: tuple | None = option(None, f"effects to keep: {','.join(EFFECTS)} (default: every effect the scene calls for)",
                                   metavar="LIST", listed=True)
    disable: tuple = option((), "effects to switch off", cli=False)
    bands: int | None = option(None, "bands of pixels launched apart (default: a few per thread)", cli=False)
    algorithm: str = option("raytrace", "raytrace (default), or zbuffer: rasterized, the tracer's local shading, "
                                        "no shadows or reflections", choices=ALGORITHMS)
    primary_query: str = option("auto", "what finds the camera rays' first hits, the image being the same: auto "
                                        "(default: the Z-buffer where it is the cheaper), raytrace (the BVH), or "
                                        "zbuffer (hybrid: the Z-buffer's triangle wherever it is certain, the rest traced)",
                                choices=PRIMARY_QUERIES)
    shadow_query: str = option("auto", "what answers the shadow rays, the image being the same: auto (default: the "
                                       "light-space grid where it is the cheaper; an area light's rays skipped where "
                                       "a hit is proven to see it whole), bvh (Warp's any-hit query, every ray), or "
                                       "grid",
                               choices=SHADOW_QUERIES)
    reflection_query: str = option("auto", "what answers the reflection rays, the image being the same: auto (default: "
                                           "the planar mirrors' virtual cameras from a static view's second frame, where "
                                           "rasterizing is the cheaper), bvh (Warp's closest-hit query), or mirrors",
                                   choices=REFLECTION_QUERIES)
    report_truncated: bool = option(False, "report the weight per pixel of the rays max_depth cut off "
                                           "(stats.truncated)", cli=False)
    aovs: tuple = option((), f"AOVs of the camera rays' first hits: {','.join(AOVS)}", metavar="LIST", listed=True,
                         cli_name="aov")
    pixel_tile: tuple | None = option(None, "the tracer's pixel order: (width, height) tiles (default: 8x8)", cli=False)
    raster_tile: int = option(RASTER_TILE, "the Z-buffer algorithm's raster tiles, pixels a side", cli=False)

    def __post_init__(self):
        put = lambda name, value: object.__setattr__(self, name, value)  # noqa: E731 (frozen)
        for f in fields(self):
            choices = f.metadata["choices"]
            if choices and f.metadata["check_choices"] and getattr(self, f.name) not in choices:
                raise ArgumentError("render", f.name, f"unknown {f.name.replace('_', ' ')} '{getattr(self, f.name)}'; "
                                                      f"expected one of: {', '.join(choices)}")
        put("aovs", check_aovs(self.aovs))
        if self.effects is not None and not isinstance(self.effects, str):
            put("effects", tuple(self.effects))
        put("disable", tuple(self.disable or ()))
        if self.threads is not None:
            put("threads", int(self.threads))
            if self.threads < 1:
                raise ArgumentError("render", "threads", f"expected an integer >= 1, got {self.threads}")
        if self.algorithm == "zbuffer":
            # The Z-buffer has no camera rays to follow: what only the tracer can honour is refused.
            for name, what in (("aovs", "AOVs come from"), ("report_truncated", "truncated weights are"),
                               ("pixel_tile", "the pixel order is")):
                if getattr(self, name):
                    raise ArgumentError("render", name, f"{what} the tracer's camera rays: not with {{algorithm}}",
                                        {"algorithm": "zbuffer"})

    @classmethod
    def of(cls, options: "RenderOptions | None", kwargs: dict, caller: str = "render") -> "RenderOptions":
        """``options`` with ``kwargs`` (keyword arguments named as the fields) over it; an old spelling
        (RENAMED) warns once and is read as its new name."""
        kwargs = renamed(kwargs, caller)
        unknown = set(kwargs) - {f.name for f in fields(cls)}
        if unknown:
            raise TypeError(f"{caller}() got an unexpected keyword argument '{sorted(unknown)[0]}'")
        if options is None:
            return cls(**kwargs)
        return replace(options, **kwargs) if kwargs else options

    @classmethod
    def schema(cls) -> list[dict]:
        """Each option as data: name, default, help, choices, and how the command line offers it."""
        return [{"name": f.name, "default": None if f.default is MISSING else f.default, **f.metadata}
                for f in fields(cls)]


def check_aovs(names, field: str = "aovs", source: str | None = None) -> tuple:
    """The AOV names asked for, checked and in AOVS order; an unknown or repeated one is a SceneError
    naming ``field`` of ``source`` (a job file), or with source=None render()'s argument ``aovs``."""

    def bad(message):
        return ArgumentError("render", field, message) if source is None else SceneError(source, field, message)

    if names is None:
        return ()
    if isinstance(names, str) or not isinstance(names, (list, tuple)) or not all(isinstance(n, str) for n in names):
        raise bad(f"expected a list of AOV names, got {show(names)}")
    for n in names:
        if n not in AOVS:
            raise bad(f"unknown AOV '{n}'; expected some of: {', '.join(AOVS)}")
    if len(set(names)) != len(names):
        raise bad(f"an AOV is named twice: {', '.join(names)}")
    return tuple(n for n in AOVS if n in names)


def _callers_level() -> int:
    """The warnings stacklevel of the first frame outside warprt: the line that used the old spelling."""
    package = os.path.dirname(os.path.abspath(__file__))
    frame, level = sys._getframe(1), 1
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(package + os.sep):
        frame, level = frame.f_back, level + 1
    return level


def renamed(kwargs: dict, caller: str = "render") -> dict:
    """``kwargs`` with the first release's spellings (RENAMED) read as their new names, each with a
    one-line DeprecationWarning; both spellings at once is an error."""
    old = [k for k in kwargs if k in RENAMED]
    if not old:
        return kwargs
    out = dict(kwargs)
    for k in old:
        new = RENAMED[k]
        if new in out:
            raise TypeError(f"{caller}() got both '{k}' and its new name '{new}'")
        warnings.warn(f"{caller}(): '{k}' is now '{new}' ('{k}' goes in the next release)", DeprecationWarning,
                      stacklevel=_callers_level())
        out[new] = out.pop(k)
    return out
