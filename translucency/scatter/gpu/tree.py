"""Method ``tree`` on an NVIDIA GPU: the walk of the source tree and its sum in one kernel (docs/physics.md §8.3).

The CPU lists what each group of receivers evaluates (:func:`~translucency.scatter.treewalk.walk_lists`) and sums
the lists (:func:`~translucency.scatter.listsums.grouped_sum`). A GPU thread cannot grow a list, so each thread walks
the tree for its receiver's group and sums each source or cluster at its receiver as the walk meets it. The walk's
tests are the CPU's own (:func:`~translucency.scatter.treewalk.small_and_far`,
:func:`~translucency.scatter.treewalk.bound_index`, :func:`~translucency.scatter.treewalk.aggregate_error`) and so
is a pair's sum (:func:`~translucency.scatter.kernels.weighted_pair`), so the GPU evaluates what the CPU evaluates,
in float64, only in another order. The receivers of a group are neighbouring threads and walk alike, so a warp's
threads mostly take the same branches.

=========== ========================================================================= =====
symbol      meaning                                                                   unit
=========== ========================================================================= =====
table       sources, then the nodes' aggregates: position, normal, refracted direction mm, 1
allow       per group and channel, the error a node's aggregate may make              flux / (mm^2 sr)
=========== ========================================================================= =====
"""

from __future__ import annotations

import math

import numpy as np
from numba import cuda, int64

from .. import kernels, treewalk
from ..spread import spread_factor
from .compiled import for_the_device, lane_groups, to_device
from .probe import said_plainly

__all__ = ["WalkedSums"]


_pair = for_the_device(kernels.weighted_pair)
_small_and_far = for_the_device(treewalk.small_and_far)
_bound_index = for_the_device(treewalk.bound_index)
_aggregate_error = for_the_device(treewalk.aggregate_error)
_table_rows = for_the_device(kernels.table_rows)
_spread_factor = for_the_device(spread_factor)


@cuda.jit(device=True, inline=True)
def _line(bends, c, at):
    """Lane ``c``'s four numbers of the profile's bends at entry ``at``
    (:func:`~translucency.scatter.spread.profile_bends`)."""
    return bends[c, 0, at], bends[c, 1, at], bends[c, 2, at], bends[c, 3, at]


@cuda.jit(device=True, inline=True)
def _cluster_factors(cov, offset, head_offset, bends, log_first, per_log):
    """Three lanes' :func:`~translucency.scatter.spread.spread_factor` of a cluster of covariance ``cov`` (six
    numbers, mm^2) at the receiver ``offset`` from its centre (mm), its bends read at the group's first receiver
    (``head_offset``), as the CPU's sums take them (``listsums._gathered_spread``)."""
    h0, h1, h2 = head_offset
    at = _bound_index(math.sqrt(h0 * h0 + h1 * h1 + h2 * h2), log_first, per_log, bends.shape[2])
    spread = (cov[0], cov[1], cov[2], cov[3], cov[4], cov[5])
    trace = cov[0] + cov[1] + cov[2]
    o0, o1, o2 = offset
    return (
        _spread_factor(o0, o1, o2, spread, trace, _line(bends, 0, at)),
        _spread_factor(o0, o1, o2, spread, trace, _line(bends, 1, at)),
        _spread_factor(o0, o1, o2, spread, trace, _line(bends, 2, at)),
    )


#: Threads per block.
THREADS = 128
#: Depth of a thread's stack of nodes to visit: a walk holds at most one node per level of the tree and one more,
#: and a tree of 2^60 leaves would need 61.
STACK = 64


@cuda.jit
def _walked_sums(
    model,
    nodes,
    node_flux,
    lit,
    table,
    node_spread,
    flux,
    lanes,
    bends,
    receivers,
    groups,
    allow,
    walk,
    opening,
    out,
    counts,
):
    """Thread ``r``: receiver ``r``'s sum of three lanes over what its group's walk takes. ``nodes`` are the tree's
    ``(order, start, end, left, right, centre, radius)``; ``node_spread`` the covariance of each node's positions
    (:func:`~translucency.scatter.hierarchy.aggregate`); ``flux`` the three lanes' rows of flux per column of
    ``table``, ``lanes`` their parameters and ``bends`` their profile's bends (``(3, 4, K)``,
    :func:`~translucency.scatter.spread.profile_bends`), by which a cluster's pair is scaled
    (:func:`~translucency.scatter.spread.spread_factor`); ``receivers`` the points and normals, ``groups`` the
    groups' centres and radii; ``walk`` is ``(group, reach mm)``; ``opening`` ``(theta^2, min_distance mm, bound,
    log_first, per_log, curvature)`` (:class:`~translucency.scatter.hierarchy.Opening`). Writes ``out[r]`` and the
    sources and clusters summed into ``counts[r]``."""
    r = cuda.grid(1)
    points, normals = receivers
    if r >= points.shape[0]:
        return
    order, start, end, left, right, centre, radius = nodes
    g_centre, g_spread = groups
    group, reach = walk
    theta2, min_distance, bound, log_first, per_log, curvature = opening
    F0, F1, F2 = flux
    X0, X1, X2, N0, N1, N2, W0, W1, W2 = _table_rows(table)
    g = r // group
    head = g * group
    n_src = lit.shape[0]
    n_c = node_flux.shape[1]
    n_bound = bound.shape[1]
    x0, x1, x2 = points[r, 0], points[r, 1], points[r, 2]
    n_o = (normals[r, 0], normals[r, 1], normals[r, 2])
    cx, cy, cz, spread = g_centre[g, 0], g_centre[g, 1], g_centre[g, 2], g_spread[g]
    stack = cuda.local.array(STACK, int64)
    stack[0] = 0
    top = 1
    a0 = 0.0
    a1 = 0.0
    a2 = 0.0
    n_direct = 0
    n_cluster = 0
    while top > 0:
        top -= 1
        k = stack[top]
        weight = 0.0
        for c in range(n_c):
            weight += node_flux[k, c]
        if weight <= 0.0:
            continue
        dx = cx - centre[k, 0]
        dy = cy - centre[k, 1]
        dz = cz - centre[k, 2]
        rk = radius[k]
        near = math.sqrt(dx * dx + dy * dy + dz * dz) - spread
        if near > reach + rk:
            continue
        accept = _small_and_far(near, rk, theta2, min_distance)
        if accept:
            at_bound = _bound_index(near - rk, log_first, per_log, n_bound)
            for c in range(n_c):
                if _aggregate_error(near, rk, curvature[c], node_flux[k, c], bound[c, at_bound]) > allow[g, c]:
                    accept = False
                    break
        if accept or left[k] < 0:
            first, last = (0, 1) if accept else (start[k], end[k])
            f0, f1, f2 = 1.0, 1.0, 1.0
            if accept:
                j = n_src + k
                offset = (x0 - X0[j], x1 - X1[j], x2 - X2[j])
                head_offset = (points[head, 0] - X0[j], points[head, 1] - X1[j], points[head, 2] - X2[j])
                f0, f1, f2 = _cluster_factors(node_spread[k], offset, head_offset, bends, log_first, per_log)
            for i in range(first, last):
                j = n_src + k if accept else order[i]
                if accept or lit[j]:
                    e0, e1, e2, _ = _pair(
                        model,
                        (x0 - X0[j], x1 - X1[j], x2 - X2[j]),
                        (N0[j], N1[j], N2[j], W0[j], W1[j], W2[j]),
                        n_o,
                        lanes,
                        (F0[j], F1[j], F2[j]),
                        (0, 0, 0),
                    )
                    a0 += e0 * f0
                    a1 += e1 * f1
                    a2 += e2 * f2
                    if accept:
                        n_cluster += 1
                    else:
                        n_direct += 1
        else:
            stack[top] = left[k]
            stack[top + 1] = right[k]
            top += 2
    out[r, 0] = a0
    out[r, 1] = a1
    out[r, 2] = a2
    counts[r, 0] = n_direct
    counts[r, 1] = n_cluster


class WalkedSums:
    """:class:`translucency.scatter.hierarchy.ListedWalk` on the GPU: the tree and the sources with their nodes'
    aggregates copied to the device once; called with ``(rcv_points mm, rcv_normals, allow, group)`` it walks and sums
    (:func:`_walked_sums`) and returns ``(B (n_rcv, C), direct (n_rcv,), clustered (n_rcv,))``, the counts those of
    each receiver's group, as the CPU's."""

    #: Receivers per call of :func:`~translucency.scatter.hierarchy.tree_sum`: about 100 bytes each on the device
    #: (points, normals, the group's sphere and allowance, ``B`` of three lanes, the counts), 400 MB.
    block = 1 << 22
    #: Receivers that share a walk: the CPU's (:data:`~translucency.scatter.treewalk.GROUP_RECEIVERS`). A warp's 32
    #: threads walk 32 / ``group`` trees; larger groups walk alike but evaluate more (bench/gpu.py tries 4 to 32).
    group = treewalk.GROUP_RECEIVERS

    @said_plainly
    def __init__(self, model, tree, sources, params, channel_of, rule, reach=math.inf):
        self.model = int(model)
        self.rule, self.reach = rule, float(reach)
        self.n_out = sources.n_channels
        lanes = kernels.channel_lanes(params, channel_of, self.n_out)

        self.nodes = (
            to_device(tree.order, np.int64),
            to_device(tree.start, np.int64),
            to_device(tree.end, np.int64),
            to_device(tree.left, np.int64),
            to_device(tree.right, np.int64),
            to_device(tree.centre),
            to_device(tree.radius),
        )
        self.node_flux = to_device(sources.node_flux)
        self.lit = to_device(sources.lit, np.bool_)
        self.table = to_device(sources.records[:, :9].T)
        rows = [to_device(sources.records[:, 9 + c]) for c in range(self.n_out)]
        self.spread = to_device(sources.spread)
        self.groups = [  # per group of three lanes: flux rows, parameters, the profile's bends
            (tuple(rows[c] for c in channels), lane_params, to_device(rule.bends[list(channels)]))
            for _, channels, lane_params in lane_groups(lanes, self.n_out)
        ]
        self.opening = (
            rule.theta * rule.theta,
            float(rule.min_distance),
            to_device(rule.bound),
            float(rule.log_first),
            float(rule.per_log),
            to_device(rule.curvature),
        )

    @said_plainly
    def __call__(self, rcv_points, rcv_normals, allow, group):
        n_rcv = int(rcv_points.shape[0])
        if n_rcv == 0:
            empty = np.zeros(0, dtype=np.int64)
            return np.zeros((0, self.n_out)), empty, empty
        centre, spread, members = treewalk.group_spheres(rcv_points, group)
        if allow is None:
            limit = np.full((centre.shape[0], self.n_out), np.inf)
        else:
            limit = np.asarray(allow, dtype=np.float64)[members].min(axis=1)
        receivers = (to_device(rcv_points), to_device(rcv_normals))
        groups = (to_device(centre), to_device(spread))
        limit = to_device(limit)
        B = np.empty((n_rcv, 3 * len(self.groups)))
        counts = cuda.device_array((n_rcv, 2), dtype=np.int64)
        blocks = -(-n_rcv // THREADS)
        for g, (flux, lanes, bends) in enumerate(self.groups):
            out = cuda.device_array((n_rcv, 3), dtype=np.float64)
            _walked_sums[blocks, THREADS](
                self.model,
                self.nodes,
                self.node_flux,
                self.lit,
                self.table,
                self.spread,
                flux,
                lanes,
                bends,
                receivers,
                groups,
                limit,
                (int(group), self.reach),
                self.opening,
                out,
                counts,
            )
            B[:, 3 * g : 3 * g + 3] = out.copy_to_host()
        counted = counts.copy_to_host()
        return np.ascontiguousarray(B[:, : self.n_out]), counted[:, 0], counted[:, 1]
