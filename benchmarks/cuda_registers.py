"""Registers, stack and spills per warprt kernel on a GPU, read by ptxas from the PTX that Warp's NVRTC
writes for the kernels of every path (cuda_compile.RUNS); no GPU needed, ptxas (CUDA toolkit) is.

    python -m benchmarks.cuda_registers            # a Markdown table for sm_90
    python -m benchmarks.cuda_registers --arch 75
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from .cuda_compile import Failure, compile_module, render_every_path

ENTRY = re.compile(r"Compiling entry function '(\w+)'")
FRAME = re.compile(r"(\d+) bytes stack frame, (\d+) bytes spill stores, (\d+) bytes spill loads")
USED = re.compile(r"Used (\d+) registers")
# NVRTC may write a newer PTX ISA than the installed ptxas reads; warprt's kernels use nothing newer.
TOO_NEW = re.compile(r"Unsupported \.version (\d+\.\d+); current version is '(\d+\.\d+)'")


@dataclass
class Usage:
    entry: str
    registers: int = 0
    stack: int = 0
    spill_stores: int = 0
    spill_loads: int = 0


def ptxas(ptx: Path, arch: int) -> str:
    """ptxas -v's report on ``ptx`` for sm_``arch``, the PTX's .version lowered once if ptxas asks."""
    text = ptx.read_bytes().rstrip(b"\0").decode()  # NVRTC's PTX ends in a NUL, which ptxas reads as text
    for _ in range(2):
        ptx.write_text(text)
        run = subprocess.run(["ptxas", "-v", f"-arch=sm_{arch}", str(ptx), "-o", "/dev/null"],
                             capture_output=True, text=True)
        too_new = TOO_NEW.search(run.stderr)
        if run.returncode == 0 or not too_new:
            break
        text = re.sub(rf"^\.version {re.escape(too_new[1])}$", f".version {too_new[2]}", text, count=1, flags=re.M)
    if run.returncode:
        raise RuntimeError(f"ptxas on {ptx.name}: {run.stderr.strip().splitlines()[0]}")
    return run.stderr


def usages(report: str) -> list[Usage]:
    """Each entry function of a ptxas -v report with its registers, stack frame and spills."""
    out = []
    for line in report.splitlines():
        if m := ENTRY.search(line):
            out.append(Usage(m[1]))
        elif out and (m := FRAME.search(line)):
            out[-1].stack, out[-1].spill_stores, out[-1].spill_loads = map(int, m.groups())
        elif out and (m := USED.search(line)):
            out[-1].registers = int(m[1])
    return out


def kernel_name(entry: str, module_name: str, variant: str) -> str:
    """A kernel as a reader knows it: a factory's kernel by its variant, the others by module.kernel."""
    kernel = re.sub(r"(_[0-9a-f]{8})?_cuda_kernel_forward$", "", entry)
    if module_name.startswith("warprt."):
        return f"{module_name.removeprefix('warprt.')}.{kernel}"
    return re.sub(r"_aov(_[a-z]+)+", "_aovs", variant)  # RUNS ask for every AOV


def table(arch: int) -> list[str]:
    rows = [f"| kernel (sm_{arch}) | registers | stack frame (bytes) | spill stores | spill loads |", "|---|--:|--:|--:|--:|"]
    with tempfile.TemporaryDirectory() as tmp:
        for run in render_every_path():
            for module in run.modules:
                ptx = compile_module(module, arch, Path(tmp), ptx=True)
                if isinstance(ptx, Failure):
                    raise RuntimeError(str(ptx))
                for u in usages(ptxas(ptx, arch)):
                    rows.append(f"| {kernel_name(u.entry, module.name, run.variant)} | {u.registers} | {u.stack} | "
                                f"{u.spill_stores} | {u.spill_loads} |")
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arch", type=int, default=90, help="the compute capability, e.g. 75 or 90 (default 90)")
    args = ap.parse_args(argv)
    if shutil.which("ptxas") is None:
        print("ptxas not found: install the CUDA toolkit (or pip install nvidia-cuda-nvcc) to count registers",
              file=sys.stderr)
        return 2
    print("\n".join(table(args.arch)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
