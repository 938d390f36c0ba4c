"""Every (source, receiver) pair's ``S_d`` summed on an NVIDIA GPU: method ``exact`` (docs/physics.md §5.3).

The same sum as :func:`translucency.scatter.kernels.vertex_sum`, by the same code: each GPU thread runs the
CPU kernel's loop over sources (:func:`~translucency.scatter.kernels.vertex_sources`, compiled for CUDA) over a
chunk of the sources for one receiver, in float64, and the chunks' sums are added in a fixed order on the host,
so that a result does not depend on the scheduling. The sources are split into chunks only so that a small
mesh still gives the GPU enough threads.

=============== ================================================================ =====
symbol          meaning                                                          unit
=============== ================================================================ =====
table           sources: position, unit normal, unit refracted direction (9, n)  mm, 1
weights         flux per output channel and source (C, n)                        flux
partial         per chunk of sources, receiver and lane: the chunk's sum         flux / (mm^2 sr)
=============== ================================================================ =====
"""

from __future__ import annotations

import numpy as np
from numba import config, cuda

from .. import kernels

__all__ = ["PairSums", "vertex_sum"]

#: The CPU's loop over the sources, as the kernel calls it: compiled for CUDA, or run as Python in numba's simulator
#: (which cannot hand its arrays to a function compiled for the CPU).
_every_source = kernels.vertex_sources.py_func if config.ENABLE_CUDASIM else kernels.vertex_sources
#: Threads per block along the receivers.
THREADS = 128
#: Threads a call gives the GPU at least, where the receivers times the chunks of sources allow it.
TARGET_THREADS = 1 << 19
#: Fewest sources in a chunk (one thread's loop).
MIN_CHUNK = 256


@cuda.jit
def _chunk_sums(model, table, F0, F1, F2, p0, p1, p2, k0, k1, k2, rcv_points, rcv_normals, chunk, partial, clamps):
    """Thread ``(o, part)``: receiver ``o``'s sum over the sources ``part * chunk ..`` of three lanes (parameters
    ``p0, p1, p2``, flux rows ``F0, F1, F2``), by the CPU's own loop
    (:func:`~translucency.scatter.kernels.vertex_sources`)."""
    o, part = cuda.grid(2)
    n_src = table.shape[1]
    lo = part * chunk
    if o >= rcv_points.shape[0] or lo >= n_src:
        return
    hi = min(lo + chunk, n_src)
    rows = (
        table[0, lo:hi],
        table[1, lo:hi],
        table[2, lo:hi],
        table[3, lo:hi],
        table[4, lo:hi],
        table[5, lo:hi],
        table[6, lo:hi],
        table[7, lo:hi],
        table[8, lo:hi],
    )
    a0, a1, a2, count = _every_source(
        model,
        hi - lo,
        rows,
        (rcv_points[o, 0], rcv_points[o, 1], rcv_points[o, 2]),
        (rcv_normals[o, 0], rcv_normals[o, 1], rcv_normals[o, 2]),
        (p0, p1, p2),
        (F0[lo:hi], F1[lo:hi], F2[lo:hi]),
        (k0, k1, k2),
    )
    partial[part, o, 0] = a0
    partial[part, o, 1] = a1
    partial[part, o, 2] = a2
    clamps[part, o] += count


def chunk_size(n_rcv: int, n_src: int) -> int:
    """Sources per thread: all of them when the receivers alone give :data:`TARGET_THREADS`, else fewer, never
    under :data:`MIN_CHUNK`."""
    chunks = max(1, min(-(-TARGET_THREADS // max(n_rcv, 1)), -(-n_src // MIN_CHUNK)))
    return -(-n_src // chunks)


class PairSums:
    """:func:`translucency.scatter.kernels.vertex_sum` on the GPU for one set of sources, copied to the device
    once; call it with blocks of receivers. Arguments as ``vertex_sum``'s (float64, mm)."""

    def __init__(self, model, src_points, src_normals, src_w12, src_flux, params, channel_of):
        table, weights = kernels.source_columns(src_points, src_normals, src_w12, src_flux)
        self.model = int(model)
        self.n_src = table.shape[1]
        self.n_out = weights.shape[0]
        lanes = kernels.channel_lanes(params, channel_of, self.n_out)
        counted = kernels.clamp_counted(channel_of, lanes.shape[0])
        self.table = cuda.to_device(np.ascontiguousarray(table, dtype=np.float64))
        rows = [cuda.to_device(np.ascontiguousarray(row, dtype=np.float64)) for row in weights]
        # per group of three lanes: flux rows (the last repeated past the end), parameters, clamp counting
        self.groups = [
            (
                *(rows[min(c, self.n_out - 1)] for c in range(c0, c0 + 3)),
                *(tuple(float(v) for v in lanes[c]) for c in range(c0, c0 + 3)),
                *(int(counted[c]) for c in range(c0, c0 + 3)),
            )
            for c0 in range(0, lanes.shape[0], 3)
        ]

    def __call__(self, rcv_points, rcv_normals):
        """``(B (n_rcv, C) float64, clamped (n_rcv,) int64)`` at these receivers (mm, unit normals)."""
        n_rcv = int(rcv_points.shape[0])
        if n_rcv == 0 or self.n_src == 0:
            return np.zeros((n_rcv, self.n_out)), np.zeros(n_rcv, dtype=np.int64)
        chunk = chunk_size(n_rcv, self.n_src)
        chunks = -(-self.n_src // chunk)
        points = cuda.to_device(np.ascontiguousarray(rcv_points, dtype=np.float64))
        normals = cuda.to_device(np.ascontiguousarray(rcv_normals, dtype=np.float64))
        clamps = cuda.to_device(np.zeros((chunks, n_rcv), dtype=np.int64))
        blocks = (-(-n_rcv // THREADS), chunks)
        B = np.empty((n_rcv, 3 * len(self.groups)))
        for g, group in enumerate(self.groups):
            partial = cuda.device_array((chunks, n_rcv, 3), dtype=np.float64)
            _chunk_sums[blocks, (THREADS, 1)](self.model, self.table, *group, points, normals, chunk, partial, clamps)
            B[:, 3 * g : 3 * g + 3] = partial.copy_to_host().sum(axis=0)
        return np.ascontiguousarray(B[:, : self.n_out]), clamps.copy_to_host().sum(axis=0)


def vertex_sum(model, src_points, src_normals, src_w12, src_flux, rcv_points, rcv_normals, params, channel_of):
    """:func:`translucency.scatter.kernels.vertex_sum` on the GPU: same arguments, same ``(B, clamped)``."""
    return PairSums(model, src_points, src_normals, src_w12, src_flux, params, channel_of)(rcv_points, rcv_normals)
