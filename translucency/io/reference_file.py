"""Reference files: path-traced radiance per vertex of a mesh, as ``.npz`` or ``.vtp``, written atomically.

A reference is compared with the models vertex by vertex, so it carries its mesh (points in mm, triangles,
the normals it was traced along) beside the arrays, and the settings it was traced with:

==================== ============ ===============================================================
array                shape, type  meaning, unit
==================== ============ ===============================================================
radiance             (n, 3) f64   radiance leaving the surface along the normal, the subsurface
                                  part, W/(m^2 sr) per W/m^2 of irradiance (NaN: not traced)
radiance_stderr      (n, 3) f64   its standard error, same unit
radiance_reentered   (n, 3) f64   the part of ``radiance`` that left the surface and entered again
normals              (n, 3) f64   the unit normals the radiance was traced along
==================== ============ ===============================================================

In an ``.npz`` these are keys (with ``points``, ``triangles`` and ``metadata``, a JSON string); in a ``.vtp``
they are ``point_data`` of the PolyData and the settings are ``field_data`` (one JSON string,
``metadata``, and ``length_unit = "mm"``).
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError, MeshError, WriteError
from .atomic import write_bytes, write_error
from .readable import regular_file

__all__ = ["REFERENCE_ARRAYS", "REFERENCE_SUFFIXES", "ReferenceFile", "read_reference_file", "write_reference_file"]

#: The per-vertex arrays of a reference file, (n, 3) each.
REFERENCE_ARRAYS = ("radiance", "radiance_stderr", "radiance_reentered")
#: Suffixes a reference is written as and read from.
REFERENCE_SUFFIXES = (".npz", ".vtp")


@dataclass(frozen=True)
class ReferenceFile:
    """A reference read back: the mesh in mm, the normals and arrays of :data:`REFERENCE_ARRAYS`, the settings.

    Attributes
    ----------
    points : ndarray, shape (n, 3)
        Vertex positions, mm.
    triangles : ndarray, shape (m, 3)
        Vertex indices.
    normals : ndarray, shape (n, 3)
        Unit normals the radiance was traced along.
    radiance, radiance_stderr, radiance_reentered : ndarray, shape (n, 3)
        W/(m^2 sr) per W/m^2 (NaN where a vertex was not traced).
    metadata : dict
        The settings it was traced with (material, coefficients, light, spp, seed, time, unit).
    """

    points: np.ndarray
    triangles: np.ndarray
    normals: np.ndarray
    radiance: np.ndarray
    radiance_stderr: np.ndarray
    radiance_reentered: np.ndarray
    metadata: dict = field(default_factory=dict)


def _suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in REFERENCE_SUFFIXES:
        raise InvalidParameterError(f"a reference is written as .npz or .vtp; {path.name} has neither suffix.")
    return suffix


def write_reference_file(path, points, triangles, normals, arrays: dict, metadata: dict) -> Path:
    """Write a reference (mesh in mm, normals, :data:`REFERENCE_ARRAYS`, settings) to ``.npz`` or ``.vtp``, atomically;
    its folder is made when missing.

    Raises
    ------
    InvalidParameterError
        Another suffix, or an array of the wrong shape.
    WriteError
        When the disk refuses the file (nothing is left behind).
    """
    path = Path(path)
    suffix = _suffix(path)
    points = np.asarray(points, dtype=np.float64)
    n = len(points)
    values = {"normals": np.asarray(normals, dtype=np.float64)}
    values.update({name: np.asarray(arrays[name], dtype=np.float64) for name in REFERENCE_ARRAYS})
    for name, value in values.items():
        if value.shape != (n, 3):
            raise InvalidParameterError(f"reference file: {name} must have shape ({n}, 3), got {value.shape}.")
    text = json.dumps(metadata, default=_plain)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise write_error(path, exc) from None
    if suffix == ".npz":
        buffer = io.BytesIO()
        np.savez_compressed(
            buffer, points=points, triangles=np.asarray(triangles, dtype=np.int64), metadata=np.array(text), **values
        )
        return write_bytes(path, buffer.getvalue())
    import pyvista as pv

    from .formats.vtk import encode_polydata

    faces = np.hstack([np.full((len(triangles), 1), 3), np.asarray(triangles, dtype=np.int64)]).ravel()
    poly = pv.PolyData(points, faces)
    for name, value in values.items():
        poly.point_data[name] = value
    poly.field_data["metadata"] = [text]
    poly.field_data["length_unit"] = ["mm"]
    try:
        data = encode_polydata(poly, suffix)
    except (RuntimeError, TypeError, ValueError) as exc:
        raise WriteError(f"encoding {path.name} failed ({exc}); write the reference as .npz instead.") from None
    return write_bytes(path, data)


def _plain(value):
    """JSON for numpy scalars and arrays in the metadata."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return str(value)


def read_reference_file(path) -> ReferenceFile:
    """Read a reference written by :func:`write_reference_file` (``.npz`` or ``.vtp``).

    Raises
    ------
    InvalidParameterError
        Another suffix, a path that is not a regular file, or a file without the reference's arrays (one sentence
        naming what is missing).
    MeshError
        A file that cannot be read, settings that are not JSON, arrays whose shapes disagree with the mesh, or
        radiance that is infinite, negative or never traced.
    """
    path = Path(path)
    suffix = _suffix(path)
    if not path.exists():
        raise InvalidParameterError(f"reference file {path} does not exist; make one with 'translucency reference'.")
    regular_file(path, InvalidParameterError, "reference file", "reference file")
    needed = ("normals", *REFERENCE_ARRAYS)
    if suffix == ".npz":
        try:
            with np.load(path, allow_pickle=False) as data:
                values = {name: np.array(data[name]) for name in data.files}
        except Exception:  # noqa: BLE001 - numpy raises OSError, ValueError, EOFError or zipfile's BadZipFile
            raise MeshError(
                f"cannot read {path.name}: it is not an .npz archive of arrays (empty, truncated or another kind of "
                "file); make the reference again with 'translucency reference'."
            ) from None
        missing = [name for name in ("points", "triangles", *needed) if name not in values]
        if missing:
            raise InvalidParameterError(
                f"{path.name} is not a reference file (no {', '.join(missing)}); make one with "
                "'translucency reference'."
            )
        metadata = _metadata(values.get("metadata"), path)
    else:
        import pyvista as pv

        from .formats.vtk import mesh_from_vtk_polydata, read_vtk_data

        unreadable = MeshError(
            f"cannot read {path.name} as VTK PolyData; is it a .vtp written by 'translucency reference'?"
        )
        try:
            poly = read_vtk_data(path, suffix)
        except MeshError:
            raise unreadable from None
        if not isinstance(poly, pv.PolyData):
            raise unreadable
        points, triangles, point_data = mesh_from_vtk_polydata(poly, what=path.name)
        missing = [name for name in needed if name not in point_data]
        if missing:
            raise InvalidParameterError(
                f"{path.name} is not a reference file (no point_data {', '.join(missing)}); make one with "
                "'translucency reference'."
            )
        values = {"points": points, "triangles": triangles}
        values.update({name: np.asarray(point_data[name], dtype=np.float64) for name in needed})
        metadata = _metadata(poly.field_data["metadata"][0] if "metadata" in poly.field_data else None, path)
    return _checked(values, metadata, path)


def _metadata(value, path: Path) -> dict:
    """The settings a reference was traced with, from their JSON text (empty when the file has none)."""
    if value is None:
        return {}
    try:
        metadata = json.loads(str(value))
    except ValueError:
        metadata = None
    if not isinstance(metadata, dict):
        raise MeshError(
            f"{path.name}: its settings (metadata) are not a JSON table; make the reference again with "
            "'translucency reference'."
        )
    return metadata


def _checked(values: dict, metadata: dict, path: Path) -> ReferenceFile:
    """A :class:`ReferenceFile` from the arrays read, once their shapes agree with the mesh and the radiance is
    finite (NaN where not traced) and not negative, with at least one vertex traced."""

    def refuse(what: str):
        raise MeshError(f"{path.name}: {what}; make the reference again with 'translucency reference'.")

    try:
        points = np.asarray(values["points"], dtype=np.float64)
        triangles = np.asarray(values["triangles"], dtype=np.int64)
        arrays = {name: np.asarray(values[name], dtype=np.float64) for name in ("normals", *REFERENCE_ARRAYS)}
    except (TypeError, ValueError):
        refuse("its arrays are not numbers")
    n = len(points)
    if points.ndim != 2 or points.shape[1:] != (3,) or n == 0 or not np.all(np.isfinite(points)):
        refuse("its points are not an (n, 3) array of finite numbers")
    if (
        triangles.ndim != 2
        or triangles.shape[1:] != (3,)
        or (triangles.size and not 0 <= triangles.min() <= triangles.max() < n)
    ):
        refuse(f"its triangles are not an (m, 3) array of vertex indices below {n}")
    for name, value in arrays.items():
        if value.shape != (n, 3):
            refuse(f"{name} has shape {value.shape}, not ({n}, 3) for its {n} points")
    radiance = arrays["radiance"]
    traced = ~np.isnan(radiance)
    if not traced.any():
        refuse("no vertex was traced (the radiance is NaN everywhere)")
    for name in REFERENCE_ARRAYS:
        value = arrays[name][traced]
        if not np.all(np.isfinite(value)) or value.min() < 0:
            refuse(f"{name} has infinite, NaN or negative values where the radiance was traced")
    return ReferenceFile(points=points, triangles=triangles, **arrays, metadata=metadata)
