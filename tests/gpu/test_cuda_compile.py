"""Every warprt kernel compiles for CUDA, sm_75 and sm_90, with the NVRTC inside Warp: no GPU, no driver.
A CUDA-only error fails with its module's name and NVRTC's first error line (docs/gpu.md)."""

import json
import subprocess
import sys
from pathlib import Path

import warp as wp

from benchmarks.cuda_compile import ARCHS, RUNS, Failure, compile_module
from marks import slow

ROOT = Path(__file__).resolve().parents[2]


@slow  # a dozen tiny renders, then the modules they load x two architectures through NVRTC (35 s on 2 shared cores)
def test_every_module_of_every_path_compiles_for_cuda():
    """In a fresh process, as CI's own command would run it: this test's worker has loaded every kernel
    variant the suite rendered before it (hundreds), and the check is of the paths' modules."""
    r = subprocess.run([sys.executable, "-m", "benchmarks.cuda_compile", "--json"], cwd=ROOT, capture_output=True,
                       text=True, timeout=900)
    out = json.loads(r.stdout.strip().splitlines()[-1])
    assert [run["label"] for run in out["runs"]] == [label for label, *_ in RUNS]
    loaded = [m for run in out["runs"] for m in run["modules"]]
    assert sorted(loaded) == sorted(out["modules"]) and len(loaded) >= 10  # each module loaded by one run
    assert out["failed"] == [], "NVRTC refused:\n" + "\n".join(out["failed"])
    assert out["compiled"] == len(out["modules"]) * len(ARCHS) and r.returncode == 0


# The negative control: C++ that the CPU's compiler never sees, and that NVRTC refuses.
@wp.func_native("""
#if defined(__CUDA_ARCH__)
    host_only_call(out, tid);
#endif
    out[tid] = x;
""")
def host_only(x: float, out: wp.array(dtype=float), tid: int): ...


@wp.kernel(module="unique", enable_backward=False)
def host_only_kernel(out: wp.array(dtype=float)):
    tid = wp.tid()
    host_only(1.0, out, tid)


def test_a_cuda_only_error_names_its_module_and_nvrtc_first_error(tmp_path):
    failure = compile_module(host_only_kernel.module, ARCHS[0], tmp_path)
    assert isinstance(failure, Failure)
    assert failure.module == host_only_kernel.module.name and failure.arch == ARCHS[0]
    assert 'error: identifier "host_only_call" is undefined' in failure.error
    assert str(failure).startswith(f"{host_only_kernel.module.name} (sm_{ARCHS[0]}): ")

