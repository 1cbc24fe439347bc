"""Launching the boundary term's per-point kernels (backward(edges=True): the colours either side of each
point, its edge's speed) over bands of points on the CPU's threads. Each point reads and writes rows of its
own (its rays' colours, its own copies of the parameters and their adjoints), so the bands run at once and
give the same values, to the bit, on any thread count."""
from __future__ import annotations

from .._warp import wp
from .launch import run_bands

import numpy as np

BANDS_PER_THREAD = 4  # a point's cost varies (a ray that misses, a shadow ray's BVH walk): bands balance it


def host_array(values: np.ndarray, dtype, device: str, grad: bool = False) -> wp.array:
    """``values`` (a NumPy array of the dtype's scalars, made for this launch and kept by the array) as a Warp
    array on ``device``: on the CPU the same memory, not a copy (a copy of the shadows' points' rows costs
    about 8 ms a MB-sized array on a loaded machine, measured); ``grad``: with an adjoint."""
    return wp.array(np.ascontiguousarray(values), dtype=dtype, device=device, requires_grad=grad,
                    copy=not wp.get_device(device).is_cpu)


def launch_points(kernel, n: int, args: list, rows: list, threads: int, device: str, adjoints: list | None = None):
    """Launch ``kernel`` over n points in bands, ``threads`` at once: ``args`` its arguments (inputs, then
    outputs), ``rows`` per argument the rows each point owns in it (a band gets its points' rows; 0: the whole
    argument to every band). With ``adjoints`` (per argument its adjoint, or None) the adjoint kernel alone:
    the forward's values are not read, and Warp's adjoint kernel runs the forward's body itself. Recorded on
    no tape: these launches are backward's own, not steps of a Warp program around it."""
    if n == 0:
        return
    wp.load_module(kernel.module, device=device)  # once, before the threads: launch_bands' note

    def cut(a, k: int, first: int, count: int):
        return a[k * first:k * (first + count)] if k and a is not None else a

    def band(first: int, count: int):
        part = [cut(a, k, first, count) for a, k in zip(args, rows)]
        if adjoints is None:
            wp.launch(kernel, dim=count, inputs=part, device=device, record_tape=False)
        else:
            wp.launch(kernel, dim=count, inputs=part, adj_inputs=[cut(a, k, first, count) for a, k in
                                                                  zip(adjoints, rows)], adjoint=True, device=device,
                      record_tape=False)

    run_bands(band, n, threads, BANDS_PER_THREAD * threads, device)
