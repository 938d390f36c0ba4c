"""The one triangle-mesh type of translucency: points in mm, triangles, per-vertex properties.

Every loader returns a :class:`TriangleMesh`, every repair and decimation step takes one and returns
a new one, and the solver receives its plain arrays (``points``, ``triangles``). The record holds
arrays only; its conversions to and from ``pyvista.PolyData`` live in :mod:`translucency.io.polydata`.
A mesh is immutable:
its arrays are private read-only copies (an array that is already read-only and owns its memory, such as another
mesh's, is taken as it is), so a mesh handed to the solver cannot change under it, and
"changing" a mesh means building a new one with :meth:`TriangleMesh.replace`. What is measured on a mesh (its
vertex normals and areas, total area, mean edge length) is kept with it, and a step that measured them on the way
(the cleaning) hands them over with :meth:`TriangleMesh.remember`.

=============== ======================================================== =====
field           meaning                                                  unit
=============== ======================================================== =====
points          vertex positions, (n, 3) float64                         mm
triangles       vertex indices of each triangle, (m, 3) int64            1
point_data      per-vertex properties of the file (colours, confidence)  any
source          the file the mesh was read from, or None                 --
mm_per_unit     length of one unit of the source file                    mm
unit_inferred   True when mm_per_unit was inferred from the size         --
=============== ======================================================== =====

Per-vertex colours are stored under the key ``"colors"`` as (n, 3) or (n, 4) uint8 (RGB or RGBA),
and normals that came with the file under ``"normals"`` as (n, 3) float; every other property keeps
its name from the file.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from ..errors import MeshError
from .measure import mean_edge_length, triangle_areas, vertex_areas, vertex_normals

__all__ = ["TriangleMesh", "validate_mesh_arrays"]


def _read_only_copy(array: np.ndarray, dtype=None) -> np.ndarray:
    """``array`` itself when it is read-only, owns its memory and has the type and layout asked for, else a read-only
    copy."""
    if (
        isinstance(array, np.ndarray)
        and type(array) is np.ndarray
        and array.base is None
        and not array.flags.writeable
        and array.flags.c_contiguous
        and (dtype is None or array.dtype == dtype)
    ):
        return array
    copy = np.array(array, dtype=dtype, copy=True, order="C")
    copy.setflags(write=False)
    return copy


def validate_mesh_arrays(points, triangles, *, what: str = "the mesh") -> tuple[np.ndarray, np.ndarray]:
    """Check and convert mesh arrays, raising :class:`MeshError` with one sentence on any defect.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Vertex positions (any length unit); converted to float64.
    triangles : array_like, shape (m, 3)
        Vertex indices of each triangle; converted to int64.
    what : str
        How the sentence names the mesh (for example the file name).

    Returns
    -------
    points : ndarray, shape (n, 3), float64
    triangles : ndarray, shape (m, 3), int64

    Raises
    ------
    MeshError
        Wrong shapes, no triangles, NaN or infinite coordinates, or indices out of range.
    """
    try:
        points = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise MeshError(f"{what} has vertex coordinates that are not numbers; pass an (n, 3) array of floats.") from exc
    if points.ndim != 2 or points.shape[1] != 3:
        raise MeshError(f"{what} has points of shape {points.shape}, not (n, 3); pass one row of x, y, z per vertex.")
    triangles = np.asarray(triangles)
    if triangles.size == 0:
        triangles = triangles.reshape(0, 3)
    if triangles.ndim != 2 or triangles.shape[1] != 3:
        raise MeshError(
            f"{what} has triangles of shape {triangles.shape}, not (m, 3); pass three vertex indices per triangle."
        )
    if triangles.dtype.kind not in "iu":
        if triangles.dtype.kind == "f" and np.all(np.isfinite(triangles)) and np.all(triangles == np.round(triangles)):
            triangles = triangles.astype(np.int64)
        else:
            raise MeshError(f"{what} has triangle indices that are not integers; pass integer vertex indices.")
    triangles = triangles.astype(np.int64, copy=False)
    if len(points) == 0:
        raise MeshError(f"{what} has no vertices; pass a mesh with at least one triangle.")
    if len(triangles) == 0:
        raise MeshError(
            f"{what} has {len(points)} vertices but no triangles (a point cloud); "
            "reconstruct a surface from it first (for example in MeshLab) and load that mesh."
        )
    finite = None if np.isfinite(points.sum()) else np.isfinite(points).all(axis=1)  # a NaN or inf makes the sum one
    if finite is not None and not finite.all():
        bad = int(np.count_nonzero(~finite))
        raise MeshError(
            f"{what} has {bad} {'vertex' if bad == 1 else 'vertices'} with NaN or infinite coordinates "
            f"(the first is vertex {int(np.flatnonzero(~finite)[0])}); repair or remove them and load the mesh again."
        )
    low, high = int(triangles.min()), int(triangles.max())
    if low < 0 or high >= len(points):
        bad_index = low if low < 0 else high
        row = int(np.flatnonzero((triangles == bad_index).any(axis=1))[0])
        raise MeshError(
            f"{what} has a triangle (number {row}) that refers to vertex {bad_index}, "
            f"but the vertices are numbered 0 to {len(points) - 1}; the file is corrupt, export it again."
        )
    return points, triangles


@dataclasses.dataclass(frozen=True, eq=False)
class TriangleMesh:
    """A triangle mesh in mm with per-vertex properties; immutable.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Vertex positions in mm (converted to float64).
    triangles : array_like, shape (m, 3)
        Vertex indices of each triangle, counter-clockwise seen from outside (converted to int64).
        A mesh has at least one triangle; unreferenced vertices are allowed.
    point_data : mapping of str to array_like, optional
        Per-vertex properties, each with ``n`` rows (colours under ``"colors"`` as uint8).
    source : path, optional
        The file the mesh came from.
    mm_per_unit : float, optional
        Length in mm of one unit of the source file (1 for mm, 1000 for m); ``points`` are already
        multiplied by it.
    unit_inferred : bool, optional
        True when the file stated no unit and ``mm_per_unit`` was inferred from its size
        (:func:`translucency.io.units.infer_unit`).

    Raises
    ------
    MeshError
        If the arrays are not a valid triangle mesh (see :func:`validate_mesh_arrays`).
    """

    points: np.ndarray
    triangles: np.ndarray
    point_data: Mapping[str, np.ndarray] = dataclasses.field(default_factory=dict)
    source: Path | None = None
    mm_per_unit: float = 1.0
    unit_inferred: bool = False

    def __post_init__(self):
        points, triangles = validate_mesh_arrays(self.points, self.triangles)
        data = {}
        for name, values in dict(self.point_data).items():
            values = np.asarray(values)
            if values.ndim == 0 or len(values) != len(points):
                raise MeshError(
                    f"point_data[{name!r}] has {values.shape[0] if values.ndim else 0} rows but the mesh has "
                    f"{len(points)} vertices; give one row per vertex."
                )
            data[str(name)] = _read_only_copy(values)
        mm_per_unit = float(self.mm_per_unit)
        if not (np.isfinite(mm_per_unit) and mm_per_unit > 0):
            raise MeshError(f"mm_per_unit is {self.mm_per_unit!r}; pass a positive length in mm per file unit.")
        object.__setattr__(self, "points", _read_only_copy(points, np.float64))
        object.__setattr__(self, "triangles", _read_only_copy(triangles, np.int64))
        object.__setattr__(self, "point_data", MappingProxyType(data))
        object.__setattr__(self, "source", None if self.source is None else Path(self.source))
        object.__setattr__(self, "mm_per_unit", mm_per_unit)
        object.__setattr__(self, "unit_inferred", bool(self.unit_inferred))
        object.__setattr__(self, "_measured", {})

    # --- sizes -------------------------------------------------------------------------------------
    @property
    def n_points(self) -> int:
        """Number of vertices."""
        return len(self.points)

    @property
    def n_triangles(self) -> int:
        """Number of triangles."""
        return len(self.triangles)

    @property
    def bounds(self) -> np.ndarray:
        """Axis-aligned bounding box of the referenced vertices, ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]`` in mm."""
        referenced = np.zeros(self.n_points, dtype=bool)
        referenced[self.triangles.ravel()] = True
        used = self.points[referenced]
        return np.stack([used.min(axis=0), used.max(axis=0)])

    @property
    def extent(self) -> float:
        """Largest side of the bounding box of the referenced vertices, in mm."""
        low, high = self.bounds
        return float(np.max(high - low))

    @property
    def surface_area(self) -> float:
        """Total area of the triangles, in mm² (computed once: the mesh is immutable)."""
        if "surface_area" not in self._measured:
            self._measured["surface_area"] = float(triangle_areas(self.points, self.triangles).sum())
        return self._measured["surface_area"]

    @property
    def mean_edge_length(self) -> float:
        """Mean length of the unique edges, in mm (:func:`~translucency.geometry.measure.mean_edge_length`, computed
        once)."""
        if "mean_edge_length" not in self._measured:
            self._measured["mean_edge_length"] = float(mean_edge_length(self.points, self.triangles))
        return self._measured["mean_edge_length"]

    # --- per-vertex geometry -------------------------------------------------------------------------
    def vertex_normals(self, copy: bool = True) -> np.ndarray:
        """Area-weighted unit vertex normals, (n, 3) float64: a copy of those computed once (``copy=False``: the
        mesh's own, read-only).

        See :func:`translucency.geometry.measure.vertex_normals`.
        """
        if "vertex_normals" not in self._measured:
            normals = vertex_normals(self.points, self.triangles)
            normals.flags.writeable = False  # computed here: kept without a copy
            self.remember(vertex_normals=normals)
        return np.array(self._measured["vertex_normals"]) if copy else self._measured["vertex_normals"]

    def vertex_areas(self, method: str = "barycentric", copy: bool = True) -> np.ndarray:
        """Area of each vertex's share of the surface in mm², (n,) float64 (the barycentric ones: a copy of those
        computed once; ``copy=False``: the mesh's own, read-only).

        See :func:`translucency.geometry.measure.vertex_areas`.
        """
        if method != "barycentric":
            return vertex_areas(self.points, self.triangles, method=method)
        if "vertex_areas" not in self._measured:
            self.remember(vertex_areas=vertex_areas(self.points, self.triangles))
        return np.array(self._measured["vertex_areas"]) if copy else self._measured["vertex_areas"]

    def remember(self, *, vertex_normals=None, vertex_areas=None, surface_area=None, mean_edge_length=None) -> None:
        """Keep measures of this very mesh computed elsewhere (the cleaning measures them on the way), so that they
        are not computed again: unit vertex normals (n, 3), barycentric vertex areas (n,) in mm², the total area in
        mm² and the mean unique-edge length in mm. The caller vouches that they are this mesh's; the arrays are
        kept read-only."""
        given = dict(
            vertex_normals=vertex_normals,
            vertex_areas=vertex_areas,
            surface_area=surface_area,
            mean_edge_length=mean_edge_length,
        )
        for name, value in given.items():
            if value is None:
                continue
            if isinstance(value, np.ndarray):
                value = _read_only_copy(value, np.float64)
            else:
                value = float(value)
            self._measured[name] = value

    # --- building new meshes -------------------------------------------------------------------------
    def replace(self, **changes: Any) -> TriangleMesh:
        """Return a new mesh with some fields replaced (``points``, ``triangles``, ``point_data``, ...)."""
        return dataclasses.replace(self, **changes)

    def __reduce__(self):
        """Pickled as its fields (the read-only view of ``point_data`` is not picklable itself): a mesh can be
        sent to and from another process."""
        fields = (self.points, self.triangles, dict(self.point_data), self.source, self.mm_per_unit, self.unit_inferred)
        return (TriangleMesh, fields)

    def __repr__(self) -> str:
        name = self.source.name if self.source is not None else "no file"
        keys = ", ".join(self.point_data) or "none"
        return (
            f"TriangleMesh({self.n_points} points, {self.n_triangles} triangles, extent {self.extent:.4g} mm, "
            f"point_data: {keys}, source: {name})"
        )
