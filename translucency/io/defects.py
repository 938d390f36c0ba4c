"""Inventory of the defects of a triangle mesh (what a scan repair has to fix), counted with numpy.

:func:`find_defects` counts, with the definitions below, everything :mod:`translucency.io.clean`
repairs, so a repair can be reported as honest before/after numbers. The definitions follow those
of the shared scans' README (trimesh's conventions), so the counts can be checked against it.

========================== ======================================================================
count                      definition
========================== ======================================================================
duplicate_vertices         vertices at exactly the position of another vertex (a group of k
                           coincident vertices counts k - 1)
unreferenced_vertices      vertices used by no triangle
null_faces                 triangles with a repeated vertex index
duplicate_faces            triangles on the same three vertices as an earlier one (any order)
zero_area_faces            triangles with distinct indices whose area is at most
                           ``ZERO_AREA_RATIO / 2`` times their longest edge squared (collinear
                           or coincident corners)
non_manifold_edges         edges shared by more than two triangles
non_manifold_vertices      vertices whose triangles form more than one fan (triangles around the
                           vertex linked through edges of exactly two triangles, so the ends of
                           a non-manifold edge count too)
boundary_edges             edges of exactly one triangle
boundary_loops             connected chains of boundary edges (holes and outer borders)
largest_boundary_loop      number of edges of the longest of them
components                 connected pieces: triangles linked through edges of exactly two
                           triangles (a triangle hanging on a non-manifold edge, or touching the
                           rest at a vertex only, is a piece of its own)
inconsistent_edges         edges of two triangles that run the same direction in both (the two
                           triangles disagree on which side is out)
========================== ======================================================================

Null faces are left out of every count after ``null_faces``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..geometry.measure import degenerate_triangles
from ..geometry.topology import (
    boundary_loops,
    count_non_manifold_vertices,
    duplicate_triangles,
    face_components,
    first_at_same_position,
    manifold_pairs,
    unique_edges,
)

__all__ = [
    "MeshDefects",
    "find_defects",
    "zero_area_mask",
    "ZERO_AREA_RATIO",
]

#: A triangle is zero-area when ``2 A <= ZERO_AREA_RATIO * (longest edge)²`` (height/edge below 1e-10).
ZERO_AREA_RATIO = 1e-10


@dataclasses.dataclass(frozen=True)
class MeshDefects:
    """Counts of the defects of a triangle mesh (the module docstring has the full definitions).

    Every field is a count (a number of vertices, triangles, edges, loops or pieces; no unit).

    Attributes
    ----------
    vertices, triangles : int
        Size of the mesh as given (every vertex and triangle, defects included).
    duplicate_vertices : int
        Vertices at exactly the position of another (k coincident vertices count k - 1).
    unreferenced_vertices : int
        Vertices used by no triangle.
    null_faces : int
        Triangles with a repeated vertex index (left out of every count below).
    duplicate_faces : int
        Triangles on the same three vertices as an earlier one, in any order.
    zero_area_faces : int
        Triangles with distinct indices and zero area relative to their size (:data:`ZERO_AREA_RATIO`).
    non_manifold_edges : int
        Edges shared by more than two triangles.
    non_manifold_vertices : int
        Vertices whose triangles form more than one fan.
    boundary_edges : int
        Edges of exactly one triangle.
    boundary_loops : int
        Connected chains of boundary edges (holes and outer borders).
    largest_boundary_loop : int
        Edges of the longest boundary loop.
    components : int
        Connected pieces (triangles linked through edges of exactly two triangles).
    inconsistent_edges : int
        Edges of two triangles that run the same direction in both (the triangles disagree on which
        side is out).
    """

    vertices: int
    triangles: int
    duplicate_vertices: int
    unreferenced_vertices: int
    null_faces: int
    duplicate_faces: int
    zero_area_faces: int
    non_manifold_edges: int
    non_manifold_vertices: int
    boundary_edges: int
    boundary_loops: int
    largest_boundary_loop: int
    components: int
    inconsistent_edges: int

    def as_dict(self) -> dict[str, int]:
        """The counts as a plain dict."""
        return dataclasses.asdict(self)


def zero_area_mask(points, triangles) -> np.ndarray:
    """True for the triangles whose area is zero relative to their size (see :data:`ZERO_AREA_RATIO`).

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Vertex positions (any length unit).
    triangles : array_like of int, shape (m, 3)

    Returns
    -------
    ndarray of bool, shape (m,)
    """
    return degenerate_triangles(points, triangles, ZERO_AREA_RATIO)


def _count_duplicate_vertices(points: np.ndarray) -> int:
    if len(points) == 0:
        return 0
    return int(np.count_nonzero(first_at_same_position(points) != np.arange(len(points))))


def find_defects(points, triangles) -> MeshDefects:
    """Count the defects of a triangle mesh (:func:`defects_and_components` without the components)."""
    return defects_and_components(points, triangles)[0]


def defects_and_components(points, triangles) -> tuple[MeshDefects, tuple[int, np.ndarray] | None]:
    """Count the defects of a triangle mesh, and give its face components ``(count, label per triangle)``
    as :func:`~translucency.geometry.topology.face_components` finds them (None when every face is null),
    so that a repair which keeps the faces does not find them again (None too when some face is null).

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Vertex positions (any length unit).
    triangles : array_like of int, shape (m, 3)
        Vertex indices of each triangle (valid indices; see :func:`translucency.geometry.mesh.validate_mesh_arrays`).

    Returns
    -------
    MeshDefects

    Examples
    --------
    >>> import numpy as np
    >>> points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 5]], dtype=float)
    >>> find_defects(points, [[0, 1, 2]]).unreferenced_vertices
    1
    """
    labels = None
    points = np.ascontiguousarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    n, m = len(points), len(triangles)
    referenced = np.zeros(n, dtype=bool)
    referenced[triangles.ravel()] = True

    null = (
        (triangles[:, 0] == triangles[:, 1])
        | (triangles[:, 1] == triangles[:, 2])
        | (triangles[:, 0] == triangles[:, 2])
    )
    proper = triangles[~null]
    duplicate_faces = int(np.count_nonzero(duplicate_triangles(proper)))
    zero_area = int(np.count_nonzero(zero_area_mask(points, proper)))

    inconsistent = non_manifold_edges = loops = largest = non_manifold_vertices = components = boundary_edges = 0
    if len(proper):
        edges, edge_of_corner = unique_edges(proper)
        slot_edge = edge_of_corner.ravel()
        faces_per_edge = np.bincount(slot_edge, minlength=len(edges))
        # +1 when a triangle runs along the edge from its smaller to its larger index, else -1;
        # the two triangles of a consistently oriented edge run it in opposite directions
        direction = np.where(proper.ravel() == edges[slot_edge, 0], 1.0, -1.0)
        direction_sum = np.bincount(slot_edge, weights=direction, minlength=len(edges))
        inconsistent = int(np.count_nonzero((faces_per_edge == 2) & (direction_sum != 0)))
        non_manifold_edges = int(np.count_nonzero(faces_per_edge > 2))
        boundary = edges[faces_per_edge == 1]
        boundary_edges = len(boundary)
        loops, largest = boundary_loops(boundary)
        pairs = manifold_pairs(edge_of_corner, faces_per_edge)
        non_manifold_vertices = count_non_manifold_vertices(proper, edge_of_corner, faces_per_edge, n, pairs)
        components, labels = face_components(proper, pairs=pairs)

    defects = MeshDefects(
        vertices=n,
        triangles=m,
        duplicate_vertices=_count_duplicate_vertices(points),
        unreferenced_vertices=int(np.count_nonzero(~referenced)),
        null_faces=int(np.count_nonzero(null)),
        duplicate_faces=int(duplicate_faces),
        zero_area_faces=zero_area,
        non_manifold_edges=non_manifold_edges,
        non_manifold_vertices=non_manifold_vertices,
        boundary_edges=int(boundary_edges),
        boundary_loops=int(loops),
        largest_boundary_loop=int(largest),
        components=int(components),
        inconsistent_edges=inconsistent,
    )
    # labels of every triangle only (a null face has none)
    return defects, (int(components), labels) if labels is not None and len(proper) == m else None
