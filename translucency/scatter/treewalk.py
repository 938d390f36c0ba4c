"""Which nodes of the source tree each group of receivers takes as one aggregated source: the tree's walk.

A node is a cluster for a group of receivers when the group is farther than ``min_distance`` from its bounding
sphere, it is small seen from the group, and the estimate of its aggregate's error is within the group's allowance
(:class:`~translucency.scatter.hierarchy.Opening`, docs/physics.md §8.3); otherwise it is opened, down to the
leaves' lit sources. Neighbouring groups share the upper part of the walk: runs of them list together what each
of their groups would decide alike (:func:`shared_walks`), and each group walks on alone from what its run left
undecided.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..threads import for_ranges

#: Receivers that share one walk of the tree (consecutive along the solver's space-filling curve).
#: The group's bounding sphere is tested, which is conservative for each member, so a group reaches the error
#: of single receivers with a larger theta and in less far-field time; larger groups evaluate more clusters
#: than the shared walk and the first estimate, made at a group's first and last receivers alone, save
#: (bench/README.md, "Kernel throughput").
GROUP_RECEIVERS = 8
#: Groups share the upper part of their walk: runs of WALK_FANOUT**k consecutive groups (k = SHARED_LEVELS .. 1,
#: the coarsest first) list together what each of their groups would decide alike, and each group walks on from
#: what its run left undecided (:func:`_traverse`). The lists are those of every group walked alone.
WALK_FANOUT = 4
SHARED_LEVELS = 3


def group_spheres(rcv_points, group):
    """Each group's bounding sphere (centre, radius; mm) and its members' rows (the last group repeats its last
    receiver)."""
    n_rcv = rcv_points.shape[0]
    n_groups = -(-n_rcv // group)
    members = np.minimum(np.arange(n_groups * group).reshape(n_groups, group), n_rcv - 1)
    centre = rcv_points[members].mean(axis=1)
    spread = np.linalg.norm(rcv_points[members] - centre[:, None, :], axis=2).max(axis=1)
    return centre, spread, members


def shared_walks(centre, spread, limit, levels: int = SHARED_LEVELS, fanout: int = WALK_FANOUT, scale: float = 0.0):
    """The runs of consecutive groups that share the upper part of their walk (:func:`_traverse`), for groups of
    bounding spheres ``centre (g, 3)``, ``spread (g,)`` (mm) and least allowances ``limit (g, C)``: ``levels`` levels
    of runs of ``fanout**k`` groups, the coarsest first. Each run has a point (its groups' mean centre), by how much
    less and more than its distance to a node's centre each group's nearest distance may be (mm, with a margin for
    the rounding of distances between points up to ``scale`` mm from the origin), and its groups' least and largest
    allowance (the least of the numbers: a group's NaN allowance passes every node it meets; a NaN largest
    allowance opens nothing for all).
    Returns ``(points, less, more, allow_lo, allow_hi, level_first, level_span)``, the runs of every level one after
    another (``level_first``: each level's first)."""
    n_groups = centre.shape[0]
    spans = [fanout**k for k in range(int(levels), 0, -1)]
    finite = np.abs(centre[np.isfinite(centre)])
    margin = 1e-9 * (1.0 + max(float(scale), float(finite.max(initial=0.0))))
    parts, first = [], [0]
    for span in spans:
        n_runs = -(-n_groups // span)
        members = np.minimum(np.arange(n_runs * span).reshape(n_runs, span), n_groups - 1)
        point = centre[members].mean(axis=1)
        offset = np.linalg.norm(centre[members] - point[:, None, :], axis=2)
        less = (offset + spread[members]).max(axis=1) + margin
        more = (offset - spread[members]).max(axis=1) + margin
        allow = limit[members]
        parts.append((point, less, more, np.fmin.reduce(allow, axis=1), allow.max(axis=1)))
        first.append(first[-1] + n_runs)
    if not parts:
        n_c = limit.shape[1]
        parts = [(np.zeros((0, 3)), np.zeros(0), np.zeros(0), np.zeros((0, n_c)), np.zeros((0, n_c)))]
    joined = tuple(np.ascontiguousarray(np.concatenate(column)) for column in zip(*parts))
    return (*joined, np.asarray(first[:-1], dtype=np.int64), np.asarray(spans, dtype=np.int64))


def walk_lists(
    tree, node_flux, lit, rcv_points, rule, allow=None, reach=math.inf, group=GROUP_RECEIVERS, count_only=False
):
    """The tree walk of :func:`~translucency.scatter.hierarchy.tree_sum` on its own: for every group of ``group``
    consecutive receivers (positions mm), the sources and clusters it evaluates under ``rule``
    (:class:`~translucency.scatter.hierarchy.Opening`), each node's aggregate error held to the group's ``allow``
    (``(n_rcv, C)``, the least of its members; None: no limit, the first estimate's walk).

    Nodes without flux (``node_flux (nodes, C)``) are skipped, and only sources with ``lit`` are listed. Returns
    ``(starts, direct, clustered, columns)``: the group's list is ``columns[starts[g] : starts[g] + direct[g]
    + clustered[g]]``, entries ``j < n`` source ``j`` and ``n + k`` node ``k``'s cluster (``count_only``: the
    counts only, ``columns`` empty).
    """
    centre, spread, members = group_spheres(rcv_points, group)
    node_flux = np.ascontiguousarray(node_flux, dtype=np.float64)  # one layout: numba compiles the walk once
    n_groups = centre.shape[0]
    if allow is None:
        limit = np.full((n_groups, node_flux.shape[1]), np.inf)
    else:
        limit = np.ascontiguousarray(np.asarray(allow, dtype=np.float64)[members].min(axis=1))
    g_direct = np.zeros(n_groups, dtype=np.int64)
    g_clustered = np.zeros(n_groups, dtype=np.int64)
    nodes = (tree.order, tree.start, tree.end, tree.left, tree.right, tree.centre, tree.radius)
    # the nodes' farthest coordinate (mm), from the root's sphere alone: a walk is made per block of receivers
    scale = float(np.abs(tree.centre[0]).max() + tree.radius[0]) if tree.radius.size else 0.0
    walk = (
        nodes,
        node_flux,
        lit,
        centre,
        spread,
        limit,
        reach,
        rule.kernel_arguments(),
        shared_walks(centre, spread, limit, SHARED_LEVELS, WALK_FANOUT, scale),
    )
    pieces = {}  # each range's list, by its first group (one pass: each range grows its own list)

    def walk_range(worker, lo, hi):
        pieces[lo] = _traverse(lo, hi, *walk, g_direct, g_clustered)

    for_ranges(walk_range, n_groups)
    g_counts = g_direct + g_clustered
    g_starts = np.zeros(n_groups, dtype=np.int64)
    np.cumsum(g_counts[:-1], out=g_starts[1:])
    if count_only or not pieces:
        return g_starts, g_direct, g_clustered, np.empty(0, dtype=np.int64)
    columns = np.concatenate([pieces[lo] for lo in sorted(pieces)])
    return g_starts, g_direct, g_clustered, columns


@numba.njit(cache=True, inline="always", error_model="numpy")
def small_and_far(near, radius, theta2, min_distance):
    """Whether a node of bounding ``radius`` whose centre is ``near`` from a group of receivers (mm) may be one cluster
    for it: farther than ``min_distance`` from the node's sphere and ``radius < theta * near`` (``theta2 = theta^2``;
    :class:`Opening`, docs/physics.md §8.3)."""
    return near > radius + min_distance and radius * radius < theta2 * near * near


@numba.njit(cache=True, inline="always", error_model="numpy")
def bound_index(distance, log_first, per_log, n_bound):
    """The entry of :class:`Opening`'s table of a pair's magnitude (or of the profile's bends) at the nearest tabulated
    distance below ``distance`` (mm), within the table (its first at a distance of 0, which has no logarithm)."""
    return min(max(int((math.log(max(distance, 1e-300)) - log_first) * per_log), 0), n_bound - 1)


@numba.njit(cache=True, inline="always", error_model="numpy")
def aggregate_error(near, radius, curvature, flux, pair_bound):
    """The estimate of one channel's error of a node's aggregate (:class:`Opening`): ``radius^2 (1 / near^2 +
    curvature) flux pair_bound``, with ``near`` its centre's distance from the receivers (mm), ``curvature`` =
    ``sigma_tr^2`` (1/mm^2), its ``flux`` and a pair's magnitude at its nearest point (1/(mm^2 sr); the table of
    :class:`Opening`)."""
    return (radius * radius / (near * near) + radius * radius * curvature) * flux * pair_bound


#: What a walk does with a node (:func:`_expand`).
CLUSTER, OPEN, UNDECIDED = 1, 2, 3


@numba.njit(cache=True)
def _grown(values, at, more):
    """A copy of ``values`` twice as long and ``more`` longer, its first ``at`` entries kept (for a list that fills)."""
    grown = np.empty(2 * values.shape[0] + more, dtype=values.dtype)
    grown[:at] = values[:at]
    return grown


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _expand(first, last, heads, sphere, allowance, walk, out, at, at_heads):
    """Walk down from the nodes ``heads[first:last]`` for groups of receivers whose nearest distances to a node's
    centre are between ``|point - centre| - less`` and ``|point - centre| + more`` (mm; ``sphere = (point, less,
    more, alone)``) and whose allowances are between ``allow_lo[row]`` and ``allow_hi[row]`` (``allowance = (allow_lo,
    allow_hi, row)``), in the tree and its sources ``walk = (tree, node_flux, lit, reach, rule)`` (:func:`walk_lists`).

    A node beyond ``reach`` is skipped. It is a :data:`CLUSTER` when :func:`small_and_far` and its
    :func:`aggregate_error` within ``allow_lo`` hold at the nearest distance, and :data:`OPEN` (its children walked, or
    a leaf's lit sources listed) when they fail at the farthest distance with ``allow_hi``. Both tests are monotone in
    the distance and the allowance, so these decisions are every group's. Otherwise the node is
    :data:`UNDECIDED`: the groups may differ, as they may where a run's distances are not numbers (a receiver at
    NaN). For one group (``alone``: ``less == -more``, ``allow_lo`` the same as ``allow_hi``) nothing is undecided.

    Appends the listed sources and clusters (source ``j``, or ``n + node``) to ``out`` from ``at`` and the
    undecided nodes to ``heads`` from ``at_heads`` (past ``last``). Returns ``(out, at, heads, at_heads, direct,
    clustered)``: the arrays, grown as needed, and the counts of sources and clusters appended."""
    point, less, more, alone = sphere
    allow_lo, allow_hi, row = allowance
    tree, node_flux, lit, reach, rule = walk
    order, start, end, left, right, centre, radius = tree
    theta, min_distance, bound, log_first, per_log, curvature = rule
    theta2 = theta * theta
    n_src = lit.shape[0]
    n_c = node_flux.shape[1]
    n_bound = bound.shape[1]
    stack = np.empty(128, dtype=np.int64)
    px, py, pz = point[0], point[1], point[2]
    n_direct = 0
    n_cluster = 0
    for head in range(first, last):
        top = 1
        stack[0] = heads[head]
        while top > 0:
            top -= 1
            k = stack[top]
            weight = 0.0
            for c in range(n_c):
                weight += node_flux[k, c]
            if weight <= 0.0:
                continue
            dx = px - centre[k, 0]
            dy = py - centre[k, 1]
            dz = pz - centre[k, 2]
            distance = math.sqrt(dx * dx + dy * dy + dz * dz)
            rk = radius[k]
            near_lo = distance - less
            near_hi = distance + more
            if not alone and not near_lo <= near_hi:  # a run's bounds that are not numbers: its groups decide alone
                what = UNDECIDED
            elif near_lo > reach + rk:
                continue
            else:
                what = UNDECIDED if near_hi > reach + rk else OPEN
            if what == OPEN and small_and_far(near_lo, rk, theta2, min_distance):
                what = CLUSTER
                at_bound = bound_index(near_lo - rk, log_first, per_log, n_bound)
                for c in range(n_c):
                    if (
                        aggregate_error(near_lo, rk, curvature[c], node_flux[k, c], bound[c, at_bound])
                        > allow_lo[row, c]
                    ):
                        what = OPEN
                        break
            if what == OPEN and not alone and small_and_far(near_hi, rk, theta2, min_distance):
                what = UNDECIDED  # the farthest may take it: open only if its aggregate errs too much even there
                at_bound = bound_index(near_hi - rk, log_first, per_log, n_bound)
                for c in range(n_c):
                    if (
                        aggregate_error(near_hi, rk, curvature[c], node_flux[k, c], bound[c, at_bound])
                        > allow_hi[row, c]
                    ):
                        what = OPEN
                        break
            if what == CLUSTER:
                if at == out.shape[0]:
                    out = _grown(out, at, np.int64(1))
                out[at] = n_src + k
                at += 1
                n_cluster += 1
            elif what == UNDECIDED:
                if at_heads == heads.shape[0]:
                    heads = _grown(heads, at_heads, np.int64(1))
                heads[at_heads] = k
                at_heads += 1
            elif what == OPEN and left[k] < 0:
                if at + end[k] - start[k] > out.shape[0]:
                    out = _grown(out, at, end[k] - start[k])
                for i in range(start[k], end[k]):
                    j = order[i]
                    if lit[j]:
                        out[at] = j
                        at += 1
                        n_direct += 1
            elif what == OPEN:
                stack[top] = left[k]
                stack[top + 1] = right[k]
                top += 2
    return out, at, heads, at_heads, n_direct, n_cluster


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _traverse(lo, hi, tree, node_flux, lit, rcv_points, rcv_spread, allow, reach, rule, shared, direct, clustered):
    """Walk the tree for groups ``lo .. hi - 1`` of receivers (a sphere each: ``rcv_points`` centres, ``rcv_spread``
    radii, mm; ``allow (groups, C)`` the least allowance of each): count the lit sources and clusters each evaluates
    into ``direct`` and ``clustered``, and return their columns (source ``j`` or ``n + node``), group after group,
    in one array that grows as it fills. A node is a cluster for a group when :func:`_expand` takes it at its
    sphere's nearest distance.

    ``shared`` (:func:`shared_walks`) holds, level by level from the coarsest, the spheres of runs of consecutive
    groups: a run walks from its parent's undecided nodes and lists what every group of it would decide alike
    (:func:`_expand` between the nearest and the farthest distance its groups may have, and between their least
    and largest allowance); each group lists that and walks on from its last run's undecided nodes. The lists are
    those of each group walked alone from the root, in another order."""
    centres, less, more, allow_lo, allow_hi, level_first, level_span = shared
    walk = (tree, node_flux, lit, reach, rule)
    n_levels = level_span.shape[0]
    columns = np.empty(max(1024, 256 * (hi - lo)), dtype=np.int64)
    at = 0
    listed = np.empty(1024, dtype=np.int64)  # the runs' lists, level after level
    listed_end = np.zeros(n_levels + 1, dtype=np.int64)
    heads = np.empty(1024, dtype=np.int64)  # the root, then the runs' undecided nodes, level after level
    heads[0] = 0
    heads_end = np.zeros(n_levels + 2, dtype=np.int64)
    heads_end[1] = 1
    run_direct = np.zeros(n_levels, dtype=np.int64)
    run_cluster = np.zeros(n_levels, dtype=np.int64)
    for o in range(lo, hi):
        for level in range(n_levels):
            if o != lo and o % level_span[level] != 0:
                continue
            run = level_first[level] + o // level_span[level]
            sphere = (centres[run], less[run], more[run], np.bool_(False))
            listed, end_listed, heads, end_heads, run_direct[level], run_cluster[level] = _expand(
                heads_end[level],
                heads_end[level + 1],
                heads,
                sphere,
                (allow_lo, allow_hi, run),
                walk,
                listed,
                listed_end[level],
                heads_end[level + 1],
            )
            listed_end[level + 1] = end_listed
            heads_end[level + 2] = end_heads
        if at + listed_end[n_levels] > columns.shape[0]:
            columns = _grown(columns, at, listed_end[n_levels])
        columns[at : at + listed_end[n_levels]] = listed[: listed_end[n_levels]]
        at += listed_end[n_levels]
        sphere = (rcv_points[o], rcv_spread[o], -rcv_spread[o], np.bool_(True))
        first, last = heads_end[n_levels], heads_end[n_levels + 1]
        columns, at, heads, _, n_direct, n_cluster = _expand(
            first, last, heads, sphere, (allow, allow, o), walk, columns, at, last
        )
        direct[o] = n_direct + run_direct.sum()
        clustered[o] = n_cluster + run_cluster.sum()
    return columns[:at]


#: The compiled kernels of the walk: numba compiles each on first use; the set-up compiles them ahead
#: (:mod:`translucency.app.warmup`).
WALK_KERNELS = (
    _traverse,
    _expand,
)
