"""benchmarks.cuda_registers reads ptxas's report right, and gets one from NVRTC's PTX where ptxas is installed."""

import shutil

import pytest
import warp as wp

from benchmarks.cuda_compile import compile_module
from benchmarks.cuda_registers import Usage, kernel_name, ptxas, usages

# ptxas -v on the default trace kernel (CUDA 13.0, sm_90), as printed.
REPORT = """ptxas info    : 154 bytes gmem
ptxas info    : Compiling entry function 'make_trace_kernel__locals__trace_593a35ae_cuda_kernel_forward' for 'sm_90'
ptxas info    : Function properties for make_trace_kernel__locals__trace_593a35ae_cuda_kernel_forward
    304 bytes stack frame, 8 bytes spill stores, 12 bytes spill loads
ptxas info    : Used 119 registers, used 0 barriers, 304 bytes cumulative stack size, 1024 bytes smem
ptxas info    : Compile time = 297.860 ms
"""


def test_a_report_gives_each_entry_its_registers_stack_and_spills():
    assert usages(REPORT) == [Usage("make_trace_kernel__locals__trace_593a35ae_cuda_kernel_forward", 119, 304, 8, 12)]


def test_a_factory_kernel_is_named_by_its_variant_and_a_module_kernel_by_its_module():
    assert kernel_name("x_cuda_kernel_forward", "make_trace_kernel__locals__trace_593a35ae", "trace_adsSrn") == "trace_adsSrn"
    assert kernel_name("bin_kernel_6de5f32a_cuda_kernel_forward", "warprt.geometry.shadow_grid", "") == \
        "geometry.shadow_grid.bin_kernel"


@wp.kernel(module="unique", enable_backward=False)
def scale(a: wp.array(dtype=float), s: float):
    i = wp.tid()
    a[i] = a[i] * s


@pytest.mark.skipif(shutil.which("ptxas") is None, reason="ptxas (CUDA toolkit) is not installed")
def test_ptxas_reads_nvrtc_ptx_of_a_kernel(tmp_path):
    """NVRTC may write a newer PTX .version than ptxas reads (9.4 against CUDA 13.0's 9.0): lowered, it assembles."""
    (usage,) = usages(ptxas(compile_module(scale.module, 90, tmp_path, ptx=True), 90))
    assert usage.entry.startswith("scale_") and 0 < usage.registers < 64 and usage.spill_stores == 0
