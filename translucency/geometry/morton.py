"""Morton (Z-order) curve of a point set: an order in which points close in space sit close in memory."""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["morton_order", "by_lowest_vertex"]


def morton_order(points, bits: int = 16) -> np.ndarray:
    """Permutation that sorts points along a Morton (Z-order) curve of their bounding box.

    Points close in space end up close in the order, so that work over neighbours reads nearby
    memory. ``bits`` per axis (a ``2^bits`` grid; at most 21 so that the code fits 63 bits).

    Returns
    -------
    ndarray of int64, shape (n,)
        ``points[order]`` is the curve's order.
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if len(points) == 0:
        return np.zeros(0, dtype=np.int64)
    low = points.min(axis=0)
    size = float(np.ptp(points, axis=0).max()) or 1.0
    cells = np.minimum(((points - low) / size * (1 << bits)).astype(np.uint64), np.uint64((1 << bits) - 1))
    return np.argsort(_interleaved(cells, bits), kind="stable").astype(np.int64)


@numba.njit(cache=True)
def _interleaved(cells, bits):  # pragma: no cover - compiled
    """The Morton code of each row of ``cells`` (n, 3) uint64: bit ``b`` of axis ``a`` at bit ``3 b + a``."""
    code = np.zeros(cells.shape[0], dtype=np.uint64)
    one = np.uint64(1)
    for i in range(cells.shape[0]):
        c = np.uint64(0)
        for bit in range(bits):
            for axis in range(3):
                c |= ((cells[i, axis] >> np.uint64(bit)) & one) << np.uint64(3 * bit + axis)
        code[i] = c
    return code


def by_lowest_vertex(triangles, n_vertices: int) -> np.ndarray:
    """The rows of ``triangles`` (m, 3) in the order of their lowest vertex index, ties in their given order (what
    a stable sort on ``triangles.min(axis=1)`` gives), by counting: linear in ``m`` and ``n_vertices``."""
    triangles = np.ascontiguousarray(triangles, dtype=np.int64)
    return triangles[_counting_order(triangles, int(n_vertices))]


@numba.njit(cache=True)
def _counting_order(triangles, n):  # pragma: no cover - compiled
    lowest = np.empty(triangles.shape[0], dtype=np.int64)
    start = np.zeros(n + 1, dtype=np.int64)
    for t in range(triangles.shape[0]):
        v = min(triangles[t, 0], triangles[t, 1], triangles[t, 2])
        lowest[t] = v
        start[v + 1] += 1
    for v in range(n):
        start[v + 1] += start[v]
    order = np.empty(triangles.shape[0], dtype=np.int64)
    for t in range(triangles.shape[0]):
        order[start[lowest[t]]] = t
        start[lowest[t]] += 1
    return order
