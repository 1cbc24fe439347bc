"""The ``warprt`` command line: render, info, batch (many frames from a job file) and compare.

Bad input is one line on stderr naming the file and field, exit status 2, no output file;
a traceback only with --debug. Library warnings are one line each (diagnostics.py).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import sys
import tomllib
from pathlib import Path

from . import __version__, diagnostics, interrupt
from .errors import ArgumentError, SceneError, one_line
from .options import DEVICES, RenderOptions
from .scene import AREA_ESTIMATORS, EFFECTS, input_kind
from .timing import timed

EXAMPLES = """examples:
  warprt render                               the built-in default scene -> warprt.png
  warprt render scenes/cornell.toml -o c.png  a scene file
  warprt render bunny.obj -o bunny.png        a mesh file, framed automatically, with its own materials,
                                              textures and colours: .obj (+.mtl) .ply .stl .off .glb .gltf
                                              .usd .usda .usdc .usdz
  warprt render scene.xml -o s.png            a Mitsuba 3 scene file, read by Mitsuba's parser (warprt[mitsuba])
  warprt render part.stl --up z               a z-up mesh (most CAD and robotics files); --up=-y for -y
  warprt render model.glb --camera Camera.001 one of the file's cameras (default: its first; auto: framed)
  warprt render s.toml -o s.exr --stats-file s.json -q
                                              linear float EXR (or .npy), statistics as JSON, nothing on stderr
  warprt render s.toml --spp 16 --max-depth 5 --width 1024 --height 768
  warprt render s.toml --no-shadows --effects ambient,diffuse --stats
  warprt render s.toml --algorithm zbuffer    rasterized: the tracer's local shading, no shadows/reflections
  warprt render s.toml --set camera.fovy=30 --set 'lights[0].color=[1,0.9,0.8]'
  warprt render s.toml -o s.exr --aov depth,normal,object
                                              AOVs of the camera rays' first hits: channels in the EXR
                                              (.npz: arrays; .png: s.depth.exr, ... beside it)
  warprt info s.toml                          triangles, objects, materials, lights, bounds, effects, memory
  warprt batch orbit.toml -o out              the frames of a job file (orbit, cameras, path, sweep),
                                              one worker process per core; out/manifest.jsonl
  warprt compare s.toml -o cmp.png --width 320 --height 240
                                              warprt | Mitsuba 3 | |difference| x 10; prints SSIM, PSNR

Bad input is one line on stderr naming the file and the field, exit status 2, and no output file
(0 done, 130 interrupted, 1 internal error). Outputs are written whole, through symlinks, never onto an input.
"""


def _flag(option: dict) -> str:
    """The flag of a RenderOptions field the command line offers (RenderOptions.schema()): its name."""
    return "--" + (option["cli_name"] or option["name"]).replace("_", "-")


RENDER_OPTIONS = [o for o in RenderOptions.schema() if o["cli"]]
# The first release's flags for the queries, kept for one more with a warning (RenderOptions.RENAMED).
OLD_FLAGS = {"--primary": "primary_query", "--shadow-rays": "shadow_query", "--reflection-rays": "reflection_query"}
# Where the library names an argument the flags set (render(): shadow_query: ...), main() rewords the
# error as the flag, by the function that takes the argument.
FLAGS = {
    "render": {o["name"]: _flag(o) for o in RENDER_OPTIONS},
    "load_scene": {"up": "--up", "camera": "--camera"},
    "batch": {"workers": "--workers", "ray": "--ray", "shard": "--shard", "device": "--device"},
}


class _Parser(argparse.ArgumentParser):
    """argparse, with its usage errors as the one line (and exit status 2) of every other bad input."""

    def error(self, message):
        print(f"warprt: error: command line: {message} (see '{self.prog} --help')", file=sys.stderr)
        sys.exit(2)


def _parse_set(items) -> dict:
    """--set section.key=value; the value is read as a TOML value, or as a string if it is not one."""
    out = {}
    for item in items or ():
        if "=" not in item:
            raise SceneError("command line", "--set", f"expected section.key=value, got '{item}'")
        key, value = item.split("=", 1)
        try:
            out[key.strip()] = tomllib.loads(f"v = {value}")["v"]
        except tomllib.TOMLDecodeError:
            out[key.strip()] = value
    return out


def _add_scene_options(p: argparse.ArgumentParser):
    p.add_argument("scene", nargs="?", help="scene file (.toml), Mitsuba scene (.xml) or mesh file; default: the built-in scene")
    p.add_argument("--set", action="append", metavar="SECTION.KEY=VALUE",
                   help="override any scene field, value in TOML syntax: camera.fovy=30, 'lights[0].color=[1,1,1]' (repeatable)")
    p.add_argument("--width", type=int, metavar="PIXELS", help="image width in pixels")
    p.add_argument("--height", type=int, metavar="PIXELS", help="image height in pixels")
    p.add_argument("--spp", type=int, metavar="N", help="samples per pixel (a square: 1, 4, 9, 16, ...)")
    p.add_argument("--max-depth", type=int, metavar="N", help="ray levels: 1 = primary rays only, 2 = one reflection, ...")
    p.add_argument("--light-samples", type=int, metavar="N",
                   help="points per area light, one shadow ray each (a square: 16, 64, 256, ...; default 16)")
    p.add_argument("--adaptive", type=float, metavar="T",
                   help="Whitted's adaptive supersampling: each pixel's centre traced, its --spp samples only where "
                        "its 3x3 neighbourhood differs by more than T (e.g. 0.005; 0: off, the default)")
    p.add_argument("--area-estimator", choices=AREA_ESTIMATORS, metavar="{samples,analytic}",
                   help="area lights: each point a point light (samples, the default), or a rectangle's, a mesh "
                        "light's or a sphere's unshadowed diffuse term in closed form, its points estimating its "
                        "visibility (analytic)")
    p.add_argument("--light-spread", action="store_true",
                   help="with --spp > 1, each pixel sample takes its own share of every area light's points")
    p.add_argument("--no-shadows", action="store_true", help="switch shadow rays off")
    p.add_argument("--up", metavar="AXIS", help="a mesh file's up axis: x, y, z, -x, -y or -z (write --up=-z); "
                                               "default: what the file says (USD, glTF), else y")
    p.add_argument("--camera", metavar="NAME|INDEX", help="a model file's camera to render from (glTF, USD; default: "
                                                          "its first), or 'auto' to frame the mesh")


def _load(args):
    from .scene import check_setting, load_scene

    overrides = _parse_set(args.set)
    # A flag's bad value is reported as that flag, not as the scene field it sets.
    for flag, key in (("width", "camera.width"), ("height", "camera.height"), ("spp", "render.spp"),
                      ("max_depth", "render.max_depth"), ("light_samples", "render.light_samples")):
        v = getattr(args, flag)
        if v is not None:
            overrides[key] = check_setting("command line", "--" + flag.replace("_", "-"), key, v)
    if args.no_shadows:
        overrides["render.shadows"] = False
    if args.adaptive is not None:
        if not 0.0 <= args.adaptive < float("inf"):
            raise SceneError("command line", "--adaptive", f"expected a number >= 0 (0: off), got {args.adaptive}")
        overrides["render.adaptive"] = args.adaptive
    if args.area_estimator is not None:
        overrides["render.area_estimator"] = args.area_estimator
    if args.light_spread:
        overrides["render.light_spread"] = True
    return load_scene(args.scene, overrides, up=args.up, camera=args.camera)


def _check_device(device: str):
    if device == "cpu":
        return
    from ._warp import init_warp, wp

    init_warp()
    if not wp.is_cuda_available():
        raise SceneError("command line", "--device", f"'{device}' is not available on this machine (Warp found no CUDA device); use --device cpu")


def _add_render_options(p: argparse.ArgumentParser):
    """A flag for each RenderOptions field the command line offers, with its help, choices and default
    from the schema; the old query flags hidden, setting the same fields."""
    for o in RENDER_OPTIONS:
        kw = {"dest": o["name"], "help": o["help"]}
        if o["choices"]:
            kw.update(choices=list(o["choices"]), default=o["default"])
        else:
            kw["metavar"] = o["metavar"]
            if o["type"] is not None:
                kw["type"] = o["type"]
        if o["name"] == "aovs":
            kw["help"] += "; in the .exr or .npz, beside a .png as <stem>.<aov>.exr"
        p.add_argument(_flag(o), **kw)
    for old, name in OLD_FLAGS.items():
        choices = next(o["choices"] for o in RENDER_OPTIONS if o["name"] == name)
        p.add_argument(old, dest=name, choices=list(choices), help=argparse.SUPPRESS, action=_OldFlag)


class _OldFlag(argparse.Action):
    """A flag of the first release: sets its field and notes itself for a warning."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        namespace.old_flags = getattr(namespace, "old_flags", []) + [option_string]


def _render_options(args) -> RenderOptions:
    """The RenderOptions the flags say; a flag of the first release warns, naming its new spelling."""
    for old in getattr(args, "old_flags", []):
        diagnostics.warn("command line", old, f"is now {_flag({'name': OLD_FLAGS[old], 'cli_name': None})} "
                                              f"({old} goes in the next release)")
    values = {}
    for o in RENDER_OPTIONS:
        v = getattr(args, o["name"])
        if o["listed"] and v is not None:
            v = [x.strip() for x in v.split(",")]
        if v is not None:
            values[o["name"]] = v
    return RenderOptions(**values)


def cmd_render(args) -> int:
    from .image import render
    from .image.film import aov_paths, check_distinct, check_output_path, check_text_path, write_image, write_text
    from .image.memory import peak_rss
    from .image.progress import Progress

    # Everything that can be checked before the render is: a render whose result cannot be
    # saved, or that cannot start, should fail at once and leave nothing behind.
    options = _render_options(args)
    aovs = options.aovs
    outputs = {"--output": check_output_path(args.output, "--output", aovs)}
    outputs.update({f"--aov {name}": p for name, p in aov_paths(outputs["--output"], aovs).items()})
    if args.stats_file:
        outputs["--stats-file"] = check_text_path(args.stats_file, "--stats-file")
    check_distinct(outputs)
    scene = _load(args)
    check_distinct(outputs, _inputs(scene))
    _check_device(args.device)
    result = render(scene, options, progress=None if args.quiet else Progress())
    out, stats = outputs["--output"], result.stats
    with timed(stats.times, "write"):
        write_image(out, result.image, "--output", result.aovs)
    stats.memory["peak_rss"] = peak_rss()
    # The file first: a reader of stdout that stops early (| head) must not cost the statistics file.
    if args.stats_file:
        write_text(args.stats_file, json.dumps(stats.to_dict(), indent=2) + "\n", "--stats-file")
    if args.stats:
        print(json.dumps(stats.to_dict(), indent=2))
    if not args.quiet and not args.stats and stats.algorithm == "zbuffer":
        print(f"wrote {out} ({stats.width}x{stats.height}, {stats.effects}; "
              f"{stats.triangles:,} triangles rasterized in {stats.times['render']:.3f} s)", file=sys.stderr)
    elif not args.quiet and not args.stats:
        r = stats.rays
        with_aovs = f" with AOVs {','.join(aovs)}" if aovs else ""
        print(f"wrote {out}{with_aovs} ({stats.width}x{stats.height}, {stats.effects}; "
              f"{r['total']:,} rays in {stats.times['trace']:.3f} s)", file=sys.stderr)
    return 0


def _inputs(scene) -> list:
    """The files a scene was read from, as check_distinct names them."""
    files = list(scene.files)
    return [("scene file" if i == 0 and input_kind(f) != "mesh" else "mesh file", f)
            for i, f in enumerate(files)]


def _rounded(v) -> list:
    return [round(float(x), 6) for x in v]


def _describe_light(light, scene) -> str:
    """One line of `warprt info`: the light's name, type and key numbers; an area light's emitting area
    and power (pi L_e A: a one-sided Lambertian emitter's radiant flux, per channel); an environment's image
    or radiance, scale and rotation."""
    from .scene import emitter_area

    kind = light.type
    words = [f"{light.name or '-':<16} {kind:<11}"]
    if kind == "area":
        over = f"object {light.object!r}" if light.object is not None else light.shape
        area = emitter_area(scene, light)
        power = [math.pi * c * area for c in light.radiance]
        return " ".join(words + [f"{over} radiance {_rounded(light.radiance)} area {area:.6g} power {_rounded(power)}"])
    if kind == "environment":
        shown = light.image.describe() if light.image is not None else f"radiance {_rounded(light.radiance)}"
        return " ".join(words + [f"{shown} scale {light.scale:.6g} rotate {_rounded(light.rotate)}"])
    if light.position is not None:
        words.append(f"at {_rounded(light.position)}")
    if kind != "point" and light.direction is not None:
        words.append(f"along {_rounded(light.direction)}")
    words.append(f"color {_rounded(light.color)}")
    if kind == "spot":
        words.append(f"cone {light.cutoff_angle:.4g} deg, beam {light.beam:.4g} deg")
    if light.falloff != "none":
        words.append(f"falloff {light.falloff}")
    return " ".join(words)


def cmd_info(args) -> int:
    from .scene import scene_effects

    scene = _load(args)
    lo, hi = scene.bounds()
    cam = scene.camera
    print(f"scene      {scene.source}")
    print(f"image      {cam.width}x{cam.height}, spp {scene.render.spp}, max_depth {scene.render.max_depth}")
    print(f"camera     eye {list(cam.eye)} center {list(cam.center)} up {list(cam.up)} fovy {cam.fovy:g} near {cam.near:g}")
    print(f"objects    {len(scene.objects)}")
    for o in scene.objects:
        extras = [w for w, on in (("smooth", o.smooth),
                                  ("uv", o.uv is not None), ("vertex colours", o.colors is not None)) if on]
        print(f"  {o.name:<16} {len(o.faces):>10,} triangles  material {o.material}" + "".join(f"  {w}" for w in extras))
    print(f"triangles  {scene.triangle_count:,}")
    used = {o.material for o in scene.objects}
    print(f"materials  {', '.join(m for m in scene.materials if m in used)}")
    for name in (m for m in scene.materials if m in used):
        for key, t in scene.materials[name].textures.items():
            print(f"  {name:<16} {key} x {t.describe()}")
    emissive = scene.emissive_lights
    print(f"lights     {len(scene.lights)}" + (f" and {len(emissive)} emissive objects" if emissive else ""))
    for light in scene.lights + emissive:
        print(f"  {_describe_light(light, scene)}")
    if scene.cameras:
        print(f"cameras    {len(scene.cameras)} in the file")
        for c in scene.cameras:
            aspect = f" aspect {c.aspect:.4g}" if c.aspect else ""
            print(f"  {c.name:<16} {c.kind} fovy {c.fovy:.4g} near {c.near:.4g}{aspect} eye {_rounded(c.eye)} "
                  f"looking {_rounded(b - a for a, b in zip(c.eye, c.center))}")
    print(f"bounds     {[round(float(x), 6) for x in lo]} .. {[round(float(x), 6) for x in hi]}")
    print(f"effects    {scene_effects(scene)}")
    # The geometry as a render builds it: its arrays and BVH, measured rather than estimated.
    from ._warp import init_warp
    from .geometry import Geometry
    from .image.memory import geometry_memory, human, peak_rss

    init_warp()
    mem = geometry_memory(Geometry(scene))
    print(f"memory     {human(mem['total'])} geometry: " + ", ".join(
        f"{k.replace('_', ' ')} {human(v)}" for k, v in mem.items() if k != "total") + f"; peak RSS {human(peak_rss())}")
    return 0


def _reference():
    """The Mitsuba reference: the repository's top-level reference/ package (not in the wheel)."""
    try:
        import reference
    except ImportError:
        root = Path(__file__).resolve().parents[2]  # src/warprt/cli.py -> the checkout
        if str(root) not in sys.path:
            sys.path.insert(0, str(root))
        try:
            import reference
        except ImportError:
            raise SceneError("command line", "compare", "needs the reference/ package of a warprt checkout "
                             "(run it from the repository, installed with pip install -e '.[test]')") from None
    return reference


def cmd_compare(args) -> int:
    from .image.film import check_distinct, check_output_path

    out = check_output_path(args.output, "--output")
    reference = _reference()
    scene = _load(args)
    check_distinct({"--output": out}, _inputs(scene))
    try:
        variant = reference.mitsuba_variant()
    except ImportError as e:
        raise SceneError("command line", "compare", f"needs Mitsuba 3 (pip install -e '.[test]'): {e}") from None
    effects = args.effects.split(",") if args.effects else None
    result = reference.compare(scene, effects=effects, threads=args.threads, output=out)
    cam = scene.camera
    print(f"scene    {scene.source} ({cam.width}x{cam.height}, spp {scene.render.spp}, effects {result.effects})")
    print(f"SSIM     {result.ssim:.6f}")
    print(f"PSNR     {result.psnr:.2f} dB")
    print(f"off      {100 * result.frac_off:.3f}% of pixels differ by more than 2/255 in a channel "
          f"({int(result.off_mask.sum())} of {result.off_mask.size}); max |difference| {result.max_abs:.4f}")
    print(f"times    warprt {result.times['warprt']:.3f} s, Mitsuba ({variant}) {result.times['mitsuba']:.3f} s")
    print(f"wrote    {out} (warprt | Mitsuba | |difference| x 10)")
    return 0


BATCH_EXAMPLES = """examples:
  warprt batch orbit.toml                      frames beside the job file, one worker per core
  warprt batch orbit.toml -o out --workers 2   2 worker processes, each with half the cores
  warprt batch sweep.toml --ray                a local Ray instance (pip install 'warprt[ray]')
  warprt batch sweep.toml --ray head:6379      join a Ray cluster (the output folder must be shared)
  warprt batch orbit.toml --shard 1/4          frames k with k mod 4 = 1 (manifest.shard-1-of-4.jsonl)
  sbatch --array=0-3 --wrap 'warprt batch orbit.toml -o /shared/out --shard auto'
  warprt batch orbit.toml --resume             render only frames without a manifest line and files

The manifest (DIR/manifest.jsonl) gets one JSON line per finished frame. Bad input is one line on
stderr naming the job file and the field or frame, exit status 2, before anything is rendered.
"""


def cmd_batch(args) -> int:
    from .dataset import batch

    _check_device(args.device)
    r = batch(args.job, args.output_dir, workers=args.workers, ray=args.ray, shard=args.shard, resume=args.resume,
              quiet=args.quiet, device=args.device)
    if not args.quiet:
        fps = f", {r.frames_per_second:.2f} frames/s" if r.frames_per_second else ""
        workers = f" on {r.workers} {r.backend} workers x {r.threads} threads" if r.workers else ""
        print(f"warprt batch: {r.rendered} frames rendered, {r.skipped} already done, of {r.frames}{workers} in "
              f"{r.seconds:.1f} s{fps}", file=sys.stderr)
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="warprt", description="A Whitted ray tracer in NVIDIA Warp kernels.",
                     epilog=EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"warprt {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    p = sub.add_parser("render", help="render a scene to an image", epilog=EXAMPLES,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    _add_scene_options(p)
    p.add_argument("-o", "--output", default="warprt.png", help="output image: .png (sRGB 8-bit), .exr, .npy or .npz (linear float)")
    _add_render_options(p)
    p.add_argument("--stats", action="store_true", help="print render statistics (times, rays, memory) as JSON on stdout")
    p.add_argument("--stats-file", metavar="FILE", help="write render statistics as JSON to this file")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="print nothing but errors: no progress bar (shown only on a terminal, after 1 s), no summary")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    p.set_defaults(func=cmd_render)

    p = sub.add_parser("info", help="summarise a scene: triangles, objects, materials, lights, bounds, effects")
    _add_scene_options(p)
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    p.set_defaults(func=cmd_info)

    p = sub.add_parser("batch", help="render a frame sequence or parameter sweep from a job file",
                       epilog=BATCH_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("job", help="job file (.toml): scene, output, aovs, [set], [orbit] / [[cameras]] / [path], [sweep]")
    p.add_argument("-o", "--output-dir", metavar="DIR", help="folder for the frames and the manifest (default: the job file's folder)")
    p.add_argument("--workers", type=int, metavar="N", help="worker processes or Ray actors (default: one per core); "
                                                            "each renders with cores // N threads")
    p.add_argument("--ray", nargs="?", const="local", metavar="ADDRESS",
                   help="run on Ray: a local instance, or join the cluster at ADDRESS ('auto', 'host:6379')")
    p.add_argument("--shard", metavar="I/N", help="render frames k with k mod N = I; 'auto' or 'auto/N' reads "
                                                  "SLURM_ARRAY_TASK_ID/COUNT or JOB_COMPLETION_INDEX")
    p.add_argument("--resume", action="store_true", help="skip frames whose manifest line and files exist")
    p.add_argument("--device", choices=DEVICES, default="cpu",
                   help="Warp device the workers render on (default: cpu); on cuda one worker unless --workers")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar (shown only on a terminal), no summary")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    p.set_defaults(func=cmd_batch)

    p = sub.add_parser("compare", help="render with warprt and with Mitsuba 3 (the reference): SSIM, PSNR, side-by-side image")
    _add_scene_options(p)
    p.add_argument("-o", "--output", default="compare.png", help="side-by-side image: warprt | Mitsuba | |difference| x 10")
    p.add_argument("--effects", help=f"comma-separated effects to keep, on both sides: {','.join(EFFECTS)}")
    p.add_argument("--threads", type=int, metavar="N", help="warprt worker threads (default: all cores)")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    p.set_defaults(func=cmd_compare)
    return parser


# What a shell reports for a command that wrote to a pipe whose reader had gone (128 + SIGPIPE): cat and
# git die of SIGPIPE there, silently, and so does warprt (`warprt info s.toml | head -1`).
EXIT_BROKEN_PIPE = 128 + signal.SIGPIPE


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    # A subcommand's own --debug default would hide 'warprt --debug render ...'.
    args.debug = getattr(args, "debug", False) or "--debug" in (sys.argv[1:] if argv is None else argv)
    try:
        with diagnostics.quiet(getattr(args, "quiet", False)), \
                diagnostics.collecting(_source(args), hold=False):
            code = args.func(args)
            sys.stdout.flush()  # a reader that has gone shows here, inside the handlers below
        return code
    except BrokenPipeError:
        return _reader_gone()
    except SceneError as e:
        if args.debug:
            raise
        if isinstance(e, ArgumentError):
            e = e.worded("command line", FLAGS.get(e.function, {}))
        return _fail(f"warprt: error: {one_line(e)}", 2)  # one line, always
    except KeyboardInterrupt:
        return _fail("warprt: interrupted", 130)
    except Exception as e:
        if args.debug:
            raise
        return _fail(f"warprt: internal error: {type(e).__name__}: {one_line(e)} "
                     "(run with --debug for a traceback)", 1)


def _source(args) -> str:
    """What a warning without a file of its own names: the scene, or batch's job file."""
    return str(getattr(args, "scene", None) or getattr(args, "job", None) or "default scene")


def _fail(line: str, code: int) -> int:
    try:
        print(line, file=sys.stderr)
        sys.stderr.flush()
    except BrokenPipeError:  # stderr's reader has gone too: the exit status is all that is left
        pass
    return code


def _reader_gone() -> int:
    """stdout's reader has gone: stop quietly. Later writes to stdout (the interpreter's own flush at
    exit) go nowhere instead of failing again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):  # stdout is not a file descriptor (captured in-process)
        pass
    return EXIT_BROKEN_PIPE


def run():
    """The console script: main(), then exit without tearing the interpreter down. Everything the
    command makes is written, renamed into place and closed by then; finalizing Warp's and LLVM's
    native state and every module only delays the prompt (0.11 s of a 0.57 s cold render of the
    default scene, measured with `python -m warprt render -q`)."""
    interrupt.install()  # a Ctrl-C Python drops is noted and raised again by the band loop (interrupt.py)
    try:
        code = main()
    except SystemExit as e:  # argparse's --help, --version and usage errors; sys.exit's meaning kept
        code = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
        if not isinstance(e.code, (int, type(None))):
            print(e.code, file=sys.stderr)
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        code = _reader_gone()
    try:
        sys.stderr.flush()
    except BrokenPipeError:
        pass
    if "warprt._warp" in sys.modules:  # a temporary kernel cache, made where the usual one is read-only
        sys.modules["warprt._warp"].remove_fallback_cache()
    if code == EXIT_BROKEN_PIPE:
        signal.signal(signal.SIGPIPE, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGPIPE)
    os._exit(code)


if __name__ == "__main__":
    run()
