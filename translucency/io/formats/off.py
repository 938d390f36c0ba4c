"""OFF (and COFF, NOFF, STOFF): our own reader; vertex colours, normals and texture coordinates are kept."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ...errors import MeshError
from ..triangulate import triangulate_polygons
from .common import set_colors

__all__ = ["read_off"]


def read_off(path: Path):
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
        set_colors(point_data, colors, path.name)
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
