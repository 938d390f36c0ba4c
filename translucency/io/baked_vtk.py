"""Baked VTK files: a result's PolyData as VTK XML PolyData (``.vtp``) or legacy VTK (``.vtk``), atomically.

Every per-vertex array of the PolyData is kept as it is, as ``point_data`` (PyVista, ParaView and VTK
read them by name), and the settings as ``field_data`` (strings and numbers). The pipeline's
:meth:`~translucency.app.shading.result.ShadeResult.to_pyvista` builds that PolyData:

============== ============ ==============================================================
point array    shape, type  meaning, unit
============== ============ ==============================================================
radiance       (n, 3) f64   linear radiance toward the normal, W/(m^2 sr) per W/m^2 of
                            irradiance of the light
B              (n, 3) f64   the view-independent factor B(x_o), same unit
colors         (n, 3) u8    display colours (exposure + sRGB)
luminance      (n,) f64     Rec. 709 luminance of the radiance, same unit as radiance
incident_flux  (n, 3) f64   flux density entering the surface, T12 E cos V, W/m^2
normals        (n, 3) f64   unit vertex normals
============== ============ ==============================================================

The points are in mm (``field_data["length_unit"]``). VTK's writers encode into memory
(:func:`translucency.io.formats.vtk.encode_polydata`) and the bytes go through the atomic writer
(:mod:`translucency.io.atomic`): a reader sees the old file or the complete new one.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import InvalidParameterError, WriteError
from .atomic import write_bytes
from .baked import check_bake_path
from .formats.vtk import encode_polydata

__all__ = ["VTK_BAKE_SUFFIXES", "write_baked_polydata"]

#: Suffixes :func:`write_baked_polydata` writes: XML PolyData and binary legacy VTK.
VTK_BAKE_SUFFIXES = (".vtp", ".vtk")


def write_baked_polydata(path, poly, *, source=None) -> Path:
    """Write a PolyData (every point and field array) as a ``.vtp`` or ``.vtk`` file, atomically.

    Parameters
    ----------
    path : str or path-like
        Destination ending in ``.vtp`` or ``.vtk``; its folder must exist.
    poly : pyvista.PolyData
        The mesh to write, e.g.
        :meth:`ShadeResult.to_pyvista() <translucency.app.shading.result.ShadeResult.to_pyvista>`.
    source : path-like, optional
        The scan the values were computed on, which is never written over.

    Returns
    -------
    Path

    Raises
    ------
    InvalidParameterError
        Another suffix, a missing folder, a folder in place of the file, or the scan itself.
    WriteError
        When VTK cannot encode the data or the disk refuses the file; nothing is left behind.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in VTK_BAKE_SUFFIXES:
        raise InvalidParameterError(f"cannot write {path.name} as a VTK file; give it a .vtp or .vtk name.")
    check_bake_path(path, source)
    try:
        data = encode_polydata(poly, suffix)
    except (RuntimeError, TypeError, ValueError) as exc:
        raise WriteError(f"encoding {path.name} failed ({exc}); write the result as .ply instead.") from None
    return write_bytes(path, data)
