"""Read mesh files of every common format into a :class:`~translucency.geometry.mesh.TriangleMesh` in mm.

=========================== ====================================================================
format                      reader
=========================== ====================================================================
PLY (ascii, binary LE/BE)   plyfile, with fast paths for triangle lists; ``face`` polygons and
                            ``tristrips`` strips; every vertex property is kept
OFF (and COFF, NOFF, STOFF) translucency's own reader (vertex colours and normals are kept)
OBJ                         translucency's own reader (vertex colours kept; vertices are not
                            split at texture seams, unlike VTK's OBJ reader)
STL, VTK, VTP, VTU, VTM,    VTK's readers (point arrays are kept; colours as ``"colors"``)
BYU (.g), glTF, VTK HDF
3DS, DAE, WRL, X3D, CTM,    pymeshlab (vertex colours and quality are kept); note that pymeshlab
GTS, PTX, VMI, ...          drops invalid faces and vertices itself instead of reporting them
=========================== ====================================================================

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
import stat
import warnings
from pathlib import Path

import numpy as np

from ..errors import MeshError
from ..geometry.mesh import TriangleMesh, validate_mesh_arrays
from .triangulate import triangulate_polygon_lists, triangulate_polygons, triangulate_strips
from .units import UnitInferredWarning, check_extent, infer_unit, inferred_unit_message, parse_unit

__all__ = ["load_mesh", "read_mesh_arrays", "mesh_from_vtk_polydata", "SUPPORTED_FORMATS", "detect_format"]

_VTK_FORMATS = {
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

_PYMESHLAB_FORMATS = {
    ".3ds": "3D Studio",
    ".dae": "Collada",
    ".wrl": "VRML",
    ".x3d": "X3D",
    ".x3dv": "X3D (VRML encoding)",
    ".ctm": "OpenCTM",
    ".gts": "GNU Triangulated Surface",
    ".ptx": "Leica PTX",
    ".vmi": "VCG mesh image",
    ".qobj": "quad OBJ",
    ".tri": "TRI",
    ".asc": "ASCII points",
    ".xyz": "XYZ points",
    ".pts": "points",
    ".apts": "points",
    ".nvm": "NVM",
    ".out": "Bundler",
    ".e57": "E57",
}

#: File suffixes that :func:`load_mesh` reads, with a description.
SUPPORTED_FORMATS: dict[str, str] = {
    ".ply": "Stanford PLY (ascii or binary, triangles, polygons or triangle strips)",
    ".off": "Object File Format (OFF, COFF, NOFF, STOFF)",
    ".obj": "Wavefront OBJ (vertex colours kept)",
    **{suffix: name for suffix, (_, _, name) in _VTK_FORMATS.items()},
    **_PYMESHLAB_FORMATS,
}

_COMMON_FORMATS = ".ply, .obj, .stl, .off, .vtk, .vtp"

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
    mm_per_unit = None if unit is None else parse_unit(unit)
    path = Path(path)
    points, triangles, point_data = read_mesh_arrays(path, format=format)
    if mm_per_unit is None:
        extent_in_file = _extent(points, triangles)
        inferred = infer_unit(extent_in_file, path.name)
        warnings.warn(inferred_unit_message(path.name, extent_in_file, inferred), UnitInferredWarning, stacklevel=2)
        mm_per_unit = parse_unit(inferred)
    points = points * mm_per_unit
    if not np.isfinite(points).all():
        raise MeshError(
            f"{path.name} has coordinates too large to convert to mm; check the file's unit and coordinates."
        )
    check_extent(_extent(points, triangles), mm_per_unit, path.name, stacklevel=2)
    return TriangleMesh(points, triangles, point_data, source=path, mm_per_unit=mm_per_unit,
                        unit_inferred=unit is None)


def _extent(points: np.ndarray, triangles: np.ndarray) -> float:
    """Largest side of the bounding box of the vertices the triangles use (in the points' unit)."""
    referenced = np.zeros(len(points), dtype=bool)
    referenced[triangles.ravel()] = True
    used = points[referenced]
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
            points, triangles, point_data = _read_ply(path)
        elif suffix == ".off":
            points, triangles, point_data = _read_off(path)
        elif suffix == ".obj":
            points, triangles, point_data = _read_obj(path)
        elif suffix in _VTK_FORMATS:
            points, triangles, point_data = _read_with_vtk(path, suffix)
        else:
            points, triangles, point_data = _read_with_pymeshlab(path, suffix)
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


def _misnamed(path: Path, suffix: str, sniffed: str) -> str:
    expected = SUPPORTED_FORMATS[suffix].split(" (")[0]
    return (
        f"{path.name} does not hold {expected} data but {sniffed[1:].upper()} data; "
        f"rename it to {path.stem}{sniffed} or pass format={sniffed[1:]!r}."
    )


# --------------------------------------------------------------------------------------------------
# file checks
# --------------------------------------------------------------------------------------------------
def _special_kind(mode: int) -> str:
    """What a file that is not a regular file is, in words ("a FIFO (named pipe)", ...)."""
    for test, words in ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
                        (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return words
    return "a special file"


def _check_readable(path: Path, format: str | None) -> str:
    """Check that the file exists and can be read, and return the suffix of the format to read it as."""
    try:
        mode = os.stat(path).st_mode  # follows links: what would be opened
    except FileNotFoundError:
        mode = None
    except OSError as exc:
        raise MeshError(f"{path.name} cannot be read ({exc.strerror or exc}); check the file and the disk.") from None
    if mode is None:
        raise MeshError(f"{path} does not exist; check the path and the file name.")
    if stat.S_ISDIR(mode):
        raise MeshError(f"{path} is a directory, not a mesh file; pass the path of a mesh file inside it.")
    if not stat.S_ISREG(mode):  # opening a FIFO would wait for a writer, a device would read forever
        raise MeshError(f"{path} is {_special_kind(mode)}, not a regular file; pass a mesh file stored on disk.")
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
                f" (its content looks like {sniffed[1:].upper()}: rename it to {path.stem}{sniffed} or pass format={sniffed[1:]!r})"
                if sniffed
                else ""
            )
            raise MeshError(
                f"{path.name} has an unknown mesh format {repr(suffix) if suffix else '(no extension)'}{hint}; "
                f"use a supported one ({_COMMON_FORMATS} or another of translucency.io.SUPPORTED_FORMATS)."
            )
    if not first:
        raise MeshError(f"{path.name} is empty (0 bytes); export the mesh again.")
    return suffix


# --------------------------------------------------------------------------------------------------
# PLY
# --------------------------------------------------------------------------------------------------
_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}  # fmt: skip


class PlyHeader:
    """The parts of a PLY header the reader needs: format, elements and their properties."""

    def __init__(self, path: Path):
        with open(path, "rb") as stream:
            head = stream.read(1 << 20)
            stream.seek(0, os.SEEK_END)
            self.file_size = stream.tell()
        if not (head.startswith(b"ply\n") or head.startswith(b"ply\r\n")):
            raise MeshError(f"{path.name} is not a PLY file (it does not start with 'ply'); check the file's format.")
        end = re.search(rb"end_header[ \t]*\r?\n", head)
        if end is None:
            raise MeshError(
                f"{path.name} has a corrupt or truncated PLY header (no 'end_header' line); export the mesh again."
            )
        self.size = end.end()
        self.format = None
        self.elements: list[tuple[str, int, list[tuple[str, str | None, str]]]] = []
        self.comments: list[str] = []
        for raw in head[: end.start()].decode("ascii", errors="replace").splitlines()[1:]:
            words = raw.split()
            if not words or words[0] in ("obj_info",):
                continue
            try:
                if words[0] == "comment":
                    self.comments.append(raw.split("comment", 1)[1].strip())
                elif words[0] == "format":
                    self.format = words[1]
                elif words[0] == "element":
                    self.elements.append((words[1], int(words[2]), []))
                elif words[0] == "property" and words[1] == "list":
                    self.elements[-1][2].append((words[4], _PLY_TYPES[words[2]], _PLY_TYPES[words[3]]))
                elif words[0] == "property":
                    self.elements[-1][2].append((words[2], None, _PLY_TYPES[words[1]]))
                else:
                    raise ValueError(raw)
            except (IndexError, KeyError, ValueError):
                raise MeshError(
                    f"{path.name} has a corrupt PLY header (line {raw.strip()[:60]!r}); export the mesh again."
                ) from None
        if self.format not in ("ascii", "binary_little_endian", "binary_big_endian"):
            raise MeshError(f"{path.name} has a corrupt PLY header (format {self.format!r}); export the mesh again.")
        for name, count, _ in self.elements:
            if count < 0:
                raise MeshError(
                    f"{path.name} has a corrupt PLY header ({count} {name} elements); export the mesh again."
                )

    def minimum_body_size(self) -> int:
        """Smallest number of bytes the body can have for the announced element counts."""
        total = 0
        for _, count, properties in self.elements:
            if self.format == "ascii":
                total += count * len(properties)  # at least one character per value
            else:
                total += count * sum(np.dtype(length or value).itemsize for _, length, value in properties)
        return total

    def element(self, name: str):
        for element in self.elements:
            if element[0] == name:
                return element
        return None


def _read_ply(path: Path):
    import plyfile

    header = PlyHeader(path)
    body = header.file_size - header.size
    needed = header.minimum_body_size()
    if body < needed:
        counts = " and ".join(f"{count} '{name}'" for name, count, _ in header.elements) + " elements"
        raise MeshError(
            f"{path.name} is truncated: its header announces {counts}, which need at least {needed} bytes, "
            f"but only {body} follow the header; download or export the file again."
        )
    vertex = header.element("vertex")
    if vertex is None:
        raise MeshError(f"{path.name} has no 'vertex' element; it is not a mesh PLY file.")
    names = [p[0] for p in vertex[2]]
    if not {"x", "y", "z"} <= set(names):
        raise MeshError(f"{path.name} has vertices without x, y, z properties; it is not a mesh PLY file.")

    data = _read_ply_ascii_fast(path, header) if header.format == "ascii" else None
    if data is None:
        data = _read_ply_with_plyfile(path, header, plyfile)
    vertex_data, polygons, strips = data

    points = np.stack([np.asarray(vertex_data[k], dtype=np.float64) for k in ("x", "y", "z")], axis=1)
    triangles = [polygons] if polygons is not None else []
    if strips is not None:
        triangles.append(strips)
    triangles = np.concatenate(triangles) if triangles else np.empty((0, 3), np.int64)
    point_data = _ply_point_data(vertex_data, [p for p in vertex[2] if p[1] is None])
    return points, triangles, point_data


def _face_list_property(header: PlyHeader):
    """The (element name, list property name) of the polygons, if any."""
    for name in ("face", "faces", "polygon"):
        element = header.element(name)
        if element is None:
            continue
        lists = [p[0] for p in element[2] if p[1] is not None]
        for preferred in ("vertex_indices", "vertex_index"):
            if preferred in lists:
                return name, preferred
        if lists:
            return name, lists[0]
    return None


def _read_ply_with_plyfile(path: Path, header: PlyHeader, plyfile):
    face = _face_list_property(header)
    errors = (plyfile.PlyParseError, ValueError, TypeError, IndexError, EOFError, UnicodeDecodeError, MemoryError,
              OverflowError)  # OverflowError: an ascii list length beyond its count type (300 for uchar)
    ply = None
    if face is not None and header.format != "ascii":
        for corners in (3, 4):  # fast paths: all triangles or all quads, read as one record array
            try:
                ply = plyfile.PlyData.read(str(path), mmap="c", known_list_len={face[0]: {face[1]: corners}})
                break
            except errors:
                ply = None
    if ply is None:
        try:
            with warnings.catch_warnings():  # numpy's loadtxt warns about every empty ascii list (a face "0")
                warnings.simplefilter("ignore")
                ply = plyfile.PlyData.read(str(path), mmap="c")
        except errors as exc:
            raise MeshError(
                f"{path.name} is corrupt or truncated ({_short(exc)}); download or export the file again."
            ) from exc
    vertex_data = {
        p.name: np.array(ply["vertex"].data[p.name]) for p in ply["vertex"].properties if not hasattr(p, "len_dtype")
    }
    polygons = None
    if face is not None:
        lists = ply[face[0]].data[face[1]]
        if lists.dtype != object:  # fixed-length lists of the fast path
            lists = np.asarray(lists, dtype=np.int64)
            polygons = triangulate_polygons(np.arange(len(lists) + 1) * lists.shape[1], lists.ravel())
        else:
            polygons = triangulate_polygon_lists(lists)
    strips = None
    if header.element("tristrips") is not None:
        element = ply["tristrips"]
        prop = next((p.name for p in element.properties if hasattr(p, "len_dtype")), None)
        if prop is not None and element.count:
            lists = list(element.data[prop])
            sizes = np.array([len(s) for s in lists], dtype=np.int64)
            offsets = np.concatenate([[0], np.cumsum(sizes)])
            strips = triangulate_strips(np.concatenate(lists), offsets)
    return vertex_data, polygons, strips


def _read_ply_ascii_fast(path: Path, header: PlyHeader):
    """Read an ascii PLY of one scalar vertex element and one triangle face element with numpy; None if not that."""
    face = _face_list_property(header)
    if face is None or len(header.elements) != 2 or header.elements[0][0] != "vertex":
        return None
    vertex_name, n_vertices, vertex_props = header.elements[0]
    face_name, n_faces, face_props = header.elements[1]
    if any(p[1] is not None for p in vertex_props) or len(face_props) != 1 or face_name != face[0]:
        return None
    with open(path, "rb") as stream:
        stream.seek(header.size)
        body = stream.read()
    tokens = body.split()
    n_vertex_values = n_vertices * len(vertex_props)
    if len(tokens) != n_vertex_values + 4 * n_faces:
        return None  # polygons, or a damaged file: plyfile reads it or says what is wrong
    try:
        values = np.array(tokens[:n_vertex_values], dtype=np.float64).reshape(n_vertices, len(vertex_props))
        faces = np.array(tokens[n_vertex_values:], dtype=np.int64).reshape(n_faces, 4)
    except ValueError:
        return None
    if n_faces and not np.all(faces[:, 0] == 3):
        return None
    vertex_data = {name: values[:, i].astype(dtype) for i, (name, _, dtype) in enumerate(vertex_props)}
    return vertex_data, faces[:, 1:].copy(), None


def _ply_point_data(vertex_data: dict, properties) -> dict[str, np.ndarray]:
    """Per-vertex properties other than x, y, z; colours as uint8 "colors", normals as "normals"."""
    native = {
        name: np.asarray(values).astype(np.asarray(values).dtype.newbyteorder("="), copy=False)
        for name, values in vertex_data.items()
    }
    point_data: dict[str, np.ndarray] = {}
    used = {"x", "y", "z"}
    for prefix in ("", "diffuse_"):
        keys = [prefix + c for c in ("red", "green", "blue")]
        if all(k in native for k in keys) and "colors" not in point_data:
            channels = keys + ([prefix + "alpha"] if prefix + "alpha" in native else [])
            point_data["colors"] = _as_rgb8(np.stack([native[k] for k in channels], axis=1))
            used.update(channels)
    if all(k in native for k in ("nx", "ny", "nz")):
        point_data["normals"] = np.stack([native[k] for k in ("nx", "ny", "nz")], axis=1).astype(np.float64)
        used.update(("nx", "ny", "nz"))
    for name, _, _ in properties:
        if name not in used and name in native:
            point_data[name] = native[name]
    return point_data


def _as_rgb8(colors: np.ndarray) -> np.ndarray:
    """Colours as uint8; float colours in [0, 1] are scaled by 255."""
    if colors.dtype == np.uint8:
        return colors
    colors = colors.astype(np.float64)
    if colors.size and np.nanmax(colors) <= 1.0:
        colors = colors * 255.0
    return np.clip(np.round(np.nan_to_num(colors)), 0, 255).astype(np.uint8)


# --------------------------------------------------------------------------------------------------
# OFF
# --------------------------------------------------------------------------------------------------
def _read_off(path: Path):
    with open(path, "rb") as stream:
        raw = stream.read()
    text = raw.decode("latin-1")
    lines = [line.split("#", 1)[0].split() for line in text.splitlines()]
    lines = [words for words in lines if words]
    if not lines:
        raise MeshError(f"{path.name} holds no OFF data; export the mesh again.")
    keyword = lines[0][0]
    match = re.fullmatch(r"(ST)?(C)?(N)?(4)?(n)?OFF", keyword)
    if match is None:
        raise MeshError(
            f"{path.name} is not an OFF file (it starts with {keyword[:20]!r}, not 'OFF'); check the file's format."
        )
    if match.group(4) or match.group(5):
        raise MeshError(f"{path.name} is a {keyword} file (not 3D coordinates); convert it to a 3D OFF or PLY file.")
    rest = lines[0][1:]
    if rest and rest[0].upper() == "BINARY":
        raise MeshError(
            f"{path.name} is a binary OFF file, which is not supported; convert it to PLY (for example with MeshLab)."
        )
    body = lines[1:]
    if not rest:
        if not body:
            raise MeshError(f"{path.name} is truncated (no vertex and face counts after 'OFF'); export the mesh again.")
        rest, body = body[0], body[1:]
    try:
        n_vertices, n_faces = int(rest[0]), int(rest[1])
    except (IndexError, ValueError):
        raise MeshError(
            f"{path.name} has a corrupt OFF header (counts {' '.join(rest)[:40]!r}); export the mesh again."
        ) from None
    if n_vertices < 0 or n_faces < 0:
        raise MeshError(f"{path.name} has a corrupt OFF header (negative counts); export the mesh again.")
    if len(body) < n_vertices + n_faces:
        raise MeshError(
            f"{path.name} is truncated: it announces {n_vertices} vertices and {n_faces} faces but has only "
            f"{len(body)} data lines; export the mesh again."
        )
    vertex_lines = body[:n_vertices]
    width = min(len(words) for words in vertex_lines) if vertex_lines else 3
    try:
        values = np.array([words[:width] for words in vertex_lines], dtype=np.float64)
    except ValueError:
        raise MeshError(
            f"{path.name} has vertex lines that are not numbers; the file is corrupt, export it again."
        ) from None
    if width < 3:
        raise MeshError(
            f"{path.name} has vertex lines with fewer than 3 coordinates; the file is corrupt, export it again."
        )
    points = values[:, :3]
    point_data: dict[str, np.ndarray] = {}
    column = 3
    if match.group(3) and width >= column + 3:
        point_data["normals"] = values[:, column : column + 3]
        column += 3
    if match.group(2) and width >= column + 3:
        n_channels = 4 if width >= column + 4 else 3
        colors = values[:, column : column + n_channels]
        point_data["colors"] = (
            _as_rgb8(colors) if colors.max(initial=0) <= 1.0 else np.clip(np.round(colors), 0, 255).astype(np.uint8)
        )
        column += n_channels
    if match.group(1) and width >= column + 2:
        point_data["texture_coordinates"] = values[:, column : column + 2]
    try:
        face_lines = body[n_vertices : n_vertices + n_faces]
        sizes = np.array([int(words[0]) for words in face_lines], dtype=np.int64)
        if np.any(sizes < 0) or any(len(words) < 1 + k for words, k in zip(face_lines, sizes)):
            raise ValueError("face lines shorter than their counts")
        connectivity = np.array(
            [int(i) for words, k in zip(face_lines, sizes) for i in words[1 : 1 + k]], dtype=np.int64
        )
    except ValueError:
        raise MeshError(f"{path.name} has corrupt face lines; export the mesh again.") from None
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    return points, triangulate_polygons(offsets, connectivity), point_data


# --------------------------------------------------------------------------------------------------
# OBJ
# --------------------------------------------------------------------------------------------------
def _read_obj(path: Path):
    """Vertices (``v x y z [r g b]``) and faces (``f a b c ...``, ``a/t/n`` forms, negative = relative).

    Texture coordinates and normals are per face corner in OBJ, not per vertex, so they are not
    kept; vertices are never split at texture seams (VTK's OBJ reader does split them).
    """
    text = path.read_bytes().decode("latin-1")
    vertex_rows: list[list[str]] = []
    face_rows: list[list[str]] = []
    vertices_before_face: list[int] = []
    for line in text.splitlines():
        line = line.strip()
        if line.startswith(("v ", "v\t")):
            vertex_rows.append(line[2:].split())
        elif line.startswith(("f ", "f\t")):
            face_rows.append(line[2:].split())
            vertices_before_face.append(len(vertex_rows))
    if not vertex_rows:
        raise MeshError(f"{path.name} has no vertex ('v') lines; it is not a mesh OBJ file, export the mesh again.")
    width = min(len(row) for row in vertex_rows)
    if width < 3:
        raise MeshError(
            f"{path.name} has vertex lines with fewer than 3 coordinates; the file is corrupt, export it again."
        )
    try:
        values = np.array([row[:width] for row in vertex_rows], dtype=np.float64)
        sizes = np.array([len(row) for row in face_rows], dtype=np.int64)
        corners = np.array([int(token.split("/", 1)[0]) for row in face_rows for token in row], dtype=np.int64)
    except ValueError:
        raise MeshError(
            f"{path.name} has vertex or face lines that are not numbers; the file is corrupt, export it again."
        ) from None
    point_data: dict[str, np.ndarray] = {}
    if width >= 6:  # v x y z r g b
        point_data["colors"] = _as_rgb8(values[:, 3:6])
    # OBJ indices start at 1; negative ones count back from the last vertex defined before the face
    before = np.repeat(np.asarray(vertices_before_face, dtype=np.int64), sizes)
    corners = np.where(corners > 0, corners - 1, np.where(corners < 0, before + corners, -(len(values) + 1)))
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    return values[:, :3], triangulate_polygons(offsets, corners), point_data


# --------------------------------------------------------------------------------------------------
# VTK readers (STL, VTK, VTP, ...)
# --------------------------------------------------------------------------------------------------
def _check_binary_stl(path: Path) -> None:
    """Refuse a binary STL shorter than its header's triangle count says.

    VTK's reader reads whatever whole 50-byte records follow the header, so a file cut at a record
    boundary would silently lose triangles. ASCII STL (text starting with ``solid``) is left to VTK.
    """
    with open(path, "rb") as stream:
        head = stream.read(512)
        stream.seek(0, os.SEEK_END)
        size = stream.tell()
    text = head.lstrip()
    if size < 84 or (text.startswith(b"solid") and all(32 <= c < 127 or c in b"\t\r\n" for c in text)):
        return
    count = int.from_bytes(head[80:84], "little")
    needed = 84 + 50 * count
    if size < needed:
        raise MeshError(
            f"{path.name} is truncated: its header announces {count} triangles, which need {needed} bytes, "
            f"but the file has {size}; download or export the file again."
        )


def _read_with_vtk(path: Path, suffix: str):
    import importlib

    import pyvista

    if suffix == ".stl":
        _check_binary_stl(path)
    module, class_name, description = _VTK_FORMATS[suffix]
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
    if not isinstance(data, pyvista.PolyData):
        from vtkmodules.vtkFiltersGeometry import vtkDataSetSurfaceFilter

        surface = vtkDataSetSurfaceFilter()
        surface.SetInputData(data)
        surface.Update()
        data = pyvista.wrap(surface.GetOutput())
    return mesh_from_vtk_polydata(data, what=path.name)


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
        key = name
        if name.lower() in ("rgb", "rgba", "colors", "colours") and values.ndim == 2 and values.shape[1] in (3, 4):
            key, values = "colors", _as_rgb8(values)
        elif name.lower() == "normals" and values.ndim == 2 and values.shape[1] == 3:
            key = "normals"
        point_data[key] = values
    return points, triangles, point_data


# --------------------------------------------------------------------------------------------------
# pymeshlab (everything else)
# --------------------------------------------------------------------------------------------------
def _read_with_pymeshlab(path: Path, suffix: str):
    from ._pymeshlab import import_pymeshlab

    pymeshlab = import_pymeshlab()
    mesh_set = pymeshlab.MeshSet()
    try:
        mesh_set.load_new_mesh(str(path))
    except pymeshlab.PyMeshLabException as exc:
        raise MeshError(
            f"{path.name} is not a readable {SUPPORTED_FORMATS[suffix]} file ({_short(exc)}); check or export the file again."
        ) from exc
    mesh = mesh_set.current_mesh()
    points = np.array(mesh.vertex_matrix(), dtype=np.float64).reshape(-1, 3)
    triangles = np.array(mesh.face_matrix(), dtype=np.int64).reshape(-1, 3)
    point_data: dict[str, np.ndarray] = {}
    if mesh.has_vertex_color():
        point_data["colors"] = _as_rgb8(np.array(mesh.vertex_color_matrix()))
    if mesh.has_vertex_scalar():
        point_data["quality"] = np.array(mesh.vertex_scalar_array(), dtype=np.float64)
    return points, triangles, point_data


def _short(exc: BaseException) -> str:
    """First line of an exception's message, shortened, for inclusion in a sentence."""
    text = " ".join(str(exc).split())
    return (text[:117] + "...") if len(text) > 120 else (text or type(exc).__name__)
