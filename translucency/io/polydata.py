"""A :class:`~translucency.geometry.mesh.TriangleMesh` to and from a ``pyvista.PolyData``.

The mesh record holds plain arrays; PyVista appears only here, at the edge (and in the app).
Every mesh-level entry point of the library (``clean_mesh``, ``decimate_mesh``, ``shade``, ``Scene``,
``compare``, ``Viewer``) takes either kind through :func:`as_triangle_mesh`, in the manner of
fast-simplification's ``simplify`` (arrays) / ``simplify_mesh`` (PolyData) pair: a PolyData's length
unit is the keyword ``unit=``, inferred from its size when absent, exactly as for a file.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError, option
from ..geometry.mesh import TriangleMesh, validate_mesh_arrays
from .load import mesh_from_vtk_polydata, to_millimetres
from .units import parse_unit

__all__ = ["to_pyvista", "from_pyvista", "as_triangle_mesh", "is_pyvista_mesh", "LENGTH_UNIT_FIELD"]

#: ``field_data`` entry naming the length unit of a PolyData's points (``"mm"`` on every PolyData this
#: library returns); :func:`as_triangle_mesh` reads it when no ``unit`` is given, instead of inferring.
LENGTH_UNIT_FIELD = "length_unit"


def to_pyvista(mesh: TriangleMesh):
    """Return a ``pyvista.PolyData`` with the same points (mm), triangles and point data as ``mesh``;
    its ``field_data["length_unit"]`` is ``"mm"``."""
    import pyvista

    faces = np.empty((mesh.n_triangles, 4), dtype=np.int64)
    faces[:, 0] = 3
    faces[:, 1:] = mesh.triangles
    poly = pyvista.PolyData(np.array(mesh.points), faces.ravel())
    for name, values in mesh.point_data.items():
        poly.point_data[name] = np.array(values)
    poly.field_data[LENGTH_UNIT_FIELD] = ["mm"]
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


def is_pyvista_mesh(value) -> bool:
    """Whether ``value`` is a PyVista/VTK dataset (checked without importing PyVista when it is not loaded)."""
    import sys

    vtk_object = sys.modules.get("vtkmodules.vtkCommonDataModel")
    return vtk_object is not None and isinstance(value, vtk_object.vtkDataSet)


def as_triangle_mesh(mesh, unit=None, *, entry: str = "this function") -> TriangleMesh:
    """``mesh`` as a :class:`TriangleMesh` in mm: a TriangleMesh as it is, a PyVista (or VTK) dataset
    converted.

    Parameters
    ----------
    mesh : TriangleMesh or pyvista.PolyData or pyvista.DataSet
        A PolyData's polygons are fan-triangulated and its triangle strips unrolled (lines and vertices
        dropped); any other dataset (an ``UnstructuredGrid``, say) gives its outer surface. Its point
        arrays are kept as ``point_data`` (colours under ``"colors"``, normals under ``"normals"``).
    unit : {"mm", "cm", "m", "in"} or float, optional
        Length unit of a dataset's points, or mm per unit. None: the dataset's
        ``field_data["length_unit"]`` when it has one (every PolyData this library returns says
        ``"mm"``), else inferred from the size and said in one
        :class:`~translucency.io.units.UnitInferredWarning`, exactly as for a file. A TriangleMesh is
        already in mm, and a unit given with one is refused.
    entry : str
        The function's name, for the error sentences.

    Raises
    ------
    InvalidParameterError
        For anything else than a TriangleMesh or a dataset, or a unit given with a TriangleMesh.
    MeshError
        For a dataset with no triangles, bad coordinates or an implausible size.
    """
    if isinstance(mesh, TriangleMesh):
        if unit is not None:
            raise InvalidParameterError(
                f"{entry} got {option('unit', unit)} with a TriangleMesh, which is already in mm; pass the unit "
                "where the mesh is read (load_mesh(path, unit=...)), or pass a PolyData."
            )
        return mesh
    if not is_pyvista_mesh(mesh):
        raise InvalidParameterError(
            f"{entry} needs a TriangleMesh or a pyvista.PolyData, not {type(mesh).__name__}; read a file with "
            "load_mesh(path, unit=...) or pyvista.read(path) first."
        )
    import pyvista

    data = pyvista.wrap(mesh)
    if not isinstance(data, pyvista.PolyData):
        from vtkmodules.vtkFiltersGeometry import vtkDataSetSurfaceFilter

        surface = vtkDataSetSurfaceFilter()
        surface.SetInputData(data)
        surface.Update()
        data = pyvista.wrap(surface.GetOutput())
    name = f"the {type(pyvista.wrap(mesh)).__name__}"
    if unit is None and LENGTH_UNIT_FIELD in data.field_data:
        recorded = str(np.asarray(data.field_data[LENGTH_UNIT_FIELD]).ravel()[0])
        try:
            parse_unit(recorded)
        except InvalidParameterError:
            raise InvalidParameterError(
                f"{name} says its length unit is {recorded!r} (field_data['{LENGTH_UNIT_FIELD}']), which is not a "
                f"unit; pass {option('unit')}."
            ) from None
        unit = recorded
    points, triangles, point_data = mesh_from_vtk_polydata(data, what=name)
    points, triangles = validate_mesh_arrays(points, triangles, what=name)
    points, mm_per_unit = to_millimetres(points, triangles, unit, name)
    return TriangleMesh(points, triangles, point_data, mm_per_unit=mm_per_unit, unit_inferred=unit is None)
