"""Formats VTK reads (STL, legacy VTK, VTP, VTU, VTM, BYU, glTF, VTK HDF), PolyData to arrays, and
PolyData to the bytes of a ``.vtp`` or ``.vtk`` file (:func:`encode_polydata`).

VTK's own error text names its classes and addresses, so a file VTK cannot read is reported in our
sentence instead; point arrays are kept (colours as ``"colors"``).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from ...errors import MeshError
from ..triangulate import triangulate_polygons, triangulate_strips
from .common import set_colors

__all__ = ["VTK_FORMATS", "read_with_vtk", "mesh_from_vtk_polydata", "encode_polydata"]

VTK_FORMATS = {
    ".stl": ("vtkmodules.vtkIOGeometry", "vtkSTLReader", "STL"),
    ".vtk": ("vtkmodules.vtkIOLegacy", "vtkDataSetReader", "legacy VTK"),
    ".vtp": ("vtkmodules.vtkIOXML", "vtkXMLGenericDataObjectReader", "VTK XML PolyData"),
    ".vtu": ("vtkmodules.vtkIOXML", "vtkXMLGenericDataObjectReader", "VTK XML UnstructuredGrid"),
    ".vtm": ("vtkmodules.vtkIOXML", "vtkXMLGenericDataObjectReader", "VTK XML MultiBlock"),
    ".g": ("vtkmodules.vtkIOGeometry", "vtkBYUReader", "Movie.BYU"),
    ".gltf": ("vtkmodules.vtkIOGeometry", "vtkGLTFReader", "glTF"),
    ".glb": ("vtkmodules.vtkIOGeometry", "vtkGLTFReader", "binary glTF"),
    ".vtkhdf": ("vtkmodules.vtkIOHDF", "vtkHDFReader", "VTK HDF"),
    ".hdf": ("vtkmodules.vtkIOHDF", "vtkHDFReader", "VTK HDF"),
}


def read_with_vtk(path: Path, suffix: str):
    """Points, triangles and per-vertex arrays of a VTK file (:func:`read_vtk_data`, then its surface)."""
    import pyvista

    data = read_vtk_data(path, suffix)
    if not isinstance(data, pyvista.PolyData):
        from vtkmodules.vtkFiltersGeometry import vtkDataSetSurfaceFilter

        surface = vtkDataSetSurfaceFilter()
        surface.SetInputData(data)
        surface.Update()
        data = pyvista.wrap(surface.GetOutput())
    return mesh_from_vtk_polydata(data, what=path.name)


def read_vtk_data(path: Path, suffix: str):
    """A VTK file as a PyVista dataset (blocks combined), read with VTK's own messages kept from the user: a file
    VTK cannot read, or one without vertices, is one sentence (:class:`MeshError`)."""
    import importlib

    import pyvista

    module, class_name, description = VTK_FORMATS[suffix]
    reader = getattr(importlib.import_module(module), class_name)()
    reader.SetFileName(str(path))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pyvista.vtk_verbosity("off"), pyvista.VtkErrorCatcher(send_to_logging=False) as catcher:
            reader.Update()
            output = reader.GetOutputDataObject(0)
    if catcher.error_events:  # VTK's own text names its classes and addresses: not for the user
        raise MeshError(f"{path.name} is not a readable {description} file; check or export the file again.")
    if output is None:
        raise MeshError(f"{path.name} is not a readable {description} file; check or export the file again.")
    data = pyvista.wrap(output)
    if isinstance(data, pyvista.MultiBlock):
        data = data.combine(merge_points=False) if data.n_blocks else pyvista.PolyData()
    if data is None or data.n_points == 0:
        raise MeshError(
            f"{path.name} holds no vertices (an empty or unreadable {description} file); export the mesh again."
        )
    return data


def mesh_from_vtk_polydata(poly, *, what: str = "the PolyData"):
    """Triangles and per-vertex arrays of a VTK/PyVista PolyData, without running a VTK filter.

    Polygons are fan-triangulated and triangle strips unrolled in numpy, so that corrupt indices
    are reported (:class:`MeshError`) instead of reaching VTK code.

    Parameters
    ----------
    poly : pyvista.PolyData or vtkPolyData
    what : str
        How error sentences name the data.

    Returns
    -------
    points : ndarray, shape (n, 3), float64
    triangles : ndarray, shape (m, 3), int64
    point_data : dict of str to ndarray
    """
    import pyvista
    from vtkmodules.util.numpy_support import vtk_to_numpy

    poly = pyvista.wrap(poly)
    points = np.array(poly.points, dtype=np.float64).reshape(-1, 3)

    def cells(cell_array):
        if cell_array is None or cell_array.GetNumberOfCells() == 0:
            return np.zeros(1, np.int64), np.zeros(0, np.int64)
        return (
            vtk_to_numpy(cell_array.GetOffsetsArray()).astype(np.int64),
            vtk_to_numpy(cell_array.GetConnectivityArray()).astype(np.int64),
        )

    triangles = [triangulate_polygons(*cells(poly.GetPolys()))]
    strip_offsets, strip_indices = cells(poly.GetStrips())
    if len(strip_indices):
        triangles.append(triangulate_strips(strip_indices, strip_offsets))
    triangles = np.concatenate(triangles)
    point_data: dict[str, np.ndarray] = {}
    for name in poly.point_data.keys():
        if name.startswith("vtkOriginal"):
            continue
        values = np.array(poly.point_data[name])
        if values.ndim == 0 or len(values) != len(points) or values.dtype == object:
            continue
        if name.lower() in ("rgb", "rgba", "colors", "colours") and values.ndim == 2 and values.shape[1] in (3, 4):
            set_colors(point_data, values, what)
        elif name.lower() == "normals" and values.ndim == 2 and values.shape[1] == 3:
            point_data["normals"] = values
        else:
            point_data[name] = values
    return points, triangles, point_data


def encode_polydata(poly, suffix: str) -> bytes:
    """The bytes of a PolyData as a VTK XML PolyData (``".vtp"``) or binary legacy VTK (``".vtk"``) file.

    VTK's writers encode into memory (they are kept off the disk: on a full disk they stop silently
    or crash); every point, cell and field array is kept, float64 stays float64.

    Raises
    ------
    RuntimeError
        When VTK cannot encode the data.
    """
    from vtkmodules.vtkIOLegacy import vtkPolyDataWriter
    from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

    legacy = suffix.lower() == ".vtk"
    writer = vtkPolyDataWriter() if legacy else vtkXMLPolyDataWriter()
    writer.SetInputData(poly)
    if legacy:
        writer.SetFileTypeToBinary()
    writer.WriteToOutputStringOn()
    if not writer.Write():
        raise RuntimeError(f"VTK could not encode the mesh as {suffix}")
    output = writer.GetOutputStdString() if legacy else writer.GetOutputString()
    return output if isinstance(output, bytes) else output.encode("utf-8")
