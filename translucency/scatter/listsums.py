"""The far field's sums over the tree's lists (docs/physics.md §8.3): each group of receivers' sources and clusters
gathered once into buffers of the thread, then summed at each receiver of the group by the exact kernel's loop
(:func:`~translucency.scatter.kernels.vertex_sources`), the mesh's own sources in float64 and the clusters in the
precision the walk's :class:`~translucency.scatter.hierarchy.Opening` asks for."""

from __future__ import annotations

import math

import numba
import numpy as np

from ..threads import for_ranges, thread_count
from .kernels import (
    MODEL_DIRECTIONAL,
    group_inputs,
    in_precision_of,
    rows_kernel,
    store_three,
    table_rows,
    vertex_sources,
)
from .spread import spread_factor
from .treewalk import bound_index


def grouped_sum(
    model,
    rcv_points,
    rcv_normals,
    records,
    spread,
    bends,
    n_sources,
    g_starts,
    g_counts,
    group,
    columns,
    lanes,
    precision=np.float64,
):
    """Per receiver ``r`` of group ``g = r // group``: ``B[r, c] = sum_k S_d(source columns[k]; x_r)[c] * flux[c]``
    over ``k`` in ``g_starts[g] .. g_starts[g] + g_counts[g]``, for receivers that share their list ``group`` at a
    time (the tree's walks).

    The sources are rows of ``records (P, 9 + C)``: position (mm), unit normal, unit refracted direction, flux per
    channel, one row each, so that gathering one reads one or two cache lines. The rows from ``n_sources`` on are
    clusters: each with the covariance of its positions in ``spread (P - n_sources, 6)`` (mm^2,
    :func:`~translucency.scatter.hierarchy.aggregate`), by which its flux is scaled at each receiver
    (:func:`~translucency.scatter.spread.spread_factor`, with ``bends``: the table of
    :func:`~translucency.scatter.spread.profile_bends`, the ``log`` of its first distance in mm and its steps per unit
    of ``log`` distance). ``lanes`` is :func:`~translucency.scatter.kernels.channel_lanes` of the parameters; ``model``
    as in :func:`~translucency.scatter.kernels.vertex_sum`. Each group's sources are gathered once into contiguous
    buffers of the thread, their positions taken from the group's first receiver, and every receiver of the group
    runs the exact kernel's loop over them: ``1 / group`` of the scattered reads, and loops that vectorise.

    The rows below ``n_sources`` (the mesh's own sources) are summed in float64, the others (the clusters) in
    ``precision`` (``np.float64``, or ``np.float32``: twice the pairs a vector step, each within about ``2e-5`` of
    itself; docs/physics.md §8.3). The near field's correction takes the nearest sources' values off again, and
    where the mesh is coarse next to ``1 / sigma_tr`` the two cancel to many digits. Returns ``(n_rcv, C)`` float64.
    """
    n_channels = records.shape[1] - 9
    out = np.zeros((rcv_points.shape[0], n_channels))
    longest = max(int(g_counts.max()) if g_counts.size else 0, 1)
    sources = np.empty((thread_count(), 9 + n_channels, longest))
    clusters = np.empty((thread_count(), 16 + 5 * n_channels, longest), dtype=precision)
    scaled = np.empty((thread_count(), 3, longest), dtype=precision)
    for_ranges(
        rows_kernel(model, _grouped_rows_directional, _grouped_rows_radial),
        g_starts.shape[0],
        model,
        (rcv_points, rcv_normals),
        (
            records,
            np.ascontiguousarray(spread, dtype=np.float64),
            (np.ascontiguousarray(bends[0], dtype=np.float64), float(bends[1]), float(bends[2])),
            int(n_sources),
        ),
        (g_starts, g_counts, int(group), columns),
        (np.ascontiguousarray(lanes, dtype=np.float64), np.ascontiguousarray(lanes, dtype=precision)),
        (sources, clusters, scaled),
        out,
    )
    return out


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _grouped_rows_directional(worker, lo, hi, model, receivers, table, lists, lanes, buffers, out):
    """:func:`_grouped_rows` of the directional dipole (``model`` is ignored: a constant here)."""
    _grouped_rows(worker, lo, hi, MODEL_DIRECTIONAL, receivers, table, lists, lanes, buffers, out)


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _grouped_rows_radial(worker, lo, hi, model, receivers, table, lists, lanes, buffers, out):
    """:func:`_grouped_rows` of the standard and better dipoles."""
    _grouped_rows(worker, lo, hi, model, receivers, table, lists, lanes, buffers, out)


@numba.njit(cache=True, inline="always")
def _gathered(buffer, at, records, i, origin, n_out):
    """Row ``i`` of ``records`` into column ``at`` of ``buffer`` (in its precision), its position from ``origin``."""
    buffer[0, at] = records[i, 0] - origin[0]
    buffer[1, at] = records[i, 1] - origin[1]
    buffer[2, at] = records[i, 2] - origin[2]
    for row in range(3, 9 + n_out):
        buffer[row, at] = records[i, row]


@numba.njit(cache=True, inline="always", fastmath=True)
def _buffer_sums(model, buffer, n, lanes, c0, x_o, n_o, flux_rows):
    """Three channels' sums (from ``c0``) over the ``n`` gathered sources of ``buffer`` at a receiver whose offset
    from the buffer's origin is ``x_o`` (mm) and normal ``n_o``, both in the buffer's precision, with the flux
    ``flux_rows``."""
    _, _, _, p0, p1, p2 = group_inputs(buffer[9:], lanes, c0)
    a0, a1, a2, _ = vertex_sources(model, n, table_rows(buffer), x_o, n_o, (p0, p1, p2), flux_rows, (0, 0, 0))
    return a0, a1, a2


@numba.njit(cache=True, inline="always")
def _gathered_spread(clusters, at, spread, node, bends, distance, n_out):
    """Into column ``at`` of ``clusters``, after its source's rows (:func:`_gathered`): the covariance of node
    ``node``'s positions (``spread``), its trace, and each channel's two bends of the profile at the nearest tabulated
    distance below ``distance`` (mm, from the group's first receiver; ``bends``: :func:`grouped_sum`'s), as lines in
    the distance that each receiver of the group reads at its own."""
    table, log_first, per_log = bends
    row = 9 + n_out
    for m in range(6):
        clusters[row + m, at] = spread[node, m]
    clusters[row + 6, at] = spread[node, 0] + spread[node, 1] + spread[node, 2]
    k = bound_index(distance, log_first, per_log, table.shape[2])
    for c in range(n_out):
        for m in range(4):
            clusters[row + 7 + 4 * c + m, at] = table[c, m, k]


@numba.njit(cache=True, inline="always", fastmath=True)
def _spread_flux(clusters, n, n_out, c0, x_o, scaled):
    """The flux of three channels (from ``c0``) of the ``n`` gathered clusters, each times its
    :func:`~translucency.scatter.spread.spread_factor` at the receiver ``x_o`` (mm from the buffer's origin), with
    the spread and bends gathered by :func:`_gathered_spread`, into ``scaled (3, n)``; returns its three rows."""
    k0, k1, k2 = c0, min(c0 + 1, n_out - 1), min(c0 + 2, n_out - 1)
    F0, F1, F2 = clusters[9 + k0], clusters[9 + k1], clusters[9 + k2]
    row = 9 + n_out
    S = clusters[row : row + 6]
    T = clusters[row + 6]
    L0, L1, L2 = (
        clusters[row + 7 + 4 * k0 : row + 11 + 4 * k0],
        clusters[row + 7 + 4 * k1 : row + 11 + 4 * k1],
        clusters[row + 7 + 4 * k2 : row + 11 + 4 * k2],
    )
    s0, s1, s2 = scaled[0], scaled[1], scaled[2]
    for j in range(n):
        x0, x1, x2 = x_o[0] - clusters[0, j], x_o[1] - clusters[1, j], x_o[2] - clusters[2, j]
        spread = (S[0, j], S[1, j], S[2, j], S[3, j], S[4, j], S[5, j])
        s0[j] = F0[j] * spread_factor(x0, x1, x2, spread, T[j], (L0[0, j], L0[1, j], L0[2, j], L0[3, j]))
        s1[j] = F1[j] * spread_factor(x0, x1, x2, spread, T[j], (L1[0, j], L1[1, j], L1[2, j], L1[3, j]))
        s2[j] = F2[j] * spread_factor(x0, x1, x2, spread, T[j], (L2[0, j], L2[1, j], L2[2, j], L2[3, j]))
    return s0, s1, s2


@numba.njit(cache=True, inline="always", fastmath=True, error_model="numpy")
def _grouped_rows(worker, lo, hi, model, receivers, table, lists, lanes, buffers, out):
    """Groups ``lo .. hi - 1`` of :func:`grouped_sum` (``receivers``: points and normals; ``table``: the records,
    the clusters' spread, the profile's bends and ``n_sources``; ``lists``: starts, counts, group and columns): gather
    the list (the sources into the float64 buffer, the clusters with their spread into the other; positions from the
    group's first receiver), then each receiver of the group over both."""
    points, normals = receivers
    records, spread, bends, n_sources = table
    starts, counts, group, columns = lists
    n_out = records.shape[1] - 9
    n_rcv = points.shape[0]
    lanes64, lanes_far = lanes
    sources, clusters, scaled = buffers[0][worker], buffers[1][worker], buffers[2][worker]
    like = clusters[0, 0]  # its value is not read: its type is the clusters' precision
    for g in range(lo, hi):
        first, n = starts[g], counts[g]
        head = g * group
        origin = (points[head, 0], points[head, 1], points[head, 2])
        n_near, n_far = 0, 0
        for k in range(n):
            i = columns[first + k]
            if i < n_sources:
                _gathered(sources, n_near, records, i, origin, n_out)
                n_near += 1
            else:
                _gathered(clusters, n_far, records, i, origin, n_out)
                distance = math.sqrt(clusters[0, n_far] ** 2 + clusters[1, n_far] ** 2 + clusters[2, n_far] ** 2)
                _gathered_spread(clusters, n_far, spread, i - n_sources, bends, distance, n_out)
                n_far += 1
        for r in range(head, min(n_rcv, head + group)):
            x_o = (points[r, 0] - origin[0], points[r, 1] - origin[1], points[r, 2] - origin[2])
            n_o = (normals[r, 0], normals[r, 1], normals[r, 2])
            x_far = (in_precision_of(x_o[0], like), in_precision_of(x_o[1], like), in_precision_of(x_o[2], like))
            n_far_o = (in_precision_of(n_o[0], like), in_precision_of(n_o[1], like), in_precision_of(n_o[2], like))
            for channel_group in range(lanes64.shape[0] // 3):
                c0 = 3 * channel_group
                near_flux = group_inputs(sources[9 : 9 + n_out], lanes64, c0)[:3]
                a0, a1, a2 = _buffer_sums(model, sources, n_near, lanes64, c0, x_o, n_o, near_flux)
                far_flux = _spread_flux(clusters, n_far, n_out, c0, x_far, scaled)
                b0, b1, b2 = _buffer_sums(model, clusters, n_far, lanes_far, c0, x_far, n_far_o, far_flux)
                store_three(out, r, c0, n_out, a0 + b0, a1 + b1, a2 + b2)


#: The compiled kernel of the directional dipole's sums of lists (a ``tree`` solve's far field): numba compiles it on
#: first use; the set-up compiles it ahead (:mod:`translucency.app.warmup`).
LIST_KERNELS = (_grouped_rows_directional,)
