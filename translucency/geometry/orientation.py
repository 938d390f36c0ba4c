"""Orientation of triangle meshes: coherent winding, then normals pointing out of the object.

Two steps, both vectorised (no loop over faces):

1. **Coherent orientation** (:func:`coherent_orientation`). Two triangles sharing a manifold edge
   agree when they run along it in opposite directions. Flipping a triangle toggles its agreement
   with every neighbour, so a coherent orientation is a choice of sign per triangle; it is found
   for all components at once as the connected components of the *orientation double cover*: each
   triangle has a node "kept" and a node "flipped", agreeing neighbours link kept-kept and
   flipped-flipped, disagreeing ones kept-flipped. In an orientable component the two nodes of a
   triangle fall in different components of the cover, and either of the two is a coherent
   orientation; the one that flips fewer triangles is taken. A non-orientable component (a Möbius
   strip) has both nodes in one component and is left unchanged (and counted).
2. **Outward orientation** (:func:`outward_flips`). For each connected component the signed volume
   ``V = sum_t (p0 - c) . ((p1 - c) x (p2 - c)) / 6`` is computed about the area-weighted centroid
   ``c`` of the component; a component with ``V < 0`` is flipped. For a closed component ``V`` is
   its enclosed volume whatever ``c`` is, so this is exact. For an open component (a single-view
   range scan, a scan with large holes left open) ``V > 0`` means the surface faces, on area
   average, away from its own centroid: right for the convex-ish surfaces scans are made of, and
   documented as a heuristic; close holes first when the object is meant to be closed.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph

from .measure import centroids_and_volumes
from .topology import face_components, unique_edges

__all__ = ["coherent_orientation", "outward_flips", "flip_triangles"]


def flip_triangles(triangles: np.ndarray, flip: np.ndarray) -> np.ndarray:
    """Return a copy of ``triangles`` with the rows where ``flip`` is True reversed (corners 1 and 2 swapped)."""
    out = np.array(triangles, dtype=np.int64, copy=True)
    out[flip, 1], out[flip, 2] = triangles[flip, 2], triangles[flip, 1]
    return out


def coherent_orientation(triangles) -> tuple[np.ndarray, int]:
    """Which triangles to flip so that every manifold edge is run in opposite directions by its two triangles.

    Parameters
    ----------
    triangles : array_like of int, shape (m, 3)

    Returns
    -------
    flip : ndarray of bool, shape (m,)
        Triangles to reverse (the smaller of the two coherent choices in each component).
    non_orientable_components : int
        Components with no coherent orientation (left unflipped).
    """
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    m = len(triangles)
    if m == 0:
        return np.zeros(0, dtype=bool), 0
    _, edge_of_corner = unique_edges(triangles)
    slot_edge = edge_of_corner.ravel()
    faces_per_edge = np.bincount(slot_edge)
    slots = np.flatnonzero(faces_per_edge[slot_edge] == 2)
    slots = slots[np.argsort(slot_edge[slots], kind="stable")]
    first, second = slots[0::2], slots[1::2]
    face_a, face_b = first // 3, second // 3
    start = triangles.ravel()
    agree = start[first] != start[second]  # opposite directions along the shared edge
    # node f: triangle f kept; node f + m: triangle f flipped
    a = np.concatenate([face_a, face_a + m])
    b = np.concatenate([np.where(agree, face_b, face_b + m), np.where(agree, face_b + m, face_b)])
    graph = sparse.coo_matrix((np.ones(len(a), dtype=np.int8), (a, b)), shape=(2 * m, 2 * m))
    _, label = csgraph.connected_components(graph, directed=False)
    kept, flipped = label[:m], label[m:]
    orientable = kept != flipped
    # in each cover component count the triangles whose "kept" node lies there; keep the larger side
    kept_count = np.bincount(kept, minlength=label.max() + 1)
    keep_here = (kept_count[kept] > kept_count[flipped]) | (
        (kept_count[kept] == kept_count[flipped]) & (kept < flipped)
    )
    flip = orientable & ~keep_here
    non_orientable = len(np.unique(kept[~orientable]))
    return flip, int(non_orientable)


def outward_flips(points, triangles, components=None) -> tuple[np.ndarray, int]:
    """Which triangles to flip so that every component faces outward (positive signed volume).

    The triangles must already be coherently oriented (see :func:`coherent_orientation`).

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Vertex positions in mm.
    triangles : array_like of int, shape (m, 3)
    components : (int, ndarray), optional
        :func:`~translucency.geometry.topology.face_components` of these triangles, when already known.

    Returns
    -------
    flip : ndarray of bool, shape (m,)
        Triangles of the components to reverse.
    components_flipped : int
    """
    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if len(triangles) == 0:
        return np.zeros(0, dtype=bool), 0
    count, component = face_components(triangles) if components is None else components
    # signed volume of the tetrahedra (c, p0, p1, p2) = (p0 - c) . ((p1 - p0) x (p2 - p0)) / 6, per component
    _, _, volume = centroids_and_volumes(points, triangles, component, count)
    flip_component = volume < 0
    return flip_component[component], int(np.count_nonzero(flip_component))
