"""warprt's kernels compiled for CUDA on a machine without a GPU: tiny CPU renders through every path load
each Warp module warprt has, then NVRTC (inside Warp, no driver needed) compiles each for every ARCHS.

    python -m benchmarks.cuda_compile          # exit 1, naming each module and NVRTC's first error line
    python -m benchmarks.cuda_compile --json   # the same as one JSON object (the test reads it)

Run it in a fresh process: it compiles every warprt module the process has loaded, and a process that has
rendered much before (a test worker) holds hundreds of kernel variants.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import warprt
from warprt.image import AOVS

SCENES = Path(__file__).resolve().parent.parent / "scenes"

# Turing, the oldest architecture CUDA 13 still targets, and Hopper, the H200 a session may be lent.
ARCHS = (75, 90)
# Turing's as PTX: NVRTC's front end (where a CUDA-only error shows) without ptxas, which Hopper's CUBIN runs
# (measured: 45 s against 68 s an architecture for every module); Hopper's as the CUBIN a GPU would load.
PTX_ARCHS = (75,)

TRACED = dict(primary_query="raytrace", shadow_query="bvh", reflection_query="bvh")
SHORTCUTS = dict(primary_query="zbuffer", shadow_query="grid", reflection_query="mirrors")
EVERYTHING = dict(SHORTCUTS, aovs=AOVS, report_truncated=True)

# (label, scene, overrides, render options). Each kernel switch (the shortcuts, AOVs, the truncated
# weights, each effect) is compiled off and on: every shortcut at once costs one kernel variant where one
# per path would cost five, and a wp.static switch's code does not depend on the others'.
RUNS = (
    ("traced", "mirrors", {}, TRACED),
    ("glass, spp 4, shortcuts, AOVs, truncated", "mirrors", {"materials.red.ior": 1.5, "render.spp": 4}, EVERYTHING),
    ("Z-buffer, textures, spp 4", "textured", {"render.spp": 4}, dict(algorithm="zbuffer")),
    ("textured glass", "whitted", {}, TRACED),
    ("absorbing glass", "glass_cube", {}, TRACED),
    ("light model, single-sided", "sun", {"materials.wall.double_sided": False}, TRACED),
    ("vertex colours, AOVs", "vertex_colors", {}, dict(TRACED, aovs=AOVS)),
    ("area lights (Mitsuba's Cornell box)", "cornell_box.xml", {}, TRACED),
    ("gradients: record and differentiable shading", "seed", {"render.max_depth": 1}, dict(TRACED, grad=True)),
    # Every gradient switch on at once (the record and replay variants of the others are the seed run's):
    # spp 4, an image texture, the light model (a sun), mirror levels.
    ("gradients: spp 4, texture, light model, mirrors", "sun",
     {"render.spp": 4, "materials.ground.kd_texture": {"image": "textures/globe.png", "scale": [2, 1]}},
     dict(TRACED, grad=True)),
    ("gradients: area lights", "cornell_box.xml", {}, dict(TRACED, grad=True)),
    # The ray tree's record and per-level replay: textured glass, a mirror, smooth objects (their vertices'
    # normals made again: backward's default takes every vertex and the camera).
    ("gradients: glass (the ray tree)", "whitted", {}, dict(TRACED, grad=True)),
    ("gradients: vertex colours", "vertex_colors", {}, dict(TRACED, grad=True)),
)


@dataclass
class Run:
    label: str
    variant: str  # the kernel variant render() reported (stats.variant)
    modules: list  # the Warp modules holding warprt kernels this run was the first to load


def render_every_path(width: int = 16, height: int = 12) -> list[Run]:
    """Render RUNS on the CPU at width x height."""
    runs = []
    for label, name, overrides, options in RUNS:
        before = {id(m) for m in warprt_modules()}
        path = SCENES / (name if "." in name else f"{name}.toml")
        scene = warprt.load_scene(path, {"camera.width": width, "camera.height": height, **overrides})
        options = dict(options)
        grad = options.pop("grad", False)
        with warprt.Renderer(scene, **options) as r:
            variant = r.render(grad=grad).stats.variant
            if grad:  # the differentiable kernel loads with its first backward pass
                r.backward(np.zeros((height, width, 3), np.float32), edges=False)
        runs.append(Run(label, variant, [m for m in warprt_modules() if id(m) not in before]))
    return runs


def warprt_modules() -> list:
    """The Warp modules holding a warprt kernel that this process has loaded for a device (launched):
    those named after warprt's Python modules and the 'unique' ones its kernel factories make."""
    from warp._src.context import user_modules

    return [m for m in list(user_modules.values())
            if m.execs and any(k.func.__module__.startswith("warprt.") for k in m.kernels.values())]


@dataclass
class Failure:
    module: str
    arch: int
    error: str  # NVRTC's first error line

    def __str__(self) -> str:
        return f"{self.module} (sm_{self.arch}): {self.error}"


@contextlib.contextmanager
def native_stderr(into: Path):
    """File descriptor 2 into ``into``: Warp's native code prints NVRTC's log there, not to sys.stderr."""
    sys.stderr.flush()
    saved = os.dup(2)
    with open(into, "wb") as f:
        os.dup2(f.fileno(), 2)
    try:
        yield
    finally:
        sys.stderr.flush()
        os.dup2(saved, 2)
        os.close(saved)


def first_error(log: str, fallback: str) -> str:
    """NVRTC's first error line in ``log`` ('file.cu(62): error: ...'), else ``fallback``."""
    lines = [ln.strip() for ln in log.splitlines()]
    return next((ln for ln in lines if ": error" in ln or ln.startswith("error")), fallback)


def compile_module(module, arch: int, out: Path, ptx: bool = False) -> Path | Failure:
    """``module`` compiled by NVRTC for sm_``arch`` into ``out``: the CUBIN (or PTX), or the Failure."""
    import warp as wp

    log = out / f"nvrtc_{module.name}_{arch}.log"
    try:
        with native_stderr(log):
            (path,) = wp.compile_aot_module(module, arch=arch, use_ptx=ptx, module_dir=out)
        return path
    except Exception as e:  # Warp says only 'CUDA kernel build failed'; NVRTC's reason is in the log
        return Failure(module.name, arch, first_error(log.read_text(errors="replace"), str(e)))


def compile_all(modules, out: Path, archs=ARCHS, ptx: bool = False) -> tuple[list[Path], list[Failure]]:
    """Each module for each of ``archs``: PTX for PTX_ARCHS (every one with ``ptx``), else the CUBIN."""
    done, failed = [], []
    for module in modules:
        for arch in archs:
            result = compile_module(module, arch, out, ptx or arch in PTX_ARCHS)
            (failed if isinstance(result, Failure) else done).append(result)
    return done, failed


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ptx", action="store_true", help="PTX for every architecture (NVRTC without its ptxas step); "
                                                       "by default only for PTX_ARCHS")
    ap.add_argument("--json", action="store_true", help="print the runs, modules and results as one JSON object")
    args = ap.parse_args(argv)
    start = time.perf_counter()
    runs = render_every_path()
    modules = warprt_modules()
    with tempfile.TemporaryDirectory() as out:
        done, failed = compile_all(modules, Path(out), ptx=args.ptx)
    if args.json:
        print(json.dumps({"runs": [{"label": r.label, "variant": r.variant, "modules": [m.name for m in r.modules]}
                                   for r in runs],
                          "modules": [m.name for m in modules], "archs": list(ARCHS),
                          "ptx": [a for a in ARCHS if args.ptx or a in PTX_ARCHS], "compiled": len(done),
                          "failed": [str(f) for f in failed]}))
        return 1 if failed else 0
    print(f"{len(modules)} modules x sm_{', sm_'.join(map(str, ARCHS))}: {len(done)} compiled, {len(failed)} failed "
          f"in {time.perf_counter() - start:.0f} s")
    for f in failed:
        print(f"  {f}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
