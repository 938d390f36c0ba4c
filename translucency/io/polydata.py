"""A :class:`~translucency.geometry.mesh.TriangleMesh` to and from a ``pyvista.PolyData``.

The mesh record holds plain arrays; PyVista appears only here, at the edge (and in the app).
"""

from __future__ import annotations

import numpy as np

from ..geometry.mesh import TriangleMesh
from .load import mesh_from_vtk_polydata

__all__ = ["to_pyvista", "from_pyvista"]


def to_pyvista(mesh: TriangleMesh):
    """Return a ``pyvista.PolyData`` with the same points (mm), triangles and point data as ``mesh``."""
    import pyvista

    faces = np.empty((mesh.n_triangles, 4), dtype=np.int64)
    faces[:, 0] = 3
    faces[:, 1:] = mesh.triangles
    poly = pyvista.PolyData(np.array(mesh.points), faces.ravel())
    for name, values in mesh.point_data.items():
        poly.point_data[name] = np.array(values)
    return poly


def from_pyvista(poly, *, source=None, mm_per_unit: float = 1.0) -> TriangleMesh:
    """Build a mesh from a ``pyvista.PolyData`` (polygons are triangulated, lines and points dropped).

    Parameters
    ----------
    poly : pyvista.PolyData
        Surface with points already in mm.
    source : path, optional
        Recorded as :attr:`TriangleMesh.source`.
    mm_per_unit : float
        Recorded as :attr:`TriangleMesh.mm_per_unit`.
    """
    points, triangles, point_data = mesh_from_vtk_polydata(poly, what="the PolyData")
    return TriangleMesh(points, triangles, point_data, source=source, mm_per_unit=mm_per_unit)
