"""Import pymeshlab once, checking that its OpenGL-dependent filters are there.

pymeshlab loads the filter plugins that need OpenGL only when the system has ``libGL`` and
``libOpenGL``; without them it imports fine but silently lacks filters such as
``meshing_close_holes``, and the repair would fail later with an AttributeError. This helper turns
that into one clear sentence. Every use of pymeshlab goes through :func:`import_pymeshlab`: the repair
(:mod:`translucency.io.clean`), the decimation (:mod:`translucency.io.decimate`) and the pymeshlab-based
reader (:mod:`translucency.io.formats.pymeshlab`).
"""

from __future__ import annotations

import functools

from ..errors import TranslucencyError

__all__ = ["import_pymeshlab"]


@functools.cache
def import_pymeshlab():
    """Return the ``pymeshlab`` module after checking that its OpenGL-dependent filters loaded.

    Raises
    ------
    TranslucencyError
        When pymeshlab is not installed or its OpenGL-dependent filters are missing.
    """
    try:
        import pymeshlab
    except ImportError as exc:
        raise TranslucencyError(
            "pymeshlab is not installed or cannot load its libraries; install it with "
            "pip install 'pymeshlab>=2025.7,<2025.8' and the system packages libgl1 and libopengl0."
        ) from exc
    if not hasattr(pymeshlab.MeshSet(), "meshing_close_holes"):
        raise TranslucencyError(
            "pymeshlab lost its OpenGL-dependent filters: install the system packages libgl1 and libopengl0 "
            "(apt-get install libgl1 libopengl0)."
        )
    return pymeshlab
