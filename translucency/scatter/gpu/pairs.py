"""Every (source, receiver) pair's ``S_d`` summed on an NVIDIA GPU: method ``exact`` (docs/physics.md §5.3) and
relighting's far field per light (§8.7), with relighting's near-field product where its operator fits there.

The same sum as :func:`translucency.scatter.kernels.vertex_sum`, by the same code: each GPU thread runs the
CPU kernel's loop over sources (:func:`~translucency.scatter.kernels.vertex_sources`, compiled for CUDA) over a
chunk of the sources for one receiver, in float64, and the chunks' sums are added in a fixed order on the host,
so that a result does not depend on the scheduling. The sources are split into chunks only so that a small
mesh still gives the GPU enough threads. Relighting's far field (:class:`RelitFarField`) takes off the pairs of
each receiver's near list, summed by the CPU's loop over a list
(:func:`~translucency.scatter.kernels.indexed_sources`).

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
from .compiled import for_the_device, lane_groups, to_device
from .probe import said_plainly

__all__ = ["PairSums", "RelitFarField", "vertex_sum"]

#: The CPU's loop over the sources, as the kernel calls it: compiled for CUDA, or run as Python in numba's simulator
#: (which cannot hand its arrays to a function compiled for the CPU).
_every_source = for_the_device(kernels.vertex_sources)
_listed_sources = for_the_device(kernels.indexed_sources)
_table_rows = for_the_device(kernels.table_rows)
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


@cuda.jit
def _listed_sums(model, table, F0, F1, F2, p0, p1, p2, starts, columns, factors, rcv_points, rcv_normals, out):
    """Thread ``o``: receiver ``o``'s sum over the listed sources ``columns[starts[o] : starts[o + 1]]`` of three
    lanes, by the CPU's own loop (:func:`~translucency.scatter.kernels.indexed_sources`)."""
    o = cuda.grid(1)
    if o >= rcv_points.shape[0]:
        return
    rows = _table_rows(table)
    a0, a1, a2 = _listed_sources(
        model,
        starts[o],
        starts[o + 1],
        columns,
        factors,
        rows,
        (rcv_points[o, 0], rcv_points[o, 1], rcv_points[o, 2]),
        (rcv_normals[o, 0], rcv_normals[o, 1], rcv_normals[o, 2]),
        (p0, p1, p2),
        (F0, F1, F2),
    )
    out[o, 0] = a0
    out[o, 1] = a1
    out[o, 2] = a2


@cuda.jit
def _near_rows(starts, columns, coefs, values, lit, width, out):
    """Thread ``r``: relighting's near-field product of receiver ``r`` (as the CPU's ``relight._apply_rows``):
    ``out[r, c] = sum_k coefs[k, c width : (c + 1) width] . values[columns[k], c width : (c + 1) width]`` over its
    entries ``k`` from ``starts[r]`` to ``starts[r + 1]``, the columns without light (``lit`` false) skipped."""
    r = cuda.grid(1)
    if r >= out.shape[0]:
        return
    for c in range(out.shape[1]):
        s = 0.0
        for k in range(starts[r], starts[r + 1]):
            column = columns[k]
            if lit[column]:
                for t in range(c * width, (c + 1) * width):
                    s += coefs[k, t] * values[column, t]
        out[r, c] = s


#: Share of the GPU's free memory the near field's operator may take there (else its product stays on the CPU).
NEAR_SHARE_OF_FREE = 0.5
#: Relighting's far field on a GPU is every pair of a light where the vertices squared are at most this many (the
#: default bunny's 7.9e8), and the tree's walk at the operators' ``tol`` beyond (the Igea's 1.8e10 pairs would take
#: about a second at the budget's rate). An estimate, not a measurement: bench/gpu.py times both.
ALL_PAIRS_UP_TO = 2e9


def chunk_size(n_rcv: int, n_src: int) -> int:
    """Sources per thread: all of them when the receivers alone give :data:`TARGET_THREADS`, else fewer, in as many
    chunks as that takes but no more than one per :data:`MIN_CHUNK` sources."""
    chunks = max(1, min(-(-TARGET_THREADS // max(n_rcv, 1)), -(-n_src // MIN_CHUNK)))
    return -(-n_src // chunks)


class PairSums:
    """:func:`translucency.scatter.kernels.vertex_sum` on the GPU for one set of sources, copied to the device
    once; call it with blocks of receivers. Arguments as ``vertex_sum``'s (float64, mm)."""

    @said_plainly
    def __init__(self, model, src_points, src_normals, src_w12, src_flux, params, channel_of):
        table, weights = kernels.source_columns(src_points, src_normals, src_w12, src_flux)
        self.model = int(model)
        self.n_src = table.shape[1]
        self.n_out = weights.shape[0]
        lanes = kernels.channel_lanes(params, channel_of, self.n_out)
        counted = kernels.clamp_counted(channel_of, lanes.shape[0])
        self.table = to_device(table)
        rows = [to_device(row) for row in weights]
        # per group of three lanes: flux rows, parameters, clamp counting
        self.groups = [
            (*(rows[c] for c in channels), *lane_params, *(int(counted[c]) for c in launch))
            for launch, channels, lane_params in lane_groups(lanes, self.n_out)
        ]

    @said_plainly
    def __call__(self, rcv_points, rcv_normals):
        """``(B (n_rcv, C) float64, clamped (n_rcv,) int64)`` at these receivers (mm, unit normals)."""
        n_rcv = int(rcv_points.shape[0])
        if n_rcv == 0 or self.n_src == 0:
            return np.zeros((n_rcv, self.n_out)), np.zeros(n_rcv, dtype=np.int64)
        chunk = chunk_size(n_rcv, self.n_src)
        chunks = -(-self.n_src // chunk)
        points, normals = to_device(rcv_points), to_device(rcv_normals)
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


class RelitFarField:
    """Relighting's far field on the GPU (:mod:`translucency.scatter.relight`): for each light, every pair of its
    lit sources at every vertex, less the pairs the near field's operator holds itself (``near_starts``,
    ``near_columns``: vertex ``r``'s are ``near_columns[near_starts[r] : near_starts[r + 1]]``), all summed in
    float64 with the light's own refracted directions, so nothing is fitted. Positions in mm.

    Where the near field's operator (``near_coefs``, float32, per entry its channels' ten coefficients) takes at most
    :data:`NEAR_SHARE_OF_FREE` of the GPU's free memory, it is held there too and :attr:`holds_near` is True: a light's
    near-field product is then made on the GPU with the far field (:meth:`apply_light`).

    ``far_sum(w12, flux) -> (B, evaluations)``, where given, sums the light's far field at every vertex in place of
    every pair (the tree's walk on the GPU, :data:`ALL_PAIRS_UP_TO`); the near lists' pairs are taken off it as off
    every pair's."""

    @said_plainly
    def __init__(self, model, points, normals, params, near_starts, near_columns, near_coefs=None, far_sum=None):
        self.model = int(model)
        self.points = np.ascontiguousarray(points, dtype=np.float64)
        self.normals = np.ascontiguousarray(normals, dtype=np.float64)
        self.params = np.ascontiguousarray(params, dtype=np.float64)
        self.channel_of = np.arange(self.params.shape[0])
        self.starts = to_device(near_starts, np.int64)
        self.columns = to_device(near_columns, np.int32)
        self.factors = cuda.to_device(np.ones(len(near_columns), dtype=np.float32))
        self.device_points = cuda.to_device(self.points)
        self.device_normals = cuda.to_device(self.normals)
        self.holds_near = near_coefs is not None and near_coefs.nbytes <= NEAR_SHARE_OF_FREE * _free_bytes()
        if self.holds_near:
            self.coefs = to_device(near_coefs, np.float32)
        self.far_sum = far_sum
        #: memory held on the host, bytes (the device holds the lists and the vertices)
        self.nbytes = 0

    @said_plainly
    def apply_light(self, w12, values, lit) -> tuple[np.ndarray, int]:
        """``(B (n, C), evaluations)``: the far field for a light entering along ``w12 (n, 3)``, plus the near field's
        product where :attr:`holds_near`, from the light's inputs as ``relight._inputs`` writes them: ``values (n, 10
        C)``, each channel's first the flux ``Phi = phi A`` entering at the vertex, and ``lit (n,)``, whether any
        does; and the pairs and clusters its far field evaluated."""
        width = values.shape[1] // self.params.shape[0]
        flux = np.ascontiguousarray(values[:, ::width])
        sources = np.flatnonzero(lit)
        # w12 means nothing where no light enters (it may be anything there): the near lists' sum reads it
        w12 = np.where(lit[:, None], w12, -self.normals)
        if self.far_sum is None:
            every = PairSums(
                self.model,
                self.points[sources],
                self.normals[sources],
                w12[sources],
                flux[sources],
                self.params,
                self.channel_of,
            )
            B, _ = every(self.points, self.normals)
            evaluations = sources.size * self.points.shape[0]
        else:
            B, evaluations = self.far_sum(w12, flux)
        B -= self._listed(w12, flux)
        if self.holds_near:
            near = cuda.device_array(B.shape, dtype=np.float64)
            _near_rows[-(-B.shape[0] // THREADS), THREADS](
                self.starts, self.columns, self.coefs, cuda.to_device(values), cuda.to_device(lit), width, near
            )
            B += near.copy_to_host()
        return B, evaluations

    def _listed(self, w12, flux) -> np.ndarray:
        """The pairs of the near lists, summed as the far field summed them."""
        n, n_out = flux.shape
        sources = PairSums(self.model, self.points, self.normals, w12, flux, self.params, self.channel_of)
        out = np.empty((n, 3 * len(sources.groups)))
        part = cuda.device_array((n, 3), dtype=np.float64)
        for g, group in enumerate(sources.groups):
            _listed_sums[-(-n // THREADS), THREADS](
                self.model,
                sources.table,
                *group[:6],
                self.starts,
                self.columns,
                self.factors,
                self.device_points,
                self.device_normals,
                part,
            )
            out[:, 3 * g : 3 * g + 3] = part.copy_to_host()
        return out[:, :n_out]


def _free_bytes() -> float:
    """The GPU's free memory, bytes (unbounded in the simulator, which has none of its own)."""
    if config.ENABLE_CUDASIM:
        return float("inf")
    free, _ = cuda.current_context().get_memory_info()
    return float(free)
