"""Baked PLY files: the per-vertex result of a run, with every setting in the header, written atomically.

A bake is a binary little-endian PLY that MeshLab/pymeshlab, trimesh, plyfile, Open3D and PyVista
read (the colours all of them; the float properties plyfile, and trimesh in ``metadata["_ply_raw"]``;
``quality`` MeshLab/pymeshlab as the per-vertex quality). Its vertex element holds

================================ ========= ==========================================================
property                         type      meaning
================================ ========= ==========================================================
x y z                            float32   position, mm
nx ny nz                         float32   unit vertex normal (area-weighted, or the mesh's normals)
red green blue                   uchar     display colour (display transform already applied)
radiance_r radiance_g radiance_b float32   linear outgoing radiance toward the normal, L = T21 B,
                                           W/(m^2 sr) per W/m^2 of irradiance of the light
b_r b_g b_b                      float32   the view-independent factor B(x_o) of DESIGN.md, same unit
quality                          float32   Rec. 709 luminance of the radiance, same unit (when given;
                                           :func:`translucency.app.shading.result.write_result` always does)
================================ ========= ==========================================================

followed by a ``face`` element (``list uchar int vertex_indices``, triangles). The header carries
one ``comment`` line per setting, the units among them (``length_unit`` is the coordinates' unit,
always mm; ``source_unit`` and ``source_mm_per_unit`` are the scan file's)::

    comment translucency format = "translucency-bake"
    comment translucency material = "marble"
    comment translucency coefficients.sigma_a = [0.0021, 0.0041, 0.0071]
    comment translucency length_unit = "mm"
    comment translucency radiance_unit = "W/(m^2 sr) per W/m^2 of irradiance of the light"
    comment translucency source_unit = "m"
    comment translucency source_mm_per_unit = 1000.0

(``translucency <key> = <JSON value>``; nested dicts become dotted keys; a value too long for one
line of :data:`MAX_COMMENT_LINE` characters is written as compact JSON and continues on lines
``<key> += <more JSON text>``, which keeps every header line short for readers with fixed line
buffers). Floats are written with ``repr`` precision,
so :func:`read_baked_ply` returns the metadata exactly as given (tuples come back as lists).

The header is written by plyfile, from the record layout above. The file is
written by the atomic writer (:mod:`translucency.io.atomic`): to a temporary file in the
destination folder, flushed to disk, then renamed over the destination, so an existing bake is only
ever replaced by a complete one and a failed write leaves no partial file. Writing over the mesh's
own source file is refused.

The same settings travel in the other outputs (:mod:`translucency.io.baked_vtk`,
:mod:`translucency.io.baked_gltf`): :func:`complete_metadata` fills in what every output records,
:func:`check_bake_path` checks a destination, :func:`flat_metadata` flattens the settings into the
strings and numbers a VTK file's field data holds, :func:`json_metadata` turns them into JSON's types.
"""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InvalidParameterError, MeshError
from ..geometry.mesh import TriangleMesh
from .atomic import same_file, write_bytes
from .units import RADIANCE_UNIT, unit_metadata

__all__ = [
    "BAKED_FORMATS",
    "BakedPly",
    "check_bake_path",
    "complete_metadata",
    "flat_metadata",
    "json_metadata",
    "write_baked_ply",
    "read_baked_ply",
    "REQUIRED_METADATA",
    "MAX_COMMENT_LINE",
    "metadata_to_comments",
    "comments_to_metadata",
]

#: Settings every bake must record (DESIGN.md: every result carries its settings); the units
#: (:func:`~translucency.io.units.unit_metadata`: ``length_unit``, ``source_unit``, ...,
#: ``radiance_unit``) and ``version`` are filled in from the mesh and the package when absent.
REQUIRED_METADATA = ("material", "coefficients", "source_unit", "lights", "model", "method", "tolerance", "version")

#: The formats a result is written in, by the suffix of the output's name: PLY (this module),
#: VTK XML PolyData and legacy VTK (:mod:`translucency.io.baked_vtk`), binary and text glTF
#: (:mod:`translucency.io.baked_gltf`).
BAKED_FORMATS = ("ply", "vtp", "vtk", "glb", "gltf")

#: Longest header comment line written (unless a metadata key alone is longer); longer values
#: continue on "+=" lines, which keeps every line short for readers with fixed line buffers.
MAX_COMMENT_LINE = 200

_PREFIX = "translucency "
_KEY = re.compile(r"[A-Za-z0-9_\-]+")
FORMAT_NAME = "translucency-bake"
FORMAT_VERSION = 1

_VERTEX_DTYPE = np.dtype(
    [
        ("x", "<f4"), ("y", "<f4"), ("z", "<f4"),
        ("nx", "<f4"), ("ny", "<f4"), ("nz", "<f4"),
        ("red", "u1"), ("green", "u1"), ("blue", "u1"),
        ("radiance_r", "<f4"), ("radiance_g", "<f4"), ("radiance_b", "<f4"),
        ("b_r", "<f4"), ("b_g", "<f4"), ("b_b", "<f4"),
    ]
)  # fmt: skip
_QUALITY_DTYPE = np.dtype(_VERTEX_DTYPE.descr + [("quality", "<f4")])
_FACE_DTYPE = np.dtype([("count", "u1"), ("vertex_indices", "<i4", (3,))])


@dataclasses.dataclass(frozen=True, eq=False)
class BakedPly:
    """The content of a baked PLY, as :func:`read_baked_ply` returns it.

    Attributes
    ----------
    points : ndarray, shape (n, 3), float64
        Vertex positions, mm (stored float32).
    triangles : ndarray, shape (m, 3), int64
        Vertex indices of each triangle.
    normals : ndarray, shape (n, 3), float64
        Unit vertex normals (stored float32).
    colors_rgb8 : ndarray, shape (n, 3), uint8
        Display colours, sRGB after the exposure.
    radiance : ndarray, shape (n, 3), float64
        Linear radiance toward the normal, W/(m^2 sr) per W/m^2 of irradiance of the light (stored float32).
    b : ndarray, shape (n, 3), float64
        The view-independent factor B, same unit (stored float32).
    metadata : dict
        Every setting of the run, from the header's comments.
    comments : list of str
        The header's comment lines as written.
    quality : ndarray, shape (n,), float64, or None
        The Rec. 709 luminance of ``radiance``, same unit (stored float32); None in a file without it.
    """

    points: np.ndarray
    triangles: np.ndarray
    normals: np.ndarray
    colors_rgb8: np.ndarray
    radiance: np.ndarray
    b: np.ndarray
    metadata: dict
    comments: list
    quality: np.ndarray | None = None


# --------------------------------------------------------------------------------------------------
# metadata <-> header comments
# --------------------------------------------------------------------------------------------------
def _json_default(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Path):
        return str(value)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return dataclasses.asdict(value)
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def _flatten(metadata: dict, prefix: str = "") -> list[tuple[str, Any]]:
    items = []
    for key, value in metadata.items():
        key = str(key)
        if not _KEY.fullmatch(key):
            raise InvalidParameterError(
                f"metadata key {key!r} is not usable in a PLY header; use letters, digits, '_' and '-' only."
            )
        name = f"{prefix}{key}"
        if isinstance(value, dict) and value:
            items.extend(_flatten(value, name + "."))
        else:
            items.append((name, value))
    return items


def metadata_to_comments(metadata: dict) -> list[str]:
    """Header comment lines (without the word ``comment``) that encode a metadata dict.

    Parameters
    ----------
    metadata : dict
        JSON-serialisable values (numpy arrays and scalars, paths and dataclasses are converted);
        keys of letters, digits, ``_`` and ``-``.

    Returns
    -------
    list of str
        ASCII lines ``translucency <key> = <json>`` (and ``+=`` continuation lines).
    """
    lines = []
    for key, value in _flatten(metadata):
        try:
            lines.extend(_json_lines(key, value))
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError(
                f"metadata {key!r} cannot be written to the header ({exc}); pass numbers, strings, lists or dicts."
            ) from exc
    return lines


def _json_lines(key: str, value) -> list[str]:
    """The header lines of one metadata value: one readable line, or compact pieces cut anywhere.

    A value whose JSON text fits on one line of at most :data:`MAX_COMMENT_LINE` characters keeps
    its spaces (JSON text never starts or ends with one, so readers that strip header lines do not
    change it). A longer value is written without any whitespace (compact separators, spaces inside
    strings escaped as ``\\u0020``) and cut into ``+=`` pieces at fixed lengths.
    """
    head = f"{_PREFIX}{key} = "
    text = json.dumps(value, default=_json_default, ensure_ascii=True, allow_nan=True)
    if len(head) + len(text) <= MAX_COMMENT_LINE:
        return [head + text]
    compact = json.dumps(value, default=_json_default, ensure_ascii=True, allow_nan=True, separators=(",", ":"))
    compact = compact.replace(" ", "\\u0020")  # every space of compact JSON text is inside a string
    size = max(MAX_COMMENT_LINE - len(head) - 1, 40)
    pieces = [compact[i : i + size] for i in range(0, len(compact), size)]
    return [head + pieces[0]] + [f"{_PREFIX}{key} += {piece}" for piece in pieces[1:]]


def comments_to_metadata(comments: list[str]) -> dict:
    """Decode the metadata written by :func:`metadata_to_comments`; other comments are ignored.

    Parameters
    ----------
    comments : list of str
        Header comment texts (without the word ``comment``).

    Returns
    -------
    dict
        Nested dict of the decoded values.
    """
    texts: dict[str, str] = {}
    for comment in comments:
        comment = comment.strip()
        if not comment.startswith(_PREFIX):
            continue
        match = re.fullmatch(r"(\S+) (\+?=) (.*)", comment[len(_PREFIX) :])
        if match is None:
            continue
        key, operator, text = match.groups()
        if operator == "+=":
            texts[key] = texts.get(key, "") + text
        else:
            texts[key] = text
    metadata: dict = {}
    for key, text in texts.items():
        try:
            value = json.loads(text)
        except json.JSONDecodeError:
            value = text
        node = metadata
        parts = key.split(".")
        for part in parts[:-1]:
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                break
        else:
            node[parts[-1]] = value
    return metadata


def flat_metadata(metadata: dict) -> dict:
    """The settings as flat ``{key: value}`` with values a VTK file's field data holds: strings and numbers.

    Nested dicts become dotted keys (``coefficients.sigma_a``) and lists of dicts indexed ones
    (``lights.0.direction``); a number stays a number, a list of numbers a list of numbers, a list of
    strings a list of strings; ``True``/``False`` become ``"true"``/``"false"`` and ``None`` ``"none"``;
    anything else (an empty list, a mixed list) its JSON text.

    Parameters
    ----------
    metadata : dict
        As for :func:`metadata_to_comments`.

    Returns
    -------
    dict
        Keys in the order of ``metadata``.
    """
    flat: dict = {}
    for key, value in _flatten(json_metadata(metadata)):
        _flat_value(flat, key, value)
    return flat


def json_metadata(value):
    """``value`` with numpy values, paths and dataclasses turned into JSON's types (a JSON round trip)."""
    try:
        return json.loads(json.dumps(value, default=_json_default, allow_nan=True))
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(
            f"the metadata cannot be written ({exc}); pass numbers, strings, lists or dicts."
        ) from exc


def _flat_value(flat: dict, key: str, value) -> None:
    if isinstance(value, bool):
        flat[key] = "true" if value else "false"
    elif value is None:
        flat[key] = "none"
    elif isinstance(value, (int, float, str)):
        flat[key] = value
    elif isinstance(value, dict):  # an empty dict (_flatten opens the others)
        flat[key] = "{}"
    elif value and all(isinstance(v, dict) for v in value):
        for index, item in enumerate(value):
            for name, inner in _flatten(item, f"{key}.{index}."):
                _flat_value(flat, name, inner)
    elif value and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        flat[key] = [float(v) for v in value] if any(isinstance(v, float) for v in value) else list(value)
    elif value and all(isinstance(v, str) for v in value):
        flat[key] = list(value)
    else:
        flat[key] = json.dumps(value)


# --------------------------------------------------------------------------------------------------
# writing
# --------------------------------------------------------------------------------------------------
def check_bake_path(path, source=None) -> Path:
    """Check a destination of a bake before writing it; returns it as a Path.

    Parameters
    ----------
    path : str or path-like
        The output file; its folder must exist.
    source : path-like, optional
        The scan the values were computed on; the output may not be that file.

    Raises
    ------
    InvalidParameterError
        The scan itself, a missing folder, or a folder in place of the file.
    """
    path = Path(path)
    if source is not None and path.exists() and same_file(path, source):
        raise InvalidParameterError(
            f"{path} is the scan the mesh was read from; write the bake to another file (inputs are never modified)."
        )
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise InvalidParameterError(f"the folder {parent} does not exist; create it or choose another output path.")
    if path.is_dir():
        raise InvalidParameterError(f"{path} is a folder; pass a file name such as {path / ('bake' + path.suffix)}.")
    return path


def _per_vertex(name: str, values, n: int, dtype) -> np.ndarray:
    array = np.asarray(values)
    if array.shape != (n, 3):
        raise InvalidParameterError(
            f"{name} has shape {array.shape}; pass one row of 3 values (RGB) per vertex, shape ({n}, 3)."
        )
    if dtype == np.uint8:
        if array.dtype != np.uint8:
            if array.dtype.kind not in "iu" or array.min(initial=0) < 0 or array.max(initial=0) > 255:
                raise InvalidParameterError(
                    f"{name} must be 8-bit colours (uint8, 0-255), not {array.dtype}; apply the display "
                    "transform and convert first."
                )
            array = array.astype(np.uint8)
        return array
    array = array.astype(np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        as_stored = array.astype(np.float32)
    if not np.all(np.isfinite(as_stored)):
        bad = int(np.count_nonzero(~np.all(np.isfinite(as_stored), axis=1)))
        raise InvalidParameterError(
            f"{name} has {bad} vertices that are NaN, infinite or beyond float32 (3.4e38); nothing was written: a "
            "baked file holds finite values only."
        )
    return as_stored


def write_baked_ply(
    path, mesh: TriangleMesh, radiance, b, colors_rgb8, metadata: dict, *, normals=None, quality=None
) -> Path:
    """Write a baked PLY (binary little endian) atomically.

    Parameters
    ----------
    path : str or path-like
        Destination ``.ply``; its folder must exist. An existing file is replaced only once the new
        one is completely written.
    mesh : TriangleMesh
        The mesh the values belong to (points in mm are written as float32 mm).
    radiance : array_like, shape (n, 3)
        Linear outgoing radiance toward the normal, per vertex and RGB channel (the solver's unit,
        W/(m² sr) for irradiance given in W/m²).
    b : array_like, shape (n, 3)
        The diffuse radiance factor B(x_o) per vertex and channel (same unit as ``radiance``).
    colors_rgb8 : array_like of uint8, shape (n, 3)
        Display colours, display transform already applied.
    metadata : dict
        Every setting of the run: must contain :data:`REQUIRED_METADATA` (``unit`` and ``version``
        are filled in when absent); nested dicts allowed.
    normals : array_like, shape (n, 3), optional
        Vertex normals to write; default ``mesh.point_data["normals"]`` or the area-weighted normals.
    quality : array_like, shape (n,), optional
        The per-vertex ``quality`` MeshLab shows (the pipeline writes the Rec. 709 luminance of
        ``radiance``, :func:`translucency.app.display.luminance`); without it the property is absent.

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    InvalidParameterError
        Wrong shapes, non-finite values, missing settings, a missing folder, or a destination that
        is the mesh's source file.
    WriteError
        When the file cannot be written (permissions, disk full); nothing is left behind.
    """
    path = Path(path)
    if not isinstance(mesh, TriangleMesh):
        raise InvalidParameterError(f"write_baked_ply needs a TriangleMesh, not {type(mesh).__name__}.")
    n = mesh.n_points
    if mesh.n_points >= 2**31 or mesh.n_triangles >= 2**31:
        raise InvalidParameterError("the mesh is too large for a PLY with 32-bit indices; decimate it first.")
    check_bake_path(path, mesh.source)

    radiance = _per_vertex("radiance", radiance, n, np.float32)
    b = _per_vertex("b", b, n, np.float32)
    colors = _per_vertex("colors_rgb8", colors_rgb8, n, np.uint8)
    if normals is None:
        normals = mesh.point_data["normals"] if "normals" in mesh.point_data else mesh.vertex_normals()
    normals = _per_vertex("normals", normals, n, np.float32)
    if quality is not None:
        quality = _per_vertex("quality", np.repeat(np.reshape(quality, (-1, 1)), 3, axis=1), n, np.float32)[:, 0]
    points = mesh.points.astype(np.float32)
    if not np.all(np.isfinite(points)):
        raise InvalidParameterError("the mesh coordinates overflow float32; scale the mesh to mm before baking.")

    settings = complete_metadata(metadata, mesh)
    comments = [f"{_PREFIX}format = {json.dumps(FORMAT_NAME)}", f"{_PREFIX}format_version = {FORMAT_VERSION}"]
    comments += metadata_to_comments(settings)

    vertices = np.empty(n, dtype=_VERTEX_DTYPE if quality is None else _QUALITY_DTYPE)
    for i, axis in enumerate("xyz"):
        vertices[axis] = points[:, i]
        vertices["n" + axis] = normals[:, i]
    for i, (channel, colour) in enumerate(zip("rgb", ("red", "green", "blue"))):
        vertices[colour] = colors[:, i]
        vertices["radiance_" + channel] = radiance[:, i]
        vertices["b_" + channel] = b[:, i]
    if quality is not None:
        vertices["quality"] = quality
    faces = np.empty(mesh.n_triangles, dtype=_FACE_DTYPE)
    faces["count"] = 3
    faces["vertex_indices"] = mesh.triangles.astype(np.int32)

    write_bytes(path, [_ply_header(vertices, faces, comments), vertices, faces])  # the records without a copy
    return path


def _ply_header(vertices: np.ndarray, faces: np.ndarray, comments: list[str]) -> bytes:
    """The PLY header of a bake, written by plyfile for these vertex and face records.

    plyfile declares the elements and checks the comments; the records are written as whole arrays,
    the same bytes plyfile's own writer gives (which writes list properties one face at a time).
    """
    import plyfile

    elements = [
        plyfile.PlyElement.describe(vertices, "vertex"),
        plyfile.PlyElement("face", [plyfile.PlyListProperty("vertex_indices", "uchar", "int")], len(faces)),
    ]
    ply = plyfile.PlyData(elements, text=False, byte_order="<", comments=comments)
    return (ply.header + "\n").encode("ascii")


def complete_metadata(metadata, mesh: TriangleMesh) -> dict:
    """The settings of a bake with what every output records filled in where absent: the units
    (:func:`~translucency.io.units.unit_metadata` of the mesh and ``radiance_unit``), ``version`` and
    ``source`` (the scan's file name).

    Raises
    ------
    InvalidParameterError
        ``metadata`` not a dict, or lacking one of :data:`REQUIRED_METADATA`.
    """
    if not isinstance(metadata, dict):
        raise InvalidParameterError(f"metadata must be a dict of settings, not {type(metadata).__name__}.")
    settings = dict(metadata)
    for key, value in unit_metadata(mesh.mm_per_unit, mesh.unit_inferred).items():
        settings.setdefault(key, value)
    settings.setdefault("radiance_unit", RADIANCE_UNIT)
    if "version" not in settings:
        from .. import __version__

        settings["version"] = __version__
    missing = [key for key in REQUIRED_METADATA if key not in settings]
    if missing:
        raise InvalidParameterError(
            f"the bake's metadata lacks {', '.join(missing)}; pass every setting of the run "
            f"({', '.join(REQUIRED_METADATA)})."
        )
    settings.setdefault("source", mesh.source.name if mesh.source is not None else None)
    return settings


# --------------------------------------------------------------------------------------------------
# reading
# --------------------------------------------------------------------------------------------------
def read_baked_ply(path) -> BakedPly:
    """Read a bake written by :func:`write_baked_ply`.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    BakedPly
        Arrays (float64 from the stored float32) and the decoded metadata.

    Raises
    ------
    MeshError
        When the file is not a readable PLY or lacks the bake's properties.
    """
    from .formats.ply import PlyHeader
    from .load import read_mesh_arrays

    path = Path(path)
    points, triangles, point_data = read_mesh_arrays(path, format="ply")
    comments = PlyHeader(path).comments
    needed = [f"{prefix}_{c}" for prefix in ("radiance", "b") for c in "rgb"]
    missing = [name for name in needed if name not in point_data]
    if missing or "colors" not in point_data or "normals" not in point_data:
        raise MeshError(
            f"{path.name} is not a translucency bake (it lacks {', '.join(missing) or 'colours or normals'}); "
            "bake the mesh first."
        )
    stack = lambda prefix: np.stack([np.asarray(point_data[f"{prefix}_{c}"], dtype=np.float64) for c in "rgb"], axis=1)  # noqa: E731
    return BakedPly(
        points=points,
        triangles=triangles,
        normals=np.asarray(point_data["normals"], dtype=np.float64),
        colors_rgb8=np.asarray(point_data["colors"])[:, :3],
        radiance=stack("radiance"),
        b=stack("b"),
        metadata=comments_to_metadata(comments),
        comments=comments,
        quality=np.asarray(point_data["quality"], dtype=np.float64) if "quality" in point_data else None,
    )
