"""Every warprt kernel compiles for CUDA, sm_75 and sm_90, with the NVRTC inside Warp: no GPU, no driver.
A CUDA-only error fails with its module's name and NVRTC's first error line (docs/gpu.md)."""

import warp as wp

from benchmarks.cuda_compile import ARCHS, RUNS, Failure, compile_all, compile_module, render_every_path, warprt_modules
from marks import slow


@slow  # seven tiny renders, then ten modules x two architectures through NVRTC (35 s on 2 shared cores)
def test_every_module_of_every_path_compiles_for_cuda(tmp_path):
    runs = render_every_path()
    assert [r.label for r in runs] == [label for label, *_ in RUNS]
    modules = warprt_modules()
    assert all(m in modules for r in runs for m in r.modules)
    done, failed = compile_all(modules, tmp_path)
    assert not failed, "NVRTC refused:\n" + "\n".join(map(str, failed))
    assert len(done) == len(modules) * len(ARCHS)


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

