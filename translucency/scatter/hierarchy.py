"""A hierarchy over the source vertices (a binary kd-tree with bounding spheres) and its error criterion.

The structure depends on the geometry only and is reused when the light or the material changes;
the aggregated sources at the nodes depend on the incident flux and are recomputed per solve (cheap,
bottom-up). A node seen from a receiver under a small enough angle is replaced by one aggregated
source (Jensen & Buhler 2002; docs/physics.md §8.3): total flux per channel, flux-weighted position,
flux-weighted normal and refracted direction (both renormalised).

Criterion (:class:`Opening`, the relative opening criterion of Springel 2005 for this kernel): a node is
accepted when the receiver is farther than ``min_distance`` from its bounding sphere, ``radius / distance <
theta`` (at most :data:`THETA_MAX`), and the estimate of its aggregate's error, ``radius^2 (1 / distance^2 +
sigma_tr^2)`` times its flux times a pair's magnitude at its nearest distance (the bound of §8.4, at most
:data:`LARGEST_MARGIN` times the largest ``S_d`` of sampled geometries there), is at most ``eps`` of the
receiver's ``B`` as a first walk (the first two tests alone) estimates it. Clusters whose share of ``B`` is small
are taken at a wide angle; only those that make much of ``B`` are opened far down (docs/physics.md §8.3).
The tree is walked once per small group of neighbouring receivers, with the distance from the group's
bounding sphere (conservative for each member), by :mod:`translucency.scatter.treewalk`, where neighbouring
groups share the upper part of their walk.

========== ========================================================== =====
symbol     meaning                                                    unit
========== ========================================================== =====
theta      opening ratio: bounding radius over distance               1
radius     bounding-sphere radius of a node (about its box centre)    mm
========== ========================================================== =====
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from ..geometry.topology import kernel_array
from ..threads import for_ranges, thread_count
from .surface import PerSurface
from .treewalk import GROUP_RECEIVERS, walk_lists

LEAF_SIZE = 8
#: The largest opening ratio (radius over distance) of a cluster, and the first estimate's (docs/physics.md §8.3).
THETA_MAX = 0.5
#: A node's aggregate may err by EPS_PER_TOL * tol of each receiver's estimated B, by its estimate: a second-order
#: estimate, where the sums take the second order off (:mod:`translucency.scatter.spread`), so what is left is far
#: below it (tests/scatter/test_tolerance.py checks the per-vertex tolerance; bench/README.md, "Kernel throughput", what
#: it costs). The same for every model.
EPS_PER_TOL = 2.0
#: A pair's magnitude in the criterion: the bound of §8.4, but at most this many times the largest ``S_d`` of sampled
#: geometries at that distance (:func:`~translucency.scatter.cutoff.largest_values`), which the bound exceeds more and
#: more with the distance (docs/physics.md §8.3; bench/README.md, "Kernel throughput", how it was chosen).
LARGEST_MARGIN = 20.0
#: The receivers whose first estimate sets the allowance's floor: those with the most incident flux.
BRIGHTEST_RECEIVERS = 64
#: The table of a pair's magnitude: first and last distance (mm) and the number of log-spaced distances. A node
#: nearer than the first distance would take the table's first value, below its own: no cluster is that near unless
#: 1 / sigma_t' is. Beyond the last, the bound is 0 in double precision.
BOUND_TABLE_MM = (1e-6, 1e5, 4000)
#: No cluster closer than CLUSTER_MEAN_FREE_PATHS / min sigma_t' to the receiver (the solver's
#: ``min_distance``): nearer than that S_d varies with the angles between normals and refracted
#: directions as much as with the distance, which a cluster's size-over-distance test does not see.
CLUSTER_MEAN_FREE_PATHS = 1.0
#: The lists' clusters are summed in float32 where ``tol`` is at least this (each within about 2e-5 of itself, well
#: inside tol; docs/physics.md §8.3), in float64 below it.
FLOAT32_TOL = 1e-3


class SourceTree:
    """Binary kd-tree over points: node ``k`` covers ``order[start[k]:end[k]]``.

    Attributes
    ----------
    order : (n,) int64
        Permutation of the points: every node covers a contiguous range of it.
    start, end, left, right : (n_nodes,) int64
        Ranges and children (-1 for a leaf). Node 0 is the root; children follow their parent.
    centre : (n_nodes, 3) float64
        Bounding-box centre, mm.
    radius : (n_nodes,) float64
        Bounding-sphere radius about ``centre``, mm.
    """

    def __init__(self, points: np.ndarray, leaf_size: int = LEAF_SIZE):
        points = np.ascontiguousarray(points, dtype=np.float64)
        self.order, self.start, self.end, self.left, self.right = _built(points, max(1, int(leaf_size)))
        self.centre, self.radius = _bounds(points, self.order, self.start, self.end, self.left, self.right)

    @property
    def n_nodes(self) -> int:
        """Number of nodes."""
        return int(self.start.size)


_TREES = PerSurface("source tree")


def tree_of(surface, leaf_size: int = LEAF_SIZE) -> SourceTree:
    """The kd-tree over every vertex of ``surface`` (a :class:`~translucency.scatter.surface.SurfaceGeometry`) with
    leaves of ``leaf_size``: geometry only, kept while the surface lives and reused across lights and materials."""
    return _TREES.get(surface, int(leaf_size), lambda: SourceTree(surface.points, leaf_size))


#: The tree's build splits its top levels alone, then builds this many subtrees per thread side by side.
SUBTREES_PER_THREAD = 4


def _built(points, leaf_size):
    """The tree's ``(order, start, end, left, right)``: a node of more than ``leaf_size`` points is split at
    the median of its box's longest axis (the lower half first); nodes are numbered depth first, a
    parent before its children, the left subtree before the right. The top levels are split here until there are
    :data:`SUBTREES_PER_THREAD` subtrees a thread (or every node is a leaf), and the subtrees are built on the
    threads: each splits its own rows and numbers its own nodes from where a depth-first count puts them
    (:func:`_node_count`), so the tree is the same as one built in one pass."""
    n = points.shape[0]
    count = _node_count(n, leaf_size)
    start = np.empty(count, dtype=np.int64)
    end = np.empty(count, dtype=np.int64)
    left = np.full(count, -1, dtype=np.int64)
    right = np.full(count, -1, dtype=np.int64)
    order = np.arange(n)
    points = points.copy()  # moved with ``order``: the passes over a node read memory in sequence
    tasks = [(0, n, 0)]  # rows lo .. hi - 1 and the node they start at, in depth-first order
    while len(tasks) < SUBTREES_PER_THREAD * thread_count():
        at = max(range(len(tasks)), key=lambda k: tasks[k][1] - tasks[k][0])  # the largest subtree
        lo, hi, node = tasks[at]
        if hi - lo <= leaf_size:
            break
        start[node], end[node] = lo, hi
        mid = lo + (hi - lo) // 2
        _split(points, order, lo, hi, mid)
        left[node], right[node] = node + 1, node + 1 + _node_count(mid - lo, leaf_size)
        tasks[at : at + 1] = [(lo, mid, left[node]), (mid, hi, right[node])]
    tasks = np.array(tasks, dtype=np.int64).reshape(-1, 3)
    for_ranges(_build_subtrees, tasks.shape[0], points, order, tasks, leaf_size, start, end, left, right)
    return order, start, end, left, right


def _node_count(n: int, leaf_size: int) -> int:
    """Nodes of the tree over ``n`` points (a node of more than ``leaf_size`` splits into ``n // 2`` and the rest)."""
    sizes = {}

    def count(k):
        if k <= leaf_size:
            return 1
        if k not in sizes:
            sizes[k] = 1 + count(k // 2) + count(k - k // 2)
        return sizes[k]

    return count(int(n))


@numba.njit(cache=True, nogil=True)
def _split(points, order, lo, hi, mid):
    """Rows ``lo .. hi - 1`` split at ``mid`` along their box's longest axis (:func:`_select`)."""
    _select(points, order, lo, hi, mid, _longest_axis(points, lo, hi))


@numba.njit(cache=True, nogil=True)
def _build_subtrees(worker, first, last, points, order, tasks, leaf_size, start, end, left, right):
    """Subtrees ``first .. last - 1`` of ``tasks`` (rows lo, hi, first node) of :func:`_built`, each depth first."""
    stack = np.empty((128, 4), dtype=np.int64)  # lo, hi, parent, side; depth is log2(n / leaf_size)
    for task in range(first, last):
        stack[0, 0], stack[0, 1], stack[0, 2], stack[0, 3] = tasks[task, 0], tasks[task, 1], -1, 0
        top, count = 1, tasks[task, 2]
        while top > 0:
            top -= 1
            lo, hi, parent, side = stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3]
            node = count
            count += 1
            start[node], end[node] = lo, hi
            if parent >= 0:
                if side == 0:
                    left[parent] = node
                else:
                    right[parent] = node
            if hi - lo <= leaf_size:
                continue
            mid = lo + (hi - lo) // 2
            _split(points, order, lo, hi, mid)
            stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3] = mid, hi, node, 1
            stack[top + 1, 0], stack[top + 1, 1], stack[top + 1, 2], stack[top + 1, 3] = lo, mid, node, 0
            top += 2


@numba.njit(cache=True, inline="always")
def _longest_axis(points, lo, hi):
    """The axis (0, 1, 2) along which the box of ``points[lo:hi]`` is longest (the first of equals)."""
    low = np.full(3, np.inf)
    high = np.full(3, -np.inf)
    for i in range(lo, hi):
        for k in range(3):
            v = points[i, k]
            low[k] = min(low[k], v)
            high[k] = max(high[k], v)
    axis = 0
    for k in range(1, 3):
        if high[k] - low[k] > high[axis] - low[axis]:
            axis = k
    return axis


@numba.njit(cache=True, inline="always")
def _select(points, order, lo, hi, kth, axis):
    """Reorder rows ``lo:hi`` of ``points`` and ``order`` alike so that the rows before ``kth`` are at most,
    and those from it on at least, the ``kth`` smallest along ``axis`` (Hoare's selection with a
    median-of-three pivot)."""
    hi -= 1
    while hi > lo:
        m = (lo + hi) // 2
        a, b, c = points[lo, axis], points[m, axis], points[hi, axis]
        pivot = max(min(a, b), min(max(a, b), c))
        i, j = lo, hi
        while i <= j:
            while points[i, axis] < pivot:
                i += 1
            while points[j, axis] > pivot:
                j -= 1
            if i <= j:
                order[i], order[j] = order[j], order[i]
                for k in range(3):
                    points[i, k], points[j, k] = points[j, k], points[i, k]
                i += 1
                j -= 1
        if kth <= j:
            hi = j
        elif kth >= i:
            lo = i
        else:
            return


def _leaves_then_levels(start, left, right):
    """The leaves in the order of their ranges, and the internal nodes by depth, deepest first: the order
    in which every node's children are done before the node (plain numpy, nothing to compile)."""
    leaves = np.flatnonzero(left < 0)
    leaves = leaves[np.argsort(start[leaves], kind="stable")]
    levels, level = [], np.zeros(1, dtype=np.int64)
    while level.size:
        inner = level[left[level] >= 0]
        if inner.size:
            levels.append(inner)
        level = np.concatenate([left[inner], right[inner]])
    return leaves, levels[::-1]


def _bounds(points, order, start, end, left, right):
    """Bounding-box centre (mm) and bounding-sphere radius about it of every node."""
    lo, hi = _boxes(points, order, start, end, left, right)
    return 0.5 * (lo + hi), np.sqrt(np.sum((0.5 * (hi - lo)) ** 2, axis=1))


@numba.njit(cache=True, nogil=True)
def _boxes(points, order, start, end, left, right):
    """Each node's box ``(lo, hi)`` (mm): a leaf's from its points, an inner node's from its two children's
    (nodes are numbered parent first, so in reverse every node's children come before it)."""
    n_nodes = start.shape[0]
    lo = np.full((n_nodes, 3), np.inf)
    hi = np.full((n_nodes, 3), -np.inf)
    for node in range(n_nodes - 1, -1, -1):
        if left[node] < 0:
            for j in range(start[node], end[node]):
                point = order[j]
                for k in range(3):
                    lo[node, k] = min(lo[node, k], points[point, k])
                    hi[node, k] = max(hi[node, k], points[point, k])
        else:
            for k in range(3):
                lo[node, k] = min(lo[left[node], k], lo[right[node], k])
                hi[node, k] = max(hi[left[node], k], hi[right[node], k])
    return lo, hi


def aggregate(order, start, end, left, right, points, normals, w12, flux):
    """Aggregated source of every node: flux per channel, flux-weighted position, normal and w12, and the
    flux-weighted covariance of its positions.

    Leaves sum their sources (on every thread), then every internal node its two children, deepest first.
    Returns ``node_flux (nodes, C)``, ``weight (nodes,)`` (total flux over channels), the mean
    position (mm), unit normal and unit refracted direction ``(nodes, 3)`` (0 where no flux), and ``spread (nodes,
    6)``: the covariance ``xx, yy, zz, xy, xz, yz`` (mm^2) of the positions weighted by ``weight``
    (:func:`~translucency.scatter.spread.spread_factor`; docs/physics.md §8.3).
    """
    n_nodes = start.shape[0]
    n_out = flux.shape[1]
    sums = np.zeros((n_nodes, n_out + 16))
    leaves = np.flatnonzero(left < 0)
    points = kernel_array(points, np.float64)
    # second moments about the points' box centre, not the origin: fewer digits lost to the mean's square
    origin = 0.5 * (points.min(axis=0) + points.max(axis=0)) if points.shape[0] else np.zeros(3)
    for_ranges(
        _leaf_sums,
        leaves.size,
        order,
        start,
        end,
        leaves,
        points,
        *(kernel_array(a, np.float64) for a in (normals, w12, flux)),
        origin,
        sums,
    )
    node_flux, weight = np.empty((n_nodes, n_out)), np.empty(n_nodes)
    out_pos, out_nrm, out_dir, spread = (np.zeros((n_nodes, width)) for width in (3, 3, 3, 6))
    _node_means(left, right, sums, origin, node_flux, weight, out_pos, out_nrm, out_dir, spread)
    return node_flux, weight, out_pos, out_nrm, out_dir, spread


@numba.njit(cache=True, nogil=True)
def _leaf_sums(worker, lo, hi, order, start, end, leaves, points, normals, w12, flux, origin, out):
    """Per leaf ``leaves[lo:hi]``, into its row of ``out (nodes, C + 16)``: the flux per channel, its total over
    channels ``w``, the ``w``-weighted sums of position, normal and ``w12``, and of the products ``xx, yy, zz, xy,
    xz, yz`` of the positions less ``origin`` (no (n, C + 16) table of the sources first)."""
    n_out = flux.shape[1]
    for leaf in leaves[lo:hi]:
        for i in range(start[leaf], end[leaf]):
            j = order[i]
            w = 0.0
            for c in range(n_out):
                out[leaf, c] += flux[j, c]
                w += flux[j, c]
            out[leaf, n_out] += w
            for k in range(3):
                out[leaf, n_out + 1 + k] += w * points[j, k]
                out[leaf, n_out + 4 + k] += w * normals[j, k]
                out[leaf, n_out + 7 + k] += w * w12[j, k]
            x = points[j, 0] - origin[0]
            y = points[j, 1] - origin[1]
            z = points[j, 2] - origin[2]
            out[leaf, n_out + 10] += w * x * x
            out[leaf, n_out + 11] += w * y * y
            out[leaf, n_out + 12] += w * z * z
            out[leaf, n_out + 13] += w * x * y
            out[leaf, n_out + 14] += w * x * z
            out[leaf, n_out + 15] += w * y * z


@numba.njit(cache=True, nogil=True)
def _node_means(left, right, sums, origin, node_flux, weight, out_pos, out_nrm, out_dir, spread):
    """:func:`aggregate`'s outputs from the leaves' ``sums``: every internal node's sums as its two children's
    (nodes are numbered parent first, so in reverse every node's children come before it), then the flux, the
    weighted means, the unit normal and ``w12``, and the covariance about the mean."""
    n_nodes, n_out = node_flux.shape
    for node in range(n_nodes - 1, -1, -1):
        if left[node] >= 0:
            for k in range(sums.shape[1]):
                sums[node, k] = sums[left[node], k] + sums[right[node], k]
    for node in range(n_nodes):
        for c in range(n_out):
            node_flux[node, c] = sums[node, c]
        w = sums[node, n_out]
        weight[node] = w
        if not w > 0.0:
            continue
        for k in range(3):
            out_pos[node, k] = sums[node, n_out + 1 + k] / w
        x = out_pos[node, 0] - origin[0]
        y = out_pos[node, 1] - origin[1]
        z = out_pos[node, 2] - origin[2]
        products = (x * x, y * y, z * z, x * y, x * z, y * z)
        for k in range(6):
            spread[node, k] = sums[node, n_out + 10 + k] / w - products[k]
        for k in range(3):
            spread[node, k] = max(spread[node, k], 0.0)  # a variance rounded below 0
        _unit_into(sums[node, n_out + 4 : n_out + 7], out_nrm[node])
        _unit_into(sums[node, n_out + 7 : n_out + 10], out_dir[node])


@numba.njit(cache=True, inline="always")
def _unit_into(v, out):
    """``v / |v|`` into ``out`` (left as it is where ``v`` is 0)."""
    length = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    if length > 0.0:
        for k in range(3):
            out[k] = v[k] / length


def _sums(order, start, end, left, right, values):
    """Sum of ``values (n, K)`` over the vertices of every node, ``(nodes, K)``: the leaves by their ranges,
    then every level of internal nodes from its two children, deepest first."""
    totals = np.zeros((start.shape[0], values.shape[1]))
    leaves, levels = _leaves_then_levels(start, left, right)
    filled = leaves[end[leaves] > start[leaves]]
    if filled.size:
        totals[filled] = np.add.reduceat(values[order], start[filled], axis=0)
    for nodes in levels:
        totals[nodes] = totals[left[nodes]] + totals[right[nodes]]
    return totals


def node_sums(tree: SourceTree, values) -> np.ndarray:
    """Sum of ``values (n, K)`` over the vertices of every node of ``tree``: ``(nodes, K)`` float64."""
    return _sums(tree.order, tree.start, tree.end, tree.left, tree.right, np.asarray(values, dtype=np.float64))


@dataclass(frozen=True)
class AggregatedSources:
    """The sources of one solve and the aggregated source of every node of a :class:`SourceTree`, as
    one table for :func:`~translucency.scatter.listsums.grouped_sum` (built once per solve by
    :func:`aggregated_sources`, used for every block of receivers).

    Attributes
    ----------
    records : (n + nodes, 9 + C) float64
        Rows ``0..n-1`` the sources, ``n + k`` the aggregated source of node ``k``: position (mm), unit normal,
        unit refracted direction, flux per channel.
    n_sources : int
        ``n``, the rows that are sources.
    node_flux : (nodes, C) float64
        Flux per channel of each node (0: nothing to evaluate under it).
    lit : (n,) bool
        Sources with any flux.
    spread : (rows - n, 6) float64
        The covariance of the positions under each aggregate of ``records`` (:func:`aggregate`), mm^2.
    """

    records: np.ndarray
    n_sources: int
    node_flux: np.ndarray
    lit: np.ndarray
    spread: np.ndarray

    @property
    def n_channels(self) -> int:
        """The flux's channels ``C``."""
        return self.records.shape[1] - 9


def aggregated_sources(tree: SourceTree, points, normals, w12, flux) -> AggregatedSources:
    """The sources (positions mm, unit normals, unit ``w12``, ``flux (n, C)``) and their aggregates at
    every node of ``tree`` (:func:`aggregate`), in the table :func:`tree_sum` walks."""
    node_flux, _, node_pos, node_nrm, node_dir, spread = aggregate(
        tree.order, tree.start, tree.end, tree.left, tree.right, points, normals, w12, flux
    )
    records = _source_records((points, normals, w12, flux), (node_pos, node_nrm, node_dir, node_flux))
    return AggregatedSources(records, points.shape[0], node_flux, flux.sum(axis=1) > 0, spread)


def _source_records(sources, nodes) -> np.ndarray:
    """The ``records (s + k, 9 + C)`` of :class:`AggregatedSources`: first the ``sources`` ``(positions, normals,
    w12, flux)``, then the ``nodes``' aggregates in the same order, filled in place (no stacked copies)."""
    n = sources[0].shape[0]
    records = np.empty((n + nodes[0].shape[0], 9 + sources[3].shape[1]))
    for k in range(4):
        width = sources[k].shape[1]
        records[:n, 3 * k : 3 * k + width] = sources[k]
        records[n:, 3 * k : 3 * k + width] = nodes[k]
    return records


@dataclass(frozen=True)
class Opening:
    """When the walk takes a node as one aggregated source (docs/physics.md §8.3), built by :func:`opening`.

    A node is a cluster for a group of receivers when the group is farther than ``min_distance`` (mm) from the
    node's bounding sphere, the node is small seen from it (``radius < theta * distance``), and the error its
    aggregate may make, ``radius^2 (1 / distance^2 + sigma_tr^2) flux bound(distance - radius)`` per channel (``bound``
    a pair's magnitude, below), is
    at most the group's allowance ``eps * max(B_est, floor)`` (the relative opening criterion: the first
    estimate ``B_est`` from a walk with the first two tests alone).

    Attributes
    ----------
    theta : float
        Largest opening ratio, radius over distance.
    min_distance : float
        No cluster nearer than this to the group, mm.
    eps : float
        The allowance's share of each receiver's estimated ``B``.
    bound : (C, K) float64
        A pair's magnitude at ``K`` log-spaced distances, 1/(mm^2 sr): :func:`~translucency.scatter.cutoff.pair_bound`,
        at most :data:`LARGEST_MARGIN` times :func:`~translucency.scatter.cutoff.largest_values`.
    log_first, per_log : float
        ``log`` of the table's first distance (mm) and table steps per unit of ``log`` distance.
    curvature : (C,) float64
        ``sigma_tr^2`` per channel, 1/mm^2: how fast ``S_d`` bends across a node far away.
    bends : (C, 4, K) float64
        The profile's bends at the same distances (:func:`~translucency.scatter.spread.profile_bends`), by which a
        cluster's sum is corrected for the spread of its sources (docs/physics.md §8.3).
    precision : type
        What the lists are summed in: ``np.float32`` where ``tol >=`` :data:`FLOAT32_TOL`, else ``np.float64``
        (:func:`~translucency.scatter.listsums.grouped_sum`).
    """

    theta: float
    min_distance: float
    eps: float
    bound: np.ndarray
    log_first: float
    per_log: float
    curvature: np.ndarray
    bends: np.ndarray
    precision: type = np.float64

    def kernel_arguments(self):
        """The fields as :func:`~translucency.scatter.treewalk.walk_lists` hands them to its kernel (one tuple)."""
        return self.theta, self.min_distance, self.bound, self.log_first, self.per_log, self.curvature


def opening(medium, model: str, tol: float) -> Opening:
    """The walk's criterion for ``tol`` (:class:`Opening`): ``theta`` = :data:`THETA_MAX`, ``eps`` =
    :data:`EPS_PER_TOL` ``* tol``, clusters no nearer than ``CLUSTER_MEAN_FREE_PATHS / min sigma_t'`` (mm), one pair's
    magnitude tabulated for ``medium`` (1/mm) and ``model`` (the bound of docs/physics.md §8.4, at most
    :data:`LARGEST_MARGIN` times the largest sampled ``S_d``; §8.3), the profile's bends at the same distances
    (:func:`~translucency.scatter.spread.profile_bends`), and sums in float32 where ``tol >=`` :data:`FLOAT32_TOL`."""
    from .cutoff import largest_values, pair_bound
    from .spread import profile_bends

    first, last, steps = BOUND_TABLE_MM
    log_first, log_last = math.log(first), math.log(last)
    distances = np.exp(np.linspace(log_first, log_last, steps))
    magnitude = np.minimum(
        pair_bound(medium, model, distances), LARGEST_MARGIN * largest_values(medium, model, distances)
    )
    # never larger farther away: the walk's tests must be monotone in the distance (treewalk.shared_walks)
    magnitude = np.minimum.accumulate(magnitude, axis=1)
    return Opening(
        theta=THETA_MAX,
        min_distance=CLUSTER_MEAN_FREE_PATHS / float(np.min(medium.sigma_t_reduced)),
        eps=EPS_PER_TOL * float(tol),
        bound=np.ascontiguousarray(magnitude, dtype=np.float64),
        log_first=log_first,
        per_log=(steps - 1) / (log_last - log_first),
        curvature=np.ascontiguousarray(np.asarray(medium.sigma_tr, dtype=np.float64) ** 2),
        bends=profile_bends(medium, model, distances),
        precision=np.float32 if tol >= FLOAT32_TOL else np.float64,
    )


def allowance(B_est, floor, eps) -> np.ndarray:
    """Each receiver's allowance for one node's error: ``eps * max(B_est, floor)`` per channel (``B_est (n, C)``
    and ``floor (C,)``, W/(m^2 sr))."""
    return eps * np.maximum(np.asarray(B_est, dtype=np.float64), np.asarray(floor, dtype=np.float64)[None, :])


def _sum_of_lists(model, rcv_points, rcv_normals, sources, lists, group, lanes, rule):
    """:func:`~translucency.scatter.listsums.grouped_sum` of the walk's ``lists`` (:func:`walk_lists`) in the
    precision of ``rule`` (:class:`Opening`), each cluster with its spread and the rule's bends of the profile."""
    from .listsums import grouped_sum

    g_starts, g_direct, g_clustered, columns = lists
    return grouped_sum(
        model,
        rcv_points,
        rcv_normals,
        sources.records,
        sources.spread,
        (rule.bends, rule.log_first, rule.per_log),
        sources.n_sources,
        g_starts,
        g_direct + g_clustered,
        group,
        columns,
        lanes,
        rule.precision,
    )


class ListedWalk:
    """A walk of the tree and its sum on the CPU, for :func:`tree_sum`: called with ``(rcv_points mm, rcv_normals,
    allow, group)``, it lists what each group of ``group`` receivers evaluates (:func:`walk_lists`; ``allow``: the
    receivers' allowances ``(n_rcv, C)`` or None) and sums the lists
    (:func:`~translucency.scatter.listsums.grouped_sum`): ``(B (n_rcv, C), direct (n_rcv,), clustered (n_rcv,))``,
    the counts those of each receiver's group. The GPU's is :class:`translucency.scatter.gpu.tree.WalkedSums`."""

    #: Receivers per call of :func:`tree_sum`: the lists of this many are held at once.
    block = 4096
    #: Receivers that share a walk (:data:`GROUP_RECEIVERS`).
    group = GROUP_RECEIVERS

    def __init__(self, model, tree, sources: AggregatedSources, params, channel_of, rule: Opening, reach=math.inf):
        from .kernels import channel_lanes

        self.model, self.tree, self.sources, self.rule, self.reach = model, tree, sources, rule, reach
        self.lanes = channel_lanes(params, channel_of, sources.n_channels)

    def __call__(self, rcv_points, rcv_normals, allow, group):
        sources = self.sources
        lists = walk_lists(self.tree, sources.node_flux, sources.lit, rcv_points, self.rule, allow, self.reach, group)
        B = _sum_of_lists(self.model, rcv_points, rcv_normals, sources, lists, group, self.lanes, self.rule)
        of = np.arange(rcv_points.shape[0]) // group  # each receiver's group
        return B, lists[1][of], lists[2][of]


def tree_sum(walked, rcv_points, rcv_normals, floor):
    """Far-field sum with the hierarchy: ``B[o, c]``, sources summed one by one and clusters used, per receiver.

    Two walks per block of ``walked.block`` receivers (docs/physics.md §8.3), each made and summed by ``walked``
    (:class:`ListedWalk` on the CPU, :class:`translucency.scatter.gpu.tree.WalkedSums` on the GPU), by its
    :class:`Opening` ``walked.rule``. The first, at each group's first and last receivers alone, takes a node as one
    aggregated source where it is small seen from that receiver (``theta``) and farther than ``min_distance``; its
    sums give each group its first estimate ``B_est`` (:func:`group_estimate`). The second
    takes a node only where its aggregate's error is also within :func:`allowance` of ``B_est`` (``floor (C,)``:
    the least ``B`` the allowance assumes, W/(m^2 sr)); otherwise its children are opened, down to the leaves'
    sources. The tree is walked once per group of ``walked.group`` consecutive receivers (the solver orders them
    along a space-filling curve) with the tests made for the group's bounding sphere, which hold for every receiver
    of the group, and the group's sources and clusters are summed at each of its receivers.

    Returns
    -------
    B : (n_rcv, C) float64
    direct, clustered : (n_rcv,) int64
        Source pairs evaluated one by one (lit sources only) and cluster evaluations, per receiver, both walks.
    """
    n_rcv = rcv_points.shape[0]
    B = np.zeros((n_rcv, floor.shape[0]))
    direct = np.zeros(n_rcv, dtype=np.int64)
    clustered = np.zeros(n_rcv, dtype=np.int64)
    group = max(1, int(walked.group))
    block = max(group, walked.block // group * group)
    for first in range(0, n_rcv, block):
        part = slice(first, min(n_rcv, first + block))
        p, nrm = rcv_points[part], rcv_normals[part]
        ends = group_ends(p.shape[0], group).ravel()
        B_ends, direct_first, clustered_first = walked(p[ends], nrm[ends], None, 1)
        np.add.at(direct[part], ends, direct_first)
        np.add.at(clustered[part], ends, clustered_first)
        B_est = group_estimate(B_ends, group, p.shape[0])
        B[part], direct_second, clustered_second = walked(p, nrm, allowance(B_est, floor, walked.rule.eps), group)
        direct[part] += direct_second
        clustered[part] += clustered_second
    return B, direct, clustered


def group_ends(n_rcv: int, group: int) -> np.ndarray:
    """The first and the last receiver of each group of ``group`` consecutive receivers of ``n_rcv`` (the last group
    may be short): ``(2, groups)`` int64."""
    first = np.arange(0, n_rcv, group)
    return np.stack([first, np.minimum(first + group, n_rcv) - 1])


def group_estimate(B_ends, group: int, n_rcv: int) -> np.ndarray:
    """Each of ``n_rcv`` receivers' first estimate ``(n_rcv, C)`` from the first walk's sums ``B_ends (2 groups, C)``
    at the receivers of :func:`group_ends` (raveled): its group's lesser of the two (the group's receivers lie
    between them along the solver's space-filling curve, and a group is the same in any block of receivers).
    docs/physics.md §8.3."""
    first, last = np.asarray(B_ends, dtype=np.float64).reshape(2, -1, np.shape(B_ends)[1])
    return np.repeat(np.minimum(first, last), group, axis=0)[:n_rcv]


def first_estimate(walked, rcv_points, rcv_normals):
    """The first walk's sum alone at receivers taken one by one (``(n_rcv, C)``; see :func:`tree_sum`), by
    ``walked`` (:class:`ListedWalk` or the GPU's)."""
    return walked(rcv_points, rcv_normals, None, 1)[0]


def brightest(flux, areas, count: int = BRIGHTEST_RECEIVERS) -> np.ndarray:
    """The ``count`` vertices with the most incident flux density (``flux (n, C)`` over their ``areas`` (n,), mm^2,
    summed over the channels), sorted: where the largest ``B`` is sought for the allowance's floor."""
    total = np.asarray(flux, dtype=np.float64).sum(axis=1)
    areas = np.asarray(areas, dtype=np.float64)
    density = np.divide(total, areas, out=np.zeros_like(total), where=areas > 0)
    if density.size <= count:
        return np.arange(density.size)
    return np.sort(np.argpartition(-density, count)[:count])


def sampled_evaluations(model, tree, points, normals, w12, flux, rcv, bright, params, channel_of, rule, floor_share):
    """Sources and clusters :func:`tree_sum` evaluates at each receiver ``rcv`` (vertex indices, in groups of
    :data:`GROUP_RECEIVERS` neighbours), for the sources' ``flux (n, C)``, counted without the whole table of
    aggregated sources (the budget's sample): the nodes' aggregates, and the first estimate at each group's first
    and last receivers and at ``bright`` (the floor: ``floor_share`` of their largest) from a table of the columns
    the walks list. The first walk's evaluations are shared out over each group's receivers."""
    from .kernels import channel_lanes

    node_flux, _, node_pos, node_nrm, node_dir, spread = aggregate(
        tree.order, tree.start, tree.end, tree.left, tree.right, points, normals, w12, flux
    )
    lit = flux.sum(axis=1) > 0
    lanes = channel_lanes(params, channel_of, flux.shape[1])
    n = points.shape[0]

    def estimate(indices, group):
        starts, direct, clustered, columns = walk_lists(
            tree, node_flux, lit, points[indices], rule, None, math.inf, group
        )
        used, position = np.unique(columns, return_inverse=True)  # sorted: the sources, then the nodes
        own, node = used[used < n], used[used >= n] - n
        records = _source_records(
            (points[own], normals[own], w12[own], flux[own]),
            (node_pos[node], node_nrm[node], node_dir[node], node_flux[node]),
        )
        compact = AggregatedSources(records, own.size, node_flux, lit, spread[node])
        lists = (starts, direct, clustered, position.astype(np.int64).ravel())
        B = _sum_of_lists(model, points[indices], normals[indices], compact, lists, group, lanes, rule)
        return B, direct + clustered

    bright_B, _ = estimate(bright, 1)
    floor = floor_share * bright_B.max(axis=0)
    ends = group_ends(rcv.size, GROUP_RECEIVERS)
    B_ends, first = estimate(rcv[ends.ravel()], 1)
    B_est = group_estimate(B_ends, GROUP_RECEIVERS, rcv.size)
    _, direct, clustered, _ = walk_lists(
        tree, node_flux, lit, points[rcv], rule, allowance(B_est, floor, rule.eps), math.inf, GROUP_RECEIVERS, True
    )
    sizes = ends[1] - ends[0] + 1
    return np.repeat(first.reshape(2, -1).sum(axis=0) / sizes + direct + clustered, sizes)


#: The compiled kernels of the source tree's build and traversal: numba compiles each on first use; the set-up compiles
#: them ahead
#: (:mod:`translucency.app.warmup`).
TREE_KERNELS = (
    _split,
    _build_subtrees,
    _boxes,
    _leaf_sums,
    _node_means,
)
