"""The catalogue of measured materials, loaded from ``data/materials.json`` with its provenance.

Two published tables, both per RGB channel in 1/mm:

* ``jensen2001`` -- Jensen et al. 2001, Table 2: reduced scattering ``sigma_s'`` (stored as
  ``sigma_s`` with ``g = 0``) and ``sigma_a``; ``eta = 1.3`` except marble (1.5).
* ``narasimhan2006`` -- Narasimhan et al. 2006, Table 1: unreduced ``sigma_s``, ``sigma_a`` and the
  measured ``g``, for the *diluted* samples that were measured; ``eta = 1.33``.

Names are looked up case-, space- and punctuation-insensitively (``"Skim milk"``, ``"skim_milk"``
and ``"SKIMMILK"`` are the same); an unknown name raises
:class:`~translucency.errors.UnknownMaterialError` listing the close matches.
"""

from __future__ import annotations

import difflib
import functools
import json
import re
from dataclasses import dataclass
from importlib import resources

import numpy as np

from ..errors import InvalidParameterError, UnknownMaterialError
from .medium import Medium

__all__ = ["Material", "material", "material_names", "catalogue", "material_tables"]


@dataclass(frozen=True)
class Material:
    """One catalogue entry: coefficients exactly as published, with where they come from.

    Attributes
    ----------
    key : str
        Lookup name (``"skim_milk"``).
    name : str
        Display name (``"Skim milk"``).
    table : str
        Source table id (``"jensen2001"`` or ``"narasimhan2006"``); see :func:`material_tables`.
    sigma_a, sigma_s, g : tuple of float
        Per RGB channel; 1/mm, 1/mm, dimensionless. For ``jensen2001`` ``sigma_s`` is the reduced
        coefficient and ``g = 0``.
    eta : float
        Relative index of refraction.
    """

    key: str
    name: str
    table: str
    sigma_a: tuple
    sigma_s: tuple
    g: tuple
    eta: float

    @property
    def source(self) -> str:
        """Citation of the table the values come from."""
        return material_tables()[self.table]["source"]

    @property
    def scattering_channels(self) -> np.ndarray:
        """Boolean per channel: does the channel scatter (``sigma_s (1 - g) > 0``)?"""
        return np.asarray(self.sigma_s) * (1.0 - np.asarray(self.g)) > 0.0

    @property
    def is_diffusive(self) -> bool:
        """True when every channel scatters, i.e. the diffusion models can represent the material."""
        return bool(np.all(self.scattering_channels))

    def medium(self, scale: float = 1.0) -> Medium:
        """The material as a :class:`~translucency.scatter.medium.Medium` (coefficients x ``scale``).

        Raises
        ------
        InvalidParameterError
            If a channel does not scatter (some Narasimhan liquids have ``sigma_s = 0`` in a channel).
        """
        if not self.is_diffusive:
            channels = ", ".join(c for c, ok in zip(("red", "green", "blue"), self.scattering_channels) if not ok)
            raise InvalidParameterError(
                f"material {self.key!r} does not scatter in the {channels} channel(s) (sigma_s = 0), so the "
                "diffusion models cannot represent it; pick a scattering material (see `translucency materials`)."
            )
        return Medium(np.array(self.sigma_a), np.array(self.sigma_s), np.array(self.g), self.eta, self.key).scaled(
            scale
        )


def lookup_key(name: str) -> str:
    """What names are compared by: lower case, ``&`` as ``and``, letters and digits only (``"Skim milk"`` and
    ``skim_milk`` are ``skimmilk``)."""
    return re.sub(r"[^a-z0-9]", "", name.lower().replace("&", "and"))


@functools.lru_cache(maxsize=1)
def _load() -> tuple[dict, dict]:
    text = resources.files("translucency.data").joinpath("materials.json").read_text(encoding="utf-8")
    data = json.loads(text)
    entries = {}
    for row in data["materials"]:
        entry = Material(
            key=row["key"],
            name=row["name"],
            table=row["table"],
            sigma_a=tuple(row["sigma_a"]),
            sigma_s=tuple(row["sigma_s"]),
            g=tuple(row["g"]),
            eta=float(row["eta"]),
        )
        entries[lookup_key(entry.key)] = entry
    return entries, data["tables"]


def material_tables() -> dict:
    """The source tables: citation, units, whether ``sigma_s`` is reduced, notes."""
    return _load()[1]


def catalogue() -> list[Material]:
    """Every catalogue entry, in table order."""
    return list(_load()[0].values())


def material_names() -> list[str]:
    """The lookup keys of every catalogue entry."""
    return [m.key for m in catalogue()]


def material(name: str) -> Material:
    """Look a material up by name (case-, space- and punctuation-insensitive).

    Raises
    ------
    UnknownMaterialError
        If no entry matches; the message lists close matches.
    """
    if isinstance(name, Material):
        return name
    entries = _load()[0]
    found = entries.get(lookup_key(str(name)))
    if found is not None:
        return found
    keys = [m.key for m in entries.values()]
    close = difflib.get_close_matches(str(name).lower().replace(" ", "_"), keys, n=5, cutoff=0.5)
    close += [k for k in keys if lookup_key(str(name)) and lookup_key(str(name)) in lookup_key(k) and k not in close]
    hint = f" Did you mean: {', '.join(close[:6])}?" if close else ""
    raise UnknownMaterialError(
        f"unknown material {name!r}.{hint} `translucency materials` lists all {len(keys)} names."
    )
