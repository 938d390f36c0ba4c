"""Formats pymeshlab reads (3DS, Collada, VRML, X3D, OpenCTM, GTS, PTX, ...).

Vertex colours and quality are kept; note that pymeshlab drops invalid faces and vertices itself
instead of reporting them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import MeshError
from .common import set_colors, short_reason

__all__ = ["PYMESHLAB_FORMATS", "read_with_pymeshlab"]

PYMESHLAB_FORMATS = {
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


def read_with_pymeshlab(path: Path, suffix: str):
    """Points (file units), triangles and per-vertex data (``colors``, ``quality``) of a file pymeshlab reads.

    ``suffix`` is one of :data:`PYMESHLAB_FORMATS` (it names the format in the error sentence).
    """
    from ..meshlab import import_pymeshlab

    pymeshlab = import_pymeshlab()
    mesh_set = pymeshlab.MeshSet()
    try:
        mesh_set.load_new_mesh(str(path))
    except pymeshlab.PyMeshLabException as exc:
        raise MeshError(
            f"{path.name} is not a readable {PYMESHLAB_FORMATS[suffix]} file ({short_reason(exc)}); check or "
            "export the file again."
        ) from exc
    mesh = mesh_set.current_mesh()
    points = np.array(mesh.vertex_matrix(), dtype=np.float64).reshape(-1, 3)
    triangles = np.array(mesh.face_matrix(), dtype=np.int64).reshape(-1, 3)
    point_data: dict[str, np.ndarray] = {}
    if mesh.has_vertex_color():
        set_colors(point_data, np.array(mesh.vertex_color_matrix()), path.name)
    if mesh.has_vertex_scalar():
        point_data["quality"] = np.array(mesh.vertex_scalar_array(), dtype=np.float64)
    return points, triangles, point_data
