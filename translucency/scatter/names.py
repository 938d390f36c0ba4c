"""The solver's choices by name: scattering models, far-field methods and devices, their defaults and their checks.

Plain data with no numba behind it, so that the command line and the settings can offer and check the
choices without compiling or importing the kernels; :mod:`translucency.scatter.kernels` maps each model
name to its code and :mod:`translucency.scatter.solve` accepts exactly these names. :func:`check_model`,
:func:`check_method`, :func:`check_tol` and :func:`check_bounces` are the one check of each choice, used
by the solver and by :class:`~translucency.app.shading.settings.ShadeSettings` alike.
"""

from __future__ import annotations

import math
import numbers

from ..errors import InvalidParameterError, setting_name

__all__ = [
    "MODELS",
    "METHODS",
    "DEFAULT_MODEL",
    "DEFAULT_METHOD",
    "DEFAULT_TOL",
    "check_model",
    "check_method",
    "check_tol",
    "DEFAULT_BOUNCES",
    "MAX_BOUNCES",
    "check_bounces",
    "DEVICES",
    "DEFAULT_DEVICE",
    "check_device",
]

#: Scattering models (the BSSRDF): FHK14's directional dipole, Jensen 2001's standard dipole,
#: d'Eon 2012's better dipole.
MODELS = ("directional", "standard", "better")
#: Far-field methods: every pair, pairs above the tolerance's cutoff radius, aggregated source clusters, operators
#: prepared once that any light reuses (docs/physics.md §8.7, §8.9), and ``auto``: ``tree`` for a surface's first
#: lights, the operators once those lights have taken as long as preparing them would (§8.10).
METHODS = ("exact", "cutoff", "tree", "relight", "auto")

#: Where the pairs of ``exact`` and of relighting's far field are summed: the CPU, an NVIDIA GPU (the optional
#: extra, :mod:`translucency.scatter.gpu`), or a GPU when one works and the CPU otherwise.
DEVICES = ("cpu", "gpu", "auto")

DEFAULT_MODEL = "directional"
DEFAULT_DEVICE = "auto"
DEFAULT_METHOD = "auto"
#: Relative error per vertex allowed to ``cutoff`` and ``tree`` (ignored by ``exact``).
DEFAULT_TOL = 1e-2
#: Times light that leaves the surface is let in again (docs/physics.md §7.4; the measurements behind the
#: default: bench/README.md, "Bounces").
DEFAULT_BOUNCES = 1
#: Most bounces accepted (each one is a gather and a solve).
MAX_BOUNCES = 8


def check_model(model) -> str:
    """The model name, checked to be one of :data:`MODELS`; else an ``InvalidParameterError`` sentence."""
    if model not in MODELS:
        raise InvalidParameterError(f"unknown model {model!r}; choose one of {', '.join(MODELS)}.")
    return model


def check_method(method) -> str:
    """The method name, checked to be one of :data:`METHODS`; else an ``InvalidParameterError`` sentence."""
    if method not in METHODS:
        raise InvalidParameterError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}.")
    return method


def check_device(device) -> str:
    """The device name, checked to be one of :data:`DEVICES`; else an ``InvalidParameterError`` sentence."""
    if device not in DEVICES:
        raise InvalidParameterError(f"{setting_name('device')} must be one of {', '.join(DEVICES)}, got {device!r}.")
    return device


def check_tol(tol):
    """The tolerance (relative error per vertex, 1), checked to be a real number in (0, 1).

    Else an ``InvalidParameterError`` sentence naming the setting as the user wrote it
    (``--tol`` or ``tol``, :func:`translucency.errors.setting_name`).
    """
    real = isinstance(tol, numbers.Real) and not isinstance(tol, bool)
    if not (real and math.isfinite(tol) and 0 < tol < 1):
        raise InvalidParameterError(f"{setting_name('tol')} must be a relative error in (0, 1), got {tol!r}.")
    return tol


def check_bounces(bounces) -> int:
    """The number of bounces, checked to be a whole number from 0 to :data:`MAX_BOUNCES`; else an
    ``InvalidParameterError`` sentence naming ``--bounces`` or ``bounces``."""
    whole = isinstance(bounces, numbers.Integral) and not isinstance(bounces, bool)
    if not (whole and 0 <= bounces <= MAX_BOUNCES):
        raise InvalidParameterError(
            f"{setting_name('bounces')} must be a whole number from 0 to {MAX_BOUNCES} (how many times light "
            f"that leaves the surface enters it again), got {bounces!r}."
        )
    return int(bounces)
