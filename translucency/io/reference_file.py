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
from .atomic import write_bytes

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
    """Write a reference (mesh in mm, normals, :data:`REFERENCE_ARRAYS`, settings) to ``.npz`` or ``.vtp``, atomically.

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
        Another suffix, or a file without the reference's arrays (one sentence naming what is missing).
    MeshError
        A file that cannot be read.
    """
    path = Path(path)
    suffix = _suffix(path)
    if not path.is_file():
        raise InvalidParameterError(f"reference file {path} does not exist; make one with 'translucency reference'.")
    needed = ("normals", *REFERENCE_ARRAYS)
    if suffix == ".npz":
        try:
            with np.load(path, allow_pickle=False) as data:
                values = {name: np.array(data[name]) for name in data.files}
        except (OSError, ValueError) as exc:
            raise MeshError(
                f"cannot read {path.name} ({exc}); is it an .npz written by 'translucency reference'?"
            ) from None
        missing = [name for name in ("points", "triangles", *needed) if name not in values]
        if missing:
            raise InvalidParameterError(
                f"{path.name} is not a reference file (no {', '.join(missing)}); make one with "
                "'translucency reference'."
            )
        metadata = json.loads(str(values["metadata"])) if "metadata" in values else {}
    else:
        import pyvista as pv

        from .formats.vtk import mesh_from_vtk_polydata

        try:
            poly = pv.read(path)
        except (OSError, ValueError, RuntimeError):
            poly = None
        if not isinstance(poly, pv.PolyData) or poly.n_points == 0:
            raise MeshError(
                f"cannot read {path.name} as VTK PolyData; is it a .vtp written by 'translucency reference'?"
            )
        points, triangles, point_data = mesh_from_vtk_polydata(poly, what=path.name)
        missing = [name for name in needed if name not in point_data]
        if missing:
            raise InvalidParameterError(
                f"{path.name} is not a reference file (no point_data {', '.join(missing)}); make one with "
                "'translucency reference'."
            )
        values = {"points": points, "triangles": triangles}
        values.update({name: np.asarray(point_data[name], dtype=np.float64) for name in needed})
        metadata = json.loads(str(poly.field_data["metadata"][0])) if "metadata" in poly.field_data else {}
    return ReferenceFile(
        points=np.asarray(values["points"], dtype=np.float64),
        triangles=np.asarray(values["triangles"], dtype=np.int64),
        normals=values["normals"],
        radiance=values["radiance"],
        radiance_stderr=values["radiance_stderr"],
        radiance_reentered=values["radiance_reentered"],
        metadata=metadata,
    )
