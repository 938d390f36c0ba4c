"""Adaptive cross approximation of the far field's blocks, held in fixed point, and the count of what they hold before
they are found.

A far block of the relighting operator (docs/physics.md §8.9; :mod:`translucency.scatter.lowrank`), rows the
receivers and columns the (source, term) pairs of one channel, is approximated by crosses (Bebendorf 2000): each
step evaluates one row and one column of fits (:func:`~translucency.scatter.fits.fitted_run`). A block that needs
more than :func:`rank_limit` crosses is split into its children's blocks (:func:`split`). A block's crosses are then
recompressed (:func:`_recompressed`): fewer, orthogonal components, the last of them to be held in 8 bits instead of
16 (docs/physics.md §8.9), and written in fixed point (:func:`fixed_point`). A worker finds a run of blocks in one
compiled call (:func:`run_of_crosses`); the budget counts what every block's crosses would hold from a sample of
them found by the same call (:func:`sampled_count`), so that a block counted holds what the build holds, to the
byte.
"""

from __future__ import annotations

import numba
import numpy as np

from ..threads import for_ranges, thread_count
from .fits import AFFINE_TERMS, fitted_run, run_scratch

__all__ = [
    "CHECK_ROWS",
    "FIXED_STEPS",
    "NARROW_SHARE",
    "NARROW_STEPS",
    "RECOMPRESS_SHARE",
    "SAMPLED_BLOCKS",
    "V8_STEP",
    "V_STEP",
    "CROSS_KERNELS",
    "Approximations",
    "Room",
    "block_rows",
    "cross_approximation",
    "far_items",
    "fixed_point",
    "found_crosses",
    "rank_limit",
    "rank_limits",
    "run_of_crosses",
    "sampled_count",
    "split",
]


def rank_limit(rows: int, columns: int) -> int:
    """Crosses a block of ``rows x columns`` may take before it is split: while they hold about half the bytes of
    storing it whole (``2 k (rows + columns) <= 4 rows columns / 2``: the crosses in 16 bits, a dense block in 32;
    the rows' float32 scales left out), and at most 96."""
    return int(max(1, min(96, rows * columns // (rows + columns))))


def rank_limits(rows, columns) -> np.ndarray:
    """:func:`rank_limit` of every block of ``rows`` and ``columns`` (arrays, one entry per block), int64."""
    return np.array([rank_limit(int(m), int(c)) for m, c in zip(rows, columns)], dtype=np.int64)


#: A cross approximation also stops when this many rows in a row (the next pivot, then rows drawn at random) are
#: each held to ``eps`` of their own norm by the crosses so far.
CHECK_ROWS = 3


#: A block's crosses are recompressed (:func:`_recompressed`) to the fewest orthogonal components whose singular
#: values left out hold at most this share of ``eps`` of the block's Frobenius norm (the crosses themselves stop at
#: ``eps``; the two errors add about in quadrature).
RECOMPRESS_SHARE = 0.5
#: Columns of a block the recompression takes at a time (``k`` rows of them stay in the fastest cache).
RECOMPRESS_COLUMNS = 128
#: Steps of the 8-bit fixed point of a component's ``V`` held narrow: its largest entry is this many steps.
NARROW_STEPS = 127
#: The last (smallest) components of a block whose ``V`` rounded to :data:`NARROW_STEPS` steps adds at most this share
#: of ``eps`` of the block's Frobenius norm are held in 8 bits instead of 16.
NARROW_SHARE = 0.25

#: Steps of the 16-bit fixed point the blocks are held in: a row's largest entry is this many steps.
FIXED_STEPS = 32767
#: ``V`` is stored as int16: each component's ``V`` is divided by its largest entry, so every entry is in [-1, 1]
#: and is kept to 2**-15 of it (far below ``eps``); the smallest components of a block as int8 in steps of
#: :data:`V8_STEP` (``crosses.NARROW_SHARE``). ``U`` is int16, each row in steps of its own float32 scale, its
#: largest entry :data:`FIXED_STEPS` steps (docs/physics.md §8.9).
V_STEP = 1.0 / FIXED_STEPS
V8_STEP = 1.0 / NARROW_STEPS


#: The largest ``k x k`` a recompression hands to LAPACK's ``syevd``; larger ones take Jacobi rotations. Above it
#: OpenBLAS starts threads of its own inside the call, which compete with the workers' (bench/README.md, "The
#: preparation, 8 December 2026").
LAPACK_LARGEST = 64


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _symmetric_eigen(A):
    """Eigenvalues (descending) and eigenvectors (columns) of the symmetric ``A`` (``k x k``, overwritten): LAPACK's
    ``syevd`` up to :data:`LAPACK_LARGEST`, else cyclic Jacobi rotations (Golub and Van Loan, §8.5) until the
    off-diagonal part is 1e-12 of the whole."""
    k = A.shape[0]
    if k <= LAPACK_LARGEST:
        ascending, vectors = np.linalg.eigh(A)
        return ascending[::-1].copy(), np.ascontiguousarray(vectors[:, ::-1])
    E = np.eye(k)
    whole = 0.0
    for p in range(k):
        for q in range(k):
            whole += A[p, q] * A[p, q]
    for _ in range(64):
        off = 0.0
        for p in range(k):
            for q in range(p + 1, k):
                off += A[p, q] * A[p, q]
        if off <= 1e-24 * whole:
            break
        for p in range(k - 1):
            for q in range(p + 1, k):
                apq = A[p, q]
                if apq == 0.0:
                    continue
                theta = (A[q, q] - A[p, p]) / (2.0 * apq)
                t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + np.sqrt(theta * theta + 1.0))
                c = 1.0 / np.sqrt(t * t + 1.0)
                s = t * c
                for r in range(k):
                    arp, arq = A[r, p], A[r, q]
                    A[r, p] = c * arp - s * arq
                    A[r, q] = s * arp + c * arq
                for r in range(k):
                    apr, aqr = A[p, r], A[q, r]
                    A[p, r] = c * apr - s * aqr
                    A[q, r] = s * apr + c * aqr
                for r in range(k):
                    erp, erq = E[r, p], E[r, q]
                    E[r, p] = c * erp - s * erq
                    E[r, q] = s * erp + c * erq
    values = np.empty(k)
    for p in range(k):
        values[p] = A[p, p]
    order = np.argsort(-values)
    return values[order], np.ascontiguousarray(E[:, order])


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _all_finite(A, rows, columns):
    """Whether every entry of ``A[:rows, :columns]`` is finite, read from its bits (its exponent not all ones): numba
    compiles a function called from a fast-math kernel with fast math, where ``np.isfinite`` may be taken as true."""
    box = np.empty(1)
    bits = box.view(np.uint64)
    for i in range(rows):
        for j in range(columns):
            box[0] = A[i, j]
            if (bits[0] >> np.uint64(52)) & np.uint64(0x7FF) == np.uint64(0x7FF):
                return False
    return True


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _small_product(A, B):
    """``A @ B`` of two small matrices, without BLAS (whose threads compete with the workers')."""
    C = np.zeros((A.shape[0], B.shape[1]))
    for i in range(A.shape[0]):
        for p in range(A.shape[1]):
            weight = A[i, p]
            for j in range(B.shape[1]):
                C[i, j] += weight * B[p, j]
    return C


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _recompressed(U, V, m, n, k, eps, outer):
    """The crosses ``U[:m, :k] V[:k, :n]`` of one block (rows scaled) recompressed in place (Bebendorf 2008, §1.1.5),
    ``outer[:k, :k]`` their ``V V^T`` (the cross approximation keeps it as it goes):
    with ``U = Q R`` (modified Gram-Schmidt) and ``R V V^T R^T = W S^2 W^T`` (:func:`_symmetric_eigen`), the block is
    ``sum_q (Q W S)_q (S^-1 W^T R V)_q``, components in order of their singular values ``s_q``. The fewest are kept
    whose left-out ``s_q`` hold at most :data:`RECOMPRESS_SHARE` ``eps`` of ``|S|``, each ``V`` row divided by its
    largest entry (so that it is in [-1, 1]) and ``U``'s column multiplied by it. Returns ``(kept, narrow)``: the
    components kept, and how many of the last of them may be held in 8 bits (:data:`NARROW_STEPS`): their rounding
    ``s_q |dV_q|`` adds, in quadrature, at most :data:`NARROW_SHARE` ``eps`` of ``|S|``. Crosses that are not all
    finite are left as they are (``(k, 0)``)."""
    if k == 0:
        return 0, 0
    if not (_all_finite(U, m, k) and _all_finite(V, k, n)):  # a NaN or an infinity stays as it is: B shows it
        return k, 0
    Q = np.empty((k, m))  # U's columns as rows, then orthonormalised
    for a in range(m):
        for p in range(k):
            Q[p, a] = U[a, p]
    R = np.zeros((k, k))
    for p in range(k):
        current = Q[p]
        for q in range(p):
            earlier = Q[q]
            dot = 0.0
            for a in range(m):
                dot += earlier[a] * current[a]
            R[q, p] = dot
            for a in range(m):
                current[a] -= dot * earlier[a]
        norm = 0.0
        for a in range(m):
            norm += current[a] * current[a]
        norm = np.sqrt(norm)
        R[p, p] = norm
        inverse = 1.0 / norm if norm > 0.0 else 0.0
        for a in range(m):
            current[a] *= inverse
    # R V V^T R^T: the Gram matrix of R V, the block being Q (R V)
    gram = _small_product(_small_product(R, np.ascontiguousarray(outer[:k, :k])), np.ascontiguousarray(R.T))
    squares, W = _symmetric_eigen(gram)
    total2 = 0.0
    for q in range(k):
        total2 += max(squares[q], 0.0)
    kept = k
    left = 0.0
    while kept > 0 and left + max(squares[kept - 1], 0.0) <= (RECOMPRESS_SHARE * eps) ** 2 * total2:
        kept -= 1
        left += max(squares[kept], 0.0)
    narrow = 0
    rounded2 = 0.0
    budget2 = (NARROW_SHARE * eps) ** 2 * total2
    to_v = _small_product(np.ascontiguousarray(W.T), R)  # the new V's rows: (W^T R) V, each s_q times a unit row
    V_new = np.zeros((kept, n))
    for j0 in range(0, n, RECOMPRESS_COLUMNS):
        j1 = min(n, j0 + RECOMPRESS_COLUMNS)
        for q in range(kept):
            row = V_new[q, j0:j1]
            for p in range(k):
                weight = to_v[q, p]
                source = V[p, j0:j1]
                for j in range(j1 - j0):
                    row[j] += weight * source[j]
    column = np.empty(m)
    for q in range(kept - 1, -1, -1):
        row = V_new[q]
        largest = 0.0
        for j in range(n):
            largest = max(largest, abs(row[j]))
        if largest == 0.0:
            largest = 1.0
        error2 = 0.0
        for j in range(n):
            v = row[j] / largest
            row[j] = v
            e = np.rint(v * NARROW_STEPS) / NARROW_STEPS - v
            error2 += e * e
        column[:] = 0.0
        for p in range(k):
            weight = W[p, q] * largest
            basis = Q[p]
            for a in range(m):
                column[a] += weight * basis[a]
        for a in range(m):
            U[a, q] = column[a]
        error2 *= largest * largest
        if narrow == kept - 1 - q and rounded2 + error2 <= budget2:
            narrow += 1
            rounded2 += error2
    for q in range(kept):
        for j in range(n):
            V[q, j] = V_new[q, j]
    return kept, narrow


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _steps(x):
    """``x`` rounded to the nearest whole step (halves to even), at most :data:`FIXED_STEPS` either way, as int16."""
    return np.int16(min(max(np.rint(x), -FIXED_STEPS), FIXED_STEPS))


@numba.njit(cache=True, nogil=True, error_model="numpy")
def fixed_point(U, V, crosses, scales, V_out, V8_out):
    """One block's components in fixed point: ``U (rows, k)`` as 16-bit steps of one float32 scale per row (its
    largest entry :data:`FIXED_STEPS` steps) written a component at a time to ``crosses (k, rows)``, the scales to
    ``scales``; ``V (k, columns)`` (in [-1, 1]) as steps of :data:`V_STEP` to ``V_out (k - k8, columns)`` (int16) and
    its last ``k8`` rows as steps of :data:`V8_STEP` to ``V8_out (k8, columns)`` (int8)."""
    m, k = U.shape
    wide = V_out.shape[0]
    for a in range(m):
        largest = 0.0
        for q in range(k):
            size = abs(U[a, q])
            if size > largest or size != size:  # a NaN stays, as it would in numpy's max: B shows it
                largest = size
        scale = np.float32(largest / FIXED_STEPS)
        scales[a] = scale
        step = np.float64(scale) if scale > 0.0 else 1.0
        for q in range(k):
            crosses[q, a] = _steps(U[a, q] / step)
    for q in range(wide):
        for j in range(V.shape[1]):
            V_out[q, j] = _steps(V[q, j] / V_STEP)
    for q in range(k - wide):
        for j in range(V.shape[1]):
            V8_out[q, j] = np.int8(min(max(np.rint(V[wide + q, j] * NARROW_STEPS), -NARROW_STEPS), NARROW_STEPS))


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _grown_grams(k, pivot, U_row, pivot_column, column_dots, row_dots, u2, v2, grams):
    """The Gram matrices ``grams = (U^T U, V V^T)`` of :func:`cross_approximation` grown by its new cross ``k``
    (``u_k``, ``v_k``), and ``sum_q (u_k . u_q) (v_k . v_q)`` over the earlier ones (the cross terms of the block's
    norm): ``u_k . u_q = c . u_q - sum_p V[p, j] (u_p . u_q)`` and ``v_k . v_q = (f . v_q - sum_p U[i, p] (v_p . v_q)) /
    pivot``, with ``c . u_q`` (``column_dots``) and ``f . v_q`` (``row_dots``) taken in the passes that subtracted the
    earlier crosses from the column's and the row's fits ``c``, ``f``; ``pivot_column`` is ``V[:k, j]``, ``U_row``
    ``U[i]``, ``u2`` and ``v2`` the new cross's squared norms. Costs ``k^2``, not two more passes over ``U`` and
    ``V``."""
    gram_u, gram_v = grams[0], grams[1]
    cross = 0.0
    for q in range(k):
        uu = column_dots[q]
        vv = row_dots[q]
        for p in range(k):  # the Gram matrices are symmetric: read along a row
            uu -= pivot_column[p] * gram_u[q, p]
            vv -= U_row[p] * gram_v[q, p]
        vv /= pivot
        gram_u[k, q] = gram_u[q, k] = uu
        gram_v[k, q] = gram_v[q, k] = vv
        cross += uu * vv
    gram_u[k, k] = u2
    gram_v[k, k] = v2
    return cross


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def cross_approximation(model, P, N, r0, r1, c0, c1, params, dirs, pinv, row_scale, eps, kmax, U, V, space):
    """Adaptive cross approximation with partial pivoting of one channel (``params`` of one row): rows ``r0:r1``
    x sources ``c0:c1`` (columns ``4 (j - c0) + t``), each row scaled by ``row_scale[row]``: the crosses in
    ``U[:m, :k]`` and ``V[:k, :4 n]``, then recompressed (:func:`_recompressed`; ``U V`` unscaled on return):
    ``(found, kept, narrow)``, the crosses found (-1 when ``kmax`` were not enough) and :func:`_recompressed`'s.

    It stops when the last cross is below ``eps`` of the block's Frobenius norm (Bebendorf's estimate, on the
    scaled entries: each row relative to its own receiver's scale), or when the next pivot row and
    :data:`CHECK_ROWS` - 1 rows drawn at random are each held to ``eps`` of their own norm. ``space`` is
    :func:`~translucency.scatter.fits.run_scratch`'s for runs at least as long as the block's sides."""
    m = r1 - r0
    n = (c1 - c0) * AFFINE_TERMS
    fits = np.empty((max(m, c1 - c0), 1, AFFINE_TERMS))
    used = np.zeros(m, dtype=np.bool_)
    column_cache = np.empty((m, AFFINE_TERMS))
    pivot_column = np.empty(kmax + 1)
    # the Gram matrices of U's columns and V's rows as they grow, and the dot products of a new row's fits with V's
    # rows and of a new column's with U's columns, taken in the passes that subtract the crosses so far: a new
    # cross's dot products with the earlier ones then cost k^2, not two more passes over U and V
    grams = np.empty((2, kmax + 1, kmax + 1))  # U^T U, V V^T
    row_dots = np.empty(kmax + 1)
    column_dots = np.empty(kmax + 1)
    cached = -1
    fitted = np.empty(n)
    row = np.empty(n)
    seed = (r0 * 7919 + c0 * 104729 + 1) & 0x7FFFFFFF
    i = 0
    k = 0
    passed = 0
    visited = 0
    norm2 = 0.0
    while True:
        used[i] = True
        visited += 1
        full2 = 0.0
        fitted_run(model, P, N, r0 + i, c0, c1, np.bool_(True), params, dirs, pinv, space, fits)
        for b in range(c1 - c0):
            for t in range(AFFINE_TERMS):
                value = fits[b, 0, t] * row_scale[i]
                fitted[b * AFFINE_TERMS + t] = value
                row[b * AFFINE_TERMS + t] = value
                full2 += value * value
        for q in range(k):
            u = U[i, q]
            dot = 0.0
            for j in range(n):
                v = V[q, j]
                dot += fitted[j] * v
                row[j] -= u * v
            row_dots[q] = dot
        j = 0
        best = 0.0
        residual2 = 0.0
        for q in range(n):
            residual2 += row[q] * row[q]
            if abs(row[q]) > best:
                best = abs(row[q])
                j = q
        if residual2 <= eps * eps * full2:  # this row is held: check another, drawn at random
            passed += 1
            if passed >= CHECK_ROWS or visited >= m:
                break
            seed = (seed * 1103515245 + 12345) & 0x7FFFFFFF
            i = seed % m
            for _ in range(m):
                if not used[i]:
                    break
                i = (i + 1) % m
            continue
        passed = 0
        if k == kmax:
            return -1, 0, 0
        source = j // AFFINE_TERMS
        if source != cached:
            fitted_run(model, P, N, c0 + source, r0, r1, np.bool_(False), params, dirs, pinv, space, fits)
            for a in range(m):
                for t in range(AFFINE_TERMS):
                    column_cache[a, t] = fits[a, 0, t] * row_scale[a]
            cached = source
        term = j % AFFINE_TERMS
        pivot = row[j]
        best = -1.0
        following = -1
        for q in range(k):
            pivot_column[q] = V[q, j]  # read once: down a column of V, each entry on a cache line of its own
            column_dots[q] = 0.0
        u2 = 0.0
        for a in range(m):
            entry = column_cache[a, term]
            value = entry
            for q in range(k):
                w = U[a, q]
                value -= w * pivot_column[q]
                column_dots[q] += entry * w
            U[a, k] = value
            u2 += value * value
            if not used[a] and abs(value) > best:
                best = abs(value)
                following = a
        v2 = 0.0
        for q in range(n):
            V[k, q] = row[q] / pivot
            v2 += V[k, q] * V[k, q]
        norm2 += u2 * v2 + 2.0 * _grown_grams(k, pivot, U[i], pivot_column, column_dots, row_dots, u2, v2, grams)
        k += 1
        if following < 0:
            break
        i = following
        if u2 * v2 <= eps * eps * abs(norm2):
            break
    kept, narrow = _recompressed(U, V, m, n, k, eps, grams[1])
    # unscaled in U, whose rows then have the receivers' own magnitudes: V stays in [-1, 1], and neither leaves
    # float32's range where the rows of a block differ by more than it spans
    for q in range(kept):
        for a in range(m):
            U[a, q] /= row_scale[a]
    return k, kept, narrow


def _scratch(held: list, rows: int, ranks: int, columns: int) -> tuple[np.ndarray, np.ndarray]:
    """A worker's ``U (rows, ranks)`` and ``V (ranks, columns)`` buffers, grown when a block needs more."""
    U, V = held
    if U.shape[0] < rows or U.shape[1] < ranks:
        held[0] = U = np.empty((max(rows, U.shape[0]), max(ranks, U.shape[1])))
    if V.shape[0] < ranks or V.shape[1] < columns:
        held[1] = V = np.empty((max(ranks, V.shape[0]), max(columns, V.shape[1])))
    return U, V


#: Blocks whose row scales are computed together (one call of the bound per channel over all their rows).
SCALE_CHUNK = 2048


def _row_scales(tree, P, items, channel_bound):
    """Per block and channel ``(row node, column node, channel)`` of ``items``: each receiver's row scale, one
    over the channel's §8.4 bound at the receiver's distance from the column node's centre, so that the crosses
    hold every row alike, not only the block's brightest (a dark receiver's B is all far field):
    ``(offsets, row_scales)``, block ``p``'s rows at ``row_scales[offsets[p] : offsets[p + 1]]``."""
    a, b, c = items[:, 0], items[:, 1], items[:, 2]
    m = tree.end[a] - tree.start[a]
    offsets = np.zeros(len(items) + 1, dtype=np.int64)
    np.cumsum(m, out=offsets[1:])
    owner = np.repeat(np.arange(len(items)), m)
    rows = tree.start[a][owner] + np.arange(int(offsets[-1])) - offsets[:-1][owner]
    r = np.maximum(np.linalg.norm(P[rows] - tree.centre[b][owner], axis=1), 1e-12)
    own = channel_bound(r)[c[owner], np.arange(r.size)]
    return offsets, 1.0 / np.clip(own, 1e-280, 1e280)


class Approximations:
    """What every far block's cross approximation needs (:func:`cross_approximation`), with each worker's scratch:
    the surface in the tree's order (``P``, ``N``, mm), each channel's parameters, the fit's directions, ``eps`` and
    the bound of §8.4 per channel (``channel_bound(r)``, by which the rows are scaled)."""

    def __init__(self, model, tree, P, N, params, dirs, pinv, eps, channel_bound, longest):
        self.model, self.tree, self.P, self.N = model, tree, P, N
        self.params = np.ascontiguousarray(params, dtype=np.float64)
        self.channels = [np.ascontiguousarray(params[c : c + 1]) for c in range(params.shape[0])]
        self.dirs, self.pinv, self.eps, self.channel_bound = dirs, pinv, eps, channel_bound
        self.buffers = [[np.empty((0, 0)), np.empty((0, 0))] for _ in range(thread_count())]
        # each thread's fits work in one space made for the longest run there is (made per block, the large ones
        # were fresh memory every time, which this machine fills at 0.5-2 GB/s)
        self.spaces = [run_scratch(dirs.shape[0], longest) for _ in range(thread_count())]

    def scratch(self, worker: int, rows: int, ranks: int, columns: int) -> tuple[np.ndarray, np.ndarray]:
        """Worker ``worker``'s ``U (rows, ranks)`` and ``V (ranks, columns)`` buffers (or larger), grown when a block
        needs more (:func:`_scratch`)."""
        return _scratch(self.buffers[worker], rows, ranks, columns)

    def row_scales(self, items):
        """:func:`_row_scales` of the blocks ``items`` (``(row node, column node, channel)`` rows)."""
        return _row_scales(self.tree, self.P, items, self.channel_bound)


def split(tree, a, b, c) -> list:
    """The blocks a far block ``(a, b)``'s channel ``c`` is split into when it needs more crosses than it may take:
    its children's pairs; none for a pair of leaves, which is stored whole."""
    if tree.left[a] < 0 and tree.left[b] < 0:
        return []
    rows = [a] if tree.left[a] < 0 else [tree.left[a], tree.right[a]]
    cols = [b] if tree.left[b] < 0 else [tree.left[b], tree.right[b]]
    return [(r, s, c) for r in rows for s in cols]


def far_items(far_pairs, n_channels) -> np.ndarray:
    """``(row node, column node, channel)`` of every far block and channel, ``(F C, 3)`` int64."""
    items = np.empty((len(far_pairs) * n_channels, 3), dtype=np.int64)
    items[:, :2] = np.repeat(np.asarray(far_pairs, dtype=np.int64).reshape(-1, 2), n_channels, axis=0)
    items[:, 2] = np.tile(np.arange(n_channels), len(far_pairs))
    return items


def longest_run(tree, far_pairs) -> int:
    """The most vertices of a node of ``far_pairs``: the longest run a block's fits take."""
    return int(np.max(np.maximum(tree.end - tree.start, 1)[far_pairs].max(initial=1)))


def block_rows(tree, items) -> np.ndarray:
    """The rows :func:`found_crosses` takes for the blocks ``items`` (``(row node, column node, channel)``): first
    and last row, first and last column, channel, and the crosses each may take
    (:func:`rank_limit`)."""
    start, end = tree.start, tree.end
    row_node, column_node = items[:, 0], items[:, 1]
    kmax = rank_limits(end[row_node] - start[row_node], (end[column_node] - start[column_node]) * AFFINE_TERMS)
    return np.column_stack([start[row_node], end[row_node], start[column_node], end[column_node], items[:, 2], kmax])


class Room:
    """A worker's room for a run of blocks' components in fixed point (:func:`found_crosses`), grown when one block
    needs more than it holds, kept between runs (its pages are written once)."""

    #: Elements of ``U``, ``V`` and ``V8`` (each) and rows of ``S`` a room holds at first.
    ELEMENTS = 1 << 20
    ROWS = 1 << 16

    def __init__(self):
        self.grow(self.ELEMENTS, self.ROWS)

    def grow(self, elements: int, rows: int) -> None:
        """Room for ``elements`` of each of ``U``, ``V``, ``V8`` and ``rows`` row scales."""
        self.U = np.empty(elements, dtype=np.int16)
        self.V = np.empty(elements, dtype=np.int16)
        self.V8 = np.empty(elements, dtype=np.int8)
        self.S = np.empty(rows, dtype=np.float32)


def run_of_crosses(approximations, room: Room, worker: int, blocks, offsets, row_scales):
    """The cross approximations of ``blocks`` (rows: first and last row, first and last column, channel, crosses
    it may take; tree order) in one compiled run (:func:`found_crosses`), as many as ``room`` holds (it grows when
    not even the first fits): ``(count, info, (U, V, S, V8))``, ``info`` per block done as :func:`found_crosses`
    writes it, and the parts of the room they fill."""
    rows = blocks[:, 1] - blocks[:, 0]
    cols = (blocks[:, 3] - blocks[:, 2]) * AFFINE_TERMS
    first = int(blocks[0, 5])
    if first * max(int(rows[0]), int(cols[0])) > room.U.size or int(rows[0]) > room.S.size:
        room.grow(2 * first * max(int(rows[0]), int(cols[0])), 2 * int(rows[0]))
    U, V = approximations.scratch(worker, int(rows.max()), int(blocks[:, 5].max()), int(cols.max()))
    info = np.empty((blocks.shape[0], 7), dtype=np.int64)
    used = np.zeros(4, dtype=np.int64)
    count = found_crosses(
        approximations.model, approximations.P, approximations.N, approximations.params,
        approximations.dirs, approximations.pinv, approximations.eps,
        blocks, offsets, row_scales, U, V, approximations.spaces[worker],
        (room.U, room.V, room.S, room.V8), info, used,
    )  # fmt: skip
    return count, info[:count], (room.U[: used[0]], room.V[: used[1]], room.S[: used[2]], room.V8[: used[3]])


@numba.njit(cache=True, nogil=True, error_model="numpy")
def found_crosses(model, P, N, params, dirs, pinv, eps, blocks, offsets, row_scales, U, V, space, room, info, used):
    """The cross approximations (:func:`~translucency.scatter.crosses.cross_approximation`) of ``blocks`` in turn
    (rows: first and last row, first and last column, channel, crosses it may take), each block's components in fixed
    point (:func:`fixed_point`) one after another in ``room`` (``U``, ``V`` int16, ``S`` float32, ``V8`` int8), until
    the next block might not fit: returns how many blocks were done. ``info[p]``: crosses found (-1: not enough), kept,
    held narrow, and where block ``p``'s ``U``, ``V``, ``S`` and ``V8`` start in ``room``; ``used``: how much of
    each the run filled. Block ``p``'s row scales are ``row_scales[offsets[p] : offsets[p + 1]]``."""
    U_room, V_room, S_room, V8_room = room
    u_at, v_at, s_at, v8_at = 0, 0, 0, 0
    for p in range(blocks.shape[0]):
        r0, r1, c0, c1, c, kmax = blocks[p, 0], blocks[p, 1], blocks[p, 2], blocks[p, 3], blocks[p, 4], blocks[p, 5]
        m, n = r1 - r0, (c1 - c0) * AFFINE_TERMS
        if u_at + kmax * m > U_room.size or max(v_at, v8_at) + kmax * n > V_room.size or s_at + m > S_room.size:
            used[0], used[1], used[2], used[3] = u_at, v_at, s_at, v8_at
            return p
        found, k, narrow = cross_approximation(
            model, P, N, r0, r1, c0, c1, params[c : c + 1], dirs, pinv,
            row_scales[offsets[p] : offsets[p + 1]], eps, kmax, U, V, space,
        )  # fmt: skip
        info[p, 0], info[p, 1], info[p, 2] = found, k, narrow
        info[p, 3], info[p, 4], info[p, 5], info[p, 6] = u_at, v_at, s_at, v8_at
        if found < 0:
            continue
        wide = k - narrow
        fixed_point(
            U[:m, :k],
            V[:k, :n],
            U_room[u_at : u_at + k * m].reshape((k, m)),
            S_room[s_at : s_at + m],
            V_room[v_at : v_at + wide * n].reshape((wide, n)),
            V8_room[v8_at : v8_at + narrow * n].reshape((narrow, n)),
        )
        u_at += k * m
        v_at += wide * n
        s_at += m
        v8_at += narrow * n
    used[0], used[1], used[2], used[3] = u_at, v_at, s_at, v8_at
    return blocks.shape[0]


#: Far blocks (per channel) whose cross approximations :func:`sampled_count` finds, to count what the far field
#: (:func:`~translucency.scatter.lowrank.build`) would hold before it is made, and the seed of their draw (the same
#: blocks every time).
SAMPLED_BLOCKS = 384
SAMPLE_SEED = 8


def sampled_count(
    model, tree, points, normals, params, fit, eps, far_pairs, channel_bound, blocks: int = SAMPLED_BLOCKS
) -> dict:
    """What the cross approximations of the blocks ``far_pairs`` would hold in the far field
    (:func:`~translucency.scatter.lowrank.build`), counted by finding those of ``blocks`` of them (each channel a
    block of its own), and of the blocks they are split into.

    The blocks are drawn systematically with chances in proportion to their rows and columns, ``m + 4 n``, and what a
    block drawn ``t`` times holds counts ``t / (blocks p)`` for its chance ``p`` (Hansen and Hurwitz's estimate of a
    total). It follows the surface, the medium, the model and ``eps``; its spread is the spread of the ranks between
    neighbouring blocks. With fewer far blocks than ``blocks``, every one is counted.

    Arguments as :func:`~translucency.scatter.lowrank.build`'s (``points``, ``normals`` in vertex order, mm), ``tree``
    its block tree. Returns floats: ``cross_bytes``, the bytes of ``U`` and ``V`` (16-bit entries, and 8-bit ones of
    the components held narrow); ``row_scales``, ``U``'s row scales; ``dense_entries``, the (receiver, source,
    channel) pairs stored whole in blocks that ran out of crosses; ``fits``, the fits of one pair and channel that the
    cross approximations and those dense blocks evaluate.
    """
    order = tree.order
    P = np.ascontiguousarray(points[order], dtype=np.float64)
    N = np.ascontiguousarray(normals[order], dtype=np.float64)
    items = far_items(far_pairs, params.shape[0])
    if not len(items):
        return {"cross_bytes": 0.0, "row_scales": 0.0, "dense_entries": 0.0, "fits": 0.0}
    size = tree.end - tree.start
    weight = (size[items[:, 0]] + AFFINE_TERMS * size[items[:, 1]]).astype(np.float64)
    if len(items) <= blocks:
        chosen, counted = np.arange(len(items)), np.ones(len(items))
    else:
        # systematic: evenly spaced marks on the blocks' weights laid end to end in the partition's order (block by
        # block down the tree, each block's channels in turn), from one random start
        marks = (np.random.default_rng(SAMPLE_SEED).uniform() + np.arange(blocks)) * (weight.sum() / blocks)
        draws = np.minimum(np.searchsorted(np.cumsum(weight), marks, side="right"), len(items) - 1)
        chosen, times = np.unique(draws, return_counts=True)
        counted = times * weight.sum() / (blocks * weight[chosen])
    approximations = Approximations(model, tree, P, N, params, *fit, eps, channel_bound, longest_run(tree, far_pairs))
    rooms = [Room() for _ in range(thread_count())]
    held = np.zeros((len(chosen), 4))

    def run(worker, lo, hi):
        for p in range(lo, hi):
            pending = [tuple(items[chosen[p]])]
            while pending:
                a, b, c = pending.pop()
                item = np.array([[a, b, c]], dtype=np.int64)
                offsets, row_scale = approximations.row_scales(item)
                # the build's own compiled run: the crosses of a block are then those the build finds, to the bit
                _, info, _ = run_of_crosses(
                    approximations, rooms[worker], worker, block_rows(tree, item), offsets, row_scale
                )
                found, k, narrow = (int(x) for x in info[0, :3])
                m, n = int(size[a]), int(size[b])
                crosses = found if found >= 0 else rank_limit(m, AFFINE_TERMS * n)
                held[p, 3] += (crosses + CHECK_ROWS) * n + crosses * m
                if found >= 0:
                    held[p, :2] += (2 * k * m + (2 * k - narrow) * AFFINE_TERMS * n, m)
                    continue
                children = split(tree, a, b, c)
                pending += children
                if not children:  # a pair of leaves stored whole: its pairs held, and fitted
                    held[p, 2] += m * n
                    held[p, 3] += m * n

    for_ranges(run, len(chosen))
    total = counted @ held
    return {"cross_bytes": total[0], "row_scales": total[1], "dense_entries": total[2], "fits": total[3]}


#: The compiled kernels of the cross approximations: numba compiles them on first use; the set-up compiles them ahead
#: (:mod:`translucency.app.warmup`).
CROSS_KERNELS = (
    cross_approximation,
    _recompressed,
    _symmetric_eigen,
    _small_product,
    _all_finite,
    _grown_grams,
    found_crosses,
    fixed_point,
)
