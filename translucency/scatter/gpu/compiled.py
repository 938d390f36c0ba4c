"""What the GPU's kernels are handed: the CPU's compiled functions, compiled again for CUDA by numba-cuda or, in
numba's CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``), run as Python, since the simulator cannot hand its arrays to a
function compiled for the CPU; arrays copied to the device; and the channels' lanes, three to a launch."""

from __future__ import annotations

import types

import numpy as np
from numba import config, cuda

__all__ = ["for_the_device", "lane_groups", "to_device"]


def for_the_device(function, *calls: str):
    """``function`` (a ``numba.njit`` function) as a kernel calls it: itself, or in the simulator its Python, with the
    compiled functions it calls by the names ``calls`` (those it hands arrays to) swapped for their Python too."""
    if not config.ENABLE_CUDASIM:
        return function
    code = function.py_func
    if not calls:
        return code
    names = {**code.__globals__, **{name: code.__globals__[name].py_func for name in calls}}
    return types.FunctionType(code.__code__, names, code.__name__, code.__defaults__)


def to_device(array, dtype=np.float64):
    """A contiguous copy of ``array`` as ``dtype`` on the device."""
    return cuda.to_device(np.ascontiguousarray(array, dtype=dtype))


def lane_groups(lanes, n_out: int) -> list[tuple[range, tuple, tuple]]:
    """The lanes (:func:`~translucency.scatter.kernels.channel_lanes`, rows of parameters, a multiple of three) three
    to a kernel launch, as the CPU's kernels take them (:func:`~translucency.scatter.kernels.group_inputs`): per
    launch ``(its lanes, the output channel each reads, the last one repeated past ``n_out``, their parameters as
    tuples)``."""
    return [
        (
            range(c0, c0 + 3),
            tuple(min(c, n_out - 1) for c in range(c0, c0 + 3)),
            tuple(tuple(float(v) for v in lanes[c]) for c in range(c0, c0 + 3)),
        )
        for c0 in range(0, lanes.shape[0], 3)
    ]
