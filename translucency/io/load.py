"""Read mesh files of every common format into a :class:`~translucency.geometry.mesh.TriangleMesh` in mm.

This module dispatches: it checks that the file can be read, tells the format from the content
(a file whose content is of another format than its extension says is refused with the name it
should have), hands the file to the reader of its format (one module per format in
:mod:`translucency.io.formats`), and converts the result to mm with a plausible size.

Whatever the format, polygons become triangles (fan triangulation, see
:mod:`translucency.io.triangulate`), coordinates become float64 mm (``unit`` gives the file's
length unit, see :mod:`translucency.io.units`), and a bad file raises
:class:`~translucency.errors.MeshError` with one sentence that names the file, says what is wrong
and how to fix it: missing or unreadable file, unknown format, content of another format than the
extension says, truncated or corrupt data, no triangles (a point cloud), NaN or infinite
coordinates, indices out of range, and sizes no scan can have. Reading never writes to the file.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from ..errors import MeshError, command_line_active, warn_user
from ..geometry.mesh import TriangleMesh, validate_mesh_arrays
from .formats.obj import read_obj
from .formats.off import read_off
from .formats.ply import read_ply
from .formats.pymeshlab import PYMESHLAB_FORMATS, read_with_pymeshlab
from .formats.stl import read_stl
from .formats.vtk import VTK_FORMATS, mesh_from_vtk_polydata, read_with_vtk
from .readable import regular_file
from .units import UnitInferredWarning, check_extent, infer_unit, inferred_unit_message, parse_unit

__all__ = [
    "load_mesh",
    "read_mesh_arrays",
    "to_millimetres",
    "mesh_from_vtk_polydata",
    "SUPPORTED_FORMATS",
    "detect_format",
]

#: File suffixes that :func:`load_mesh` reads, with a description.
SUPPORTED_FORMATS: dict[str, str] = {
    ".ply": "Stanford PLY (ascii or binary, triangles, polygons or triangle strips)",
    ".off": "Object File Format (OFF, COFF, NOFF, STOFF)",
    ".obj": "Wavefront OBJ (vertex colours kept)",
    **{suffix: name for suffix, (_, _, name) in VTK_FORMATS.items()},
    **PYMESHLAB_FORMATS,
}


# content signatures that are unambiguous: a file that shows one of them under another suffix is misnamed
_CONFIDENT_SIGNATURES = {".ply", ".off", ".vtk", ".vtp", ".vtu", ".vtm", ".glb"}
_XML_FAMILY = {".vtp", ".vtu", ".vtm"}


# --------------------------------------------------------------------------------------------------
# public entry points
# --------------------------------------------------------------------------------------------------
def load_mesh(path, unit: str | float | None = None, *, format: str | None = None) -> TriangleMesh:
    """Read a mesh file into a triangle mesh in mm.

    Parameters
    ----------
    path : str or path-like
        The mesh file (see :data:`SUPPORTED_FORMATS`); it is only read.
    unit : {"mm", "cm", "m", "in"} or float, optional
        Length unit of the file's coordinates, or a number of mm per unit. None (the default):
        inferred from the size, millimetres for 5 to 5000 units across and metres for 0.005 to 5
        (:func:`~translucency.io.units.infer_unit`), said in one :class:`UnitInferredWarning` line
        and recorded as ``unit_inferred``.
    format : str, optional
        Read the file as this format (a suffix such as ``"ply"`` or ``".obj"``) whatever its name.

    Returns
    -------
    TriangleMesh
        Points in mm (float64), triangles (int64), the file's per-vertex properties in
        ``point_data``, ``source`` the path, ``mm_per_unit`` the unit factor and ``unit_inferred``.

    Raises
    ------
    MeshError
        For any file that does not hold a usable triangle mesh (one sentence saying what to do),
        and, with no unit given, for a size no unit makes plausible.
    InvalidParameterError
        For an unknown unit.

    Warns
    -----
    ImplausibleSizeWarning
        When the mesh is smaller than 5 mm or larger than 5 m in the given unit; the message names
        the unit that would make it plausible (a 0.16 mm bunny: "pass unit='m'").
    UnitInferredWarning
        With no unit given: the unit chosen ("bunny.ply: no unit= given; 0.156 units across, read
        as metres (156 mm); pass unit= to override").

    Examples
    --------
    >>> mesh = load_mesh("bunny.ply", unit="m")  # doctest: +SKIP
    >>> mesh.extent  # doctest: +SKIP
    155.7
    """
    if unit is not None:
        parse_unit(unit)  # a bad unit is refused before the file is read
    path = Path(path)
    points, triangles, point_data = read_mesh_arrays(path, format=format)
    points, mm_per_unit = to_millimetres(points, triangles, unit, path.name)
    for array in (points, triangles):
        if isinstance(array, np.ndarray) and array.base is None:
            array.flags.writeable = False  # read here and held nowhere else: the mesh takes them without a copy
    return TriangleMesh(points, triangles, point_data, source=path, mm_per_unit=mm_per_unit, unit_inferred=unit is None)


def to_millimetres(points, triangles, unit, name: str) -> tuple[np.ndarray, float]:
    """Mesh coordinates in their own ``unit`` converted to mm: ``(points in mm, mm per unit)``.

    The rule every mesh entering the library follows (files and in-memory meshes alike): ``unit`` is
    ``"mm"``, ``"cm"``, ``"m"``, ``"in"`` or a number of mm per unit; None infers it from the size of the
    triangles' vertices (:func:`~translucency.io.units.infer_unit`) and says so in one
    :class:`~translucency.io.units.UnitInferredWarning`. A size implausible for the unit warns
    (:class:`~translucency.io.units.ImplausibleSizeWarning`); ``name`` names the mesh in those sentences.

    Raises
    ------
    MeshError
        With no unit, for a size no unit makes plausible; or when the coordinates overflow in mm.
    InvalidParameterError
        For an unknown unit.
    """
    if unit is None:
        extent_in_file = _extent(points, triangles)
        inferred = infer_unit(extent_in_file, name)
        warn_user(inferred_unit_message(name, extent_in_file, inferred), UnitInferredWarning)
        mm_per_unit = parse_unit(inferred)
    else:
        mm_per_unit = parse_unit(unit)
    points = np.asarray(points, dtype=np.float64) * mm_per_unit
    if not np.isfinite(points).all():
        raise MeshError(f"{name} has coordinates too large to convert to mm; check its unit and coordinates.")
    check_extent(_extent(points, triangles), mm_per_unit, name)
    return points, mm_per_unit


def _extent(points: np.ndarray, triangles: np.ndarray) -> float:
    """Largest side of the bounding box of the vertices the triangles use (in the points' unit)."""
    referenced = np.zeros(len(points), dtype=bool)
    referenced[triangles.ravel()] = True
    used = points if referenced.all() else points[referenced]
    return float(np.max(used.max(axis=0) - used.min(axis=0)))


def read_mesh_arrays(path, *, format: str | None = None) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Read a mesh file into arrays in the file's own unit (the array-level form of :func:`load_mesh`).

    Parameters
    ----------
    path : str or path-like
        The mesh file.
    format : str, optional
        Read the file as this format (a suffix such as ``"ply"``) whatever its name.

    Returns
    -------
    points : ndarray, shape (n, 3), float64
        Coordinates in the file's unit.
    triangles : ndarray, shape (m, 3), int64
        Validated: at least one triangle, all indices in range.
    point_data : dict of str to ndarray
        Per-vertex properties with n rows.

    Raises
    ------
    MeshError
    """
    path = Path(path)
    suffix = _check_readable(path, format)
    sniffed = detect_format(path)
    if (
        format is None
        and sniffed in _CONFIDENT_SIGNATURES
        and sniffed != suffix
        and not {sniffed, suffix} <= _XML_FAMILY
    ):
        raise MeshError(_misnamed(path, suffix, sniffed))
    try:
        if suffix == ".ply":
            points, triangles, point_data = read_ply(path)
        elif suffix == ".off":
            points, triangles, point_data = read_off(path)
        elif suffix == ".obj":
            points, triangles, point_data = read_obj(path)
        elif suffix == ".stl":
            points, triangles, point_data = read_stl(path)
        elif suffix in VTK_FORMATS:
            points, triangles, point_data = read_with_vtk(path, suffix)
        else:
            points, triangles, point_data = read_with_pymeshlab(path, suffix)
    except MeshError as exc:
        if format is None and sniffed is not None and sniffed != suffix:
            raise MeshError(_misnamed(path, suffix, sniffed)) from exc
        raise
    points, triangles = validate_mesh_arrays(points, triangles, what=path.name)
    return points, triangles, point_data


def detect_format(path) -> str | None:
    """Guess a file's format from its first bytes; returns a suffix such as ``".ply"`` or None."""
    try:
        with open(path, "rb") as stream:
            head = stream.read(512)
            stream.seek(0, os.SEEK_END)
            size = stream.tell()
    except OSError:
        return None
    if head.startswith(b"ply\n") or head.startswith(b"ply\r\n"):
        return ".ply"
    if re.match(rb"\s*(ST)?C?N?4?n?OFF\b", head):
        return ".off"
    if head.startswith(b"# vtk DataFile"):
        return ".vtk"
    if head.lstrip().startswith(b"<?xml") or head.lstrip().startswith(b"<VTKFile"):
        if b"PolyData" in head:
            return ".vtp"
        if b"UnstructuredGrid" in head:
            return ".vtu"
        if b"<VTKFile" in head:
            return ".vtm" if b"MultiBlock" in head else ".vtp"
        return None
    if head.startswith(b"glTF"):
        return ".glb"
    if head.startswith(b"solid") and b"facet" in head:
        return ".stl"
    if len(head) >= 84 and size == 84 + 50 * int.from_bytes(head[80:84], "little") and size > 84:
        return ".stl"
    try:
        text = head.decode("ascii")
    except UnicodeDecodeError:
        return None
    lines = [line.strip() for line in text.splitlines() if line.strip() and not line.startswith("#")]
    if lines and all(re.match(r"(v|vn|vt|f|o|g|s|usemtl|mtllib|l)\s", line + " ") for line in lines[:-1]):
        if any(line.startswith("v ") for line in lines):
            return ".obj"
    return None


def _rename_or_pass(path: Path, sniffed: str) -> str:
    """What to do with a file whose content is another format: rename it, or (in Python) pass ``format=``."""
    rename = f"rename it to {path.stem}{sniffed}"
    return rename if command_line_active() else f"{rename} or pass format={sniffed[1:]!r}"


def _misnamed(path: Path, suffix: str, sniffed: str) -> str:
    expected = SUPPORTED_FORMATS[suffix].split(" (")[0]
    return (
        f"{path.name} does not hold {expected} data but {sniffed[1:].upper()} data; {_rename_or_pass(path, sniffed)}."
    )


# --------------------------------------------------------------------------------------------------
# file checks
# --------------------------------------------------------------------------------------------------
def _check_readable(path: Path, format: str | None) -> str:
    """Check that the file exists and can be read, and return the suffix of the format to read it as."""
    regular_file(path, MeshError, kind="mesh file")
    try:
        with open(path, "rb") as stream:
            first = stream.read(1)
    except PermissionError as exc:
        raise MeshError(
            f"{path.name} cannot be read (permission denied); make it readable (chmod +r) or copy it."
        ) from exc
    except OSError as exc:
        raise MeshError(f"{path.name} cannot be read ({exc.strerror or exc}); check the file and the disk.") from exc
    if format is not None:
        suffix = "." + str(format).lower().lstrip(".")
        if suffix not in SUPPORTED_FORMATS:
            raise MeshError(
                f"unknown mesh format {format!r}; use one of {', '.join(s[1:] for s in SUPPORTED_FORMATS)}."
            )
    else:
        suffix = path.suffix.lower()
        if suffix not in SUPPORTED_FORMATS:
            sniffed = detect_format(path) if first else None
            hint = (
                f" (its content looks like {sniffed[1:].upper()}: {_rename_or_pass(path, sniffed)})" if sniffed else ""
            )
            raise MeshError(
                f"{path.name} has an unknown mesh format {repr(suffix) if suffix else '(no extension)'}{hint}; "
                f"use a supported one: {', '.join(s[1:] for s in SUPPORTED_FORMATS)}."
            )
    if not first:
        raise MeshError(f"{path.name} is empty (0 bytes); export the mesh again.")
    return suffix
