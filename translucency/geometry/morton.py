"""Morton (Z-order) curve of a point set: an order in which points close in space sit close in memory."""

from __future__ import annotations

import numpy as np

__all__ = ["morton_order"]


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
    code = np.zeros(len(points), dtype=np.uint64)
    for bit in range(bits):
        for axis in range(3):
            code |= ((cells[:, axis] >> np.uint64(bit)) & np.uint64(1)) << np.uint64(3 * bit + axis)
    return np.argsort(code, kind="stable").astype(np.int64)
