"""The solver's choices by name: scattering models and far-field methods, with their defaults.

Plain data with no numba behind it, so that the command line and the settings can offer and check the
choices without compiling or importing the kernels; :mod:`translucency.scatter.kernels` maps each model
name to its code and :mod:`translucency.scatter.solve` accepts exactly these names.
"""

from __future__ import annotations

#: Scattering models (the BSSRDF): FHK14's directional dipole, Jensen 2001's standard dipole, d'Eon 2012's better dipole.
MODELS = ("directional", "standard", "better")
#: Far-field methods: every pair, pairs above the tolerance's cutoff radius, aggregated source clusters.
METHODS = ("exact", "cutoff", "tree")

DEFAULT_MODEL = "directional"
DEFAULT_METHOD = "tree"
#: Relative error per vertex allowed to ``cutoff`` and ``tree`` (ignored by ``exact``).
DEFAULT_TOL = 1e-2
