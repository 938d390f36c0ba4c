"""The shading policy: the one room between the front rooms (command line, viewer, bake, compare) and the solver.

It joins :mod:`translucency.io` and :mod:`translucency.scatter` and reaches the solver only through its one door,
:mod:`translucency.scatter.transport`. One concept per module:

``settings``     :class:`ShadeSettings`, every choice of a solve with its default, unit and help, once
``scan``         the scan a shade starts from (the embedded default, a file, a PyVista mesh), cleaned, in mm
``resolution``   where ``B`` is computed: the full mesh or a proxy, and the error expected of a proxy
``light_cache``  the incident light kept per :class:`~translucency.app.shading.light_cache.LightKey`
``fallback``     over a budget, a coarser proxy that fits, said in one line
``result``       :class:`ShadeResult`, assembled from the solve, and :func:`write_result`
``scene``        :class:`Scene` (a mesh prepared for repeated shading), :func:`shade`, :func:`shade_scan`
``distributed``  one scan's receivers solved in blocks on a Dask cluster
"""

from .result import ShadeResult, write_result
from .scan import load_default_scan, load_scan
from .scene import Scene, scene_for, shade, shade_scan
from .settings import ShadeSettings, settings_with

__all__ = [
    "Scene",
    "ShadeResult",
    "ShadeSettings",
    "load_default_scan",
    "load_scan",
    "scene_for",
    "settings_with",
    "shade",
    "shade_scan",
    "write_result",
]
