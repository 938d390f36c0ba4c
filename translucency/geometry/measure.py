"""Per-triangle and per-vertex geometry of a triangle mesh, as plain numpy arrays (the solver's input).

Pure functions of ``points`` (n, 3) float64 in mm and ``triangles`` (m, 3) int64; nothing here
validates (validation happens where meshes are built, :mod:`translucency.geometry.mesh`).

================ ================================================================ ======
name             meaning                                                          unit
================ ================================================================ ======
triangle area    A_t = |(p1 - p0) x (p2 - p0)| / 2                                mm²
triangle normal  (p1 - p0) x (p2 - p0) / (2 A_t), counter-clockwise = outward    1
vertex normal    normalised sum of the adjacent triangles' A_t-weighted normals   1
vertex area      the vertex's share of the surface; the shares sum to sum(A_t)    mm²
================ ================================================================ ======

Vertex areas come in two flavours (both partition the surface exactly, so they sum to the total
area, and both are zero for unreferenced vertices):

``"barycentric"`` (default)
    One third of the area of every adjacent triangle: the area of the region of points closer, in
    barycentric coordinates, to the vertex than to the others. Robust on any triangle.
``"mixed_voronoi"``
    Meyer, Desbrun, Schröder and Barr (2003), "Discrete differential-geometry operators for
    triangulated 2-manifolds", section 3.3 ("A_mixed"): the Voronoi region of the vertex inside
    each non-obtuse triangle, and for an obtuse triangle half its area to the obtuse corner and a
    quarter to each other corner. Closer to the true point density on irregular meshes.

Degenerate (zero-area) triangles contribute nothing: their normal is the zero vector and they add
no area. A vertex with no non-degenerate triangle gets the zero normal (never NaN).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..errors import InvalidParameterError
from ..threads import for_ranges
from .topology import edge_census, kernel_array

__all__ = [
    "CLEANING_KERNELS",
    "degenerate_triangles",
    "triangle_cross_products",
    "triangle_areas",
    "triangle_normals",
    "row_lengths",
    "vertex_normals",
    "vertex_measures",
    "area_centroids",
    "centroids_and_volumes",
    "extreme_points",
    "vertex_areas",
    "barycentric_vertex_areas",
    "longest_edges",
    "mean_edge_length",
    "signed_volume",
]


def _kernel_mesh(points, triangles):
    """``points`` and ``triangles`` as the kernels take them: float64 and int64 (m, 3), C-contiguous, read-only."""
    return kernel_array(points, np.float64), kernel_array(np.asarray(triangles).reshape(-1, 3), np.int64)


def triangle_cross_products(points, triangles) -> np.ndarray:
    """Return ``(p1 - p0) x (p2 - p0)`` per triangle: twice the area times the unit normal, (m, 3) in mm²."""
    points, triangles = _kernel_mesh(points, triangles)
    return _cross_products(points, triangles)


@numba.njit(cache=True, inline="always")
def _cross(points, triangles, t):
    """``(p1 - p0) x (p2 - p0)`` of triangle ``t`` as three floats (the same arithmetic as ``np.cross``)."""
    i0, i1, i2 = triangles[t, 0], triangles[t, 1], triangles[t, 2]
    a0, a1, a2 = points[i1, 0] - points[i0, 0], points[i1, 1] - points[i0, 1], points[i1, 2] - points[i0, 2]
    b0, b1, b2 = points[i2, 0] - points[i0, 0], points[i2, 1] - points[i0, 1], points[i2, 2] - points[i0, 2]
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@numba.njit(cache=True)
def _cross_products(points, triangles):
    """:func:`triangle_cross_products` in one pass."""
    out = np.empty((triangles.shape[0], 3))
    for t in range(triangles.shape[0]):
        out[t, 0], out[t, 1], out[t, 2] = _cross(points, triangles, t)
    return out


@numba.njit(cache=True)
def _vertex_sums(triangles, values, n_points):
    """Each triangle's row of ``values`` ``(m, k)`` added to its three vertices, in triangle order: ``(n_points, k)``
    (the order a bincount over the flattened corners adds in)."""
    out = np.zeros((n_points, values.shape[1]))
    for t in range(triangles.shape[0]):
        for i in range(3):
            v = triangles[t, i]
            for j in range(values.shape[1]):
                out[v, j] += values[t, j]
    return out


def degenerate_triangles(points, triangles, ratio: float) -> np.ndarray:
    """True for the triangles with ``|(p1 - p0) x (p2 - p0)| <= ratio * longest_edge**2`` (twice the area
    against the square of the longest edge: 0 for a sliver or a point), ``(m,)`` bool; one pass in numba."""
    points, triangles = _kernel_mesh(points, triangles)
    out = np.empty(triangles.shape[0], dtype=np.bool_)
    for_ranges(_degenerate, triangles.shape[0], points, triangles, float(ratio), out)
    return out


@numba.njit(cache=True, nogil=True)
def _degenerate(worker, lo, hi, points, triangles, ratio, out):
    """:func:`degenerate_triangles` of triangles ``lo .. hi - 1``."""
    for t in range(lo, hi):
        longest = 0.0
        for i in range(3):
            a, b = triangles[t, i], triangles[t, (i + 1) % 3]
            d0, d1, d2 = points[b, 0] - points[a, 0], points[b, 1] - points[a, 1], points[b, 2] - points[a, 2]
            longest = max(longest, math.sqrt(d0 * d0 + d1 * d1 + d2 * d2))
        c0, c1, c2 = _cross(points, triangles, t)
        out[t] = math.sqrt(c0 * c0 + c1 * c1 + c2 * c2) <= ratio * longest * longest


#: Triangles (or points) in a block of the sums and searches run on several threads: each block's result is kept
#: apart and the blocks' are combined in their order, so that the result does not depend on the number of threads.
BLOCK = 1 << 18
#: The most partial sums (blocks x labels) :func:`centroids_and_volumes` keeps; with more labels it sums in one block.
MAX_PARTIAL_SUMS = 1 << 20


def area_centroids(points, triangles, labels=None, count: int = 1):
    """Area (mm²) and area-weighted centroid (mm) of the triangles of each label, in one pass.

    ``labels (m,)`` gives each triangle's label in ``0 .. count - 1`` (all 0 when omitted). Returns
    ``(areas (count,), centroids (count, 3))``; a label without area has its centroid at the origin.
    """
    return centroids_and_volumes(points, triangles, labels, count)[:2]


def centroids_and_volumes(points, triangles, labels=None, count: int = 1):
    """:func:`area_centroids` and, in the same pass, each label's signed volume about its centroid ``c`` (mm³):
    ``sum_t (p0 - c) . ((p1 - p0) x (p2 - p0)) / 6``. Returns ``(areas (count,), centroids (count, 3), volumes
    (count,))``.

    The volume is summed about a corner ``r`` of the label's first triangle and moved to ``c`` at the end (``V_c = V_r
    - (c - r) . sum_t ((p1 - p0) x (p2 - p0)) / 6``), so that a surface far from the origin loses no digits to it.
    """
    points, triangles = _kernel_mesh(points, triangles)
    labels = kernel_array(np.zeros(triangles.shape[0], dtype=np.int64) if labels is None else labels, np.int64)
    count = int(count)
    blocks = max(1, -(-triangles.shape[0] // BLOCK))
    if blocks * count > MAX_PARTIAL_SUMS:
        blocks = 1
    partial = np.zeros((blocks, count, 8))  # area, area-weighted corner sums (3), volume about the reference, cross
    reference = np.full((blocks, count), -1, dtype=np.int64)
    for_ranges(_centroid_blocks, blocks, points, triangles, labels, partial, reference)
    return _combined_centroids(points, partial, reference)


@numba.njit(cache=True, nogil=True)
def _centroid_blocks(worker, lo, hi, points, triangles, labels, partial, reference):
    """:func:`centroids_and_volumes`' sums over blocks ``lo .. hi - 1`` of triangles, each block's apart; the volume
    (times 6) about a reference, the first corner of the label's first triangle in the block."""
    m, blocks = triangles.shape[0], partial.shape[0]
    for b in range(lo, hi):
        sums, first = partial[b], reference[b]
        for t in range(b * m // blocks, (b + 1) * m // blocks):
            c0, c1, c2 = _cross(points, triangles, t)
            area = 0.5 * math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
            k = labels[t]
            sums[k, 0] += area
            for i in range(3):
                sums[k, 1 + i] += area * (
                    points[triangles[t, 0], i] + points[triangles[t, 1], i] + points[triangles[t, 2], i]
                )
            p0, r = triangles[t, 0], first[k]
            if r < 0:
                first[k] = r = p0
            d0, d1, d2 = points[p0, 0] - points[r, 0], points[p0, 1] - points[r, 1], points[p0, 2] - points[r, 2]
            sums[k, 4] += d0 * c0 + d1 * c1 + d2 * c2
            sums[k, 5] += c0
            sums[k, 6] += c1
            sums[k, 7] += c2


@numba.njit(cache=True)
def _combined_centroids(points, partial, reference):
    """The blocks' sums of :func:`_centroid_blocks` added in block order: ``(areas, centroids, volumes)``."""
    count = partial.shape[1]
    areas, centroids, volumes = np.zeros(count), np.zeros((count, 3)), np.zeros(count)
    about, cross = np.zeros(count), np.zeros((count, 3))
    first = np.full(count, -1, dtype=np.int64)
    for b in range(partial.shape[0]):
        for k in range(count):
            r = reference[b, k]
            if r < 0:
                continue
            if first[k] < 0:
                first[k] = r
            areas[k] += partial[b, k, 0]
            shift = 0.0  # the block's volume moved from its reference to the label's
            for i in range(3):
                centroids[k, i] += partial[b, k, 1 + i]
                cross[k, i] += partial[b, k, 5 + i]
                shift += (points[r, i] - points[first[k], i]) * partial[b, k, 5 + i]
            about[k] += partial[b, k, 4] + shift
    for k in range(count):
        if areas[k] > 0.0:
            for i in range(3):
                centroids[k, i] /= 3.0 * areas[k]
        if first[k] >= 0:
            shift = 0.0
            for i in range(3):
                shift += (centroids[k, i] - points[first[k], i]) * cross[k, i]
            volumes[k] = (about[k] - shift) / 6.0
    return areas, centroids, volumes


#: Directions whose extreme points span the polytope that :func:`hull_candidates` culls inside.
CULL_DIRECTIONS = 64


def hull_candidates(points) -> np.ndarray:
    """The points (n, 3) that can be vertices of their convex hull: the same hull from fewer points.

    The extreme points along :data:`CULL_DIRECTIONS` directions span a polytope inside the hull; a
    point strictly inside that polytope is strictly inside the hull and is dropped (Akl and Toussaint's
    heuristic). On a dense scan this keeps a small fraction of the points (those near the hull), in one pass
    each in numba.
    """
    from scipy.spatial import ConvexHull, QhullError

    points = kernel_array(points, np.float64)
    if points.shape[0] <= 4 * CULL_DIRECTIONS:
        return np.array(points)
    k = np.arange(CULL_DIRECTIONS) + 0.5  # a Fibonacci sphere of directions
    z = 1.0 - 2.0 * k / CULL_DIRECTIONS
    angle = np.pi * (1.0 + 5.0**0.5) * k
    ring = np.sqrt(1.0 - z * z)
    directions = np.ascontiguousarray(np.stack([ring * np.cos(angle), ring * np.sin(angle), z], axis=1))
    try:
        inner = ConvexHull(points[np.unique(extreme_points(points, directions))])
    except (QhullError, ValueError):  # the extremes are flat: nothing to cull by
        return np.array(points)
    margin = 1e-9 * max(float(points.max()), -float(points.min()))  # of the largest |coordinate|
    keep = np.zeros(points.shape[0], dtype=np.bool_)
    for_ranges(_outside_or_on, points.shape[0], points, np.ascontiguousarray(inner.equations), margin, keep)
    return points[keep]


def extreme_points(points, directions) -> np.ndarray:
    """Index of the first of the points (n, 3) farthest along each direction (d, 3), ``(d,)`` int64; blocks of points
    searched on several threads."""
    points, directions = kernel_array(points, np.float64), kernel_array(directions, np.float64)
    blocks = max(1, -(-points.shape[0] // BLOCK))
    best = np.full((blocks, directions.shape[0]), -np.inf)
    index = np.zeros((blocks, directions.shape[0]), dtype=np.int64)
    for_ranges(_extremes, blocks, points, directions, best, index)
    first_best = np.argmax(best, axis=0)  # the first block that holds the largest value: the first point
    return index[first_best, np.arange(directions.shape[0])]


@numba.njit(cache=True, nogil=True)
def _extremes(worker, lo, hi, points, directions, best, index):
    """:func:`extreme_points` in blocks ``lo .. hi - 1`` of points, each block's into its row of ``best``/``index``."""
    n, blocks = points.shape[0], best.shape[0]
    for b in range(lo, hi):
        for i in range(b * n // blocks, (b + 1) * n // blocks):
            for d in range(directions.shape[0]):
                v = points[i, 0] * directions[d, 0] + points[i, 1] * directions[d, 1] + points[i, 2] * directions[d, 2]
                if v > best[b, d]:
                    best[b, d] = v
                    index[b, d] = i


@numba.njit(cache=True, nogil=True)
def _outside_or_on(worker, lo, hi, points, equations, margin, keep):
    """True in ``keep`` for the points ``lo .. hi - 1`` not strictly inside every facet ``n . x + offset < 0`` (by
    ``margin``, mm)."""
    for i in range(lo, hi):
        for f in range(equations.shape[0]):
            e = equations[f]
            if points[i, 0] * e[0] + points[i, 1] * e[1] + points[i, 2] * e[2] + e[3] >= -margin:
                keep[i] = True
                break


def triangle_areas(points, triangles) -> np.ndarray:
    """Area of each triangle.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Vertex positions in mm.
    triangles : array_like of int, shape (m, 3)
        Vertex indices of each triangle.

    Returns
    -------
    ndarray, shape (m,), float64
        Areas in mm².
    """
    return 0.5 * row_lengths(triangle_cross_products(points, triangles))


def triangle_normals(points, triangles) -> np.ndarray:
    """Unit normal of each triangle (right-hand rule on the vertex order); zero for degenerate triangles.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Vertex positions in mm.
    triangles : array_like of int, shape (m, 3)
        Vertex indices of each triangle.

    Returns
    -------
    ndarray, shape (m, 3), float64
        Unit vectors (dimensionless).
    """
    cross = triangle_cross_products(points, triangles)
    return _normalise_rows(cross)


def row_lengths(vectors) -> np.ndarray:
    """Euclidean length of each row of an ``(n, 3)`` array, in its unit (``np.linalg.norm(vectors, axis=1)`` in
    one compiled pass, without its temporaries)."""
    return _row_lengths(kernel_array(np.asarray(vectors).reshape(-1, 3), np.float64))


@numba.njit(cache=True, nogil=True)
def _row_lengths(vectors):
    lengths = np.empty(vectors.shape[0])
    for i in range(vectors.shape[0]):
        x, y, z = vectors[i, 0], vectors[i, 1], vectors[i, 2]
        lengths[i] = math.sqrt(x * x + y * y + z * z)
    return lengths


def _normalise_rows(vectors: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Each row of ``vectors`` (n, 3) divided by its length into ``out`` (a new array when not given; ``vectors``
    itself may be given); zero rows, and rows with a NaN, give zero."""
    out = np.zeros(np.shape(vectors)) if out is None else out
    _unit_rows(kernel_array(vectors, np.float64), out)
    return out


@numba.njit(cache=True, nogil=True)
def _unit_rows(vectors, out):
    # each row is first divided by its largest component, so that rows of subnormal numbers (a scan of
    # 1e-160 mm) do not lose their length to underflow in the squares; a row is read before its unit is written
    # (``out`` may be ``vectors``' memory)
    for i in range(vectors.shape[0]):
        v0, v1, v2 = vectors[i, 0], vectors[i, 1], vectors[i, 2]
        out[i, 0] = out[i, 1] = out[i, 2] = 0.0
        scale = abs(v0)
        if abs(v1) > scale:
            scale = abs(v1)
        if abs(v2) > scale:
            scale = abs(v2)
        if not scale > 0.0:  # zero, or NaN
            continue
        x, y, z = v0 / scale, v1 / scale, v2 / scale
        length = math.sqrt(x * x + y * y + z * z)
        if length > 0.0:  # not NaN
            out[i, 0], out[i, 1], out[i, 2] = x / length, y / length, z / length


def _accumulate(triangles: np.ndarray, values: np.ndarray, n_points: int) -> np.ndarray:
    """Sum per-corner values (m, 3) or per-corner vectors (m, 3, k) onto the vertices."""
    flat_index = triangles.ravel()
    if values.ndim == 2:
        return np.bincount(flat_index, weights=values.ravel(), minlength=n_points)
    k = values.shape[2]
    flat = values.reshape(-1, k)
    return np.stack([np.bincount(flat_index, weights=flat[:, i], minlength=n_points) for i in range(k)], axis=1)


def vertex_normals(points, triangles) -> np.ndarray:
    """Area-weighted unit vertex normals.

    Each vertex normal is the normalised sum of the cross products ``(p1 - p0) x (p2 - p0)`` of its
    triangles, i.e. of the triangle normals weighted by twice the triangle areas.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Vertex positions in mm.
    triangles : array_like of int, shape (m, 3)
        Vertex indices of each triangle, counter-clockwise seen from the side the normals point to.

    Returns
    -------
    ndarray, shape (n, 3), float64
        Unit normals (dimensionless); zero vectors for vertices without a non-degenerate triangle.
    """
    return vertex_measures(points, triangles)[0]


def vertex_measures(points, triangles) -> tuple[np.ndarray, np.ndarray, float]:
    """:func:`vertex_normals`, the barycentric :func:`vertex_areas` (mm²) and the total area (mm²), in one pass over
    the triangles: ``(normals (n, 3), areas (n,), total)``; the normals and areas the same to the bit as those
    functions', the total the triangles' areas summed with compensation."""
    points, triangles = _kernel_mesh(points, triangles)
    normals, areas = np.empty((points.shape[0], 3)), np.empty(points.shape[0])
    total = _vertex_measures(points, triangles, normals, areas)
    return _normalise_rows(normals, normals), areas, float(total)


@numba.njit(cache=True)
def _vertex_measures(points, triangles, normals, areas):
    """:func:`vertex_measures` into ``normals`` (not yet normalised) and ``areas``; returns the total area. Each
    vertex's sums are taken in triangle order (as :func:`_vertex_sums`), the normal's and the area's side by side in
    one row."""
    sums = np.zeros((points.shape[0], 4))
    total = compensation = 0.0
    for t in range(triangles.shape[0]):
        c0, c1, c2 = _cross(points, triangles, t)
        area = 0.5 * math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
        third = area / 3.0
        s = total + area  # Neumaier's compensated sum
        compensation += (total - s) + area if total >= area else (area - s) + total
        total = s
        for i in range(3):
            v = triangles[t, i]
            sums[v, 0] += c0
            sums[v, 1] += c1
            sums[v, 2] += c2
            sums[v, 3] += third
    for v in range(points.shape[0]):
        normals[v, 0], normals[v, 1], normals[v, 2], areas[v] = sums[v, 0], sums[v, 1], sums[v, 2], sums[v, 3]
    return total + compensation


def vertex_areas(points, triangles, method: str = "barycentric") -> np.ndarray:
    """Each vertex's share of the surface area; the shares sum to the total area.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Vertex positions in mm.
    triangles : array_like of int, shape (m, 3)
        Vertex indices of each triangle.
    method : {"barycentric", "mixed_voronoi"}
        ``"barycentric"``: a third of each adjacent triangle's area. ``"mixed_voronoi"``: Meyer et
        al. (2003) mixed Voronoi areas (see the module docstring).

    Returns
    -------
    ndarray, shape (n,), float64
        Areas in mm² (zero for unreferenced vertices).
    """
    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64)
    if method == "barycentric":
        return barycentric_vertex_areas(triangles, triangle_areas(points, triangles), len(points))
    if method == "mixed_voronoi":
        return _accumulate(triangles, _mixed_voronoi_corner_areas(points, triangles), len(points))
    raise InvalidParameterError(f"unknown vertex area method {method!r}; use 'barycentric' or 'mixed_voronoi'.")


def barycentric_vertex_areas(triangles, triangle_areas, n_points: int) -> np.ndarray:
    """One third of the area of every adjacent triangle, from areas already computed.

    Parameters
    ----------
    triangles : array_like of int, shape (m, 3)
        Vertex indices of each triangle, each in ``0 .. n_points - 1`` (not checked here: the meshes that reach
        this are validated where they are built).
    triangle_areas : array_like, shape (m,)
        Area of each triangle in mm² (:func:`triangle_areas`).
    n_points : int
        Number of vertices.

    Returns
    -------
    ndarray, shape (n_points,), float64
        Areas in mm² (zero for unreferenced vertices).
    """
    triangles = kernel_array(np.asarray(triangles).reshape(-1, 3), np.int64)
    areas = kernel_array(np.asarray(triangle_areas).reshape(-1), np.float64)
    if areas.shape[0] != triangles.shape[0]:
        raise InvalidParameterError(
            f"barycentric_vertex_areas needs one area per triangle ({triangles.shape[0]}), not {areas.shape[0]}."
        )
    # one compiled pass, the same sums to the bit as a bincount of the thirds over the flattened corners, without
    # its (m, 3) weights
    return _vertex_sums(triangles, (areas / 3.0)[:, None], int(n_points))[:, 0]


def _mixed_voronoi_corner_areas(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Area of each triangle corner's share, (m, 3) mm², Meyer et al. (2003) section 3.3."""
    p = points[triangles]  # (m, 3 corners, 3 coordinates)
    # edge vectors leaving each corner i towards the next (i+1) and previous (i+2) corners
    to_next = np.roll(p, -1, axis=1) - p
    to_prev = np.roll(p, 1, axis=1) - p
    dot = np.einsum("mij,mij->mi", to_next, to_prev)  # |a||b| cos(angle at corner i)
    twice_area = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    area = 0.5 * twice_area
    # cot(angle at corner i) = dot_i / (2 A); the Voronoi share of corner i uses the opposite
    # angles of its two edges: A_i = (|e_next|² cot(angle at prev) + |e_prev|² cot(angle at next)) / 8
    safe = np.where(twice_area > 0, twice_area, 1.0)
    cot = dot / safe[:, None]
    len_next = np.einsum("mij,mij->mi", to_next, to_next)
    len_prev = np.einsum("mij,mij->mi", to_prev, to_prev)
    voronoi = (len_next * np.roll(cot, 1, axis=1) + len_prev * np.roll(cot, -1, axis=1)) / 8.0  # Meyer eq. (7)
    obtuse_corner = dot < 0
    obtuse = obtuse_corner.any(axis=1)
    shares = np.where(obtuse[:, None], np.where(obtuse_corner, 0.5, 0.25) * area[:, None], voronoi)
    shares[twice_area <= 0] = 0.0
    return shares


def longest_edges(points, triangles) -> np.ndarray:
    """Length of the longest edge of every triangle, (m,) in mm; one pass in numba, without an (m, 3) array of
    every edge's length (480 MB at 20M triangles)."""
    points, triangles = _kernel_mesh(points, triangles)
    return _longest_edges(points, triangles)


@numba.njit(cache=True)
def _longest_edges(points, triangles):
    """:func:`longest_edges`."""
    out = np.empty(triangles.shape[0])
    for t in range(triangles.shape[0]):
        longest = 0.0
        for i in range(3):
            a, b = triangles[t, i], triangles[t, (i + 1) % 3]
            d0, d1, d2 = points[b, 0] - points[a, 0], points[b, 1] - points[a, 1], points[b, 2] - points[a, 2]
            longest = max(longest, d0 * d0 + d1 * d1 + d2 * d2)
        out[t] = math.sqrt(longest)
    return out


def triangle_centroids(points, triangles) -> np.ndarray:
    """Centroid of every triangle, (m, 3) in mm; one pass in numba."""
    points, triangles = _kernel_mesh(points, triangles)
    return _centroids(points, triangles)


@numba.njit(cache=True)
def _centroids(points, triangles):
    """:func:`triangle_centroids`."""
    out = np.empty((triangles.shape[0], 3))
    for t in range(triangles.shape[0]):
        for i in range(3):
            out[t, i] = (points[triangles[t, 0], i] + points[triangles[t, 1], i] + points[triangles[t, 2], i]) / 3.0
    return out


def mean_edge_length(points, triangles) -> float:
    """Mean length of the unique edges, in mm (nan without triangles); the lengths summed with compensation in one
    pass over every vertex's corners (:func:`~translucency.geometry.topology.edge_census`), without a table of the
    edges."""
    if np.asarray(triangles).size == 0:
        return float("nan")
    census = edge_census(triangles, points, faces=False)
    return census.edge_length_sum / census.edges


def signed_volume(points, triangles, origin=None) -> float:
    """Signed volume enclosed by the triangles, in mm³ (positive for a closed, outward-oriented surface).

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Vertex positions in mm.
    triangles : array_like of int, shape (m, 3)
        Vertex indices of each triangle.
    origin : array_like, shape (3,), optional
        Apex of the tetrahedra summed (sum of ``(p0 - o) . ((p1 - o) x (p2 - o)) / 6``). For a closed
        surface the result does not depend on it; for an open one it does, and the centroid of the
        vertices (the default) makes the result measure whether the surface faces away from its
        centre.
    """
    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64)
    if origin is None:
        origin = points[np.unique(triangles)].mean(axis=0)
    p = points - np.asarray(origin, dtype=np.float64)
    p0, p1, p2 = p[triangles[:, 0]], p[triangles[:, 1]], p[triangles[:, 2]]
    return float(np.einsum("ij,ij->i", p0, np.cross(p1, p2)).sum() / 6.0)


#: The compiled kernels of a scan's normals, areas and edges, and its up axis (centroids, hull candidates): numba
#: compiles each on first use; the set-up compiles them ahead
#: (:mod:`translucency.app.warmup`).
CLEANING_KERNELS = (
    _cross_products,
    _row_lengths,
    _unit_rows,
    _vertex_sums,
    _vertex_measures,
    _degenerate,
    _longest_edges,
    _centroids,
    _centroid_blocks,
    _combined_centroids,
    _extremes,
    _outside_or_on,
)
