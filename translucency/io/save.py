"""Write a :class:`~translucency.geometry.mesh.TriangleMesh` to a mesh file, atomically, never over its source.

The file is encoded in memory -- binary PLY, binary STL and OBJ by numpy, VTK legacy and VTK XML by
VTK's writers to a string -- and written by the atomic writer (:mod:`translucency.io.atomic`): an
existing file is replaced only by a complete one, a failed write (a full disk included) is one
sentence and leaves nothing behind, and the scan a mesh was read from is never overwritten. (VTK's
writers are kept off the disk: on a full disk they stop silently or crash.) Coordinates are written
in mm (the mesh's unit); PLY keeps the vertex normals and colours, VTK formats every point array.

========== ===================================================== =====
name       meaning                                               unit
========== ===================================================== =====
path       the output file (.ply, .vtp, .vtk, .stl or .obj)      --
points     vertex positions written                              mm
========== ===================================================== =====
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError, WriteError
from .atomic import prepare_output_file, same_file, write_bytes
from .formats.vtk import encode_polydata
from .polydata import to_pyvista

__all__ = ["WRITABLE_FORMATS", "check_output_path", "save_mesh"]

#: Suffixes :func:`save_mesh` writes.
WRITABLE_FORMATS = (".ply", ".vtp", ".vtk", ".stl", ".obj")


def check_output_path(path, source=None) -> Path:
    """Check where a mesh will be written, before any work is done; return it as a Path.

    Parameters
    ----------
    path : str or path-like
        The output file.
    source : str or path-like, optional
        The input file; the output may not be the same file (inputs are never modified).

    Raises
    ------
    InvalidParameterError
        An unsupported suffix, a missing folder, a folder in place of the file, a folder that cannot
        be written (permissions, read-only file system), or the input file itself.
    """
    path = Path(path)
    if path.suffix.lower() not in WRITABLE_FORMATS:
        raise InvalidParameterError(f"cannot write {path}: use a {', '.join(WRITABLE_FORMATS[:-1])} or .obj name.")
    prepare_output_file(path)
    if source is not None and path.exists() and same_file(path, Path(source)):
        raise InvalidParameterError(
            f"{path} is the input file; write the result to another file (inputs are never modified)."
        )
    return path


def save_mesh(path, mesh) -> Path:
    """Write ``mesh`` (points in mm, triangles, per-vertex data) to ``path``, atomically.

    Parameters
    ----------
    path : str or path-like
        Output file; its suffix (:data:`WRITABLE_FORMATS`) selects the format.
    mesh : TriangleMesh
        The mesh; never written over ``mesh.source``.

    Returns
    -------
    Path
        ``path``, once the complete file is in place.

    Raises
    ------
    InvalidParameterError
        See :func:`check_output_path`.
    WriteError
        When the writer fails or the disk refuses the file; nothing is left behind.
    """
    path = check_output_path(path, mesh.source)
    encode = {".ply": _ply_bytes, ".stl": _stl_bytes, ".obj": _obj_bytes}.get(path.suffix.lower(), _vtk_bytes)
    try:
        data = encode(mesh, path.suffix.lower())
    except (ValueError, RuntimeError) as exc:
        raise WriteError(f"encoding {path.name} failed ({exc}); choose another format.") from None
    write_bytes(path, data)
    return path


def _ply_bytes(mesh, suffix) -> list[bytes | np.ndarray]:
    """Binary little-endian PLY: x y z (double, mm), normals and colours when the mesh has them, triangles."""
    fields = [(axis, "<f8") for axis in "xyz"]
    columns = [mesh.points]
    normals, colors = mesh.point_data.get("normals"), mesh.point_data.get("colors")
    if normals is not None and np.shape(normals) == (mesh.n_points, 3):
        fields += [(name, "<f4") for name in ("nx", "ny", "nz")]
        columns.append(normals)
    if colors is not None and np.ndim(colors) == 2 and len(colors) == mesh.n_points and np.shape(colors)[1] in (3, 4):
        fields += [(name, "u1") for name in ("red", "green", "blue", "alpha")[: np.shape(colors)[1]]]
        columns.append(colors)
    vertices = np.empty(mesh.n_points, dtype=fields)
    names = iter(vertices.dtype.names)
    for column in columns:
        for values in np.asarray(column).T:
            vertices[next(names)] = values
    faces = np.empty(mesh.n_triangles, dtype=[("count", "u1"), ("indices", "<i4", (3,))])
    faces["count"], faces["indices"] = 3, mesh.triangles
    types = {"<f8": "double", "<f4": "float", "|u1": "uchar"}
    header = ["ply", "format binary_little_endian 1.0", f"element vertex {mesh.n_points}"]
    header += [f"property {types[vertices.dtype[name].str]} {name}" for name in vertices.dtype.names]
    header += [f"element face {mesh.n_triangles}", "property list uchar int vertex_indices", "end_header", ""]
    return ["\n".join(header).encode("ascii"), vertices, faces]  # the records without a copy


def _stl_bytes(mesh, suffix) -> list[bytes | np.ndarray]:
    """Binary STL: an 80-byte header, the triangle count, per triangle its unit normal and corners (mm)."""
    from ..geometry.measure import triangle_normals

    records = np.zeros(
        mesh.n_triangles, dtype=[("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attribute", "<u2")]
    )
    records["normal"] = np.nan_to_num(triangle_normals(mesh.points, mesh.triangles))
    records["corners"] = mesh.points[mesh.triangles]
    header = b"translucency mesh, mm".ljust(80, b" ")
    return [header, np.uint32(mesh.n_triangles).tobytes(), records]


def _obj_bytes(mesh, suffix) -> list[bytes]:
    """Wavefront OBJ: ``v x y z`` lines (mm, full precision), then ``f a b c`` (1-based)."""
    vertices = "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in mesh.points.tolist())
    faces = "".join(f"f {a} {b} {c}\n" for a, b, c in (mesh.triangles + 1).tolist())
    return [b"# translucency mesh, mm\n", vertices.encode("ascii"), faces.encode("ascii")]


def _vtk_bytes(mesh, suffix) -> list[bytes]:
    """VTK legacy (binary) or XML PolyData, by VTK's writers into memory; every point array is kept."""
    return [encode_polydata(to_pyvista(mesh), suffix)]
