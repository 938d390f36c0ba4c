"""Whether an NVIDIA GPU can sum pairs here, asked once per process, and a sentence when it cannot.

``NUMBA_ENABLE_CUDASIM=1`` (numba's CUDA simulator: the kernels run as Python on the CPU, for tests on
machines without a GPU) counts as a GPU named "CUDA simulator".
"""

from __future__ import annotations

import functools
import importlib.util
import os
from dataclasses import dataclass

from ...errors import DeviceError, InvalidParameterError, TranslucencyError, option

__all__ = ["GpuStatus", "gpu_status", "pair_device", "said_plainly", "SIMULATOR", "GPU_METHODS", "AUTO_METHODS"]

#: The methods whose far field a GPU sums: ``exact``'s pairs, ``tree``'s walk, and relighting's far field (every pair,
#: per light; its near field's product too where the operator fits on the GPU).
GPU_METHODS = ("exact", "tree", "relight", "auto")
#: The methods ``auto`` takes to a GPU: ``exact``'s pairs and relighting's far field are what GPUs do best; ``tree``'s
#: walk (one thread per receiver, branching, in float64) has not been measured against the CPU's yet
#: (bench/README.md, "GPU"), so ``auto`` leaves it on the CPU and ``gpu`` runs it there.
AUTO_METHODS = ("exact", "relight")

#: The name a simulated GPU reports.
SIMULATOR = "CUDA simulator"
#: What to install for the GPU back end.
INSTALL = 'pip install "translucency[gpu]"'


@dataclass(frozen=True)
class GpuStatus:
    """Whether a GPU can sum pairs here.

    Attributes
    ----------
    usable : bool
        A GPU (or the simulator) can run the kernels.
    name : str
        The device's name, or :data:`SIMULATOR`.
    reason : str
        Why not, as the end of a sentence ("" when usable).
    """

    usable: bool
    name: str = ""
    reason: str = ""


@functools.cache
def gpu_status() -> GpuStatus:
    """The GPU this process would use: the first CUDA device numba-cuda sees, or why there is none."""
    if os.environ.get("NUMBA_ENABLE_CUDASIM", "0") not in ("", "0"):
        return GpuStatus(True, SIMULATOR)
    if importlib.util.find_spec("numba_cuda") is None:
        return GpuStatus(False, reason=f"the GPU back end is not installed ({INSTALL})")
    try:
        from numba import cuda

        if not cuda.is_available():
            return GpuStatus(False, reason="numba-cuda found no CUDA driver or no NVIDIA GPU")
        name = cuda.get_current_device().name
    except Exception as error:  # a broken driver or toolkit says so in its own words
        return GpuStatus(False, reason=f"CUDA did not start: {str(error).strip().splitlines()[0]}")
    return GpuStatus(True, name.decode() if isinstance(name, bytes) else str(name))


def pair_device(device: str, method: str) -> tuple[str, str]:
    """Where a solve by ``method`` sums its pairs for the setting ``device`` (``cpu``, ``gpu`` or ``auto``):
    ``("cpu" or "gpu", what to report: "cpu" or "gpu (<name>)")``.

    A GPU sums the far field of :data:`GPU_METHODS`. ``auto`` takes a GPU where one works (not the simulator) for
    :data:`AUTO_METHODS`, and the CPU otherwise; ``gpu`` with another method, or with no GPU that works, is a
    sentence that says what to change."""
    if device == "cpu" or (device == "auto" and method not in AUTO_METHODS):
        return "cpu", "cpu"
    if method not in GPU_METHODS:
        raise InvalidParameterError(
            f"{option('device', 'gpu')} sums the far field of methods exact, tree, relight and auto; choose one of "
            f"them, or {option('device', 'auto')} for method {method}."
        )
    status = gpu_status()
    if device == "auto" and (not status.usable or status.name == SIMULATOR):
        return "cpu", "cpu"
    if not status.usable:
        raise InvalidParameterError(
            f"{option('device', 'gpu')} needs an NVIDIA GPU, and {status.reason}; choose {option('device', 'cpu')} "
            f"or {option('device', 'auto')}."
        )
    return "gpu", f"gpu ({status.name})"


def said_plainly(function):
    """``function`` (a step on the GPU) with CUDA's own errors (out of the GPU's memory, a driver's fault: numba-cuda's
    exceptions) raised as a :class:`~translucency.errors.DeviceError` sentence that names the way around."""

    @functools.wraps(function)
    def on_the_gpu(*args, **kwargs):
        try:
            return function(*args, **kwargs)
        except TranslucencyError:
            raise
        except Exception as error:
            kind = type(error)
            if "cuda" not in f"{kind.__module__}.{kind.__name__}".lower():
                raise
            reason = (str(error).strip().splitlines() or [kind.__name__])[0]
            raise DeviceError(
                f"the GPU could not sum the pairs ({reason}); run with {option('device', 'cpu')}, or free the GPU's "
                "memory for it."
            ) from error

    return on_the_gpu
