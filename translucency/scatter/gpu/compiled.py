"""How the GPU's kernels call the CPU's compiled functions: compiled again for CUDA by numba-cuda, or, in numba's CUDA
simulator (``NUMBA_ENABLE_CUDASIM=1``), run as Python, since the simulator cannot hand its arrays to a function
compiled for the CPU."""

from __future__ import annotations

import types

from numba import config

__all__ = ["for_the_device"]


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
