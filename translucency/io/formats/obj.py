"""Wavefront OBJ: our own reader (vertex colours kept; vertices are not split at texture seams)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import MeshError
from ..triangulate import triangulate_polygons
from .common import as_rgb8

__all__ = ["read_obj"]


def read_obj(path: Path):
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
        point_data["colors"] = as_rgb8(values[:, 3:6])
    # OBJ indices start at 1; negative ones count back from the last vertex defined before the face
    before = np.repeat(np.asarray(vertices_before_face, dtype=np.int64), sizes)
    corners = np.where(corners > 0, corners - 1, np.where(corners < 0, before + corners, -(len(values) + 1)))
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    return values[:, :3], triangulate_polygons(offsets, corners), point_data
