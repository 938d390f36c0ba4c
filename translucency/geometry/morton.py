"""Morton (Z-order) curve of a point set: an order in which points close in space sit close in memory."""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["morton_order", "by_lowest_vertex", "MORTON_KERNELS"]


def morton_order(points, bits: int = 16) -> np.ndarray:
    """Permutation that sorts points along a Morton (Z-order) curve of their bounding box.

    Points close in space end up close in the order, so that work over neighbours reads nearby
    memory. ``bits`` per axis (a ``2^bits`` grid; at most 21 so that the code fits 63 bits).

    Returns
    -------
    ndarray of int64, shape (n,)
        ``points[order]`` is the curve's order.
    """
    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    if len(points) == 0:
        return np.zeros(0, dtype=np.int64)
    return np.argsort(_codes(points, bits), kind="stable").astype(np.int64)


@numba.njit(cache=True, nogil=True)
def _codes(points, bits):  # pragma: no cover - compiled
    """Each point's Morton code (:func:`_interleaved`) in its cell of a ``2^bits`` grid over the points' bounding box
    (a cube of the box's longest side from its lowest corner)."""
    low = points[0].copy()
    high = points[0].copy()
    for i in range(points.shape[0]):
        for a in range(3):
            low[a] = min(low[a], points[i, a])
            high[a] = max(high[a], points[i, a])
    size = max(high[0] - low[0], high[1] - low[1], high[2] - low[2])
    size = size if size > 0.0 else 1.0
    top = np.uint64((1 << bits) - 1)
    cells = np.empty((points.shape[0], 3), dtype=np.uint64)
    for i in range(points.shape[0]):
        for a in range(3):
            cells[i, a] = min(np.uint64((points[i, a] - low[a]) / size * (1 << bits)), top)
    return _interleaved(cells, bits)


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


def by_lowest_vertex(triangles, n_vertices: int, relabel=None) -> np.ndarray:
    """The rows of ``triangles`` (m, 3) in the order of their lowest vertex index, ties in their given order (what
    a stable sort on ``triangles.min(axis=1)`` gives), by counting: linear in ``m`` and ``n_vertices``. With
    ``relabel`` (n,) int64, the rows of ``relabel[triangles]`` (vertices numbered anew, ``n_vertices`` of them) in
    that order, without that array first. Returns (m, 3) int64."""
    triangles = np.ascontiguousarray(triangles)
    relabel = np.arange(int(n_vertices)) if relabel is None else np.ascontiguousarray(relabel, dtype=np.int64)
    return _counting_order(triangles, relabel, int(n_vertices))


@numba.njit(cache=True, nogil=True)
def _counting_order(triangles, relabel, n):  # pragma: no cover - compiled
    """:func:`by_lowest_vertex`: the rows relabelled, counted by their lowest vertex, and placed."""
    relabelled = np.empty((triangles.shape[0], 3), dtype=np.int64)  # one pass of the relabel's scattered reads
    lowest = np.empty(triangles.shape[0], dtype=np.int64)
    start = np.zeros(n + 1, dtype=np.int64)
    for t in range(triangles.shape[0]):
        for c in range(3):
            relabelled[t, c] = relabel[triangles[t, c]]
        v = min(relabelled[t, 0], relabelled[t, 1], relabelled[t, 2])
        lowest[t] = v
        start[v + 1] += 1
    for v in range(n):
        start[v + 1] += start[v]
    out = np.empty((triangles.shape[0], 3), dtype=np.int64)
    for t in range(triangles.shape[0]):
        row = start[lowest[t]]
        start[lowest[t]] += 1
        for c in range(3):
            out[row, c] = relabelled[t, c]
    return out


#: The compiled kernels of the spatial order: numba compiles each on first use; the set-up compiles them ahead
#: (:mod:`translucency.app.warmup`).
MORTON_KERNELS = (_codes, _interleaved, _counting_order)
