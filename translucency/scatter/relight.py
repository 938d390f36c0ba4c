"""Relighting: ``B`` as fixed linear operators on the light that enters, prepared once per surface and material.

``B`` is linear in the flux ``Phi_i`` that enters at every source, and the directional dipole is affine in
the source's refracted direction ``w12`` once the real source's corrected distance ``d_r`` is held fixed
(docs/physics.md §8.7)::

    S_d(x_i, w12; x_o) = a_oi + b_oi . w12,    so    B_o = sum_i a_oi Phi_i + b_oi . Psi_i,   Psi_i = Phi_i w12_i

(``a`` per channel, ``b`` a 3-vector per channel; the radial models have ``b = 0``). The operators are the
solver's own sums written once with those coefficients instead of per light:

* **far field**: the ``tree`` walk of :mod:`translucency.scatter.hierarchy` with every vertex a source
  (any light may reach any vertex). A node accepted as a cluster is one source at a fixed anchor, the
  area-weighted mean position and normal of its vertices; per light its ``Phi`` and ``Psi`` are sums over
  its vertices, so the refracted directions need no averaging;
* **near field**: the correction of :mod:`translucency.scatter.nearfield` (its quadrature, with ``Psi``
  interpolated linearly like ``Phi``) as coefficients on the vertices of the near triangles
  (:func:`~translucency.scatter.nearfield.near_field_operator`), with those vertices' own pairs of the
  vertex sum: their far columns are 0, since the pair and the near triangles' vertex rule cancel and must
  be summed before they are rounded.

The real source's corrected distance ``d_r`` depends on ``w12`` too; the coefficients are least-squares
fits over the cone of refracted directions (:func:`~translucency.scatter.kernels.fitted_pairs`): affine in
the far field, quadratic near the receiver, where per vertex ``Xi = Phi w12 w12^T`` joins the inputs.
Per light: the inputs per vertex, ``Phi`` and ``Psi`` summed per node (bottom-up), and two sparse products
(:meth:`RelightOperator.apply`), whose cost is the operators' size. The clamp of ``S_d`` at 0 (§4.5) is
applied to ``B``, not per pair.

=========== ================================================================ ==============
symbol      meaning                                                          unit
=========== ================================================================ ==============
Phi         flux that enters at a vertex, ``phi A``                          W mm^2 / m^2
Psi         ``Phi w12``                                                      W mm^2 / m^2
Xi          ``Phi w12 w12^T`` (six components)                               W mm^2 / m^2
a, b        coefficients of ``S_d`` per unit ``Phi`` and ``Psi``             1/(mm^2 sr)
=========== ================================================================ ==============
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numba
import numpy as np

from ..threads import for_ranges, thread_count
from . import hierarchy, kernels, nearfield
from .kernels import AFFINE_TERMS, FIT_WORK_COLUMNS, QUADRATIC_TERMS, fitted_pairs

__all__ = ["RELIGHT_KERNELS", "RelightOperator", "prepare", "operator_bytes"]

#: Bytes per far-field entry per channel (four int16 and a power of two, :func:`_quantised`) and per
#: near-field entry per channel (ten float32), plus a column index (int32) per entry.
FAR_ENTRY_BYTES = 2 * AFFINE_TERMS + 1
NEAR_ENTRY_BYTES = 4 * QUADRATIC_TERMS
INDEX_BYTES = 4
#: Seconds per far-field entry and per near-field entry of the preparation on one thread: the rates of the time
#: estimate the budget compares against ``time_limit``, calibrated on timed preparations (bench/README.md,
#: "Relighting").
FAR_ENTRY_SECONDS = 9e-7
NEAR_ENTRY_SECONDS = 3e-5


@dataclass
class RelightOperator:
    """The prepared operators of one (surface, medium, model, tol): ``B = far . (Phi, Psi) + near . (Phi, Psi, Xi)``.

    Built by :func:`prepare` on the solver's spatially ordered surface; :meth:`apply` relights it.

    Attributes
    ----------
    key : tuple
        What the operators were made for: the medium's coefficients, model, tol.
    tree : SourceTree
        The hierarchy whose nodes are the far field's clusters.
    far_starts, far_counts : (n,) int64
        Receiver ``r``'s far columns are ``far_columns[far_starts[r] : far_starts[r] + far_counts[r]]``
        (vertices ``j < n``, node ``k`` as ``n + k``; the groups of four receivers share a list).
    far_columns : (E_group,) int32
    far_offsets : (n + 1,) int64
        Receiver ``r``'s rows of ``far_coefs`` start at ``far_offsets[r]``.
    far_coefs : (E, 4 C) int16
    far_exponents : (E, C) int8
        ``a, b0, b1, b2`` per channel, 1/(mm^2 sr) per unit flux, as ``far_coefs * 2**far_exponents``: each
        channel's four to 15 bits of its largest (:func:`_quantised`; 27 bytes an entry instead of 48).
    near_starts : (n + 1,) int64
    near_columns : (E_near,) int32
        Vertices of receiver ``r``'s near correction: ``near_columns[near_starts[r] : near_starts[r + 1]]``.
    near_coefs : (E_near, 10 C) float32
        The quadratic fit's ten coefficients per channel.
    stats : dict
        Entries, bytes, seconds of the preparation, theta.
    """

    key: tuple
    tree: hierarchy.SourceTree
    far_starts: np.ndarray
    far_counts: np.ndarray
    far_columns: np.ndarray
    far_offsets: np.ndarray
    far_coefs: np.ndarray
    far_exponents: np.ndarray
    near_starts: np.ndarray
    near_columns: np.ndarray
    near_coefs: np.ndarray
    stats: dict = field(default_factory=dict)

    @property
    def nbytes(self) -> int:
        """Memory the operators hold, bytes."""
        arrays = (
            self.far_starts,
            self.far_counts,
            self.far_columns,
            self.far_offsets,
            self.far_coefs,
            self.far_exponents,
            self.near_starts,
            self.near_columns,
            self.near_coefs,
        )
        return int(sum(a.nbytes for a in arrays))

    def apply(self, areas: np.ndarray, phi: np.ndarray, w12: np.ndarray) -> np.ndarray:
        """``B (n, C)`` for the flux density ``phi (n, C)`` (W/m^2) entering along the unit refracted
        directions ``w12 (n, 3)``, on the vertices (vertex areas ``areas``, mm^2) the operators were made on."""
        n, n_c = phi.shape
        flux = phi * areas[:, None]
        quadratic = np.stack(
            [
                w12[:, 0] ** 2,
                w12[:, 1] ** 2,
                w12[:, 2] ** 2,
                w12[:, 0] * w12[:, 1],
                w12[:, 0] * w12[:, 2],
                w12[:, 1] * w12[:, 2],
            ],
            axis=1,
        )
        near_values = np.empty((n, n_c, QUADRATIC_TERMS))
        near_values[:, :, 0] = flux
        near_values[:, :, 1:4] = flux[:, :, None] * w12[:, None, :]
        near_values[:, :, 4:] = flux[:, :, None] * quadratic[:, None, :]
        far_values = np.empty((n + self.tree.n_nodes, n_c * AFFINE_TERMS))
        far_values[:n] = near_values[:, :, :AFFINE_TERMS].reshape(n, -1)
        far_values[n:] = hierarchy.node_sums(self.tree, far_values[:n])
        B = np.zeros((n, n_c))
        for_ranges(
            _apply_quantised,
            n,
            self.far_starts,
            self.far_counts,
            self.far_columns,
            self.far_offsets,
            self.far_coefs,
            self.far_exponents,
            POWERS_OF_TWO,
            far_values,
            B,
        )
        near_counts = np.diff(self.near_starts)
        for_ranges(
            _apply_rows,
            n,
            self.near_starts[:-1],
            near_counts,
            self.near_columns,
            self.near_starts[:-1],
            self.near_coefs,
            np.ascontiguousarray(near_values.reshape(n, -1)),
            B,
        )
        return np.maximum(B, 0.0)


def operator_key(medium, model: str, tol: float) -> tuple:
    """What an operator depends on besides the surface: the medium's coefficients, the model, the tolerance."""
    return (
        medium.sigma_a.tobytes(),
        medium.sigma_s.tobytes(),
        medium.g.tobytes(),
        float(medium.eta),
        model,
        float(tol),
    )


#: theta = RELIGHT_THETA_PER_SQRT_TOL * sqrt(tol), lower than the ``tree``'s
#: :data:`~translucency.scatter.hierarchy.THETA_PER_SQRT_TOL`: an operator is made before the light is known, so
#: a cluster here is one source at a fixed anchor (the area-weighted mean of its vertices), not at the
#: flux-weighted mean where the ``tree`` puts it, and it is accurate to theta^2 only; with the ``tree``'s value
#: the per-vertex error that tol bounds goes over tol (bench/README.md, "Relighting").
RELIGHT_THETA_PER_SQRT_TOL = 0.6


def theta_and_distance(medium, tol: float) -> tuple[float, float]:
    """The far field's opening ratio (:data:`RELIGHT_THETA_PER_SQRT_TOL`) and smallest cluster distance (mm, the
    ``tree`` method's, §8.3)."""
    return hierarchy.opening(medium.sigma_t_reduced, tol, RELIGHT_THETA_PER_SQRT_TOL)


def operator_bytes(geometry, medium, tol: float, near_radius: float) -> tuple[float, dict]:
    """Memory (bytes) the operators of ``geometry`` (the spatially ordered surface) would take, counted
    before anything is made: the far field's lists by the tree walk, the near field's by the near
    triangles' corners; ``(bytes, counts)``."""
    n = geometry.n_vertices
    n_c = medium.n_channels
    tree = geometry.source_tree()
    theta, min_distance = theta_and_distance(medium, tol)
    counts = _walk_counts(tree, geometry.points, theta, min_distance)
    far_entries = int(counts[np.arange(n) // hierarchy.GROUP_RECEIVERS].sum())
    offsets, ids = geometry.near_lists(np.arange(n), near_radius)
    near_entries = int(nearfield.near_vertex_counts(geometry.triangles, np.arange(n), offsets, ids).sum())
    size = (
        far_entries * n_c * FAR_ENTRY_BYTES
        + int(counts.sum()) * INDEX_BYTES
        + near_entries * (n_c * NEAR_ENTRY_BYTES + INDEX_BYTES)
        + 40 * n
    )
    return float(size), {"far_entries": far_entries, "near_entries": near_entries, "theta": theta}


def _walk_counts(tree, points, theta, min_distance):
    """Entries of every group's far list (all vertices sources), without listing them."""
    n = points.shape[0]
    _, direct, clustered, _ = hierarchy.walk_lists(
        tree, np.ones(tree.n_nodes), np.ones(n, dtype=bool), points, theta, math.inf, min_distance, count_only=True
    )
    return direct + clustered


def prepare(
    geometry, medium, model: str, tol: float, near_radius: float, beta: float, progress=None
) -> RelightOperator:
    """The operators of ``geometry`` (the solver's spatially ordered surface, mm) for the medium (1/mm),
    model and tolerance: the far field's tree walk with every vertex a source and its fitted coefficients,
    and the near field's operator within ``near_radius`` (mm; quadrature refinement ratio ``beta``).

    ``progress(stage, fraction)`` is called with the stage ``"relight operators"``.
    """
    report = progress or (lambda stage, fraction: None)
    start = time.perf_counter()
    n = geometry.n_vertices
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta, model)
    model_code = kernels.MODELS[model]
    tree = geometry.source_tree()
    theta, min_distance = theta_and_distance(medium, tol)
    report("relight operators", 0.0)
    receivers = np.arange(n)
    offsets, ids = geometry.near_lists(receivers, near_radius)
    near_starts, near_columns, near_coefs = nearfield.near_field_operator(
        model_code,
        geometry.points,
        geometry.triangles,
        geometry.triangle_areas,
        geometry.normals,
        geometry.vertex_areas,
        receivers,
        offsets,
        ids,
        params,
        beta,
        float(np.min(medium.D)),
        kernels.fit_directions(medium.eta, QUADRATIC_TERMS),
        tables=geometry.triangle_tables(),
    )
    near_seconds = time.perf_counter() - start
    report("relight operators", 0.5)
    start = time.perf_counter()
    g_starts, g_direct, g_clustered, columns = hierarchy.walk_lists(
        tree, np.ones(tree.n_nodes), np.ones(n, dtype=bool), geometry.points, theta, math.inf, min_distance
    )
    group = np.arange(n) // hierarchy.GROUP_RECEIVERS
    far_counts = (g_direct + g_clustered)[group]
    far_starts = g_starts[group]
    far_offsets = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(far_counts, out=far_offsets[1:])
    table = anchors(tree, geometry.points, geometry.normals, geometry.vertex_areas)
    far_coefs = np.empty((int(far_offsets[-1]), AFFINE_TERMS * params.shape[0]), dtype=np.int16)
    far_exponents = np.empty((int(far_offsets[-1]), params.shape[0]), dtype=np.int8)
    dirs, pinv = kernels.fit_directions(medium.eta, AFFINE_TERMS)
    for_ranges(
        _fill_coefficients,
        n,
        model_code,
        table,
        geometry.points,
        geometry.normals,
        far_starts,
        far_counts,
        columns,
        far_offsets,
        params,
        dirs,
        pinv,
        far_coefs,
        far_exponents,
        near_starts,
        near_columns,
        near_coefs,
        np.full((thread_count(), 2 * n), -1, dtype=np.int64),
    )
    report("relight operators", 1.0)
    operator = RelightOperator(
        operator_key(medium, model, tol),
        tree,
        far_starts,
        far_counts,
        columns.astype(np.int32),
        far_offsets,
        far_coefs,
        far_exponents,
        near_starts,
        near_columns.astype(np.int32),
        near_coefs,
    )
    operator.stats = {
        "theta": theta,
        "cluster_min_distance_mm": min_distance,
        "far_entries": int(far_offsets[-1]),
        "near_entries": int(near_starts[-1]),
        "bytes": operator.nbytes,
        "seconds": {"far": time.perf_counter() - start, "near": near_seconds},
    }
    return operator


def anchors(tree, points, normals, areas):
    """Fixed source of every node of ``tree``: the area-weighted mean position (mm) and unit normal of its
    vertices, as a ``(6, n + nodes)`` table after the vertices' own (columns ``n + k``: node ``k``)."""
    _, _, position, normal, _ = hierarchy.aggregate(
        tree.order, tree.start, tree.end, tree.left, tree.right, points, normals, normals, areas[:, None]
    )
    return np.ascontiguousarray(np.concatenate([np.hstack([points, normals]), np.hstack([position, normal])]).T)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _fill_coefficients(
    worker,
    lo,
    hi,
    model,
    table,
    rcv_points,
    rcv_normals,
    starts,
    counts,
    columns,
    offsets,
    params,
    dirs,
    pinv,
    coefs,
    exponents,
    near_starts,
    near_columns,
    near_coefs,
    stamps,
):
    """Far-field coefficients of receivers ``lo .. hi - 1``: for each column of its list, the affine fit of
    :func:`~translucency.scatter.kernels.fitted_pairs` for every channel per unit ``Phi``, stored by
    :func:`_quantised`. A vertex of the receiver's near operator is held there whole: its far column is
    stored as 0, and where the walk put it inside a cluster instead, its affine fit is taken off its near row
    (the cluster holds it)."""
    n_c = params.shape[0]
    n = rcv_points.shape[0]
    scratch = np.empty((n_c, AFFINE_TERMS))
    work = np.empty((max(dirs.shape[0], 9), FIT_WORK_COLUMNS))
    owner = stamps[worker, :n]
    slot = stamps[worker, n:]
    held = np.zeros(64, dtype=np.bool_)
    for r in range(lo, hi):
        x0, x1, x2 = rcv_points[r, 0], rcv_points[r, 1], rcv_points[r, 2]
        n0, n1, n2 = rcv_normals[r, 0], rcv_normals[r, 1], rcv_normals[r, 2]
        first = near_starts[r]
        listed = near_starts[r + 1] - first
        if held.shape[0] < listed:
            held = np.zeros(2 * listed, dtype=np.bool_)
        for i in range(listed):
            owner[near_columns[first + i]] = r
            slot[near_columns[first + i]] = i
            held[i] = False
        at = offsets[r]
        for k in range(starts[r], starts[r] + counts[r]):
            j = columns[k]
            if j < n and owner[j] == r:
                held[slot[j]] = True
                coefs[at, :] = 0
                exponents[at, :] = -128
                at += 1
                continue
            _affine_at(model, table, j, x0, x1, x2, n0, n1, n2, params, dirs, pinv, work, scratch)
            for c in range(n_c):
                _quantised(scratch[c], coefs[at, c * AFFINE_TERMS : (c + 1) * AFFINE_TERMS], exponents[at], c)
            at += 1
        for i in range(listed):
            if held[i]:
                continue
            _affine_at(model, table, near_columns[first + i], x0, x1, x2, n0, n1, n2, params, dirs, pinv, work, scratch)
            for c in range(n_c):
                for t in range(AFFINE_TERMS):
                    near_coefs[first + i, c * QUADRATIC_TERMS + t] -= scratch[c, t]


@numba.njit(cache=True, inline="always")
def _affine_at(model, table, j, x0, x1, x2, n0, n1, n2, params, dirs, pinv, work, scratch):
    """The affine fit (``scratch (C, 4)``) of source column ``j`` of ``table`` for the receiver at ``x, n``."""
    fitted_pairs(
        model,
        x0 - table[0, j],
        x1 - table[1, j],
        x2 - table[2, j],
        table[3, j],
        table[4, j],
        table[5, j],
        n0,
        n1,
        n2,
        params,
        dirs,
        pinv,
        work,
        scratch,
    )


#: ``2**e`` for the exponents ``e = -128 .. 127`` of :func:`_quantised` (index ``e + 128``).
POWERS_OF_TWO = np.ldexp(1.0, np.arange(-128, 128))


@numba.njit(cache=True, inline="always")
def _quantised(values, q, exponents, c):
    """``values`` as ``q * 2**exponents[c]`` with ``q`` int16: the largest to 15 bits (relative 3e-5), the others
    to the same absolute step; a channel whose largest is below ``2**-113`` is stored as 0 (1/(mm^2 sr) per
    unit flux: nothing a light of any flux shows)."""
    largest = 0.0
    for v in values:
        largest = max(largest, abs(v))
    e = -128
    if largest > 0.0:
        e = max(-128, min(127, int(math.floor(math.log2(largest))) - 14))
    step = 2.0**e
    for t in range(values.shape[0]):
        q[t] = max(-32767, min(32767, int(round(values[t] / step)))) if largest > 0.0 else 0
    exponents[c] = e


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _apply_quantised(worker, lo, hi, starts, counts, columns, offsets, coefs, exponents, powers, values, out):
    """:func:`_apply_rows` on coefficients stored by :func:`_quantised` (four per channel)."""
    n_c = out.shape[1]
    total = np.zeros(n_c)
    for r in range(lo, hi):
        total[:] = 0.0
        at = offsets[r]
        first = starts[r]
        for k in range(counts[r]):
            row = coefs[at + k]
            exps = exponents[at + k]
            value = values[columns[first + k]]
            for c in range(n_c):
                base = c * AFFINE_TERMS
                s = (
                    row[base] * value[base]
                    + row[base + 1] * value[base + 1]
                    + row[base + 2] * value[base + 2]
                    + row[base + 3] * value[base + 3]
                )
                total[c] += powers[np.int64(exps[c]) + 128] * s
        for c in range(n_c):
            out[r, c] += total[c]


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _apply_rows(worker, lo, hi, starts, counts, columns, offsets, coefs, values, out):
    """``out[r, c] += sum_k coefs[offsets[r] + k, c] . values[columns[starts[r] + k], c]`` over ``k <
    counts[r]`` for receivers ``lo .. hi - 1`` (each channel's terms contiguous: ``a Phi + b . Psi (+ Q : Xi)``)."""
    n_c = out.shape[1]
    width = coefs.shape[1] // n_c
    total = np.zeros(n_c)
    for r in range(lo, hi):
        total[:] = 0.0
        at = offsets[r]
        first = starts[r]
        for k in range(counts[r]):
            row = coefs[at + k]
            value = values[columns[first + k]]
            for c in range(n_c):
                base = c * width
                s = 0.0
                for t in range(width):
                    s += row[base + t] * value[base + t]
                total[c] += s
        for c in range(n_c):
            out[r, c] += total[c]


#: The compiled kernels of the relighting operators' fill and products: numba compiles each on first use; the set-up
#: compiles them ahead
#: (:mod:`translucency.app.warmup`).
RELIGHT_KERNELS = (
    _fill_coefficients,
    _apply_quantised,
    _apply_rows,
)
