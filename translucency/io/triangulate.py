"""Triangle lists from polygons and from triangle strips, vectorised.

Files store surfaces as polygons (OBJ, OFF, PLY faces with more than three corners, VTK polys) or
as triangle strips (the PLY ``tristrips`` element, VTK strips). Both become an (m, 3) int64
triangle list here, with the winding of the input kept.

- Polygons with k >= 3 corners become a fan of k - 2 triangles ``(v0, v_j, v_j+1)``; this is exact
  for convex and star-shaped-from-v0 polygons, which is what scanners and exporters produce.
  Polygons with fewer than three corners are dropped.
- A strip ``s0 s1 s2 s3 ...`` gives triangles ``(s_j, s_j+1, s_j+2)``, with the first two indices
  of every odd triangle swapped so that all triangles of the strip have the same winding. An index
  of ``-1`` ends a strip and starts a new one. Triangles with a repeated index (used in strips to
  turn corners) are dropped.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "triangulate_polygons",
    "triangulate_polygon_lists",
    "triangulate_strips",
    "drop_repeated_index_triangles",
]


def drop_repeated_index_triangles(triangles: np.ndarray) -> np.ndarray:
    """Return the triangles whose three vertex indices are distinct, (k, 3) int64."""
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    keep = (
        (triangles[:, 0] != triangles[:, 1])
        & (triangles[:, 1] != triangles[:, 2])
        & (triangles[:, 0] != triangles[:, 2])
    )
    return triangles[keep]


def triangulate_polygons(offsets, connectivity) -> np.ndarray:
    """Fan-triangulate polygons given in offsets/connectivity form.

    Parameters
    ----------
    offsets : array_like of int, shape (p + 1,)
        Start of each polygon in ``connectivity``, with the total length appended (VTK's layout).
    connectivity : array_like of int
        Vertex indices of all polygons, one after the other.

    Returns
    -------
    ndarray, shape (m, 3), int64
        ``sum(max(k - 2, 0))`` triangles, in polygon order.
    """
    offsets = np.asarray(offsets, dtype=np.int64)
    connectivity = np.asarray(connectivity, dtype=np.int64)
    sizes = np.diff(offsets)
    if len(sizes) and np.all(sizes == 3):
        return connectivity.reshape(-1, 3).copy()
    n_fan = np.maximum(sizes - 2, 0)
    total = int(n_fan.sum())
    if total == 0:
        return np.empty((0, 3), dtype=np.int64)
    polygon = np.repeat(np.arange(len(sizes)), n_fan)
    # position of each triangle inside its polygon's fan: 0, 1, ..., k - 3
    first_of_polygon = np.cumsum(n_fan) - n_fan
    j = np.arange(total) - first_of_polygon[polygon]
    start = offsets[:-1][polygon]
    return np.stack([connectivity[start], connectivity[start + j + 1], connectivity[start + j + 2]], axis=1)


def triangulate_polygon_lists(polygons) -> np.ndarray:
    """Fan-triangulate a sequence of index arrays (one per polygon), as read by plyfile.

    Parameters
    ----------
    polygons : sequence of 1-D int arrays

    Returns
    -------
    ndarray, shape (m, 3), int64
    """
    sizes = np.fromiter((len(p) for p in polygons), dtype=np.int64, count=len(polygons))
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    connectivity = np.concatenate(list(polygons)).astype(np.int64) if len(polygons) else np.empty(0, np.int64)
    return triangulate_polygons(offsets, connectivity)


def triangulate_strips(indices, offsets=None) -> np.ndarray:
    """Triangles of triangle strips, keeping their winding; degenerate triangles dropped.

    Parameters
    ----------
    indices : array_like of int
        Vertex indices of all strips, one after the other; ``-1`` ends a strip (other negative
        values are kept, for the caller's range check to report).
    offsets : array_like of int, shape (s + 1,), optional
        Start of each strip in ``indices`` with the total length appended; when given, each range
        is a separate strip too (VTK's layout, or several PLY strip lists).

    Returns
    -------
    ndarray, shape (m, 3), int64
    """
    indices = np.asarray(indices, dtype=np.int64).ravel()
    n = len(indices)
    if n < 3:
        return np.empty((0, 3), dtype=np.int64)
    # a strip starts at 0, after every -1, and at every given offset
    starts = np.zeros(n, dtype=bool)
    starts[0] = True
    restart = np.flatnonzero(indices == -1)
    starts[restart[restart + 1 < n] + 1] = True
    if offsets is not None:
        offsets = np.asarray(offsets, dtype=np.int64)
        starts[offsets[(offsets >= 0) & (offsets < n)]] = True
    strip_start = np.maximum.accumulate(np.where(starts, np.arange(n), 0))
    position = np.arange(n) - strip_start  # index of each entry inside its strip
    # triangle j of a strip ends at entry j + 2: it needs positions >= 2 and no -1 among its corners
    last = np.arange(2, n)
    valid = (position[last] >= 2) & (indices[last] != -1) & (indices[last - 1] != -1) & (indices[last - 2] != -1)
    last = last[valid]
    a, b, c = indices[last - 2], indices[last - 1], indices[last]
    odd = (position[last] - 2) % 2 == 1
    first = np.where(odd, b, a)
    second = np.where(odd, a, b)
    return drop_repeated_index_triangles(np.stack([first, second, c], axis=1))
