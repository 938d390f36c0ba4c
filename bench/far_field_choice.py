"""Choosing the far field by measurement: how compressible the directional dipole's far field is, and
whether its expansions may drop the modified tangent plane.

Four measurements on the default bunny in marble (docs/physics.md §4, §8.3, §8.7):

* **ranks**: blocks of the relighting kernel (the affine fit ``S_d = a + b . w12`` of ``fitted_pairs`` in
  ``tests/scatter/pairs.py``, one pair at a time, four columns per source) between two clusters of ``m``
  nearest vertices each, at ratios of cluster radius to centre distance of about 0.35, 0.25 and 0.18; the
  number of singular values needed for a relative Frobenius error of 1e-3 and 1e-4 per channel;
* **hierarchical matrix**: the whole far field of that kernel as an H-matrix (the kd-tree of
  :class:`translucency.scatter.hierarchy.SourceTree`, a block admissible when its clusters are farther apart
  than a reduced mean free path and ``max radius <= eta * centre distance``; adaptive cross approximation with
  partial pivoting per block and channel to ``eps``): its float32 storage (floats per receiver and channel,
  what a light would read), the cross approximation's time on one thread, and its error at 400 random
  receivers against the same blocks summed in full, relative to the whole vertex sum (a light from
  ``(0.3, 1, 0.5)``, flux ``cos``);
* **nested bases**: the same far field as an H^2-matrix of skeletons (kernel-independent, as recursive
  skeletonization builds it): per tree node, the receivers and the (source, term) columns that represent its
  far field and its ancestors' (interpolative decompositions to ``eps`` per row and per column, by pivoted QR, of
  the node's children's skeletons against 300 sampled far sources or receivers), and per admissible block only
  the kernel between the two skeletons; its storage, time and error as above;
* **point sources far away**: the vertex sum ``sum_i S_d Phi_i`` of one light (Embree shadows, the model's own
  refracted directions) with the pairs farther than ``R`` evaluated as a real and a virtual point source whose
  plane is the source's tangent plane (``n_i* = n_i``, ``d_r = r``), the form an analytic multipole expansion
  of the two sources would take, against the model; per-vertex error (docs/physics.md §8.5).

Writes ``far_field_choice.json`` and ``far_field_choice.md`` into ``bench/results`` (about 8 min on 2 cores).

    .venv/bin/python bench/far_field_choice.py
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numba  # noqa: E402
import numpy as np  # noqa: E402
import scipy.linalg  # noqa: E402
from report import load_average, machine_info, output_dir, write_results  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402

from tests.scatter.pairs import FIT_WORK_COLUMNS, fitted_pairs  # noqa: E402  (one pair at a time)
from translucency import __version__  # noqa: E402,F401  (first: it selects numba's threading layer)
from translucency.app.shading.scan import load_default_scan  # noqa: E402
from translucency.app.shading.scene import Scene  # noqa: E402
from translucency.app.shading.settings import resolve_medium  # noqa: E402
from translucency.scatter import kernels  # noqa: E402
from translucency.scatter.fits import AFFINE_TERMS, fit_directions  # noqa: E402
from translucency.scatter.hierarchy import SourceTree  # noqa: E402
from translucency.scatter.kernels import pair_three  # noqa: E402
from translucency.scatter.lights import DirectionalLight  # noqa: E402
from translucency.scatter.solve import TOL_FLOOR  # noqa: E402

LIGHT = (0.3, 1.0, 0.5)


@numba.njit
def _entry(P, N, o, j, params, dirs, pinv, work, out):
    fitted_pairs(
        0, P[o, 0] - P[j, 0], P[o, 1] - P[j, 1], P[o, 2] - P[j, 2], N[j, 0], N[j, 1], N[j, 2], N[o, 0], N[o, 1],
        N[o, 2], params, dirs, pinv, work, out,
    )  # fmt: skip


@numba.njit
def _block(P, N, rows, cols, params, dirs, pinv):
    """The dense block ``(C, m, 4 n)``: columns ``t * n + j`` for the fit's terms ``t`` (1, w_x, w_y, w_z)."""
    nc = params.shape[0]
    out = np.zeros((nc, rows.size, AFFINE_TERMS * cols.size))
    work = np.empty((max(dirs.shape[0], 9), FIT_WORK_COLUMNS))
    coefs = np.empty((nc, AFFINE_TERMS))
    for a in range(rows.size):
        for b in range(cols.size):
            _entry(P, N, rows[a], cols[b], params, dirs, pinv, work, coefs)
            for c in range(nc):
                for t in range(AFFINE_TERMS):
                    out[c, a, t * cols.size + b] = coefs[c, t]
    return out


def ranks(P, N, params, dirs, pinv, trials=6):
    """Singular values needed per block for a relative Frobenius error of 1e-3 and 1e-4 (median, max over blocks
    and channels)."""
    tree = cKDTree(P)
    rng = np.random.default_rng(1)
    rows = []
    for m in (64, 256, 1024):
        for theta in (0.7, 0.5, 0.35):
            found = {1e-3: [], 1e-4: [], "ratio": []}
            for _ in range(trials):
                _, near = tree.query(P[rng.integers(len(P))], m)
                centre = P[near].mean(axis=0)
                radius = np.max(np.linalg.norm(P[near] - centre, axis=1))
                distance = np.linalg.norm(P - centre, axis=1)
                ring = np.nonzero(np.abs(distance - 2 * radius / theta) < 0.1 * radius / theta)[0]
                if ring.size == 0:
                    continue
                _, far = tree.query(P[rng.choice(ring)], m)
                other = np.max(np.linalg.norm(P[far] - P[far].mean(axis=0), axis=1))
                found["ratio"].append((radius + other) / 2 / np.linalg.norm(P[far].mean(axis=0) - centre))
                block = _block(P, N, near.astype(np.int64), far.astype(np.int64), params, dirs, pinv)
                for c in range(block.shape[0]):
                    s = np.linalg.svd(block[c], compute_uv=False)
                    tail = np.sqrt(np.cumsum((s**2)[::-1]))[::-1] / np.sqrt(np.sum(s**2))
                    for eps in (1e-3, 1e-4):
                        found[eps].append(int(np.sum(tail > eps)))
            rows.append(
                {
                    "vertices": m,
                    "ratio": round(float(np.mean(found["ratio"])), 2),
                    "rank_1e-3": (int(np.median(found[1e-3])), max(found[1e-3])),
                    "rank_1e-4": (int(np.median(found[1e-4])), max(found[1e-4])),
                    "dense_columns": AFFINE_TERMS * m,
                }
            )
            print(rows[-1], flush=True)
    return rows


@numba.njit
def _aca(P, N, r0, r1, c0, c1, params, dirs, pinv, eps, kmax):
    """Adaptive cross approximation with partial pivoting of the block rows ``r0:r1`` x sources ``c0:c1`` (four
    columns each) for one channel: ``(U (m, k), V (4 n, k), entries evaluated)``."""
    m = r1 - r0
    n = c1 - c0
    U = np.zeros((m, kmax))
    V = np.zeros((AFFINE_TERMS * n, kmax))
    work = np.empty((max(dirs.shape[0], 9), FIT_WORK_COLUMNS))
    coefs = np.empty((1, AFFINE_TERMS))
    used_rows = np.zeros(m, np.bool_)
    used_cols = np.zeros(AFFINE_TERMS * n, np.bool_)
    row = np.empty(AFFINE_TERMS * n)
    col = np.empty(m)
    norm2 = 0.0
    i = 0
    k = 0
    evaluated = 0
    while k < kmax:
        used_rows[i] = True
        for b in range(n):
            _entry(P, N, r0 + i, c0 + b, params, dirs, pinv, work, coefs)
            evaluated += 1
            for t in range(AFFINE_TERMS):
                row[t * n + b] = coefs[0, t]
        for q in range(k):
            row -= U[i, q] * V[:, q]
        j = -1
        best = 0.0
        for q in range(AFFINE_TERMS * n):
            if not used_cols[q] and abs(row[q]) > best:
                best = abs(row[q])
                j = q
        if j < 0:
            following = -1
            for q in range(m):
                if not used_rows[q]:
                    following = q
                    break
            if following < 0:
                break
            i = following
            continue
        used_cols[j] = True
        for a in range(m):
            _entry(P, N, r0 + a, c0 + j % n, params, dirs, pinv, work, coefs)
            evaluated += 1
            col[a] = coefs[0, j // n]
        for q in range(k):
            col -= V[j, q] * U[:, q]
        v = row / row[j]
        U[:, k] = col
        V[:, k] = v
        u2 = np.dot(col, col)
        v2 = np.dot(v, v)
        cross = 0.0
        for q in range(k):
            cross += np.dot(col, np.ascontiguousarray(U[:, q])) * np.dot(v, np.ascontiguousarray(V[:, q]))
        norm2 += u2 * v2 + 2.0 * cross
        k += 1
        if math.sqrt(u2 * v2) <= eps * math.sqrt(abs(norm2)):
            break
        best = -1.0
        i = -1
        for a in range(m):
            if not used_rows[a] and abs(col[a]) > best:
                best = abs(col[a])
                i = a
        if i < 0:
            break
    return U[:, :k].copy(), V[:, :k].copy(), evaluated


@numba.njit(parallel=True)
def _dense_sum(P, N, rows, skip, params, dirs, pinv, flux, w):
    """``sum_j (a + b . w_j) Phi_j`` at ``rows`` over the sources not marked in ``skip``, per channel."""
    out = np.zeros((rows.size, params.shape[0]))
    for r in numba.prange(rows.size):
        work = np.empty((max(dirs.shape[0], 9), FIT_WORK_COLUMNS))
        coefs = np.empty((params.shape[0], AFFINE_TERMS))
        for j in range(P.shape[0]):
            if skip[r, j]:
                continue
            _entry(P, N, rows[r], j, params, dirs, pinv, work, coefs)
            for c in range(params.shape[0]):
                out[r, c] += flux[j] * (
                    coefs[c, 0] + coefs[c, 1] * w[j, 0] + coefs[c, 2] * w[j, 1] + coefs[c, 3] * w[j, 2]
                )
    return out


def hierarchical(points, normals, params, dirs, pinv, min_distance, eta, eps, leaf=32):
    """The far field as an H-matrix of cross approximations: storage, time and error (module docstring)."""
    tree = SourceTree(points, leaf)
    P = np.ascontiguousarray(points[tree.order])
    N = np.ascontiguousarray(normals[tree.order])
    n = len(P)
    start, end, left, right, centre, radius = tree.start, tree.end, tree.left, tree.right, tree.centre, tree.radius
    far, near = [], []
    stack = [(0, 0)]
    while stack:
        a, b = stack.pop()
        d = np.linalg.norm(centre[a] - centre[b])
        if d - radius[a] - radius[b] >= min_distance and max(radius[a], radius[b]) <= eta * d:
            far.append((a, b))
        elif left[a] < 0 and left[b] < 0:
            near.append((a, b))
        elif left[b] < 0 or (left[a] >= 0 and radius[a] >= radius[b]):
            stack += [(left[a], b), (right[a], b)]
        else:
            stack += [(a, left[b]), (a, right[b])]
    began = time.perf_counter()
    blocks, stored, evaluated, block_ranks = [], 0, 0, []
    for c in range(params.shape[0]):
        channel = np.ascontiguousarray(params[c : c + 1])
        for a, b in far:
            U, V, count = _aca(P, N, start[a], end[a], start[b], end[b], channel, dirs, pinv, eps, 64)
            blocks.append((c, a, b, U.astype(np.float32), V.astype(np.float32)))
            stored += U.size + V.size
            evaluated += count
            block_ranks.append(U.shape[1])
    seconds = time.perf_counter() - began
    light = np.array(LIGHT) / np.linalg.norm(LIGHT)
    flux = np.clip(N @ light, 0.0, None)
    w = -(0.7 * N - 0.3 * light)
    w /= np.linalg.norm(w, axis=1)[:, None]
    B = np.zeros((n, params.shape[0]))
    for c, a, b, U, V in blocks:
        s, e = start[b], end[b]
        q = np.concatenate([flux[s:e], flux[s:e] * w[s:e, 0], flux[s:e] * w[s:e, 1], flux[s:e] * w[s:e, 2]])
        B[start[a] : end[a], c] += U @ (V.T @ q)
    rows = np.random.default_rng(0).choice(n, 400, replace=False)
    leaf_of = np.empty(n, np.int64)
    for node in np.nonzero(left < 0)[0]:
        leaf_of[start[node] : end[node]] = node
    neighbours = {}
    for a, b in near:
        neighbours.setdefault(a, []).append(b)
    skip = np.zeros((rows.size, n), np.bool_)
    for r, o in enumerate(rows):
        for b in neighbours.get(leaf_of[o], []):
            skip[r, start[b] : end[b]] = True
    far_part = _dense_sum(P, N, rows, skip, params, dirs, pinv, flux, w)
    total = _dense_sum(P, N, rows, np.zeros_like(skip), params, dirs, pinv, flux, w)
    keep = total > TOL_FLOOR * total.max(axis=0)
    error = np.abs(B[rows] - far_part)[keep] / total[keep]
    row = {
        "eta": eta,
        "eps": eps,
        "leaf": leaf,
        "far_blocks": len(far),
        "dense_blocks": len(near),
        "dense_sources_per_receiver": round(sum((end[a] - start[a]) * (end[b] - start[b]) for a, b in near) / n),
        "floats_per_receiver_and_channel": round(stored / n / params.shape[0]),
        "gb_float32": round(stored * 4 / 1e9, 2),
        "rank_mean": round(float(np.mean(block_ranks)), 1),
        "rank_max": int(np.max(block_ranks)),
        "entries_evaluated_millions": round(evaluated / 1e6, 1),
        "aca_seconds_one_thread": round(seconds, 1),
        "far_share_median": round(float(np.median(far_part[keep] / total[keep])), 4),
        "error_p50": float(np.median(error)),
        "error_p99": float(np.percentile(error, 99)),
    }
    print(row, flush=True)
    return row


@numba.njit(parallel=True)
def _coefficients(P, N, rows, cols, params, dirs, pinv):
    """The fit's coefficients ``(m, n, C, 4)`` of every (row receiver, column source) pair."""
    out = np.zeros((rows.size, cols.size, params.shape[0], AFFINE_TERMS))
    for a in numba.prange(rows.size):
        work = np.empty((max(dirs.shape[0], 9), FIT_WORK_COLUMNS))
        for b in range(cols.size):
            _entry(P, N, rows[a], cols[b], params, dirs, pinv, work, out[a, b])
    return out


def _interpolative(M, eps):
    """Rows ``skeleton`` of ``M`` and ``X`` with ``M ~ X M[skeleton]``, each row to ``eps`` of its own norm
    (pivoted QR of the row-normalised matrix)."""
    norms = np.linalg.norm(M, axis=1)
    norms[norms == 0] = 1.0
    _, upper, pivots = scipy.linalg.qr((M / norms[:, None]).T, mode="economic", pivoting=True)
    diagonal = np.abs(np.diag(upper))
    k = max(1, int(np.sum(diagonal > eps * diagonal[0])) if diagonal.size and diagonal[0] > 0 else 1)
    X = np.zeros((M.shape[0], k))
    X[pivots[:k]] = np.eye(k)
    if k < M.shape[0]:
        X[pivots[k:]] = scipy.linalg.solve_triangular(upper[:k, :k], upper[:k, k:]).T
    return pivots[:k], X * norms[:, None] / norms[pivots[:k]][None, :]


def nested(points, normals, params, dirs, pinv, min_distance, eta, eps, leaf=32, sample=300):
    """The far field as an H^2-matrix of skeletons (module docstring): ranks, storage, time and error."""
    tree = SourceTree(points, leaf)
    P = np.ascontiguousarray(points[tree.order])
    N = np.ascontiguousarray(normals[tree.order])
    n = len(P)
    start, end, left, right, centre, radius = tree.start, tree.end, tree.left, tree.right, tree.centre, tree.radius
    nodes = tree.n_nodes
    parent = np.full(nodes, -1)
    inner = left >= 0
    parent[left[inner]] = np.nonzero(inner)[0]
    parent[right[inner]] = np.nonzero(inner)[0]
    far = [[] for _ in range(nodes)]
    near = [[] for _ in range(nodes)]
    stack = [(0, 0)]
    while stack:
        a, b = stack.pop()
        d = np.linalg.norm(centre[a] - centre[b])
        if d - radius[a] - radius[b] >= min_distance and max(radius[a], radius[b]) <= eta * d:
            far[a].append(b)
        elif left[a] < 0 and left[b] < 0:
            near[a].append(b)
        elif left[b] < 0 or (left[a] >= 0 and radius[a] >= radius[b]):
            stack += [(left[a], b), (right[a], b)]
        else:
            stack += [(a, left[b]), (a, right[b])]
    rng = np.random.default_rng(0)
    samples = {}
    for k in range(nodes):  # parents first: a node's sample is part of its own far field and part of its parent's
        own = np.concatenate([np.arange(start[b], end[b]) for b in far[k]]) if far[k] else np.zeros(0, np.int64)
        inherited = samples[parent[k]] if parent[k] >= 0 else np.zeros(0, np.int64)
        own = rng.choice(own, min(own.size, sample // 2), replace=False)
        inherited = rng.choice(inherited, min(inherited.size, sample - own.size), replace=False)
        samples[k] = np.concatenate([own, inherited]).astype(np.int64)
    began = time.perf_counter()
    row_skeleton, row_X, column_skeleton, column_Z = {}, {}, {}, {}
    for k in range(nodes - 1, -1, -1):
        if samples[k].size == 0:
            continue
        leaf_node = left[k] < 0
        rows = (
            np.arange(start[k], end[k])
            if leaf_node
            else np.concatenate([row_skeleton[left[k]], row_skeleton[right[k]]])
        )
        M = _coefficients(P, N, rows, samples[k], params, dirs, pinv).reshape(rows.size, -1)
        chosen, row_X[k] = _interpolative(M, eps)
        row_skeleton[k] = rows[chosen]
        if leaf_node:
            columns = (np.arange(start[k], end[k])[:, None] * AFFINE_TERMS + np.arange(AFFINE_TERMS)).ravel()
        else:
            columns = np.concatenate([column_skeleton[left[k]], column_skeleton[right[k]]])
        sources, at = np.unique(columns // AFFINE_TERMS, return_inverse=True)
        block = _coefficients(P, N, samples[k], sources, params, dirs, pinv)
        M = block[:, at, :, columns % AFFINE_TERMS].reshape(columns.size, -1)  # (columns, samples x channels)
        chosen, column_Z[k] = _interpolative(M, eps)
        column_skeleton[k] = columns[chosen]
    skeleton_seconds = time.perf_counter() - began
    began = time.perf_counter()
    coupling, stored = {}, 0
    for a in range(nodes):
        for b in far[a]:
            sources, at = np.unique(column_skeleton[b] // AFFINE_TERMS, return_inverse=True)
            block = _coefficients(P, N, row_skeleton[a], sources, params, dirs, pinv)
            coupling[a, b] = block[:, at, :, column_skeleton[b] % AFFINE_TERMS].transpose(1, 0, 2).astype(np.float32)
            stored += coupling[a, b].size
    coupling_seconds = time.perf_counter() - began
    light = np.array(LIGHT) / np.linalg.norm(LIGHT)
    flux = np.clip(N @ light, 0.0, None)
    w = -(0.7 * N - 0.3 * light)
    w /= np.linalg.norm(w, axis=1)[:, None]
    charges = np.repeat(np.stack([flux, flux * w[:, 0], flux * w[:, 1], flux * w[:, 2]], axis=1).reshape(-1, 1), 3, 1)
    up = {}
    for k in range(nodes - 1, -1, -1):
        if k in column_Z:
            values = charges[start[k] * 4 : end[k] * 4] if left[k] < 0 else np.concatenate([up[left[k]], up[right[k]]])
            up[k] = column_Z[k].T @ values
    down = {k: np.zeros((len(s), 3)) for k, s in row_skeleton.items()}
    for (a, b), block in coupling.items():
        down[a] += np.einsum("ijc,jc->ic", block, up[b])
    B = np.zeros((n, 3))
    for k in range(nodes):
        if k in row_X:
            values = row_X[k] @ down[k]
            if left[k] < 0:
                B[start[k] : end[k]] += values
            else:
                split = len(row_skeleton[left[k]])
                down[left[k]] += values[:split]
                down[right[k]] += values[split:]
    rows = np.random.default_rng(0).choice(n, 400, replace=False)
    leaf_of = np.empty(n, np.int64)
    for node in np.nonzero(left < 0)[0]:
        leaf_of[start[node] : end[node]] = node
    skip = np.zeros((rows.size, n), np.bool_)
    for r, o in enumerate(rows):
        for b in near[leaf_of[o]]:
            skip[r, start[b] : end[b]] = True
    far_part = _dense_sum(P, N, rows, skip, params, dirs, pinv, flux, w)
    total = _dense_sum(P, N, rows, np.zeros_like(skip), params, dirs, pinv, flux, w)
    keep = total > TOL_FLOOR * total.max(axis=0)
    error = np.abs(B[rows] - far_part)[keep] / total[keep]
    bases = sum(x.size for x in row_X.values()) + sum(z.size for z in column_Z.values())
    row = {
        "eta": eta,
        "eps": eps,
        "leaf": leaf,
        "sample": sample,
        "row_rank_mean": round(float(np.mean([len(s) for s in row_skeleton.values()])), 1),
        "column_rank_mean": round(float(np.mean([len(s) for s in column_skeleton.values()])), 1),
        "coupling_floats_per_receiver": round(stored / n),
        "basis_floats_per_receiver": round(bases / n),
        "gb_float32": round((stored + bases) * 4 / 1e9, 2),
        "skeleton_seconds": round(skeleton_seconds, 1),
        "coupling_seconds": round(coupling_seconds, 1),
        "error_p50": float(np.median(error)),
        "error_p99": float(np.percentile(error, 99)),
    }
    print(row, flush=True)
    return row


@numba.njit(parallel=True, fastmath=True)
def _vertex_sum(P, N, w, flux, params, beyond, tangent_plane_far):
    """``sum_i S_d Phi_i`` per receiver; pairs farther than ``beyond`` as point sources in the tangent plane of the
    source when ``tangent_plane_far``."""
    n = P.shape[0]
    out = np.zeros((n, 3))
    for o in numba.prange(n):
        acc = np.zeros(3)
        for i in range(n):
            if flux[i, 0] + flux[i, 1] + flux[i, 2] == 0.0:
                continue
            x0, x1, x2 = P[o, 0] - P[i, 0], P[o, 1] - P[i, 1], P[o, 2] - P[i, 2]
            r2 = x0 * x0 + x1 * x1 + x2 * x2
            if not tangent_plane_far or r2 < beyond * beyond:
                v = pair_three(
                    0, x0, x1, x2, N[i, 0], N[i, 1], N[i, 2], w[i, 0], w[i, 1], w[i, 2], N[o, 0], N[o, 1], N[o, 2],
                    params[0], params[1], params[2],
                )  # fmt: skip
                for c in range(3):
                    acc[c] += v[c] * flux[i, c]
                continue
            wn = w[i, 0] * N[i, 0] + w[i, 1] * N[i, 1] + w[i, 2] * N[i, 2]
            v0, v1, v2 = w[i, 0] - 2 * wn * N[i, 0], w[i, 1] - 2 * wn * N[i, 1], w[i, 2] - 2 * wn * N[i, 2]
            xn = x0 * N[o, 0] + x1 * N[o, 1] + x2 * N[o, 2]
            for c in range(3):
                p = params[c]
                D, height = p[kernels.P_D], p[kernels.P_VIRTUAL]
                scale = p[kernels.P_NORM] / kernels.FOUR_PI_SQUARED
                real = kernels._ray_source(
                    x0 * w[i, 0] + x1 * w[i, 1] + x2 * w[i, 2], xn,
                    w[i, 0] * N[o, 0] + w[i, 1] * N[o, 1] + w[i, 2] * N[o, 2],
                    math.sqrt(r2), D, 1.0 / D, p[kernels.P_SIGMA_TR], p[kernels.P_C_PHI], p[kernels.P_C_E], scale,
                )  # fmt: skip
                y0, y1, y2 = x0 - height * N[i, 0], x1 - height * N[i, 1], x2 - height * N[i, 2]
                virtual = kernels._ray_source(
                    y0 * v0 + y1 * v1 + y2 * v2, y0 * N[o, 0] + y1 * N[o, 1] + y2 * N[o, 2],
                    v0 * N[o, 0] + v1 * N[o, 1] + v2 * N[o, 2], math.sqrt(y0 * y0 + y1 * y1 + y2 * y2), D, 1.0 / D,
                    p[kernels.P_SIGMA_TR], p[kernels.P_C_PHI], p[kernels.P_C_E], scale,
                )  # fmt: skip
                acc[c] += (real - virtual) * flux[i, c]
        out[o] = acc
    return out


def point_sources(scene, medium, params):
    """Per-vertex error of the vertex sum when pairs beyond ``R`` are tangent-plane point sources."""
    solver_mesh, _, _, geometry, _ = scene.solver_mesh(medium, "full")
    incident, _ = scene.light_cache.incident(
        geometry, solver_mesh.triangles, [DirectionalLight(LIGHT, 1.0)], medium.eta
    )
    flux = incident.phi_rgb * geometry.vertex_areas[:, None]
    args = (geometry.points, geometry.normals, incident.w12, flux, params)
    model = _vertex_sum(*args, 0.0, False)
    keep = model > TOL_FLOOR * model.max(axis=0)
    rows = []
    for beyond in (5.0, 20.0):
        error = np.abs(_vertex_sum(*args, beyond, True) - model)[keep] / model[keep]
        rows.append(
            {"beyond_mm": beyond, "error_p50": float(np.median(error)), "error_p99": float(np.percentile(error, 99))}
        )
        print(rows[-1], flush=True)
    return rows


def table(payload) -> str:
    """The three measurements as Markdown tables."""
    lines = [
        "| block vertices | radius / distance | columns | rank at 1e-3 (median, max) | rank at 1e-4 (median, max) |"
    ]
    lines.append("|---:|---:|---:|---|---|")
    for r in payload["ranks"]:
        lines.append(
            f"| {r['vertices']} | {r['ratio']} | {r['dense_columns']} | {r['rank_1e-3'][0]}, {r['rank_1e-3'][1]} "
            f"| {r['rank_1e-4'][0]}, {r['rank_1e-4'][1]} |"
        )
    lines += ["", "| eta | eps | far blocks | dense sources per receiver | floats per receiver and channel "
              "| GB (float32) | mean rank | cross approximation (1 thread) | far share (median) "
              "| error p50 | error p99 |",
              "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]  # fmt: skip
    for r in payload["hierarchical"]:
        lines.append(
            f"| {r['eta']} | {r['eps']:g} | {r['far_blocks']:,} | {r['dense_sources_per_receiver']} "
            f"| {r['floats_per_receiver_and_channel']:,} | {r['gb_float32']} | {r['rank_mean']} "
            f"| {r['aca_seconds_one_thread']} s | {r['far_share_median']:.2%} | {r['error_p50']:.1e} "
            f"| {r['error_p99']:.1e} |"
        )
    lines += ["", "| eta | eps | row rank (mean) | column rank (mean) | coupling floats per receiver "
              "| basis floats per receiver | GB (float32) | skeletons | coupling | error p50 | error p99 |",
              "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]  # fmt: skip
    for r in payload["nested"]:
        lines.append(
            f"| {r['eta']} | {r['eps']:g} | {r['row_rank_mean']} | {r['column_rank_mean']} "
            f"| {r['coupling_floats_per_receiver']:,} | {r['basis_floats_per_receiver']:,} | {r['gb_float32']} "
            f"| {r['skeleton_seconds']} s | {r['coupling_seconds']} s | {r['error_p50']:.1e} | {r['error_p99']:.1e} |"
        )
    lines += ["", "| pairs beyond | per-vertex error p50 | p99 |", "|---:|---:|---:|"]
    for r in payload["point_sources"]:
        lines.append(f"| {r['beyond_mm']:g} mm | {r['error_p50']:.1%} | {r['error_p99']:.0%} |")
    return "\n".join(lines)


def main():
    mesh = load_default_scan()
    medium = resolve_medium("marble")
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta, "directional")
    dirs, pinv = fit_directions(medium.eta, AFFINE_TERMS)
    points = np.ascontiguousarray(mesh.points)
    normals = np.ascontiguousarray(mesh.vertex_normals())
    payload = {"info": {**machine_info(), "load_average_start": load_average(), "vertices": len(points)}}
    payload["ranks"] = ranks(points, normals, params, dirs, pinv)
    min_distance = 1.0 / float(np.min(medium.sigma_t_reduced))
    payload["hierarchical"] = [
        hierarchical(points, normals, params, dirs, pinv, min_distance, eta, eps)
        for eta, eps in ((0.5, 1e-3), (0.7, 1e-2))
    ]
    payload["nested"] = [nested(points, normals, params, dirs, pinv, min_distance, 0.5, 1e-3)]
    payload["point_sources"] = point_sources(Scene(mesh), medium, params)
    write_results(output_dir(False), "far_field_choice", payload, table(payload))


if __name__ == "__main__":
    main()
