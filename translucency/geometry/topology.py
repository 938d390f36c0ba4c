"""Topology of a triangle list: unique edges, components, boundary loops and fans, counted with numpy/scipy.

Pure functions of ``triangles`` (m, 3) int64; they count and label, they neither validate nor repair
(:mod:`translucency.io.defects` builds the repair inventory from them).

Corners ``(t, i)`` are numbered ``3 t + i`` (the "slot" of corner i of triangle t); the edge of slot
``3 t + i`` runs from corner i to corner i + 1.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph

__all__ = ["unique_edges", "face_components", "boundary_loops", "next_corner", "count_non_manifold_vertices"]


def unique_edges(triangles) -> tuple[np.ndarray, np.ndarray]:
    """Undirected edges of a triangle list and, for each triangle corner edge, its edge number.

    Parameters
    ----------
    triangles : array_like of int, shape (m, 3)

    Returns
    -------
    edges : ndarray, shape (e, 2), int64
        Unique edges with the smaller index first.
    edge_of_corner : ndarray, shape (m, 3), int64
        ``edges[edge_of_corner[t, i]]`` is the edge from corner i to corner i+1 of triangle t.
    """
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    directed = np.stack([triangles, np.roll(triangles, -1, axis=1)], axis=2).reshape(-1, 2)
    undirected = np.sort(directed, axis=1)
    n = int(triangles.max()) + 1 if triangles.size else 1
    key = undirected[:, 0] * n + undirected[:, 1]
    unique_key, inverse = np.unique(key, return_inverse=True)
    edges = np.stack([unique_key // n, unique_key % n], axis=1)
    return edges, inverse.reshape(-1, 3)


def boundary_loops(boundary_edges: np.ndarray) -> tuple[int, int]:
    """Number of connected chains of boundary edges and the edge count of the largest."""
    if len(boundary_edges) == 0:
        return 0, 0
    used, local = np.unique(boundary_edges.ravel(), return_inverse=True)
    local = local.reshape(-1, 2)
    graph = sparse.coo_matrix(
        (np.ones(len(local), dtype=np.int8), (local[:, 0], local[:, 1])), shape=(len(used), len(used))
    )
    count, labels = csgraph.connected_components(graph, directed=False)
    edges_per_loop = np.bincount(labels[local[:, 0]], minlength=count)
    return int(count), int(edges_per_loop.max())


def face_components(triangles: np.ndarray, edge_of_corner: np.ndarray | None = None) -> tuple[int, np.ndarray]:
    """Connected components of triangles linked through manifold edges (edges of exactly two triangles).

    A triangle hanging on a non-manifold edge, or touching the rest only at a vertex, is a
    component of its own.

    Parameters
    ----------
    triangles : ndarray, shape (m, 3), int64
    edge_of_corner : ndarray, shape (m, 3), optional
        From :func:`unique_edges` (computed when not given).

    Returns
    -------
    count : int
    labels : ndarray, shape (m,), int64
        Component number of each triangle.
    """
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if edge_of_corner is None:
        _, edge_of_corner = unique_edges(triangles)
    m = len(triangles)
    slot_edge = edge_of_corner.ravel()
    faces_per_edge = np.bincount(slot_edge)
    slots = np.flatnonzero(faces_per_edge[slot_edge] == 2)
    slots = slots[np.argsort(slot_edge[slots], kind="stable")]
    a, b = slots[0::2] // 3, slots[1::2] // 3
    graph = sparse.coo_matrix((np.ones(len(a), dtype=np.int8), (a, b)), shape=(m, m))
    count, labels = csgraph.connected_components(graph, directed=False)
    return int(count), labels.astype(np.int64)


def next_corner(slot: np.ndarray) -> np.ndarray:
    """Slot 3 t + i -> slot 3 t + (i + 1) % 3 (the corner at the end of edge i of triangle t)."""
    return slot - slot % 3 + (slot % 3 + 1) % 3


def count_non_manifold_vertices(
    triangles: np.ndarray, edge_of_corner: np.ndarray, faces_per_edge: np.ndarray, n: int
) -> int:
    """Vertices whose incident triangles form more than one fan (linked through manifold edges).

    Corners (t, i) are graph nodes 3 t + i; a manifold edge links, at each of its two end vertices,
    the corners of its two triangles; the fans are the connected components of that graph.
    """
    m = len(triangles)
    slot_edge = edge_of_corner.ravel()  # slot 3 t + i holds the edge from corner i to corner i + 1
    manifold_slots = np.flatnonzero(faces_per_edge[slot_edge] == 2)
    order = manifold_slots[np.argsort(slot_edge[manifold_slots], kind="stable")]
    first, second = order[0::2], order[1::2]  # the two slots of each manifold edge
    corner_vertex = triangles.ravel()
    same_start = corner_vertex[first] == corner_vertex[second]
    a = np.concatenate([first, next_corner(first)])
    b = np.concatenate(
        [np.where(same_start, second, next_corner(second)), np.where(same_start, next_corner(second), second)]
    )
    graph = sparse.coo_matrix((np.ones(len(a), dtype=np.int8), (a, b)), shape=(3 * m, 3 * m))
    n_fans, fan = csgraph.connected_components(graph, directed=False)
    # every fan lies around one vertex: count the fans per vertex through one corner of each
    corner_of_fan = np.zeros(n_fans, dtype=np.int64)
    corner_of_fan[fan] = np.arange(3 * m)
    fans_per_vertex = np.bincount(corner_vertex[corner_of_fan], minlength=n)
    return int(np.count_nonzero(fans_per_vertex > 1))
