"""The far field's sums over the tree's lists (docs/physics.md §8.3): each group of receivers' sources and clusters
gathered once into buffers of the thread, then summed at each receiver of the group by the exact kernel's loop
(:func:`~translucency.scatter.kernels.vertex_sources`), the mesh's own sources in float64 and the clusters in the
precision the walk's :class:`~translucency.scatter.hierarchy.Opening` asks for."""

from __future__ import annotations

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


def grouped_sum(
    model, rcv_points, rcv_normals, records, n_sources, g_starts, g_counts, group, columns, lanes, precision=np.float64
):
    """Per receiver ``r`` of group ``g = r // group``: ``B[r, c] = sum_k S_d(source columns[k]; x_r)[c] * flux[c]``
    over ``k`` in ``g_starts[g] .. g_starts[g] + g_counts[g]``, for receivers that share their list ``group`` at a
    time (the tree's walks).

    The sources are rows of ``records (P, 9 + C)``: position (mm), unit normal, unit refracted direction, flux per
    channel, one row each, so that gathering one reads one or two cache lines; ``lanes`` is
    :func:`~translucency.scatter.kernels.channel_lanes` of the parameters; ``model`` as in
    :func:`~translucency.scatter.kernels.vertex_sum`. Each group's sources are gathered once into contiguous buffers
    of the thread, their positions taken from the group's first receiver, and every receiver of the group runs the
    exact kernel's loop over them: ``1 / group`` of the scattered reads, and loops that vectorise.

    The rows below ``n_sources`` (the mesh's own sources) are summed in float64, the others (the clusters) in
    ``precision`` (``np.float64``, or ``np.float32``: twice the pairs a vector step, each within about ``2e-5`` of
    itself; docs/physics.md §8.3). The near field's correction takes the nearest sources' values off again, and
    where the mesh is coarse next to ``1 / sigma_tr`` the two cancel to many digits. Returns ``(n_rcv, C)`` float64.
    """
    n_channels = records.shape[1] - 9
    out = np.zeros((rcv_points.shape[0], n_channels))
    size = (thread_count(), 9 + n_channels, max(int(g_counts.max()) if g_counts.size else 0, 1))
    for_ranges(
        rows_kernel(model, _grouped_rows_directional, _grouped_rows_radial),
        g_starts.shape[0],
        model,
        rcv_points,
        rcv_normals,
        records,
        int(n_sources),
        g_starts,
        g_counts,
        int(group),
        columns,
        (np.ascontiguousarray(lanes, dtype=np.float64), np.ascontiguousarray(lanes, dtype=precision)),
        (np.empty(size), np.empty(size, dtype=precision)),
        out,
    )
    return out


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _grouped_rows_directional(
    worker, lo, hi, model, points, normals, records, n_sources, starts, counts, group, columns, lanes, buffers, out
):
    """:func:`_grouped_rows` of the directional dipole (``model`` is ignored: a constant here)."""
    _grouped_rows(
        worker,
        lo,
        hi,
        MODEL_DIRECTIONAL,
        points,
        normals,
        records,
        n_sources,
        starts,
        counts,
        group,
        columns,
        lanes,
        buffers,
        out,
    )


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _grouped_rows_radial(
    worker, lo, hi, model, points, normals, records, n_sources, starts, counts, group, columns, lanes, buffers, out
):
    """:func:`_grouped_rows` of the standard and better dipoles."""
    _grouped_rows(
        worker, lo, hi, model, points, normals, records, n_sources, starts, counts, group, columns, lanes, buffers, out
    )


@numba.njit(cache=True, inline="always")
def _gathered(buffer, at, records, i, origin, n_out):
    """Row ``i`` of ``records`` into column ``at`` of ``buffer`` (in its precision), its position from ``origin``."""
    buffer[0, at] = records[i, 0] - origin[0]
    buffer[1, at] = records[i, 1] - origin[1]
    buffer[2, at] = records[i, 2] - origin[2]
    for row in range(3, 9 + n_out):
        buffer[row, at] = records[i, row]


@numba.njit(cache=True, inline="always", fastmath=True)
def _buffer_sums(model, buffer, n, lanes, c0, x_o, n_o):
    """Three channels' sums (from ``c0``) over the ``n`` gathered sources of ``buffer`` at a receiver whose offset
    from the buffer's origin is ``x_o`` (mm) and normal ``n_o``, both in the buffer's precision."""
    F0, F1, F2, p0, p1, p2 = group_inputs(buffer[9:], lanes, c0)
    a0, a1, a2, _ = vertex_sources(model, n, table_rows(buffer), x_o, n_o, (p0, p1, p2), (F0, F1, F2), (0, 0, 0))
    return a0, a1, a2


@numba.njit(cache=True, inline="always", fastmath=True, error_model="numpy")
def _grouped_rows(
    worker, lo, hi, model, points, normals, records, n_sources, starts, counts, group, columns, lanes, buffers, out
):
    """Groups ``lo .. hi - 1`` of :func:`grouped_sum`: gather the list (the sources into the float64 buffer, the
    clusters into the other; positions from the group's first receiver), then each receiver of the group over
    both."""
    n_out = records.shape[1] - 9
    n_rcv = points.shape[0]
    lanes64, lanes_far = lanes
    sources, clusters = buffers[0][worker], buffers[1][worker]
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
                n_far += 1
        for r in range(head, min(n_rcv, head + group)):
            x_o = (points[r, 0] - origin[0], points[r, 1] - origin[1], points[r, 2] - origin[2])
            n_o = (normals[r, 0], normals[r, 1], normals[r, 2])
            x_far = (in_precision_of(x_o[0], like), in_precision_of(x_o[1], like), in_precision_of(x_o[2], like))
            n_far_o = (in_precision_of(n_o[0], like), in_precision_of(n_o[1], like), in_precision_of(n_o[2], like))
            for channel_group in range(lanes64.shape[0] // 3):
                c0 = 3 * channel_group
                a0, a1, a2 = _buffer_sums(model, sources, n_near, lanes64, c0, x_o, n_o)
                b0, b1, b2 = _buffer_sums(model, clusters, n_far, lanes_far, c0, x_far, n_far_o)
                store_three(out, r, c0, n_out, a0 + b0, a1 + b1, a2 + b2)


#: The compiled kernel of the directional dipole's sums of lists (a ``tree`` solve's far field): numba compiles it on
#: first use; the set-up compiles it ahead (:mod:`translucency.app.warmup`).
LIST_KERNELS = (_grouped_rows_directional,)
