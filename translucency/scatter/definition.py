"""A material written down: a small mapping of coefficients or of appearance, checked and turned into a
:class:`~translucency.scatter.medium.Medium`.

The same keys serve a TOML or JSON file (``--material jade.toml``), the command line's inline options and
Python. One of three forms, with the optional keys ``name``, ``eta`` (default
:data:`~translucency.scatter.medium.DEFAULT_ETA`), ``g`` (default 0) and ``scale``:

============================= ====================================================================
keys                          meaning
============================= ====================================================================
``sigma_a``, ``sigma_s``      absorption and (unreduced) scattering coefficients, 1/mm, per channel
``reflectance``, ``mfp``      diffuse reflectance in (0, 1) and mean free path ``1/sigma_t'`` in mm,
                              per channel, inverted by :mod:`translucency.scatter.appearance`
``material``                  a catalogue name (its own ``eta`` and ``g``; ``eta`` may replace it)
============================= ====================================================================

``scale`` multiplies every coefficient (divides the mean free path), as Mitsuba's and pbrt's ``scale``
do: for an object whose size in the scan is not its real size, or a material measured in another unit.
A number stands for all three channels.

.. code-block:: toml

    name = "jade"
    reflectance = [0.55, 0.8, 0.5]
    mfp = [1.5, 2.0, 1.2]   # mm
    eta = 1.6
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..errors import InvalidParameterError
from .appearance import appearance_of, medium_from_appearance
from .materials import material as catalogue_entry
from .medium import DEFAULT_ETA, Medium

__all__ = ["FORMS", "OPTIONAL_KEYS", "SWEEP_KEYS", "medium_from_definition", "varied"]

#: The three forms of a definition: the keys each needs.
FORMS = {"coefficients": ("sigma_a", "sigma_s"), "appearance": ("reflectance", "mfp"), "catalogue": ("material",)}
#: Keys any form may add.
OPTIONAL_KEYS = ("name", "eta", "g", "scale")


def medium_from_definition(definition: Mapping, source: str = "the material definition") -> Medium:
    """The :class:`~translucency.scatter.medium.Medium` a definition describes (module docstring); every
    problem is one sentence naming ``source`` (a file name, or the options) and the key to change."""
    if not isinstance(definition, Mapping):
        raise InvalidParameterError(f"{source} must be a table of keys and values, got {type(definition).__name__}.")
    keys = set(definition)
    known = {key for form in FORMS.values() for key in form} | set(OPTIONAL_KEYS)
    unknown = sorted(keys - known)
    if unknown:
        raise InvalidParameterError(
            f"{source}: unknown key(s) {', '.join(unknown)}; a material takes {', '.join(sorted(known))}."
        )
    forms = [form for form, needed in FORMS.items() if keys & set(needed)]
    if len(forms) != 1:
        raise InvalidParameterError(
            f"{source} must give exactly one of sigma_a and sigma_s (coefficients), reflectance and mfp "
            f"(appearance) or material (a catalogue name), got {', '.join(sorted(keys)) or 'nothing'}."
        )
    form = forms[0]
    missing = [key for key in FORMS[form] if key not in keys]
    if missing:
        raise InvalidParameterError(f"{source}: {' and '.join(FORMS[form])} go together; add {', '.join(missing)}.")
    try:
        medium = _medium(definition, form, keys, source)
    except InvalidParameterError as exc:
        message = str(exc)
        raise InvalidParameterError(message if message.startswith(source) else f"{source}: {message}") from None
    if "scale" in keys:
        scale = definition["scale"]
        if isinstance(scale, bool) or not isinstance(scale, (int, float)) or not (np.isfinite(scale) and scale > 0):
            raise InvalidParameterError(f"{source}: scale must be a positive number, got {scale!r}.")
        medium = medium.scaled(float(scale))
    return medium


def _medium(definition: Mapping, form: str, keys: set, source: str) -> Medium:
    """The medium of a definition of a known ``form`` whose keys are complete (before ``scale``)."""
    name = str(definition.get("name", "custom"))
    eta = definition.get("eta")
    if form == "catalogue":
        if "g" in keys:
            raise InvalidParameterError(f"{source}: a catalogue material has its own g; leave g out.")
        base = catalogue_entry(str(definition["material"])).medium()
        name = str(definition.get("name", base.name))
        medium = Medium(base.sigma_a, base.sigma_s, base.g, base.eta if eta is None else eta, name)
    elif form == "coefficients":
        medium = Medium(
            _numbers(definition["sigma_a"], "sigma_a", source),
            _numbers(definition["sigma_s"], "sigma_s", source),
            _numbers(definition.get("g", 0.0), "g", source),
            DEFAULT_ETA if eta is None else eta,
            name,
        )
    else:
        medium = medium_from_appearance(
            _numbers(definition["reflectance"], "reflectance", source),
            _numbers(definition["mfp"], "mfp", source),
            DEFAULT_ETA if eta is None else eta,
            _numbers(definition.get("g", 0.0), "g", source),
            name,
        )
    return medium


def _numbers(value, key: str, source: str) -> np.ndarray:
    """A number or a list of numbers, as float64; anything else is a sentence naming ``key``."""
    items = value if isinstance(value, (list, tuple)) else [value]
    if not items or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in items):
        raise InvalidParameterError(f"{source}: {key} must be a number or a list of numbers, got {value!r}.")
    return np.asarray(items, dtype=np.float64) if isinstance(value, (list, tuple)) else np.float64(value)


#: What a sweep may vary (:func:`varied`): the mean free path or the reflectance with the other part of
#: the look kept, the coefficients' scale, or the index of refraction with the coefficients kept.
SWEEP_KEYS = ("mfp", "reflectance", "scale", "eta")


def varied(medium: Medium, key: str, value) -> Medium:
    """``medium`` with one property set to ``value`` (a number, or one per channel for ``mfp`` and
    ``reflectance``), named ``"<name> <key>=<value>"``: ``mfp`` (mm) and ``reflectance`` keep the other part
    of its look (docs/physics.md §6.4), ``scale`` multiplies its coefficients, ``eta`` replaces its index."""
    if key not in SWEEP_KEYS:
        raise InvalidParameterError(f"a sweep varies one of {', '.join(SWEEP_KEYS)}, got {key!r}.")
    label = value if np.ndim(value) == 0 else ",".join(f"{v:g}" for v in np.ravel(value))
    name = f"{medium.name} {key}={label:g}" if np.ndim(value) == 0 else f"{medium.name} {key}={label}"
    if key == "scale":
        return Medium(medium.sigma_a, medium.sigma_s, medium.g, medium.eta, name).scaled(float(value))
    if key == "eta":
        return Medium(medium.sigma_a, medium.sigma_s, medium.g, float(value), name)
    reflectance, path = appearance_of(medium)
    if key == "mfp":
        path = value
    else:
        reflectance = value
    return medium_from_appearance(reflectance, path, medium.eta, medium.g, name)
