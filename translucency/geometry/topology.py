"""Topology of a triangle list: unique edges, components, boundary loops and fans.

Pure functions of ``triangles`` (m, 3) int64; they count and label, they neither validate nor repair
(:mod:`translucency.io.defects` builds the repair inventory from them). The edges are bucketed by their
smaller vertex and the components joined by union-find in numba, in time linear in the triangles (sorting
every corner edge, as ``np.unique`` does, grows as ``m log m`` and dominates the cleaning of a large scan).

Corners ``(t, i)`` are numbered ``3 t + i`` (the "slot" of corner i of triangle t); the edge of slot
``3 t + i`` runs from corner i to corner i + 1.
"""

from __future__ import annotations

import dataclasses

import numba
import numpy as np
from scipy import sparse
from scipy.sparse import csgraph

__all__ = [
    "CLEANING_KERNELS",
    "EdgeCensus",
    "edge_census",
    "kernel_array",
    "corner_starts",
    "unique_edges",
    "corner_edge_numbers",
    "face_components",
    "manifold_pairs",
    "boundary_loops",
    "next_corner",
    "count_non_manifold_vertices",
]


def kernel_array(values, dtype) -> np.ndarray:
    """``values`` as a C-contiguous, read-only array of ``dtype`` (a view; a copy only when the type or layout
    differ), the one form this package's numba kernels are compiled for: a writable and a read-only array are
    two types to numba, and a mesh's arrays come both ways (each would compile again on a first run)."""
    array = np.ascontiguousarray(values, dtype=dtype).view()
    array.flags.writeable = False
    return array


def index_dtype(count: int):
    """The integer type of the numbers ``0 .. count - 1`` in the kernels' tables: int32 where they fit (half the
    memory of int64), int64 from 2**31 - 1 on."""
    return np.int32 if count < 2**31 - 1 else np.int64


def unique_edges(triangles) -> tuple[np.ndarray, np.ndarray]:
    """Undirected edges of a triangle list and, for each triangle corner edge, its edge number.

    Parameters
    ----------
    triangles : array_like of int, shape (m, 3)

    Returns
    -------
    edges : ndarray, shape (e, 2), int64
        Unique edges with the smaller index first, in increasing order of (smaller, larger) index.
    edge_of_corner : ndarray, shape (m, 3), int64
        ``edges[edge_of_corner[t, i]]`` is the edge from corner i to corner i+1 of triangle t.
    """
    count, larger, smaller, edge_of_slot = _numbered(triangles)
    edges = np.empty((count, 2), dtype=np.int64)
    edges[:, 0], edges[:, 1] = smaller[:count], larger[:count]
    return edges, edge_of_slot.astype(np.int64, copy=False).reshape(-1, 3)


def corner_edge_numbers(triangles) -> tuple[np.ndarray, int]:
    """:func:`unique_edges`' ``edge_of_corner`` and the number of edges, without the edges: int32 where the corners
    are fewer than 2**31 (:func:`unique_edges` widens them to int64)."""
    count, _, _, edge_of_slot = _numbered(triangles)
    return edge_of_slot.reshape(-1, 3), int(count)


def _numbered(triangles):
    """:func:`_numbered_edges` of ``triangles``, numbered in int32 where the corners are fewer than 2**31 (one
    compiled kernel for :func:`unique_edges` and :func:`corner_edge_numbers`)."""
    triangles, n = _edge_inputs(triangles)
    return _numbered_edges(triangles, n, np.empty(0, dtype=index_dtype(max(3 * triangles.shape[0], n))))


def _edge_inputs(triangles):
    """``(triangles as the kernels take them, number of vertices they index)``."""
    triangles = kernel_array(np.asarray(triangles, dtype=np.int64).reshape(-1, 3), np.int64)
    return triangles, int(triangles.max()) + 1 if triangles.size else 1


def duplicate_triangles(triangles) -> np.ndarray:
    """True for each triangle on the same three vertices (in any order) as an earlier one, ``(m,)`` bool.

    Triangles are put into buckets by their smallest vertex and compared within a bucket only (linear
    time, where a sort of 24-byte keys grows as ``m log m``).
    """
    triangles = kernel_array(np.asarray(triangles, dtype=np.int64).reshape(-1, 3), np.int64)
    n = int(triangles.max()) + 1 if triangles.size else 1
    return _duplicate_triangles(triangles, n)


@numba.njit(cache=True)
def _duplicate_triangles(triangles, n):
    """:func:`duplicate_triangles`."""
    m = triangles.shape[0]
    low = np.empty(m, dtype=np.int64)
    key = np.empty(m, dtype=np.int64)  # the other two vertices, as one number: middle * n + largest
    start = np.zeros(n + 1, dtype=np.int64)
    for t in range(m):
        a, b, c = triangles[t, 0], triangles[t, 1], triangles[t, 2]
        lo, hi = min(a, b, c), max(a, b, c)
        low[t] = lo
        key[t] = (a + b + c - lo - hi) * n + hi
        start[lo + 1] += 1
    for v in range(n):
        start[v + 1] += start[v]
    fill = start[:-1].copy()
    members = np.empty(m, dtype=np.int64)
    for t in range(m):  # in increasing t: each bucket lists its triangles in their order
        members[fill[low[t]]] = t
        fill[low[t]] += 1
    duplicate = np.zeros(m, dtype=np.bool_)
    for v in range(n):
        lo, hi = start[v], start[v + 1]
        if hi - lo > _INSERTION_SORT_LIMIT:  # a large fan: sort by key (stable), then compare neighbours
            bucket = members[lo:hi]
            bucket = bucket[np.argsort(key[bucket], kind="mergesort")]
            for k in range(1, bucket.size):
                duplicate[bucket[k]] = key[bucket[k]] == key[bucket[k - 1]]
        else:
            for i in range(lo, hi):
                for j in range(i + 1, hi):
                    if key[members[j]] == key[members[i]]:
                        duplicate[members[j]] = True
    return duplicate


def first_at_same_position(points) -> np.ndarray:
    """For each point, the first point at exactly its position (itself when it is the first), ``(n,)`` int64.

    ``-0.0`` and ``0.0`` are the same position. One pass with a hash table of the coordinates' bits
    (linear time, where a sort of 24-byte keys grows as ``n log n``).
    """
    points = np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 3))
    return _first_at_same_position(kernel_array(points.view(np.uint64), np.uint64))


@numba.njit(cache=True, inline="always")
def _position_bits(bits, i, k):
    """Bit pattern of coordinate ``k`` of point ``i``, that of ``0.0`` for ``-0.0`` (the same position)."""
    b = bits[i, k]
    return np.uint64(0) if b == np.uint64(0x8000000000000000) else b


@numba.njit(cache=True)
def _first_at_same_position(bits):
    """:func:`first_at_same_position` on the coordinates' bit patterns, by open addressing."""
    n = bits.shape[0]
    size = 1
    while size < 2 * n:
        size *= 2
    mask = np.uint64(size - 1)
    table = np.full(size, -1, dtype=np.int64)
    first = np.empty(n, dtype=np.int64)
    for i in range(n):
        x, y, z = _position_bits(bits, i, 0), _position_bits(bits, i, 1), _position_bits(bits, i, 2)
        h = x * np.uint64(0x9E3779B97F4A7C15)
        h ^= y * np.uint64(0xC2B2AE3D27D4EB4F)
        h ^= z * np.uint64(0x165667B19E3779F9)
        h ^= h >> np.uint64(29)
        slot = h & mask
        while True:
            j = table[slot]
            if j < 0:
                table[slot] = i
                first[i] = i
                break
            if _position_bits(bits, j, 0) == x and _position_bits(bits, j, 1) == y and _position_bits(bits, j, 2) == z:
                first[i] = j
                break
            slot = (slot + np.uint64(1)) & mask
    return first


#: A bucket of edges that share their smaller vertex is sorted by insertion up to this size, by numpy above.
_INSERTION_SORT_LIMIT = 32


@numba.njit(cache=True)
def _numbered_edges(triangles, n, like):
    """:func:`unique_edges`: the corner edges counted into buckets by their smaller vertex, each bucket sorted
    by the larger one, numbered in that order. Returns ``(count, larger, smaller, edge_of_slot)``: edge ``e <
    count`` is ``(smaller[e], larger[e])``; the numbers in ``like``'s integer type."""
    m = triangles.shape[0]
    start = np.zeros(n + 1, dtype=np.int64)
    for t in range(m):
        for i in range(3):
            start[min(triangles[t, i], triangles[t, (i + 1) % 3]) + 1] += 1
    for v in range(n):
        start[v + 1] += start[v]
    fill = start[:-1].copy()
    larger = np.empty(3 * m, dtype=like.dtype)
    slot_of = np.empty(3 * m, dtype=like.dtype)
    for t in range(m):
        for i in range(3):
            a, b = triangles[t, i], triangles[t, (i + 1) % 3]
            k = fill[min(a, b)]
            fill[min(a, b)] += 1
            larger[k] = max(a, b)
            slot_of[k] = 3 * t + i
    edge_of_slot = np.empty(3 * m, dtype=like.dtype)
    # edge ``e`` is (slot_of[e], larger[e]) once its bucket is done: written over entries already read (``e`` is never
    # past the entry read), so no (3 m, 2) array of the corner edges is held
    count = 0
    for v in range(n):
        lo, hi = start[v], start[v + 1]
        if hi - lo > _INSERTION_SORT_LIMIT:
            order = np.argsort(larger[lo:hi], kind="mergesort")
            larger[lo:hi] = larger[lo:hi][order]
            slot_of[lo:hi] = slot_of[lo:hi][order]
        else:
            for k in range(lo + 1, hi):
                key, slot = larger[k], slot_of[k]
                j = k - 1
                while j >= lo and (larger[j] > key or (larger[j] == key and slot_of[j] > slot)):
                    larger[j + 1] = larger[j]
                    slot_of[j + 1] = slot_of[j]
                    j -= 1
                larger[j + 1] = key
                slot_of[j + 1] = slot
        for k in range(lo, hi):
            slot = slot_of[k]
            if k == lo or larger[k] != larger[k - 1]:
                larger[count] = larger[k]
                slot_of[count] = v
                count += 1
            edge_of_slot[slot] = count - 1
    return count, larger, slot_of, edge_of_slot


@dataclasses.dataclass(frozen=True)
class EdgeCensus:
    """What :func:`edge_census` counts of a triangle list, with the definitions of :mod:`translucency.io.defects`.

    Attributes
    ----------
    null_faces : int
        Triangles with a repeated vertex index (when there are any, the counts below that need distinct corners are
        not meaningful: count ``triangles`` without them).
    unreferenced_vertices : int
        Vertices ``0 .. n - 1`` that no triangle uses.
    edges : int
        Unique undirected edges (:func:`unique_edges`' count).
    boundary_edges : ndarray, shape (b, 2), int64
        The edges of exactly one triangle, the smaller index first.
    non_manifold_edges, inconsistent_edges, non_manifold_vertices : int
        Edges of more than two triangles; edges of two triangles that run them the same way; vertices whose
        triangles form more than one fan.
    duplicate : ndarray of bool, shape (m,)
        :func:`duplicate_triangles` (empty when ``faces`` was False).
    components : int
        :func:`face_components`' count (0 when ``faces`` was False).
    labels : ndarray, shape (m,), int64
        :func:`face_components`' labels (empty when ``faces`` was False).
    edge_length_sum : float
        Sum of the unique edges' lengths in the points' unit (0 without points).
    """

    null_faces: int
    unreferenced_vertices: int
    edges: int
    boundary_edges: np.ndarray
    non_manifold_edges: int
    inconsistent_edges: int
    non_manifold_vertices: int
    duplicate: np.ndarray
    components: int
    labels: np.ndarray
    edge_length_sum: float


def edge_census(triangles, points=None, *, lengths: bool = True, faces: bool = True) -> EdgeCensus:
    """Count the edges, fans, duplicate triangles and face components of a triangle list in one pass over each
    vertex's corners (the corners grouped by vertex with a counting sort, then every vertex's star on its own).

    Parameters
    ----------
    triangles : array_like of int, shape (m, 3)
    points : array_like, shape (n, 3), optional
        Vertex positions (any length unit); ``n`` is their count (without them, ``triangles.max() + 1``).
    lengths : bool, default True
        Sum the unique edges' lengths (with ``points``).
    faces : bool, default True
        Count what needs the triangles' identity too (fans, inconsistent edges, duplicates, components); False
        counts the edges, their lengths and the boundary alone.

    Returns
    -------
    EdgeCensus
    """
    triangles, n = _edge_inputs(triangles)
    measured = np.empty((0, 3))
    if points is not None:
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        n = points.shape[0]
        measured = points if lengths else measured
    measured = kernel_array(measured, np.float64)
    like = np.empty(0, dtype=index_dtype(max(3 * triangles.shape[0], n)))
    counts, boundary, duplicate, components, labels, length = _census(triangles, n, measured, bool(faces), like)
    null, unreferenced, edges, non_manifold_edges, inconsistent, non_manifold_vertices = (int(c) for c in counts)
    return EdgeCensus(
        null_faces=null,
        unreferenced_vertices=unreferenced,
        edges=edges,
        boundary_edges=boundary,
        non_manifold_edges=non_manifold_edges,
        inconsistent_edges=inconsistent,
        non_manifold_vertices=non_manifold_vertices,
        duplicate=duplicate,
        components=int(components),
        labels=labels,
        edge_length_sum=float(length),
    )


@numba.njit(cache=True, nogil=True)
def corner_starts(triangles, n, like):
    """Where each of ``n`` vertices' corners start in the list of ``triangles``' corners grouped by vertex, the
    first pass of a counting sort: ``starts (n + 1,)`` in ``like``'s type, vertex ``v``'s corners at ``starts[v] ..
    starts[v + 1] - 1``. The callers fill the list, each with what it keeps of a corner, triangle by triangle
    (``fill = starts[:-1].copy()``), so that a vertex's corners are in triangle order."""
    starts = np.zeros(n + 1, dtype=like.dtype)
    for t in range(triangles.shape[0]):
        for c in range(3):
            starts[triangles[t, c] + 1] += 1
    for v in range(n):
        starts[v + 1] += starts[v]
    return starts


@numba.njit(cache=True)
def _stars(triangles, n, like):
    """The corners grouped by vertex, in triangle order within a vertex: ``(start, star, null)``, rows ``start[v] ..
    start[v + 1] - 1`` of ``star`` the ``(slot, next vertex, previous vertex)`` of the corners at ``v``; ``null`` the
    triangles with a repeated index."""
    m = triangles.shape[0]
    start = corner_starts(triangles, n, np.empty(0, dtype=np.int64))
    null = 0
    for t in range(m):
        a, b, c = triangles[t, 0], triangles[t, 1], triangles[t, 2]
        if a == b or b == c or a == c:
            null += 1
    fill = start[:-1].copy()
    star = np.empty((3 * m, 3), dtype=like.dtype)
    for t in range(m):
        for i in range(3):
            v = triangles[t, i]
            k = fill[v]
            fill[v] = k + 1
            star[k, 0] = 3 * t + i
            star[k, 1] = triangles[t, (i + 1) % 3]
            star[k, 2] = triangles[t, (i + 2) % 3]
    return start, star, null


@numba.njit(cache=True)
def _sort_ends(ends, code, k):
    """Sort ``ends[:k]`` (stable), ``code`` along: by insertion when short, else by a merge sort."""
    if k > 2 * _INSERTION_SORT_LIMIT:
        order = np.argsort(ends[:k], kind="mergesort")
        ends[:k] = ends[:k][order]
        code[:k] = code[:k][order]
        return
    for i in range(1, k):
        key, value = ends[i], code[i]
        j = i - 1
        while j >= 0 and ends[j] > key:
            ends[j + 1] = ends[j]
            code[j + 1] = code[j]
            j -= 1
        ends[j + 1] = key
        code[j + 1] = value


@numba.njit(cache=True)
def _mark_duplicates(star, lo, hi, v, n, keys, members, duplicate):
    """Mark, among the corners ``lo .. hi - 1`` at their triangle's smallest vertex ``v``, each triangle on the same
    other two vertices as an earlier one (:func:`duplicate_triangles`); returns how many."""
    count = 0
    for k in range(lo, hi):
        a, b = star[k, 1], star[k, 2]
        if a > v and b > v:
            keys[count] = min(a, b) * n + max(a, b)
            members[count] = star[k, 0] // 3
            count += 1
    found = 0
    if count > _INSERTION_SORT_LIMIT:
        order = np.argsort(keys[:count], kind="mergesort")
        for i in range(1, count):
            if keys[order[i]] == keys[order[i - 1]]:
                duplicate[members[order[i]]] = True
                found += 1
        return found
    for i in range(1, count):
        for j in range(i):
            if keys[j] == keys[i]:
                duplicate[members[i]] = True
                found += 1
                break
    return found


@numba.njit(cache=True, inline="always")
def _add(total, compensation, x):
    """Neumaier's compensated sum: ``(total + x, its compensation)``."""
    s = total + x
    if abs(total) >= abs(x):
        compensation += (total - s) + x
    else:
        compensation += (x - s) + total
    return s, compensation


@numba.njit(cache=True)
def _census(triangles, n, points, faces, like):
    """:func:`edge_census`: ``(counts, boundary edges, duplicate, components, labels, edge length sum)``."""
    m = triangles.shape[0]
    start, star, null = _stars(triangles, n, like)
    widest = 1
    for v in range(n):
        widest = max(widest, start[v + 1] - start[v])
    ends = np.empty(2 * widest, dtype=np.int64)
    code = np.empty(2 * widest, dtype=np.int64)  # 2 * corner in the star + 1 where the end is the corner's next
    fan = np.empty(widest, dtype=np.int64)
    keys = np.empty(widest, dtype=np.int64)
    members = np.empty(widest, dtype=np.int64)
    parent = np.empty(m if faces else 0, dtype=like.dtype)
    for t in range(parent.shape[0]):
        parent[t] = t
    duplicate = np.zeros(m if faces else 0, dtype=np.bool_)
    boundary = np.empty((64, 2), dtype=np.int64)
    found = 0  # boundary edges
    counts = np.zeros(6, dtype=np.int64)  # null, unreferenced, edges, non-manifold edges, inconsistent, fans
    counts[0] = null
    total = compensation = 0.0
    for v in range(n):
        lo, hi = start[v], start[v + 1]
        if lo == hi:
            counts[1] += 1
            continue
        k = 0
        for j in range(hi - lo):
            ends[k], code[k] = star[lo + j, 1], 2 * j + 1
            ends[k + 1], code[k + 1] = star[lo + j, 2], 2 * j
            k += 2
            fan[j] = j
        _sort_ends(ends, code, k)
        first = 0
        while first < k:
            w, last = ends[first], first + 1
            while last < k and ends[last] == w:
                last += 1
            size = last - first
            if w == v:  # an edge from v to itself (a triangle with a repeated index)
                counts[2] += 1
            elif w > v:
                counts[2] += 1
                if points.shape[0]:
                    d0, d1, d2 = points[v, 0] - points[w, 0], points[v, 1] - points[w, 1], points[v, 2] - points[w, 2]
                    total, compensation = _add(total, compensation, np.sqrt(d0 * d0 + d1 * d1 + d2 * d2))
                if size == 1:
                    if found == boundary.shape[0]:
                        boundary = np.concatenate((boundary, np.empty_like(boundary)))
                    boundary[found, 0], boundary[found, 1] = v, w
                    found += 1
                elif size > 2:
                    counts[3] += 1
            if faces and size == 2 and w != v:
                j1, j2 = code[first] >> 1, code[first + 1] >> 1
                _join(fan, j1, j2)
                if w > v:
                    if (code[first] & 1) == (code[first + 1] & 1):  # both run the edge the same way
                        counts[4] += 1
                    _join(parent, star[lo + j1, 0] // 3, star[lo + j2, 0] // 3)
            first = last
        if faces:
            roots = 0
            for j in range(hi - lo):
                if fan[j] == j:
                    roots += 1
            if roots > 1:
                counts[5] += 1
            _mark_duplicates(star, lo, hi, v, n, keys, members, duplicate)
    components, labels = _labels(parent)
    return counts, boundary[:found].copy(), duplicate, components, labels, total + compensation


@numba.njit(cache=True, inline="always")
def _root(parent, x):
    """Root of ``x`` in the union-find forest ``parent``, halving the path on the way."""
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


@numba.njit(cache=True, inline="always")
def _join(parent, a, b):
    """Join the sets of ``a`` and ``b`` (the larger root under the smaller)."""
    ra, rb = _root(parent, a), _root(parent, b)
    if ra < rb:
        parent[rb] = ra
    elif rb < ra:
        parent[ra] = rb


@numba.njit(cache=True)
def _labels(parent):
    """Component labels ``0, 1, ...`` numbered in the order of each component's first node (as scipy's
    ``connected_components`` numbers them) and their count."""
    size = parent.shape[0]
    label = np.full(size, -1, dtype=np.int64)
    count = 0
    for x in range(size):
        r = _root(parent, x)
        if label[r] < 0:
            label[r] = count
            count += 1
        label[x] = label[r]
    return count, label


@numba.njit(cache=True)
def _manifold_pairs(edge_of_slot, faces_per_edge):
    """The two corner slots of every manifold edge (edge of exactly two triangles), the smaller first."""
    first = np.full(faces_per_edge.shape[0], -1, dtype=np.int64)
    pairs = np.empty((edge_of_slot.shape[0] // 2, 2), dtype=np.int64)
    count = 0
    for s in range(edge_of_slot.shape[0]):
        e = edge_of_slot[s]
        if faces_per_edge[e] != 2:
            continue
        if first[e] < 0:
            first[e] = s
        else:
            pairs[count, 0] = first[e]
            pairs[count, 1] = s
            count += 1
    return pairs[:count]


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


def face_components(
    triangles: np.ndarray, edge_of_corner: np.ndarray | None = None, pairs: np.ndarray | None = None
) -> tuple[int, np.ndarray]:
    """Connected components of triangles linked through manifold edges (edges of exactly two triangles).

    A triangle hanging on a non-manifold edge, or touching the rest only at a vertex, is a
    component of its own.

    Parameters
    ----------
    triangles : ndarray, shape (m, 3), int64
    edge_of_corner : ndarray, shape (m, 3), optional
        From :func:`unique_edges` (computed when not given).
    pairs : ndarray, shape (k, 2), optional
        From :func:`manifold_pairs` (computed when not given).

    Returns
    -------
    count : int
    labels : ndarray, shape (m,), int64
        Component number of each triangle.
    """
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if pairs is None:
        if edge_of_corner is None:
            _, edge_of_corner = unique_edges(triangles)
        pairs = manifold_pairs(edge_of_corner)
    count, labels = _face_components(pairs, len(triangles))
    return int(count), labels


def manifold_pairs(edge_of_corner: np.ndarray, faces_per_edge: np.ndarray | None = None) -> np.ndarray:
    """The two corner slots (``3 t + i``) of every edge of exactly two triangles, ``(k, 2)`` int64, for
    :func:`face_components` and :func:`count_non_manifold_vertices` (``faces_per_edge``: computed when not
    given)."""
    slot_edge = kernel_array(np.asarray(edge_of_corner).ravel(), np.int64)
    if faces_per_edge is None:
        faces_per_edge = np.bincount(slot_edge)
    return _manifold_pairs(slot_edge, kernel_array(faces_per_edge, np.int64))


@numba.njit(cache=True)
def _face_components(pairs, m):
    """:func:`face_components` by union-find over the manifold edges' pairs of slots."""
    parent = np.arange(m)
    for k in range(pairs.shape[0]):
        _join(parent, pairs[k, 0] // 3, pairs[k, 1] // 3)
    return _labels(parent)


def next_corner(slot: np.ndarray) -> np.ndarray:
    """Slot 3 t + i -> slot 3 t + (i + 1) % 3 (the corner at the end of edge i of triangle t)."""
    return slot - slot % 3 + (slot % 3 + 1) % 3


def count_non_manifold_vertices(
    triangles: np.ndarray, edge_of_corner: np.ndarray, faces_per_edge: np.ndarray, n: int, pairs=None
) -> int:
    """Vertices whose incident triangles form more than one fan (linked through manifold edges).

    Corners (t, i) are graph nodes 3 t + i; a manifold edge links, at each of its two end vertices,
    the corners of its two triangles; the fans are the connected components of that graph. ``pairs``:
    :func:`manifold_pairs`, computed when not given.
    """
    if pairs is None:
        pairs = manifold_pairs(edge_of_corner, faces_per_edge)
    return int(_non_manifold_vertices(pairs, kernel_array(np.asarray(triangles).ravel(), np.int64), n))


@numba.njit(cache=True)
def _non_manifold_vertices(pairs, corner_vertex, n):
    """:func:`count_non_manifold_vertices`: the corners joined across manifold edges by union-find, then the
    vertices whose corners have more than one root."""
    parent = np.arange(corner_vertex.shape[0])
    for k in range(pairs.shape[0]):
        first, second = pairs[k, 0], pairs[k, 1]
        first_next = first - first % 3 + (first % 3 + 1) % 3
        second_next = second - second % 3 + (second % 3 + 1) % 3
        if corner_vertex[first] == corner_vertex[second]:
            _join(parent, first, second)
            _join(parent, first_next, second_next)
        else:
            _join(parent, first, second_next)
            _join(parent, first_next, second)
    fan = np.full(n, -1, dtype=np.int64)
    split = np.zeros(n, dtype=np.bool_)
    for c in range(corner_vertex.shape[0]):
        v = corner_vertex[c]
        r = _root(parent, c)
        if fan[v] < 0:
            fan[v] = r
        elif fan[v] != r:
            split[v] = True
    return np.count_nonzero(split)


#: The compiled kernels of a scan's defect count (edges, components, non-manifold and duplicate elements): numba
#: compiles each on first use; the set-up compiles them ahead
#: (:mod:`translucency.app.warmup`).
CLEANING_KERNELS = (
    _numbered_edges,
    _census,
    _manifold_pairs,
    _face_components,
    _non_manifold_vertices,
    _duplicate_triangles,
    _first_at_same_position,
)
