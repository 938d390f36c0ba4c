"""The far field as a hierarchical matrix: blocks between well-separated clusters as cross approximations.

The relighting operator's far field (docs/physics.md §8.7, §8.9) maps the light that enters at every vertex,
per channel ``Phi`` and ``Psi = Phi w12`` (four numbers), to ``B`` at every vertex. Its entries are the affine
fits ``a + b . w12`` of :func:`~translucency.scatter.fits.fitted_run`. The vertices are ordered by a
kd-tree (:class:`~translucency.scatter.hierarchy.SourceTree`, leaves of :data:`LEAF_SIZE`); a pair of nodes
is a block of the matrix, and

* a block whose nodes are far apart (gap at least ``gap`` mm and ``max radius <= ETA * centre distance``) is
  a product ``U V`` of low rank per channel, found by **adaptive cross approximation** with partial pivoting
  (Bebendorf 2000): rows are the receivers, columns the (source, term) pairs. It stops when the last cross
  is below ``eps`` of the block's Frobenius norm (or when the rows it checks are held to ``eps``; the crosses are
  :mod:`translucency.scatter.crosses`'); a block that needs more than
  :func:`~translucency.scatter.crosses.rank_limit` crosses is split into its children's blocks, down to dense
  pairs of leaves;
* a pair of leaves that is not far apart is stored whole (a dense block), less the pairs the near field
  holds (``held``: they are summed there, docs/physics.md §8.7); where such a pair is in a low-rank block
  instead, :meth:`FarMatrix.take_low_rank_entries` takes the value the block holds off the near field's.

The error is set by ``eps`` (the rank), not by the opening ratio: ``ETA`` stays at 0.5 for every ``tol``.
Each receiver's row is divided by the channel's bound of §8.4 at its own distance before the approximation,
so that the stopping rule holds the rows of distant (dark) receivers too, not only the block's brightest.
The crosses are recompressed (fewer, orthogonal components) and stored in 16-bit fixed point (``U`` with one float32
scale per row, one component after another), the smallest components' ``V`` in 8 bits; dense blocks in float32; a light
reads every block once.

=========== ================================================================ ==============
symbol      meaning                                                          unit
=========== ================================================================ ==============
eps         relative Frobenius error at which a cross approximation stops    1
gap         smallest distance between the bounding spheres of a far block    mm
=========== ================================================================ ==============
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field

import numba
import numpy as np

from ..threads import for_ranges, thread_count
from .crosses import (
    CROSS_KERNELS,
    SCALE_CHUNK,
    V8_STEP,
    V_STEP,
    Approximations,
    Room,
    block_rows,
    far_items,
    longest_run,
    rank_limits,
    run_of_crosses,
    split,
)
from .fits import AFFINE_TERMS, fitted_block, run_scratch
from .hierarchy import SourceTree

__all__ = ["ETA", "LEAF_SIZE", "FarMatrix", "build", "partition"]

#: Vertices per leaf of the block tree: dense blocks are pairs of leaves.
LEAF_SIZE = 32
#: A block is far (low rank) when the larger of its two bounding radii is at most ``ETA`` times the distance
#: of their centres.
ETA = 0.5


@dataclass
class FarMatrix:
    """The far field of one surface, medium, model and ``eps`` (:func:`build`), in the tree's vertex order.

    Attributes
    ----------
    order : (n,) int64
        The tree's order: row and column ``k`` of every block is vertex ``order[k]``.
    n_channels : int
    low_rank : (L, 11) int64
        Per block and channel: first and last row, first and last column (tree order), the channel, rank
        ``k``, where its ``U (rows, k)``, the first ``k - k8`` rows of its ``V (k, columns x 4)`` and its rows'
        scales start in ``U``, ``V`` and ``U_scale``, ``k8``, and where the last ``k8`` rows of its ``V`` start in
        ``V8``.
    U, V : int16
        The crosses: ``U`` in steps of ``U_scale`` per row, held a component at a time (``U`` of a block is ``(k,
        rows)``, so that a light's product runs down the rows); ``V`` row-major in steps of :data:`V_STEP`, its
        columns (source, term).
    U_scale : float32
    V8 : int8
        The smallest components' ``V`` rows, in steps of :data:`V8_STEP`.
    dense : (M, 7) int64
        Per dense block: first and last row, first and last column, first and last channel, and where its
        ``(channels, rows, columns x 4)`` entries start in ``D``.
    D : float32
    stats : dict
    """

    order: np.ndarray
    n_channels: int
    low_rank: np.ndarray
    U: np.ndarray
    U_scale: np.ndarray
    V: np.ndarray
    V8: np.ndarray
    dense: np.ndarray
    D: np.ndarray
    stats: dict = field(default_factory=dict)

    @property
    def nbytes(self) -> int:
        """Memory the blocks hold, bytes."""
        held = (self.order, self.low_rank, self.U, self.U_scale, self.V, self.V8, self.dense, self.D)
        return int(sum(a.nbytes for a in held))

    def apply(self, values: np.ndarray, scratch: dict | None = None) -> np.ndarray:
        """``B (n, C)`` for ``values (n, C, 4)``: per vertex and channel ``Phi, Psi_x, Psi_y, Psi_z`` (vertex
        order), times the far field's fits (1/(mm^2 sr) per unit flux). ``scratch`` keeps the arrays of the
        product between calls (:func:`kept_array`)."""
        n = self.order.size
        scratch = {} if scratch is None else scratch
        # per channel, the sources' four terms one after another (a block's columns are one contiguous run), and
        # how many sources before each take in light: a block without light is skipped (a light in shadow on half
        # the surface reads half the blocks)
        wide = kept_array(scratch, "wide", (self.n_channels, n * AFFINE_TERMS), np.float64)
        narrow = kept_array(scratch, "narrow", (self.n_channels, n * AFFINE_TERMS), np.float32)
        lit_before = kept_array(scratch, "lit_before", (n + 1,), np.int64)
        _tree_ordered(np.asarray(values, dtype=np.float64), self.order, wide, narrow, lit_before)
        out = kept_array(scratch, "out", (thread_count(), n, self.n_channels), np.float64)
        out.fill(0.0)
        # the crosses' products in float32, as their factors are held (B changed by 5e-7 of itself at most on the
        # default bunny; 16 lanes a step instead of 8)
        blocks = self.low_rank
        for_ranges(
            _apply_low_rank, blocks.shape[0], blocks, self.U, self.U_scale, self.V, self.V8, narrow, lit_before, out
        )
        for_ranges(_apply_dense, self.dense.shape[0], self.dense, self.D, wide, lit_before, out)
        B = np.empty((n, self.n_channels))
        B[self.order] = out.sum(axis=0)
        return B

    def take_low_rank_entries(self, starts: np.ndarray, columns: np.ndarray, coefs: np.ndarray, terms: int) -> None:
        """Take off ``coefs`` the low-rank blocks' values of the pairs (receiver ``o``, source
        ``columns[starts[o] : starts[o + 1]]``, vertex indices): pair ``h``'s channel ``c`` from ``coefs[h, c terms :
        c terms + 4]`` (``coefs (E, C terms)``, in place, nothing else made); pairs in dense blocks are left as they
        are."""
        held_starts, held_columns, rows = _held_in_order(self.order, starts, columns)
        blocks = self.low_rank
        for_ranges(
            _take_entries,
            blocks.shape[0],
            *(blocks, self.U, self.U_scale, self.V, self.V8, held_starts, held_columns, rows, coefs, int(terms)),
        )


def partition(tree: SourceTree, gap: float, eta: float = ETA) -> tuple[np.ndarray, np.ndarray]:
    """The blocks of ``tree`` against itself: ``(far (F, 2), dense (M, 2))`` node pairs. Far: the bounding
    spheres at least ``gap`` (mm) apart and the larger radius at most ``eta`` times the centres' distance;
    dense: pairs of leaves that are not. Every (row, column) pair of vertices is in exactly one block."""
    return _partition(tree.left, tree.right, tree.centre, tree.radius, float(gap), float(eta))


@numba.njit(cache=True)
def _partition(left, right, centre, radius, gap, eta):
    far = np.empty((64, 2), dtype=np.int64)
    dense = np.empty((64, 2), dtype=np.int64)
    n_far = 0
    n_dense = 0
    stack = np.empty((4096, 2), dtype=np.int64)
    stack[0, 0], stack[0, 1] = 0, 0
    top = 1
    while top > 0:
        top -= 1
        a, b = stack[top, 0], stack[top, 1]
        d = math.sqrt(
            (centre[a, 0] - centre[b, 0]) ** 2 + (centre[a, 1] - centre[b, 1]) ** 2 + (centre[a, 2] - centre[b, 2]) ** 2
        )
        if d - radius[a] - radius[b] >= gap and max(radius[a], radius[b]) <= eta * d:
            if n_far == far.shape[0]:
                far = np.concatenate((far, np.empty_like(far)))
            far[n_far, 0], far[n_far, 1] = a, b
            n_far += 1
        elif left[a] < 0 and left[b] < 0:
            if n_dense == dense.shape[0]:
                dense = np.concatenate((dense, np.empty_like(dense)))
            dense[n_dense, 0], dense[n_dense, 1] = a, b
            n_dense += 1
        else:
            if top + 2 > stack.shape[0]:
                stack = np.concatenate((stack, np.empty_like(stack)))
            if left[b] < 0 or (left[a] >= 0 and radius[a] >= radius[b]):
                stack[top, 0], stack[top, 1] = left[a], b
                stack[top + 1, 0], stack[top + 1, 1] = right[a], b
            else:
                stack[top, 0], stack[top, 1] = a, left[b]
                stack[top + 1, 0], stack[top + 1, 1] = a, right[b]
            top += 2
    return far[:n_far].copy(), dense[:n_dense].copy()


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _fill_dense(worker, lo, hi, model, P, N, dense, params, dirs, pinv, held_starts, held_columns, stamps, D):
    """Dense blocks ``lo .. hi - 1``: every fit of the block for its channels, 0 where the near field holds the
    pair (source ``j`` listed for receiver ``o`` in ``held_columns[held_starts[o] : held_starts[o + 1]]``, tree
    order). A block kept for one channel (its cross approximation failed there only) fits that channel alone."""
    n_c = params.shape[0]
    single = params.reshape(n_c, 1, params.shape[1])  # each channel's parameters as a (1, P) array of their own
    length = np.int64(0)
    for k in range(lo, hi):
        length = max(length, (dense[k, 1] - dense[k, 0]) * (dense[k, 3] - dense[k, 2]))
    space = run_scratch(dirs.shape[0], length)
    fits = np.empty((length, n_c, AFFINE_TERMS))
    mark = stamps[worker]
    for k in range(lo, hi):
        r0, r1, c0, c1, first, last, at = _dense_block(dense, k)
        m, sources = r1 - r0, c1 - c0
        n = sources * AFFINE_TERMS
        rows = params if last - first == n_c else single[first]
        fitted_block(model, P, N, r0, r1, c0, c1, rows, dirs, pinv, space, fits)
        for a in range(m):
            o = r0 + a
            for h in range(held_starts[o], held_starts[o + 1]):
                mark[held_columns[h]] = o
            for b in range(sources):
                held = mark[c0 + b] == o
                for c in range(first, last):
                    at_b = at + ((c - first) * m + a) * n + b * AFFINE_TERMS
                    for t in range(AFFINE_TERMS):
                        D[at_b + t] = 0.0 if held else fits[a * sources + b, c - first, t]


@numba.njit(cache=True, inline="always")
def _dense_block(blocks, k):
    """Row ``k`` of :attr:`FarMatrix.dense`: rows, columns, first and last channel, and where ``D``'s start."""
    return blocks[k, 0], blocks[k, 1], blocks[k, 2], blocks[k, 3], blocks[k, 4], blocks[k, 5], blocks[k, 6]


@numba.njit(cache=True, inline="always")
def _low_rank_block(blocks, k):
    """Row ``k`` of :attr:`FarMatrix.low_rank`: rows, columns, channel, rank, where ``U``, ``V`` and ``U``'s
    row scales start, the components held in 8 bits and where they start in ``V8``."""
    return (
        blocks[k, 0],
        blocks[k, 1],
        blocks[k, 2],
        blocks[k, 3],
        blocks[k, 4],
        blocks[k, 5],
        blocks[k, 6],
        blocks[k, 7],
        blocks[k, 8],
        blocks[k, 9],
        blocks[k, 10],
    )


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _apply_low_rank(worker, lo, hi, blocks, U, U_scale, V, V8, values, lit_before, out):
    """``out[worker, rows, c] += U (V values[c, columns])`` for the low-rank blocks ``lo .. hi - 1`` (``values``
    float32, per channel, four terms per source; the products in float32, each row's sum added in float64),
    skipping those without a lit source (``lit_before[j]``: how many of the sources before ``j`` are lit)."""
    target = out[worker]
    inner = np.zeros(128, dtype=np.float32)
    rows = np.zeros(1024, dtype=np.float32)
    step = np.float32(V_STEP)
    step8 = np.float32(V8_STEP)
    for k in range(lo, hi):
        r0, r1, c0, c1, c, rank, u_at, v_at, s_at, rank8, v8_at = _low_rank_block(blocks, k)
        if lit_before[c1] == lit_before[c0]:
            continue
        n = (c1 - c0) * AFFINE_TERMS
        if inner.shape[0] < rank:
            inner = np.zeros(2 * rank, dtype=np.float32)
        source = values[c, c0 * AFFINE_TERMS : c1 * AFFINE_TERMS]
        # rows taken as slices: indexed from 0 by the loop's own counter, the products vectorise
        wide = rank - rank8
        for q in range(wide):
            row = V[v_at + q * n : v_at + (q + 1) * n]
            s = np.float32(0.0)
            for j in range(n):
                s += np.float32(row[j]) * source[j]
            inner[q] = s * step
        for q in range(rank8):
            row8 = V8[v8_at + q * n : v8_at + (q + 1) * n]
            s = np.float32(0.0)
            for j in range(n):
                s += np.float32(row8[j]) * source[j]
            inner[wide + q] = s * step8
        # U a cross at a time: each cross's column runs down the block's rows in one vector loop (a row of U has
        # only k entries, too short a loop to vectorise well)
        m = r1 - r0
        if rows.shape[0] < m:
            rows = np.zeros(2 * m, dtype=np.float32)
        acc = rows[:m]
        acc[:] = 0.0
        for q in range(rank):
            column = U[u_at + q * m : u_at + (q + 1) * m]
            weight = inner[q]
            for a in range(m):
                acc[a] += np.float32(column[a]) * weight
        scales = U_scale[s_at : s_at + m]
        for a in range(m):
            target[r0 + a, c] += acc[a] * scales[a]


def kept_array(scratch: dict, name: str, shape: tuple, dtype) -> np.ndarray:
    """The array ``name`` of ``scratch`` when it has this shape and dtype, else a new one kept there (contents left
    as they are). Arrays kept between calls are written into memory the process holds already: a first write to
    fresh pages ran at 0.5-2 GB/s on the 2-core machine, 13 ms a light for the Igea's inputs."""
    array = scratch.get(name)
    if array is None or array.shape != tuple(shape) or array.dtype != np.dtype(dtype):
        array = scratch[name] = np.empty(shape, dtype=dtype)
    return array


@numba.njit(cache=True, error_model="numpy")
def _tree_ordered(values, order, wide, narrow, lit_before):
    """``values (n, C, >= 4)`` (vertex order; the first four terms per channel) in the tree's ``order``, per channel
    four terms a source, written to ``wide`` (float64) and ``narrow`` (float32), both ``(C, 4 n)``, and
    ``lit_before (n + 1,)``: how many of the sources before ``j`` have any flux."""
    n = order.size
    n_c = values.shape[1]
    lit_before[0] = 0
    for k in range(n):
        v = order[k]
        lit = False
        for c in range(n_c):
            lit = lit or values[v, c, 0] != 0.0
            for t in range(AFFINE_TERMS):
                wide[c, k * AFFINE_TERMS + t] = values[v, c, t]
                narrow[c, k * AFFINE_TERMS + t] = values[v, c, t]
        lit_before[k + 1] = lit_before[k] + (1 if lit else 0)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _take_entries(worker, lo, hi, blocks, U, U_scale, V, V8, starts, columns, rows, coefs, terms):
    """``coefs[rows[h], c terms + t] -= (U V)[o, j]`` (term ``t``) for every pair ``h`` (receiver ``o``, source ``j =
    columns[h]``, ``h`` in ``starts[o] : starts[o + 1]``, tree order) in the low-rank blocks ``lo .. hi - 1`` (each
    pair and channel is in one block, so the blocks' threads write apart)."""
    for k in range(lo, hi):
        r0, r1, c0, c1, c, rank, u_at, v_at, s_at, rank8, v8_at = _low_rank_block(blocks, k)
        n = (c1 - c0) * AFFINE_TERMS
        wide = rank - rank8
        for o in range(r0, r1):
            for h in range(starts[o], starts[o + 1]):
                j = columns[h]
                if j < c0 or j >= c1:
                    continue
                for t in range(AFFINE_TERMS):
                    s = 0.0
                    at = (j - c0) * AFFINE_TERMS + t
                    for q in range(wide):
                        s += float(U[u_at + q * (r1 - r0) + o - r0]) * V[v_at + q * n + at] * V_STEP
                    for q in range(rank8):
                        s += float(U[u_at + (wide + q) * (r1 - r0) + o - r0]) * V8[v8_at + q * n + at] * V8_STEP
                    coefs[rows[h], c * terms + t] -= s * U_scale[s_at + o - r0]


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _apply_dense(worker, lo, hi, blocks, D, values, lit_before, out):
    """``out[worker, rows, c] += D values[c, columns]`` for the dense blocks ``lo .. hi - 1`` and their
    channels (``values`` per channel, four terms per source), skipping those without a lit source (``lit_before``
    as in :func:`_apply_low_rank`)."""
    target = out[worker]
    for k in range(lo, hi):
        r0, r1, c0, c1, first, last, at = _dense_block(blocks, k)
        if lit_before[c1] == lit_before[c0]:
            continue
        m = r1 - r0
        n = (c1 - c0) * AFFINE_TERMS
        for c in range(first, last):
            source = values[c, c0 * AFFINE_TERMS : c1 * AFFINE_TERMS]
            for a in range(m):
                row = D[at + ((c - first) * m + a) * n : at + ((c - first) * m + a + 1) * n]
                s = 0.0
                for j in range(n):
                    s += row[j] * source[j]
                target[r0 + a, c] += s


class _CrossStore:
    """The components of every block in four arrays: ``U`` and ``V`` int16, ``U``'s row scales float32, the smallest
    components' ``V`` int8 (:func:`fixed_point`), a worker's run of blocks at a time (:func:`found_crosses` fills
    the worker's own room, :meth:`put_converted` copies it in under a lock: one copy a run, where a block at a time
    kept the workers waiting on each other's Python).

    Each array is reserved larger than it is likely to need and cut to what was used at the end; memory is given
    to a page only when it is first written, so what is reserved and never written costs nothing. (Blocks kept
    apart and then copied into the far field's arrays spent seconds on pages filled twice.) A store that runs out
    of room grows by half again (copied)."""

    def __init__(self, u_size: int, v_size: int, rows: int):
        self.U = np.empty(max(int(u_size), 1), dtype=np.int16)
        self.V = np.empty(max(int(v_size), 1), dtype=np.int16)
        self.S = np.empty(max(int(rows), 1), dtype=np.float32)
        self.V8 = np.empty(max(int(v_size), 1), dtype=np.int8)
        self.u_at = 0
        self.v_at = 0
        self.s_at = 0
        self.v8_at = 0
        self.lock = threading.Lock()

    def put_converted(self, U: np.ndarray, V: np.ndarray, S: np.ndarray, V8: np.ndarray) -> tuple[int, int, int, int]:
        """Store the components of a run of blocks already in fixed point (:func:`found_crosses`' ``U``, ``V``, ``S``,
        ``V8``, each one piece): where each starts in :attr:`U`, :attr:`V`, :attr:`S` and :attr:`V8`."""
        with self.lock:
            at = self.u_at, self.v_at, self.s_at, self.v8_at
            for name, part, start in zip(("U", "V", "S", "V8"), (U, V, S, V8), at):
                held = _room(getattr(self, name), start + part.size)
                held[start : start + part.size] = part
                setattr(self, name, held)
            self.u_at += U.size
            self.v_at += V.size
            self.s_at += S.size
            self.v8_at += V8.size
        return at

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(U, V, S, V8)`` cut to what was stored (in place: the memory past it is given back, nothing is copied)."""
        for name, used in (("U", self.u_at), ("V", self.v_at), ("S", self.s_at), ("V8", self.v8_at)):
            array = getattr(self, name)
            array.resize(max(used, 1), refcheck=False)
            setattr(self, name, array[:used])
        return self.U, self.V, self.S, self.V8


def _room(array: np.ndarray, size: int) -> np.ndarray:
    """``array`` if it holds ``size`` elements, else a copy with half as much again as needed."""
    if size <= array.size:
        return array
    grown = np.empty(int(1.5 * size), dtype=array.dtype)
    grown[: array.size] = array
    return grown


#: Crosses per block and channel the crosses' store reserves room for: :data:`RESERVED_SHARE` times
#: ``RANK_PER_SQUARED_DECADE log10(1 / eps)^2`` (:func:`expected_rank`, measured on the default bunny in marble at
#: ``tol`` 0.1, 0.03 and 0.01; the ranks grow faster than the digits asked), never more than a block may take
#: (:class:`_CrossStore`: room never written costs no memory; a store that runs out grows, copied). The budget
#: counts the crosses by :func:`sampled_count`, which follows the material too.
RANK_PER_SQUARED_DECADE = 2.5
RESERVED_SHARE = 1.5


def expected_rank(eps: float) -> float:
    """The crosses a far block is expected to take per channel at ``eps`` (:data:`RANK_PER_SQUARED_DECADE`)."""
    return RANK_PER_SQUARED_DECADE * math.log10(1.0 / eps) ** 2


def build(
    model: int,
    points: np.ndarray,
    normals: np.ndarray,
    params: np.ndarray,
    fit: tuple,
    eps: float,
    gap: float,
    channel_bound,
    held: tuple,
    tree: SourceTree | None = None,
    progress=None,
) -> FarMatrix:
    """The far field of the surface ``points`` (mm), ``normals`` for the kernel ``model`` (code) and channel
    parameters ``params``: far blocks by cross approximation to ``eps`` per channel, the rest dense.

    ``fit`` is :func:`~translucency.scatter.fits.fit_directions`'s ``(dirs, pinv)`` for the affine terms;
    ``gap`` (mm) the smallest distance of a far block's spheres (at least the near field's reach);
    ``channel_bound(r)`` the §8.4 bound per channel at distances ``r`` (mm), ``(C, len(r))``, by which every
    receiver's row is scaled; ``held = (starts, columns)`` the pairs the near field holds (CSR by receiver,
    vertex indices), left out. ``progress(fraction)`` is called as blocks are done.
    """
    tree = tree or SourceTree(points, LEAF_SIZE)
    order = tree.order
    P = np.ascontiguousarray(points[order], dtype=np.float64)
    N = np.ascontiguousarray(normals[order], dtype=np.float64)
    n = P.shape[0]
    n_c = params.shape[0]
    dirs, pinv = fit
    held_starts, held_columns, _ = _held_in_order(order, *held)
    far_pairs, dense_pairs = partition(tree, gap)
    report = progress or (lambda fraction: None)
    found, dense_extra, store = _crosses(model, tree, P, N, params, dirs, pinv, eps, channel_bound, far_pairs, report)
    dense_pairs = np.concatenate(
        [
            np.column_stack([dense_pairs, np.zeros(len(dense_pairs), np.int64), np.full(len(dense_pairs), n_c)]),
            np.array([(a, b, c, c + 1) for a, b, c in sorted(dense_extra)], dtype=np.int64).reshape(-1, 4),
        ]
    )
    start, end = tree.start, tree.end

    kept = np.array(found, dtype=np.int64).reshape(-1, 9)
    a, b, c, k, u_at, v_at, s_at, k8, v8_at = kept[np.argsort(kept[:, 4], kind="stable")].T  # as the store holds them
    low_rank = np.column_stack([start[a], end[a], start[b], end[b], c, k, u_at, v_at, s_at, k8, v8_at])
    U_all, V_all, U_scale, V8_all = store.arrays()
    del store

    dense = np.zeros((len(dense_pairs), 7), dtype=np.int64)
    rows, cols = dense_pairs[:, 0], dense_pairs[:, 1]
    sizes = (
        (end[rows] - start[rows]) * (end[cols] - start[cols]) * AFFINE_TERMS * (dense_pairs[:, 3] - dense_pairs[:, 2])
    )
    dense[:, 0], dense[:, 1], dense[:, 2], dense[:, 3] = start[rows], end[rows], start[cols], end[cols]
    dense[:, 4:6] = dense_pairs[:, 2:4]
    dense[1:, 6] = np.cumsum(sizes)[:-1]
    D = np.empty(int(np.sum(sizes)), dtype=np.float32)
    stamps = np.full((thread_count(), n), -1, dtype=np.int64)
    for_ranges(
        _fill_dense,
        len(dense),
        model,
        *(P, N, dense, params, dirs, pinv, held_starts, held_columns, stamps, D),
        progress=lambda f: report(0.9 + 0.1 * f),
    )
    report(1.0)
    ranks = low_rank[:, 5]
    matrix = FarMatrix(order, n_c, low_rank, U_all, U_scale, V_all, V8_all, dense, D)
    matrix.stats = {
        "eps": eps,
        "eta": ETA,
        "far_blocks": int(len(low_rank)),
        "dense_blocks": int(len(dense)),
        "rank_mean": float(ranks.mean()) if ranks.size else 0.0,
        "rank_max": int(ranks.max()) if ranks.size else 0,
        "far_floats": int(U_all.size + V_all.size + V8_all.size),
        "narrow_share": float(V8_all.size / max(V8_all.size + V_all.size, 1)),
        "dense_floats": int(D.size),
        "bytes": matrix.nbytes,
    }
    return matrix


def _held_in_order(order, starts, columns):
    """The pairs ``(starts, columns)`` (CSR by receiver, vertex indices) in the tree's order: ``(starts,
    columns, rows)``, ``rows`` the position in ``columns`` of each."""
    n = order.size
    rank_of = np.empty(n, dtype=np.int64)
    rank_of[order] = np.arange(n)
    counts = np.diff(starts)[order]
    held_starts = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(counts, out=held_starts[1:])
    rows = np.repeat(starts[order] - held_starts[:-1], counts) + np.arange(int(held_starts[-1]))
    return held_starts, rank_of[np.asarray(columns, dtype=np.int64)[rows]], rows


def _crosses(model, tree, P, N, params, dirs, pinv, eps, channel_bound, far_pairs, report):
    """Cross approximations of every far block and channel: ``(found, dense, store)``, ``found`` a list of ``(row
    node, column node, channel, k, where U, V and U's row scales start, k8, where V8 starts)`` in ``store``
    (:class:`_CrossStore`; the last ``k8`` components' ``V`` in 8 bits); a block
    that needs more crosses than :func:`~translucency.scatter.crosses.rank_limit` is split into its children's blocks
    (:func:`~translucency.scatter.crosses.split`), and a pair of leaves that does is added to ``dense`` as ``(row
    node, column node, channel)``."""
    n_c = params.shape[0]
    start, end = tree.start, tree.end
    kept_by = [[] for _ in range(thread_count())]
    approximations = Approximations(
        model, tree, P, N, params, dirs, pinv, eps, channel_bound, longest_run(tree, far_pairs)
    )
    rows = end[far_pairs[:, 0]] - start[far_pairs[:, 0]]
    cols = (end[far_pairs[:, 1]] - start[far_pairs[:, 1]]) * AFFINE_TERMS
    reserved = RESERVED_SHARE * expected_rank(eps)
    ranks = np.minimum(reserved, rank_limits(rows, cols)).astype(np.int64)
    store = _CrossStore(n_c * np.sum(ranks * rows), n_c * np.sum(ranks * cols), n_c * np.sum(rows))

    rooms = [Room() for _ in range(thread_count())]

    def run(worker, lo, hi, items):
        kept = kept_by[worker]
        for first in range(lo, hi, SCALE_CHUNK):
            chunk = items[first : min(hi, first + SCALE_CHUNK)]
            offsets, row_scales = approximations.row_scales(chunk)
            blocks = block_rows(tree, chunk)
            done = 0
            while done < len(chunk):
                count, info, parts = run_of_crosses(
                    approximations, rooms[worker], worker, blocks[done:], offsets[done:], row_scales
                )
                bases = np.array(store.put_converted(*parts), dtype=np.int64)
                for p in range(count):
                    a, b, c = chunk[done + p]
                    found, k, narrow, u_at, v_at, s_at, v8_at = info[p]
                    if found < 0:
                        kept.append((a, b, c, -1, -1, -1, -1, 0, -1))
                    else:
                        kept.append(
                            (a, b, c, k, bases[0] + u_at, bases[1] + v_at, bases[2] + s_at, narrow, bases[3] + v8_at)
                        )
                done += count

    found, dense = [], set()
    items = far_items(far_pairs, n_c)
    done, total = 0, max(len(items), 1)
    while len(items):
        at, share = done / total, len(items) / total
        for_ranges(run, len(items), items, progress=lambda f, at=at, share=share: report(0.9 * (at + f * share)))
        following = []
        for kept in kept_by:
            for a, b, c, k, u_at, v_at, s_at, k8, v8_at in kept:
                if k >= 0:
                    found.append((a, b, c, k, u_at, v_at, s_at, k8, v8_at))
                else:
                    children = split(tree, a, b, c)
                    following += children
                    if not children:
                        dense.add((int(a), int(b), int(c)))
            kept.clear()
        done += len(items)
        report(min(0.9, 0.9 * done / total))
        items = np.array(following, dtype=np.int64).reshape(-1, 3)
    return found, dense, store


#: The compiled kernels of the far field's cross approximations and products: numba compiles each on first use;
#: the set-up compiles them ahead (:mod:`translucency.app.warmup`).
LOW_RANK_KERNELS = (
    _partition,
    *CROSS_KERNELS,
    _fill_dense,
    _tree_ordered,
    _take_entries,
    _apply_low_rank,
    _apply_dense,
)
