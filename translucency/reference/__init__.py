"""Independent references for the project's own results, built on outside renderers (optional extra).

``mitsuba_check``: radiance leaving a closed triangle mesh along its normals, path-traced by Mitsuba 3's
``volpath`` integrator (the ``reference`` extra: ``pip install -e ".[reference]"``). Mitsuba is imported
only when a function of that module runs; importing this package loads nothing heavy.
"""

import importlib

_LAZY = {
    "VolpathRadiance": "translucency.reference.mitsuba_check",
    "volpath_radiance": "translucency.reference.mitsuba_check",
    "light_radiance": "translucency.reference.mitsuba_check",
}

__all__ = sorted(_LAZY)


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'translucency.reference' has no attribute {name!r}")
