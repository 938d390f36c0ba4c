"""A hierarchy over the source vertices (a binary kd-tree with bounding spheres) and its error criterion.

The structure depends on the geometry only and is reused when the light or the material changes;
the aggregated sources at the nodes depend on the incident flux and are recomputed per solve (cheap,
bottom-up). A node seen from a receiver under a small enough angle is replaced by one aggregated
source (Jensen & Buhler 2002; docs/physics.md §8.3): total flux per channel, flux-weighted position,
flux-weighted normal and refracted direction (both renormalised).

Criterion: a node is accepted when the receiver is farther than ``min_distance`` from its bounding
sphere and ``radius / distance(receiver, centre) < theta``; the error of one accepted node is of order
``theta^2`` relative to its contribution, so the solver sets ``theta = THETA_PER_SQRT_TOL * sqrt(tol)``
and ``min_distance = CLUSTER_MEAN_FREE_PATHS / min sigma_t'``.
The tree is walked once per small group of neighbouring receivers, with the distance from the group's
bounding sphere (conservative for each member, so a larger ``theta`` gives the same error).

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
from ..threads import for_ranges
from .surface import PerSurface

LEAF_SIZE = 8
#: Receivers that share one walk of the tree (consecutive along the solver's space-filling curve).
#: The group's bounding sphere is tested, which is conservative for each member, so a group reaches the error
#: of single receivers with a larger theta and in less far-field time; larger groups evaluate more clusters
#: than the shared walk saves (bench/README.md, "Kernel throughput").
GROUP_RECEIVERS = 4
#: theta = THETA_PER_SQRT_TOL * sqrt(tol); calibrated so that the per-vertex error that tol bounds
#: (99th percentile, docs/physics.md §8.5) stays below tol on the benchmark scans in every material
#: (bench/README.md, "Kernel throughput"); a lower value costs time, as the cluster evaluations grow as
#: theta^-2. tests/scatter/test_tolerance.py checks it on spheres.
THETA_PER_SQRT_TOL = 0.7
#: No cluster closer than CLUSTER_MEAN_FREE_PATHS / min sigma_t' to the receiver (the solver's
#: ``min_distance``): nearer than that S_d varies with the angles between normals and refracted
#: directions as much as with the distance, which a cluster's size-over-distance test does not see.
CLUSTER_MEAN_FREE_PATHS = 1.0


def opening(sigma_t_reduced, tol: float, theta_per_sqrt_tol: float = THETA_PER_SQRT_TOL) -> tuple[float, float]:
    """The walk's opening ratio ``theta = theta_per_sqrt_tol * sqrt(tol)`` and its smallest cluster distance
    ``CLUSTER_MEAN_FREE_PATHS / min sigma_t'`` (mm; ``sigma_t_reduced`` per channel, 1/mm; docs/physics.md §8.3)."""
    return theta_per_sqrt_tol * math.sqrt(tol), CLUSTER_MEAN_FREE_PATHS / float(np.min(sigma_t_reduced))


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
        self.order, self.start, self.end, self.left, self.right = _build(points, max(1, int(leaf_size)))
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


@numba.njit(cache=True)
def _build(points, leaf_size):
    """The tree's ``(order, start, end, left, right)``: a node of more than ``leaf_size`` points is split at
    the median of its box's longest axis (the lower half first); nodes are numbered depth first, a
    parent before its children, the left subtree before the right."""
    n = points.shape[0]
    # a split leaves at least (leaf_size + 1) // 2 points on each side, so there are at most this many nodes
    capacity = 2 * (n // max(1, (leaf_size + 1) // 2) + 1) + 1
    start = np.empty(capacity, dtype=np.int64)
    end = np.empty(capacity, dtype=np.int64)
    left = np.full(capacity, -1, dtype=np.int64)
    right = np.full(capacity, -1, dtype=np.int64)
    order = np.arange(n)
    points = points.copy()  # moved with ``order``: the passes over a node read memory in sequence
    stack = np.empty((128, 4), dtype=np.int64)  # lo, hi, parent, side; depth is log2(n / leaf_size)
    stack[0, 0], stack[0, 1], stack[0, 2], stack[0, 3] = 0, n, -1, 0
    top, count = 1, 0
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
        axis = _longest_axis(points, lo, hi)
        mid = lo + (hi - lo) // 2
        _select(points, order, lo, hi, mid, axis)
        stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3] = mid, hi, node, 1
        stack[top + 1, 0], stack[top + 1, 1], stack[top + 1, 2], stack[top + 1, 3] = lo, mid, node, 0
        top += 2
    return order, start[:count].copy(), end[:count].copy(), left[:count].copy(), right[:count].copy()


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
    """Aggregated source of every node: flux per channel, flux-weighted position, normal and w12.

    Leaves sum their sources, then every level of internal nodes its two children, deepest first.
    Returns ``node_flux (nodes, C)``, ``weight (nodes,)`` (total flux over channels) and the mean
    position (mm), unit normal and unit refracted direction ``(nodes, 3)`` (0 where no flux).
    """
    n_nodes = start.shape[0]
    n_out = flux.shape[1]
    sums = np.zeros((n_nodes, n_out + 10))
    leaves, levels = _leaves_then_levels(start, left, right)
    _leaf_sums(order, start, end, leaves, *(kernel_array(a, np.float64) for a in (points, normals, w12, flux)), sums)
    for nodes in levels:
        sums[nodes] = sums[left[nodes]] + sums[right[nodes]]
    node_flux, weight, sums = sums[:, :n_out], sums[:, n_out], sums[:, n_out + 1 :]  # flux-weighted pos, normal, w12
    # weighted sums -> means
    some = weight > 0.0
    out_pos = np.zeros((n_nodes, 3))
    out_pos[some] = sums[some, 0:3] / weight[some, None]
    unit = []
    for block in (sums[:, 3:6], sums[:, 6:9]):
        length = np.sqrt(np.sum(block**2, axis=1))
        out = np.zeros((n_nodes, 3))
        ok = some & (length > 0.0)
        out[ok] = block[ok] / length[ok, None]
        unit.append(out)
    return node_flux, weight, out_pos, unit[0], unit[1]


@numba.njit(cache=True)
def _leaf_sums(order, start, end, leaves, points, normals, w12, flux, out):
    """Per leaf, added into ``out (nodes, C + 10)``: the flux per channel, its total over channels ``w``, and
    the ``w``-weighted sums of position, normal and ``w12`` (no (n, C + 10) table of the sources first)."""
    n_out = flux.shape[1]
    for leaf in leaves:
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
    one table for :func:`~translucency.scatter.kernels.indexed_sum` (built once per solve by
    :func:`aggregated_sources`, used for every block of receivers).

    Attributes
    ----------
    table : (9, n + nodes) float64
        Columns ``0..n-1`` the sources, ``n + k`` the aggregated source of node ``k``: position (mm),
        unit normal, unit refracted direction.
    weights : (C, n + nodes) float64
        Flux per channel of each column.
    node_weight : (nodes,) float64
        Total flux over channels of each node (0: nothing to evaluate under it).
    lit : (n,) bool
        Sources with any flux.
    """

    table: np.ndarray
    weights: np.ndarray
    node_weight: np.ndarray
    lit: np.ndarray


def aggregated_sources(tree: SourceTree, points, normals, w12, flux) -> AggregatedSources:
    """The sources (positions mm, unit normals, unit ``w12``, ``flux (n, C)``) and their aggregates at
    every node of ``tree`` (:func:`aggregate`), in the table :func:`tree_sum` walks."""
    node_flux, node_weight, node_pos, node_nrm, node_dir = aggregate(
        tree.order, tree.start, tree.end, tree.left, tree.right, points, normals, w12, flux
    )
    n = points.shape[0]
    table = np.empty((9, n + tree.n_nodes))  # filled in place: no stacked copies of the sources
    for k, (source, node) in enumerate(((points, node_pos), (normals, node_nrm), (w12, node_dir))):
        table[3 * k : 3 * k + 3, :n] = source.T
        table[3 * k : 3 * k + 3, n:] = node.T
    weights = np.empty((flux.shape[1], n + tree.n_nodes))
    weights[:, :n] = flux.T
    weights[:, n:] = node_flux.T
    return AggregatedSources(table, weights, node_weight, flux.sum(axis=1) > 0)


def walk_lists(
    tree, node_weight, lit, rcv_points, theta, reach=math.inf, min_distance=0.0, group=GROUP_RECEIVERS, count_only=False
):
    """The tree walk of :func:`tree_sum` on its own: for every group of ``group`` consecutive receivers
    (positions mm), the sources and clusters it evaluates.

    Nodes with ``node_weight <= 0`` are skipped, and only sources with ``lit`` are listed. Returns
    ``(starts, direct, clustered, columns)``: the group's list is ``columns[starts[g] : starts[g] + direct[g]
    + clustered[g]]``, entries ``j < n`` source ``j`` and ``n + k`` node ``k``'s cluster (``count_only``: the
    counts only, ``columns`` empty).
    """
    n_rcv = rcv_points.shape[0]
    n_groups = -(-n_rcv // group)
    members = np.minimum(np.arange(n_groups * group).reshape(n_groups, group), n_rcv - 1)
    centre = rcv_points[members].mean(axis=1)
    spread = np.linalg.norm(rcv_points[members] - centre[:, None, :], axis=2).max(axis=1)
    g_direct = np.zeros(n_groups, dtype=np.int64)
    g_clustered = np.zeros(n_groups, dtype=np.int64)
    walk = (
        tree.order,
        tree.start,
        tree.end,
        tree.left,
        tree.right,
        tree.centre,
        tree.radius,
        node_weight,
        lit,
        centre,
        spread,
        theta,
        reach,
        min_distance,
    )
    for_ranges(
        _traverse, n_groups, *walk, np.empty(0, dtype=np.int64), np.zeros(1, dtype=np.int64), g_direct, g_clustered
    )
    g_counts = g_direct + g_clustered
    g_starts = np.zeros(n_groups, dtype=np.int64)
    np.cumsum(g_counts[:-1], out=g_starts[1:])
    if count_only:
        return g_starts, g_direct, g_clustered, np.empty(0, dtype=np.int64)
    columns = np.empty(int(g_counts.sum()), dtype=np.int64)
    for_ranges(_traverse, n_groups, *walk, columns, g_starts, g_direct, g_clustered)
    return g_starts, g_direct, g_clustered, columns


def evaluations_per_receiver(tree, flux, rcv_points, theta, min_distance=0.0, group=GROUP_RECEIVERS) -> np.ndarray:
    """Sources and clusters :func:`tree_sum` evaluates at each receiver (positions mm) for the sources' ``flux
    (n, C)``, from the walk alone: nothing aggregated, listed or evaluated (the budget's sample)."""
    flux = np.asarray(flux, dtype=np.float64)
    total = flux.sum(axis=1)
    node_weight = node_sums(tree, total[:, None])[:, 0]
    _, direct, clustered, _ = walk_lists(
        tree, node_weight, total > 0, rcv_points, theta, math.inf, min_distance, group, count_only=True
    )
    return np.repeat(direct + clustered, group)[: rcv_points.shape[0]]


def tree_sum(
    model,
    tree,
    sources: AggregatedSources,
    rcv_points,
    rcv_normals,
    params,
    channel_of,
    theta,
    block=4096,
    reach=math.inf,
    group=GROUP_RECEIVERS,
    min_distance=0.0,
):
    """Far-field sum with the hierarchy: ``B[o, c]``, sources summed one by one and clusters used, per receiver.

    A node small seen from the receiver (radius < ``theta`` x distance, receiver outside it) is one
    aggregated source (``sources``, from :func:`aggregated_sources`); otherwise its children are opened,
    down to the leaves' sources; a node is never a cluster for a receiver nearer than ``min_distance``
    (mm) to its bounding sphere. A node wholly farther than ``reach`` (mm) is skipped (the solver passes
    infinity: a skip sized on the total reflectance drops most of a dark receiver's ``B``). The tree is
    walked once per group of ``group`` consecutive receivers (the solver orders them along a
    space-filling curve) with the tests made for the group's bounding sphere -- for every receiver of
    the group they hold with at least the same margin -- and the group's list of sources and clusters
    is evaluated at each of its receivers with :func:`~translucency.scatter.kernels.grouped_sum` (the list
    gathered once per group), ``block`` receivers at a time.

    Returns
    -------
    B : (n_rcv, C) float64
    direct, clustered : (n_rcv,) int64
        Source pairs evaluated one by one (lit sources only) and cluster evaluations, per receiver.
    """
    from .kernels import channel_lanes, grouped_sum

    n_channels = sources.weights.shape[0]
    lanes = channel_lanes(params, channel_of, n_channels)
    n_rcv = rcv_points.shape[0]
    B = np.zeros((n_rcv, n_channels))
    direct = np.zeros(n_rcv, dtype=np.int64)
    clustered = np.zeros(n_rcv, dtype=np.int64)
    group = max(1, int(group))
    block = max(group, block // group * group)
    for first in range(0, n_rcv, block):
        part = slice(first, min(n_rcv, first + block))
        p, nrm = rcv_points[part], rcv_normals[part]
        g_starts, g_direct, g_clustered, columns = walk_lists(
            tree, sources.node_weight, sources.lit, p, theta, reach, min_distance, group
        )
        g_counts = g_direct + g_clustered
        of = np.arange(p.shape[0]) // group  # each receiver's group
        direct[part], clustered[part] = g_direct[of], g_clustered[of]
        B[part] = grouped_sum(model, p, nrm, sources.table, sources.weights, g_starts, g_counts, group, columns, lanes)
    return B, direct, clustered


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _traverse(
    worker,
    lo,
    hi,
    order,
    start,
    end,
    left,
    right,
    centre,
    radius,
    node_weight,
    lit,
    rcv_points,
    rcv_spread,
    theta,
    reach,
    min_distance,
    columns,
    starts,
    direct,
    clustered,
):
    """Walk the tree for every group of receivers (a sphere: ``rcv_points`` centres, ``rcv_spread``
    radii, mm): count the lit sources and clusters it evaluates (``columns`` empty), or write their
    columns (source ``j`` or ``n + node``) from ``starts[o]`` on. A node is a cluster when the sphere is
    outside the node's and ``radius < theta * (distance - spread)``: then ``radius < theta * distance``
    for every point of the sphere. Groups ``lo .. hi - 1`` (:func:`~translucency.threads.for_ranges`)."""
    n_src = lit.shape[0]
    write = columns.shape[0] > 0
    theta2 = theta * theta
    for o in range(lo, hi):
        stack = np.empty(128, dtype=np.int64)
        top = 1
        stack[0] = 0
        px = rcv_points[o, 0]
        py = rcv_points[o, 1]
        pz = rcv_points[o, 2]
        n_direct = 0
        n_cluster = 0
        at = starts[o] if write else 0
        while top > 0:
            top -= 1
            k = stack[top]
            if node_weight[k] <= 0.0:
                continue
            dx = px - centre[k, 0]
            dy = py - centre[k, 1]
            dz = pz - centre[k, 2]
            dist2 = dx * dx + dy * dy + dz * dz
            rk = radius[k]
            near = math.sqrt(dist2) - rcv_spread[o]  # the group's closest possible distance to the centre
            if near > reach + rk:  # wholly beyond the cutoff radius
                continue
            if near > rk + min_distance and rk * rk < theta2 * near * near:
                if write:
                    columns[at] = n_src + k
                    at += 1
                n_cluster += 1
            elif left[k] < 0:
                for i in range(start[k], end[k]):
                    j = order[i]
                    if lit[j]:
                        if write:
                            columns[at] = j
                            at += 1
                        n_direct += 1
            else:
                stack[top] = left[k]
                stack[top + 1] = right[k]
                top += 2
        direct[o] = n_direct
        clustered[o] = n_cluster


#: The compiled kernels of the source tree's build and traversal: numba compiles each on first use; the set-up compiles
#: them ahead
#: (:mod:`translucency.app.warmup`).
TREE_KERNELS = (
    _traverse,
    _build,
    _boxes,
    _leaf_sums,
)
