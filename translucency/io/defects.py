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
from ..geometry.topology import boundary_loops, edge_census, first_at_same_position

__all__ = [
    "MeshDefects",
    "MeshSurvey",
    "find_defects",
    "defects_and_components",
    "survey_mesh",
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
    return survey_mesh(points, triangles, lengths=False).defects


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
    survey = survey_mesh(points, triangles, lengths=False)
    return survey.defects, survey.components


@dataclasses.dataclass(frozen=True)
class MeshSurvey:
    """:func:`survey_mesh`'s result.

    Attributes
    ----------
    defects : MeshDefects
        The mesh's defects, counted.
    components : tuple of (int, ndarray) or None
        The face components ``(count, label per triangle)``; None when some face is null, or every face.
    mean_edge_length : float or None
        The mean length of the unique edges, in the points' unit; None when some face is null, or when it was not
        asked for.
    """

    defects: MeshDefects
    components: tuple[int, np.ndarray] | None
    mean_edge_length: float | None


def survey_mesh(points, triangles, *, lengths: bool = True) -> MeshSurvey:
    """:func:`defects_and_components`, and the mean unique-edge length (in the points' unit) measured on the way when
    ``lengths`` (one pass over every vertex's corners, :func:`~translucency.geometry.topology.edge_census`)."""
    points = np.ascontiguousarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    n, m = len(points), len(triangles)
    census = edge_census(triangles, points, lengths=lengths)
    proper, unreferenced = triangles, census.unreferenced_vertices
    if census.null_faces:  # counted again without them (the vertices only they use stay referenced)
        null = (
            (triangles[:, 0] == triangles[:, 1])
            | (triangles[:, 1] == triangles[:, 2])
            | (triangles[:, 0] == triangles[:, 2])
        )
        proper = triangles[~null]
        referenced = np.zeros(n, dtype=bool)
        referenced[triangles.ravel()] = True
        unreferenced = int(np.count_nonzero(~referenced))
        census = edge_census(proper, points, lengths=lengths)
    loops, largest = boundary_loops(census.boundary_edges)
    defects = MeshDefects(
        vertices=n,
        triangles=m,
        duplicate_vertices=_count_duplicate_vertices(points),
        unreferenced_vertices=unreferenced,
        null_faces=m - len(proper),
        duplicate_faces=int(np.count_nonzero(census.duplicate)),
        zero_area_faces=int(np.count_nonzero(zero_area_mask(points, proper))),
        non_manifold_edges=census.non_manifold_edges,
        non_manifold_vertices=census.non_manifold_vertices,
        boundary_edges=len(census.boundary_edges),
        boundary_loops=int(loops),
        largest_boundary_loop=int(largest),
        components=census.components if len(proper) else 0,
        inconsistent_edges=census.inconsistent_edges,
    )
    whole = len(proper) == m and m > 0  # labels of every triangle only (a null face has none)
    components = (census.components, census.labels) if whole else None
    mean = census.edge_length_sum / census.edges if whole and lengths and census.edges else None
    return MeshSurvey(defects, components, mean)
