"""Wavefront OBJ: our own reader (vertex colours kept, or the texture sampled at the vertices; vertices are
not split at texture seams)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import MeshError
from ..triangulate import triangulate_polygons
from .common import set_colors

__all__ = ["read_obj"]


def read_obj(path: Path):
    """Vertices (``v x y z [r g b]``) and faces (``f a b c ...``, ``a/t/n`` forms, negative = relative).

    Texture coordinates and normals are per face corner in OBJ, not per vertex, so they are not
    kept; vertices are never split at texture seams (VTK's OBJ reader does split them). A file without
    vertex colours whose material library names a diffuse texture (``map_Kd``) gets the texture sampled at
    its vertices as ``colors`` (:mod:`translucency.io.texture`).
    """
    text = path.read_bytes().decode("latin-1")
    vertex_rows: list[list[str]] = []
    uv_rows: list[list[str]] = []
    libraries: list[str] = []
    face_rows: list[list[str]] = []
    vertices_before_face: list[int] = []
    uvs_before_face: list[int] = []
    for line in text.splitlines():
        line = line.strip()
        if line.startswith(("v ", "v\t")):
            vertex_rows.append(line[2:].split())
        elif line.startswith(("vt ", "vt\t")):
            uv_rows.append(line[3:].split()[:2])
        elif line.startswith("mtllib"):
            libraries.append(line[6:].strip())
        elif line.startswith(("f ", "f\t")):
            face_rows.append(line[2:].split())
            vertices_before_face.append(len(vertex_rows))
            uvs_before_face.append(len(uv_rows))
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
        set_colors(point_data, values[:, 3:6], path.name)
    # OBJ indices start at 1; negative ones count back from the last vertex defined before the face
    before = np.repeat(np.asarray(vertices_before_face, dtype=np.int64), sizes)
    corners = np.where(corners > 0, corners - 1, np.where(corners < 0, before + corners, -(len(values) + 1)))
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    if "colors" not in point_data and uv_rows:
        texture = _diffuse_texture(path, libraries)
        if texture is not None:
            uv_before = np.repeat(np.asarray(uvs_before_face, dtype=np.int64), sizes)
            colors = _texture_colors(path, texture, uv_rows, face_rows, uv_before, corners, len(values))
            if colors is not None:
                point_data["colors"] = colors
    return values[:, :3], triangulate_polygons(offsets, corners), point_data


def _diffuse_texture(path: Path, libraries: list[str]):
    """The first diffuse texture (``map_Kd``) named by the file's material libraries that exists, or None."""
    for library in libraries:
        mtl = path.parent / library
        if not mtl.is_file():
            continue
        for line in mtl.read_bytes().decode("latin-1").splitlines():
            parts = line.strip().split()
            if len(parts) >= 2 and parts[0] == "map_Kd":
                texture = path.parent / parts[-1]  # options such as -s come before the file name
                if texture.is_file():
                    return texture
    return None


def _texture_colors(path, texture, uv_rows, face_rows, uv_before, corners, n_vertices):
    """The texture sampled at the vertices (uint8 RGB; black where no face uses a vertex), or None when the
    faces give no texture coordinates. ``uv_before``: texture coordinates defined before each corner's face."""
    from ..texture import read_texture, sample_at_vertices

    try:
        uv = np.array([row[:2] for row in uv_rows], dtype=np.float64)
        uv_index = np.array(
            [
                int(parts[1]) if len(parts) > 1 and parts[1] else 0
                for row in face_rows
                for parts in (t.split("/") for t in row)
            ],
            dtype=np.int64,
        )
    except ValueError:
        raise MeshError(f"{path.name} has texture coordinates that are not numbers; export it again.") from None
    # 1-based; negative ones count back from the last texture coordinate defined before the face
    uv_index = np.where(uv_index > 0, uv_index - 1, np.where(uv_index < 0, uv_before + uv_index, -1))
    usable = (uv_index >= 0) & (uv_index < len(uv)) & (corners >= 0) & (corners < n_vertices)
    if not np.any(usable):
        return None
    colors, _ = sample_at_vertices(read_texture(texture), uv[uv_index[usable]], corners[usable], n_vertices)
    return colors
