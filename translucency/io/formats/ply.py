"""PLY (ascii, binary little and big endian): its header, read by our own parser, and the reader.

The header is parsed here (format, elements, properties, comments) so that a truncated or corrupt
file is reported in one sentence before plyfile reads the body; ascii files of one vertex element
and one triangle element are read with numpy, everything else with plyfile (fast paths for all
triangles or all quads). ``face`` polygons are fan-triangulated, ``tristrips`` unrolled; every
scalar vertex property is kept (colours as uint8 ``"colors"``, normals as ``"normals"``).
"""

from __future__ import annotations

import os
import re
import warnings
from pathlib import Path

import numpy as np

from ...errors import MeshError
from ..triangulate import triangulate_polygon_lists, triangulate_polygons, triangulate_strips
from .common import set_colors, short_reason

__all__ = ["PlyHeader", "read_ply"]

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


def read_ply(path: Path):
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
    point_data = _ply_point_data(vertex_data, [p for p in vertex[2] if p[1] is None], path.name)
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
    errors = (
        plyfile.PlyParseError,
        ValueError,
        TypeError,
        IndexError,
        EOFError,
        UnicodeDecodeError,
        MemoryError,
        OverflowError,
    )  # OverflowError: an ascii list length beyond its count type (300 for uchar)
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
                f"{path.name} is corrupt or truncated ({short_reason(exc)}); download or export the file again."
            ) from exc
    vertex_data = {  # x, y, z as views: the points are stacked from them in one copy
        p.name: ply["vertex"].data[p.name] if p.name in ("x", "y", "z") else np.array(ply["vertex"].data[p.name])
        for p in ply["vertex"].properties
        if not hasattr(p, "len_dtype")
    }
    polygons = None
    if face is not None:
        lists = ply[face[0]].data[face[1]]
        if lists.dtype != object and lists.shape[1:] == (3,):  # all triangles: widened to int64 in one copy
            polygons = np.array(lists, dtype=np.int64, order="C")
        elif lists.dtype != object:  # fixed-length lists of the fast path
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


def _ply_point_data(vertex_data: dict, properties, file_name: str) -> dict[str, np.ndarray]:
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
            set_colors(point_data, np.stack([native[k] for k in channels], axis=1), file_name)
            used.update(channels)
    if all(k in native for k in ("nx", "ny", "nz")):
        point_data["normals"] = np.stack([native[k] for k in ("nx", "ny", "nz")], axis=1).astype(np.float64)
        used.update(("nx", "ny", "nz"))
    for name, _, _ in properties:
        if name not in used and name in native:
            point_data[name] = native[name]
    return point_data
