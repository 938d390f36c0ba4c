"""Closest points on a triangle mesh, exact and vectorised: the basis of the proxy-to-full-mesh mapping.

The closest point on a triangle is Ericson's (*Real-Time Collision Detection*, 2005, section 5.1.5: the
Voronoi regions of the vertices, edges and face of the triangle). Which triangles to try, for every query:

1. **a grid of grown spheres**: each triangle's bounding sphere about its centroid (radius ``R``, the largest
   centroid-to-corner distance) grown by a margin ``δ`` (:data:`GRID_MARGIN` times the median ``R``) is listed
   in the cells of a hierarchical grid that its box overlaps (at the level whose cells are at least the sphere's
   diameter: at most 8 cells each), and a query tries the triangles listed in its own cell at every level whose
   grown sphere holds it. A triangle nearer than ``d <= δ`` has its centroid within ``d + R <= δ + R`` of the
   query, so it is among them: a query found within ``δ`` of the surface is **certified** (the usual case of a
   scan's vertices against its proxy, which lie close to its surface);
2. the others: a k-d tree over the triangle centroids gives each its ``k`` nearest centroids, the nearest of
   those triangles wins, and the answer is certified per size class of triangles: one closer than the winner's
   distance ``d`` would have its centroid within ``d + R_class``, so queries whose ``k``-th centroid is nearer
   than that are searched again over every centroid of the class within ``d + R_class``.

The result is the exact closest triangle (ties: any of them). The barycentric weights are exact where it
matters for interpolation: a query that coincides with a vertex of the mesh gets the weight 1 on that vertex
and 0 on the others (the vertex regions are tested first and return exact one-hot weights), so values
interpolated at shared vertices are reproduced bit for bit.

============ ========================================================= =====
name         meaning                                                   unit
============ ========================================================= =====
distance     distance from the query to its closest surface point      mm
weights      barycentric coordinates of that point in its triangle     1
============ ========================================================= =====
"""

from __future__ import annotations

import math

import numba
import numpy as np
from scipy.spatial import cKDTree

from ..threads import for_ranges
from .topology import kernel_array

__all__ = ["closest_points_on_triangles", "closest_point_barycentric", "vertex_hausdorff_distance"]

#: Queries whose nearest centroids are looked up at once (bounds that step's memory: about 260 bytes each).
QUERY_CHUNK = 1 << 18
#: Step 1's margin δ, in median triangle radii: queries within δ of the surface are certified by the grid.
GRID_MARGIN = 0.5
#: Step 1's grid cells per axis at its finest level are counted in 19 bits (keys of 63 bits with 6 for the level):
#: a mesh wider than that many finest cells goes to step 2 whole.
GRID_BITS = 19


def closest_point_barycentric(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Barycentric coordinates of the closest point to ``p`` on triangles ``(a, b, c)``, vectorised.

    Parameters
    ----------
    p, a, b, c : ndarray, shape (..., 3)
        Query points and triangle corners (broadcast together), in mm.

    Returns
    -------
    ndarray, shape (..., 3)
        Weights ``(u, v, w)`` with ``u a + v b + w c`` the closest point; they are >= 0 and sum to 1.
        Degenerate triangles fall back to the nearest of their corners.
    """
    shape = np.broadcast_shapes(p.shape, a.shape, b.shape, c.shape)
    p, a, b, c = (np.broadcast_to(x, shape) for x in (p, a, b, c))
    ab, ac = b - a, c - a
    ap, bp, cp = p - a, p - b, p - c
    dot = lambda x, y: np.einsum("...i,...i->...", x, y)  # noqa: E731
    d1, d2 = dot(ab, ap), dot(ac, ap)
    d3, d4 = dot(ab, bp), dot(ac, bp)
    d5, d6 = dot(ab, cp), dot(ac, cp)
    vc = d1 * d4 - d3 * d2
    vb = d5 * d2 - d1 * d6
    va = d3 * d6 - d5 * d4
    out = np.empty(shape[:-1] + (3,), dtype=np.float64)
    done = np.zeros(shape[:-1], dtype=bool)

    def assign(mask, u, v, w):
        mask = mask & ~done
        out[..., 0] = np.where(mask, u, out[..., 0])
        out[..., 1] = np.where(mask, v, out[..., 1])
        out[..., 2] = np.where(mask, w, out[..., 2])
        done[...] |= mask

    with np.errstate(divide="ignore", invalid="ignore"):
        zero, one = np.zeros(shape[:-1]), np.ones(shape[:-1])
        assign((d1 <= 0) & (d2 <= 0), one, zero, zero)  # vertex region a
        assign((d3 >= 0) & (d4 <= d3), zero, one, zero)  # vertex region b
        assign((d6 >= 0) & (d5 <= d6), zero, zero, one)  # vertex region c
        t = d1 / (d1 - d3)
        assign((vc <= 0) & (d1 >= 0) & (d3 <= 0), 1 - t, t, zero)  # edge region ab
        t = d2 / (d2 - d6)
        assign((vb <= 0) & (d2 >= 0) & (d6 <= 0), 1 - t, zero, t)  # edge region ac
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        assign((va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0), zero, 1 - t, t)  # edge region bc
        denominator = va + vb + vc
        v, w = vb / denominator, vc / denominator
        assign(np.ones(shape[:-1], dtype=bool), 1 - v - w, v, w)  # face region
    # rounding leaves at most tiny negative weights; anything else is a (near-)degenerate triangle
    bad = ~np.all(np.isfinite(out), axis=-1) | np.any((out < -1e-6) | (out > 1 + 1e-6), axis=-1)
    if np.any(bad):  # degenerate triangles: nearest corner
        corner_distance = np.stack([dot(ap, ap), dot(bp, bp), dot(cp, cp)], axis=-1)
        nearest = np.argmin(corner_distance, axis=-1)
        one_hot = np.eye(3)[nearest]
        out = np.where(bad[..., None], one_hot, out)
    return np.clip(out, 0.0, 1.0)


def closest_points_on_triangles(query, points, triangles, *, k: int = 16):
    """Exact closest point on a triangle mesh for every query point.

    Parameters
    ----------
    query : array_like, shape (q, 3)
        Points to project, in mm.
    points : array_like, shape (n, 3)
        Vertex positions of the target mesh, in mm.
    triangles : array_like of int, shape (m, 3)
        Triangles of the target mesh (at least one).
    k : int, default 16
        Candidate triangles tried first per query (more only where needed for exactness).

    Returns
    -------
    triangle_index : ndarray, shape (q,), int64
        The closest triangle.
    weights : ndarray, shape (q, 3), float64
        Barycentric coordinates of the closest point in that triangle.
    distance : ndarray, shape (q,), float64
        Distance to the surface, in mm.

    Notes
    -----
    Step 1 (module docstring) answers the queries near the surface; step 2's certification is done per size
    class of triangles (radii within a factor of 2), so that a few large triangles do not widen the search for
    all queries. The scans over candidates are numba kernels (compiled once, cached on disk) run on every core.
    """
    query = np.ascontiguousarray(query, dtype=np.float64).reshape(-1, 3)
    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    corners = np.ascontiguousarray(points[triangles])  # (m, 3, 3)
    m = len(triangles)
    best_triangle = np.full(len(query), -1, dtype=np.int64)
    best_weights = np.zeros((len(query), 3), dtype=np.float64)
    best_distance = np.full(len(query), np.inf, dtype=np.float64)
    if len(query) == 0 or m == 0:
        return best_triangle, best_weights, best_distance
    centroid = corners.mean(axis=1)
    radius = np.linalg.norm(corners - centroid[:, None, :], axis=2).max(axis=1)
    corners = kernel_array(corners, np.float64)  # one signature, whatever the caller's arrays (kernel_array)

    # 1. the grid of grown spheres certifies the queries near the surface; the rest go on
    rest = np.flatnonzero(~_grid_pass(query, corners, centroid, radius, best_triangle, best_weights, best_distance))
    if rest.size:
        found = _nearest_search(query[rest], corners, centroid, radius, k)
        best_triangle[rest], best_weights[rest], best_distance[rest] = found
    return best_triangle, best_weights, best_distance


def _grid_pass(query, corners, centroid, radius, best_triangle, best_weights, best_distance) -> np.ndarray:
    """Step 1 of :func:`closest_points_on_triangles`: the best triangle of each query among those whose grown sphere
    holds it (written into ``best_*``), and which queries that certifies (within the margin of the surface)."""
    certified = np.zeros(len(query), dtype=bool)
    margin = GRID_MARGIN * float(np.median(radius))
    if not margin > 0.0:
        return certified
    grown = radius + margin
    finest = 2.0 * float(np.median(grown))
    low = (centroid - grown[:, None]).min(axis=0)  # the grid covers the triangles; a query outside goes on
    high = (centroid + grown[:, None]).max(axis=0)
    if np.max((high - low) / finest) >= 2**GRID_BITS - 1:
        return certified
    level = np.maximum(0, np.ceil(np.log2(2.0 * grown / finest))).astype(np.int64)  # cells of at least 2 grown radii
    sizes = finest * 2.0 ** np.arange(int(level.max()) + 1)
    size = sizes[level][:, None]
    first = np.floor((centroid - grown[:, None] - low) / size).astype(np.int64)
    last = np.floor((centroid + grown[:, None] - low) / size).astype(np.int64)  # first or first + 1 on each axis
    keys, members = [], []
    for step in np.ndindex(2, 2, 2):
        cell = first + np.array(step)
        inside = np.all(cell <= last, axis=1)
        keys.append(_cell_keys(level[inside], cell[inside]))
        members.append(np.flatnonzero(inside))
    keys, members = np.concatenate(keys), np.concatenate(members)
    order = np.argsort(keys, kind="stable")
    keys, members = keys[order], members[order]
    starts = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]])
    cells = keys[starts]
    starts = np.append(starts, keys.size)
    del keys, order
    for_ranges(
        _grid_rows,
        len(query),
        kernel_array(query, np.float64),
        corners,
        kernel_array(centroid, np.float64),
        kernel_array(grown * grown, np.float64),
        low,
        sizes,
        cells,
        starts,
        kernel_array(members, np.int64),
        best_triangle,
        best_weights,
        best_distance,
    )
    certified[:] = best_distance <= margin * (1.0 - 1e-9)  # rounding of the sphere test stays inside
    return certified


def _cell_keys(level, cell):
    """One int64 key per (level, cell index triple) of the grid of step 1."""
    return ((level * 2**GRID_BITS + cell[:, 0]) * 2**GRID_BITS + cell[:, 1]) * 2**GRID_BITS + cell[:, 2]


@numba.njit(cache=True, nogil=True)
def _grid_rows(
    worker,
    lo,
    hi,
    query,
    corners,
    centroid,
    grown2,
    low,
    sizes,
    cells,
    starts,
    members,
    best_triangle,
    best_weights,
    best_distance,
):  # pragma: no cover - compiled
    weights = np.empty(3)
    scale = 2**GRID_BITS
    for i in range(lo, hi):
        px, py, pz = query[i, 0], query[i, 1], query[i, 2]
        for level in range(sizes.shape[0]):
            s = sizes[level]
            ix = math.floor((px - low[0]) / s)
            iy = math.floor((py - low[1]) / s)
            iz = math.floor((pz - low[2]) / s)
            if min(ix, iy, iz) < 0 or max(ix, iy, iz) >= scale:  # outside the grid: in no triangle's grown sphere
                continue
            key = ((level * scale + ix) * scale + iy) * scale + iz
            at = np.searchsorted(cells, key)
            if at == cells.shape[0] or cells[at] != key:
                continue
            for j in range(starts[at], starts[at + 1]):
                t = members[j]
                dx, dy, dz = px - centroid[t, 0], py - centroid[t, 1], pz - centroid[t, 2]
                if dx * dx + dy * dy + dz * dz > grown2[t]:
                    continue
                _keep_closer(px, py, pz, corners, t, weights, i, best_triangle, best_weights, best_distance)


def _nearest_search(query, corners, centroid, radius, k):
    """Step 2 of :func:`closest_points_on_triangles` for ``query``: ``(triangle, weights, distance)``."""
    m = len(centroid)
    best_triangle = np.full(len(query), -1, dtype=np.int64)
    best_weights = np.zeros((len(query), 3), dtype=np.float64)
    best_distance = np.full(len(query), np.inf, dtype=np.float64)

    # 2a. the k nearest centroids: the exact answer unless a triangle is larger than their spread; in chunks of
    # queries, so that the k candidates of every query are never held at once (a distance and an index each)
    k = int(min(max(k, 1), m))
    centroids = cKDTree(centroid)
    kth_distance = np.empty(len(query))  # the k-th nearest centroid's distance, for 2b
    for first in range(0, len(query), QUERY_CHUNK):
        part = slice(first, min(len(query), first + QUERY_CHUNK))
        distance, candidate = centroids.query(query[part], k=k, workers=-1)
        kth_distance[part] = distance.reshape(-1, k)[:, -1]
        sub_triangle, sub_weights, sub_distance = best_triangle[part], best_weights[part], best_distance[part]
        _scan(
            kernel_array(query[part], np.float64),
            corners,
            kernel_array(candidate.reshape(-1, k), np.int64),
            sub_triangle,
            sub_weights,
            sub_distance,
        )
    del centroids
    if k == m:
        return best_triangle, best_weights, best_distance

    # 2b. certification per size class j (radii within a factor 2, largest R_j): a triangle of the
    # class can beat the best distance d only if its centroid lies within d + R_j; all centroids
    # nearer than the k-th one were examined, so only queries with the k-th centroid inside that
    # reach are searched again, over the class's centroids within reach
    floor = radius.max() * 1e-6 + 1e-300
    level = np.floor(np.log2(np.maximum(radius, floor))).astype(np.int64)
    for value in np.unique(level):
        members = np.flatnonzero(level == value)
        class_radius = float(radius[members].max())
        reach = best_distance * (1 + 1e-12) + class_radius * (1 + 1e-9) + 1e-300
        rows = np.flatnonzero(kth_distance <= reach)
        if len(rows) == 0:
            continue
        tree = cKDTree(centroid[members])
        for first in range(0, len(rows), QUERY_CHUNK):  # in chunks, as 2a
            part = rows[first : first + QUERY_CHUNK]
            nearest, _ = tree.query(query[part], k=1, workers=-1)
            _search_class(
                tree,
                members,
                query,
                part[nearest <= reach[part]],
                reach,
                corners,
                best_triangle,
                best_weights,
                best_distance,
            )
    return best_triangle, best_weights, best_distance


def _search_class(tree, members, query, rows, reach, corners, best_triangle, best_weights, best_distance):
    """Step 2 of :func:`closest_points_on_triangles` for one size class and some queries (``rows``): their
    nearest centroids of the class within ``reach``, 16 at first and four times more while all lie within it."""
    count = min(16, len(members))
    while len(rows):
        distance, local = tree.query(query[rows], k=count, workers=-1)
        distance = distance.reshape(len(rows), count)
        local = np.minimum(local.reshape(len(rows), count), len(members) - 1)
        inside = distance <= reach[rows, None]
        candidate = np.ascontiguousarray(np.where(inside, members[local], -1))
        sub_triangle, sub_weights, sub_distance = best_triangle[rows], best_weights[rows], best_distance[rows]
        _scan(
            kernel_array(query[rows], np.float64),
            corners,
            kernel_array(candidate, np.int64),
            sub_triangle,
            sub_weights,
            sub_distance,
        )
        best_triangle[rows], best_weights[rows], best_distance[rows] = sub_triangle, sub_weights, sub_distance
        if count >= len(members):
            break
        rows = rows[inside[:, -1]]  # all `count` nearest lie within reach: there may be more
        count = min(4 * count, len(members))


@numba.njit(cache=True, nogil=True)
def _closest_on_triangle(px, py, pz, corners, t, out):  # pragma: no cover - compiled
    # Ericson (2005) 5.1.5, the same region tests as closest_point_barycentric
    ax, ay, az = corners[t, 0, 0], corners[t, 0, 1], corners[t, 0, 2]
    bx, by, bz = corners[t, 1, 0], corners[t, 1, 1], corners[t, 1, 2]
    cx, cy, cz = corners[t, 2, 0], corners[t, 2, 1], corners[t, 2, 2]
    abx, aby, abz = bx - ax, by - ay, bz - az
    acx, acy, acz = cx - ax, cy - ay, cz - az
    apx, apy, apz = px - ax, py - ay, pz - az
    bpx, bpy, bpz = px - bx, py - by, pz - bz
    cpx, cpy, cpz = px - cx, py - cy, pz - cz
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    vc = d1 * d4 - d3 * d2
    vb = d5 * d2 - d1 * d6
    va = d3 * d6 - d5 * d4
    u, v, w = 0.0, 0.0, 0.0
    degenerate = False
    if d1 <= 0.0 and d2 <= 0.0:  # vertex region a
        u = 1.0
    elif d3 >= 0.0 and d4 <= d3:  # vertex region b
        v = 1.0
    elif d6 >= 0.0 and d5 <= d6:  # vertex region c
        w = 1.0
    elif vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:  # edge region ab
        if d1 - d3 != 0.0:
            v = d1 / (d1 - d3)
            u = 1.0 - v
        else:
            degenerate = True
    elif vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:  # edge region ac
        if d2 - d6 != 0.0:
            w = d2 / (d2 - d6)
            u = 1.0 - w
        else:
            degenerate = True
    elif va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:  # edge region bc
        if (d4 - d3) + (d5 - d6) != 0.0:
            w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
            v = 1.0 - w
        else:
            degenerate = True
    else:  # face region
        denominator = va + vb + vc
        if denominator != 0.0:
            v = vb / denominator
            w = vc / denominator
            u = 1.0 - v - w
        tolerance = 1e-6
        if denominator == 0.0 or not (
            -tolerance <= u <= 1 + tolerance and -tolerance <= v <= 1 + tolerance and -tolerance <= w <= 1 + tolerance
        ):
            degenerate = True
    if degenerate:  # nearest corner
        da = apx * apx + apy * apy + apz * apz
        db = bpx * bpx + bpy * bpy + bpz * bpz
        dc = cpx * cpx + cpy * cpy + cpz * cpz
        u, v, w = 0.0, 0.0, 0.0
        if da <= db and da <= dc:
            u = 1.0
        elif db <= dc:
            v = 1.0
        else:
            w = 1.0
    u = min(max(u, 0.0), 1.0)
    v = min(max(v, 0.0), 1.0)
    w = min(max(w, 0.0), 1.0)
    out[0] = u
    out[1] = v
    out[2] = w
    qx = u * ax + v * bx + w * cx - px
    qy = u * ay + v * by + w * cy - py
    qz = u * az + v * bz + w * cz - pz
    return np.sqrt(qx * qx + qy * qy + qz * qz)


@numba.njit(cache=True, nogil=True, inline="always")
def _keep_closer(px, py, pz, corners, t, weights, i, best_triangle, best_weights, best_distance):  # pragma: no cover
    """Query ``i`` at ``(px, py, pz)`` takes triangle ``t`` as its best when its closest point is nearer."""
    d = _closest_on_triangle(px, py, pz, corners, t, weights)
    if d < best_distance[i]:
        best_distance[i] = d
        best_triangle[i] = t
        best_weights[i, 0] = weights[0]
        best_weights[i, 1] = weights[1]
        best_weights[i, 2] = weights[2]


#: Scan candidate triangles for the closest point (module level: numba caches a closure's kernel under a new key
#: in every process, so it compiled again on every run and its cache grew by one file each time).
@numba.njit(cache=True, nogil=True)
def _scan_rows(
    worker, lo, hi, query, corners, candidates, best_triangle, best_weights, best_distance
):  # pragma: no cover
    weights = np.empty(3)
    for i in range(lo, hi):
        px, py, pz = query[i, 0], query[i, 1], query[i, 2]
        for j in range(candidates.shape[1]):
            t = candidates[i, j]
            if t < 0:
                continue
            _keep_closer(px, py, pz, corners, t, weights, i, best_triangle, best_weights, best_distance)


def _scan(query, corners, candidates, best_triangle, best_weights, best_distance) -> None:
    """Keep in ``best_*`` the closest point of each query (row of ``query``, mm) over its ``candidates`` (triangle
    rows, -1 for none) where it beats the best so far; the rows on :func:`~translucency.threads.for_ranges`' threads."""
    for_ranges(_scan_rows, query.shape[0], query, corners, candidates, best_triangle, best_weights, best_distance)


def vertex_hausdorff_distance(points_a, triangles_a, points_b, triangles_b) -> float:
    """Symmetric Hausdorff distance between two meshes, sampled at their vertices, in mm.

    ``max(max_{v in A} d(v, B), max_{v in B} d(v, A))`` with exact point-to-surface distances; a
    lower bound of the continuous Hausdorff distance that is tight for meshes much finer than their
    curvature.
    """
    used_a = np.unique(np.asarray(triangles_a))
    used_b = np.unique(np.asarray(triangles_b))
    _, _, a_to_b = closest_points_on_triangles(np.asarray(points_a)[used_a], points_b, triangles_b)
    _, _, b_to_a = closest_points_on_triangles(np.asarray(points_b)[used_b], points_a, triangles_a)
    return float(max(a_to_b.max(), b_to_a.max()))
