"""Relighting: ``B`` as fixed linear operators on the light that enters, prepared once per surface and material.

``B`` is linear in the flux ``Phi_i`` that enters at every source, and the directional dipole is affine in
the source's refracted direction ``w12`` once the real source's corrected distance ``d_r`` is held fixed
(docs/physics.md §8.7)::

    S_d(x_i, w12; x_o) = a_oi + b_oi . w12,    so    B_o = sum_i a_oi Phi_i + b_oi . Psi_i,   Psi_i = Phi_i w12_i

(``a`` per channel, ``b`` a 3-vector per channel; the radial models have ``b = 0``). The operators are the
solver's own sums written once with those coefficients instead of per light:

* **far field**: a hierarchical matrix over every vertex (:mod:`translucency.scatter.lowrank`): blocks between
  well-separated clusters as cross approximations to ``eps = tol / EPS_PER_TOL`` per receiver's row, the
  rest stored whole; its error is set by ``eps`` (the ranks), not by an opening ratio;
* **near field**: the correction of :mod:`translucency.scatter.nearfield` (its quadrature, with ``Psi``
  interpolated linearly like ``Phi``) as coefficients on the vertices of the near triangles
  (:func:`~translucency.scatter.nearfield.near_field_operator`), with those vertices' own pairs of the
  vertex sum: their far columns are 0, since the pair and the near triangles' vertex rule cancel and must
  be summed before they are rounded.

The real source's corrected distance ``d_r`` depends on ``w12`` too; the coefficients are least-squares
fits over the cone of refracted directions (:mod:`translucency.scatter.fits`): affine in
the far field, quadratic near the receiver, where per vertex ``Xi = Phi w12 w12^T`` joins the inputs.
Per light: the inputs per vertex, one pass over the far field's blocks and one sparse product
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

import contextlib
import contextvars
import threading
import time
from dataclasses import dataclass, field

import numba
import numpy as np

from ..threads import for_ranges
from . import crosses, cutoff, hierarchy, kernels, lowrank, nearfield
from .fits import AFFINE_TERMS, QUADRATIC_TERMS, fit_directions
from .hierarchy import SourceTree
from .surface import PerSurface

__all__ = [
    "AUTO_KEEP_SHARE",
    "FALLBACK_TOLS",
    "RELIGHT_KERNELS",
    "RelightOperator",
    "TreeInstead",
    "fallback_tols",
    "first_light_held_to",
    "prepare",
    "operator_bytes",
    "kept_operator",
    "keep_operator",
    "release_operator",
]

#: Bytes per near-field entry per channel (ten float32) plus its column index (int32); per entry of the far field's
#: dense blocks (float32), and per scale of a row of ``U`` (float32). The crosses are counted in bytes
#: (:func:`~translucency.scatter.crosses.sampled_count`).
NEAR_ENTRY_BYTES = 4 * QUADRATIC_TERMS
INDEX_BYTES = 4
DENSE_ENTRY_BYTES = 4
ROW_SCALE_BYTES = 4
#: The far field's cross approximations stop at ``eps = tol / EPS_PER_TOL`` of each receiver's row: the rows'
#: errors add over a receiver's far blocks, most where the far field is most of B (long diffusion lengths), and
#: the estimate that stops a cross approximation is not a bound (docs/physics.md §8.9; bench/README.md,
#: "Relighting").
EPS_PER_TOL = 6.0
#: Seconds of one fit the far field counts on one thread (the cross approximations' rows and columns,
#: :func:`~translucency.scatter.fits.fitted_run`, one channel, with their share of the crosses' own work), and per
#: near-field entry: the rates of the time estimate the budget compares against ``time_limit``, calibrated on
#: timed preparations of the default bunny in three materials at tol 0.1, 0.03 and 0.01, the horse and the Igea
#: (bench/README.md, "Relighting's budget"), with the fits counted by
#: :func:`~translucency.scatter.crosses.sampled_count`.
FIT_SECONDS = 1.2e-7
NEAR_ENTRY_SECONDS = 3.5e-6
#: What a preparation holds at its peak beyond its operators, as a share of them (its lists, each thread's
#: scratch, memory the allocator keeps), with room for the spread of the count of the crosses (bench/README.md,
#: "Relighting's budget").
PEAK_SHARE = 0.15


@dataclass
class RelightOperator:
    """The prepared operators of one (surface, medium, model, tol): ``B = far . (Phi, Psi) + near . (Phi, Psi, Xi)``.

    Built by :func:`prepare` on the solver's spatially ordered surface; :meth:`apply` relights it.

    Attributes
    ----------
    key : tuple
        What the operators were made for: the medium's coefficients, model, tol.
    far : FarMatrix or RelitFarField
        The far field (:mod:`translucency.scatter.lowrank`): ``a, b0, b1, b2`` per channel, 1/(mm^2 sr) per
        unit flux, applied to ``Phi, Psi``. The pairs the near field holds are 0 in its dense blocks; where a
        low-rank block holds one, the near row has that value taken off. On a GPU
        (:class:`translucency.scatter.gpu.pairs.RelitFarField`): every pair but the near field's, summed per light.
    near_starts : (n + 1,) int64
    near_columns : (E_near,) int32
        Vertices of receiver ``r``'s near correction: ``near_columns[near_starts[r] : near_starts[r + 1]]``.
    near_coefs : (E_near, 10 C) float32
        The quadratic fit's ten coefficients per channel.
    stats : dict
        Entries, bytes, seconds of the preparation, eps.
    scratch : dict
    scratch_lock : threading.Lock
        A light's arrays, kept between lights (:func:`~translucency.scatter.lowrank.kept_array`), and the lock a
        light holds while it uses them (a light that finds them in use by another thread makes its own).
    """

    key: tuple
    far: object
    near_starts: np.ndarray
    near_columns: np.ndarray
    near_coefs: np.ndarray
    stats: dict = field(default_factory=dict)
    scratch: dict = field(default_factory=dict, repr=False)
    scratch_lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    @property
    def nbytes(self) -> int:
        """Memory the operators hold, bytes."""
        return int(self.far.nbytes + sum(a.nbytes for a in (self.near_starts, self.near_columns, self.near_coefs)))

    def apply(self, areas: np.ndarray, phi: np.ndarray, w12: np.ndarray, light: dict | None = None) -> np.ndarray:
        """``B (n, C)`` for the flux density ``phi (n, C)`` (W/m^2) entering along the unit refracted
        directions ``w12 (n, 3)``, on the vertices (vertex areas ``areas``, mm^2) the operators were made on.
        ``light``, where given, receives this light's ``far_entries`` (the far field's entries it read, or on a GPU
        the pairs and clusters it evaluated) and ``pairs_skipped`` (lit sources times vertices, less those)."""
        light = {} if light is None else light
        if not self.scratch_lock.acquire(blocking=False):
            return self._applied(areas, phi, w12, {}, light)
        try:
            return self._applied(areas, phi, w12, self.scratch, light)
        finally:
            self.scratch_lock.release()

    def _applied(self, areas, phi, w12, scratch: dict, light: dict) -> np.ndarray:
        """:meth:`apply` with the arrays of ``scratch``."""
        n, n_c = phi.shape
        values = lowrank.kept_array(scratch, "values", (n, n_c * QUADRATIC_TERMS), np.float64)
        lit = lowrank.kept_array(scratch, "lit", (n,), np.bool_)
        _inputs(
            np.ascontiguousarray(areas, dtype=np.float64),
            np.ascontiguousarray(phi, dtype=np.float64),
            np.ascontiguousarray(w12, dtype=np.float64),
            values,
            lit,
        )
        if isinstance(self.far, lowrank.FarMatrix):
            B = self.far.apply(values.reshape(n, n_c, QUADRATIC_TERMS), scratch)
            light.update(far_entries=self.stats["far_entries"], pairs_skipped=0)  # every pair, as fitted
        else:  # the far field on a GPU: the light's own pairs, and the near field's product where it holds it
            B, evaluations = self.far.apply_light(w12, values, lit)
            light.update(far_entries=evaluations, pairs_skipped=max(0, int(lit.sum()) * n - evaluations))
            if self.far.holds_near:
                return np.maximum(B, 0.0)
        for_ranges(
            _apply_rows,
            n,
            self.near_starts[:-1],
            np.diff(self.near_starts),
            self.near_columns,
            self.near_starts[:-1],
            self.near_coefs,
            values,
            lit,
            B,
        )
        return np.maximum(B, 0.0)


@dataclass
class TreeInstead:
    """What a surface keeps in place of operators whose first light was :data:`FALLBACK_TOLS` ``tol`` or more off a
    ``tree`` solve of it (where the fits to the refracted direction of docs/physics.md §8.7 fail: an index of
    refraction of 1, a surface far smaller than a mean free path), or :data:`AUTO_KEEP_SHARE` ``tol`` under method
    ``auto`` (:func:`first_light_held_to`): the key they were made for and their statistics.
    Every light of that key is then solved by ``tree``; the operators' memory is given back.

    Attributes
    ----------
    key : tuple
        What the operators were made for (:func:`operator_key`).
    stats : dict
        Their statistics, with the first light's check (``checked_p99``, ...) and ``bytes`` 0.
    nbytes : int
        Memory held, bytes: none.
    """

    key: tuple
    stats: dict
    nbytes: int = 0


#: Operators whose first light is this many ``tol`` or more off ``tree`` at the 99th percentile are not kept: a
#: relit light is then solved by ``tree`` (:class:`TreeInstead`).
FALLBACK_TOLS = 10.0
#: Method ``auto`` keeps operators only where their first light is less than this share of ``tol`` off ``tree``
#: (:func:`first_light_held_to`): one light's check does not bound another's, and other lights of the same operators
#: were further off than the first where relighting's error is in its fits (bench/README.md, "Relighting"). It holds
#: ``tol`` where the other lights are at most ``1 / AUTO_KEEP_SHARE`` times as far off as the first.
AUTO_KEEP_SHARE = 0.75

_FALLBACK_TOLS = contextvars.ContextVar("relight_fallback_tols", default=FALLBACK_TOLS)


def fallback_tols() -> float:
    """How many ``tol`` off ``tree`` at the 99th percentile a fresh set of operators' first light may be before they
    are given up for :class:`TreeInstead`: :data:`FALLBACK_TOLS`, or what :func:`first_light_held_to` asks."""
    return _FALLBACK_TOLS.get()


@contextlib.contextmanager
def first_light_held_to(tols: float):
    """Within the ``with`` block (this thread or task only), operators prepared are kept only where their first light
    is less than ``tols`` ``tol`` off ``tree`` at the 99th percentile, and a :class:`TreeInstead` is kept in their
    place otherwise (method ``auto`` asks :data:`AUTO_KEEP_SHARE`: it holds ``tol``, docs/physics.md §8.10). A
    :class:`TreeInstead` kept under a stricter ask does not stand for a looser one: those operators are prepared
    again."""
    token = _FALLBACK_TOLS.set(float(tols))
    try:
        yield
    finally:
        _FALLBACK_TOLS.reset(token)


def operator_key(medium, model: str, tol: float, device: str = "cpu") -> tuple:
    """What an operator depends on besides the surface: the medium's coefficients, the model, the tolerance, and
    where its far field is summed (``cpu``: fitted and stored; ``gpu``: every pair per light)."""
    return (
        medium.sigma_a.tobytes(),
        medium.sigma_s.tobytes(),
        medium.g.tobytes(),
        float(medium.eta),
        model,
        float(tol),
        device,
    )


_OPERATORS = PerSurface("relighting operators", counted=False)


def kept_operator(surface, key: tuple | None = None) -> RelightOperator | TreeInstead | None:
    """The operators kept for ``surface`` (the solver's spatially ordered surface), or None (also where ``key``, of
    :func:`operator_key`, is given and they were made for another): relighting keeps one set per surface
    (:func:`translucency.scatter.solve.relight_operator` makes them)."""
    held = _OPERATORS.peek(surface, "operator")
    return None if held is None or (key is not None and held.key != key) else held


def keep_operator(surface, operator: RelightOperator | TreeInstead) -> None:
    """Keep ``operator`` for ``surface`` (instead of any set kept before)."""
    _OPERATORS.drop(surface)
    _OPERATORS.get(surface, "operator", lambda: operator)


def release_operator(surface) -> None:
    """Forget the operators kept for ``surface`` (their memory is freed when nothing else holds them)."""
    _OPERATORS.drop(surface)


def far_eps(tol: float) -> float:
    """The far field's relative error per receiver's row for the tolerance ``tol`` (:data:`EPS_PER_TOL`)."""
    return float(tol) / EPS_PER_TOL


def _block_tree(geometry) -> SourceTree:
    """The far field's block tree over the surface's vertices (leaves of :data:`lowrank.LEAF_SIZE`), kept with the
    surface."""
    return hierarchy.tree_of(geometry, lowrank.LEAF_SIZE)


def _gap(medium) -> float:
    """The smallest distance (mm) between the spheres of a far block: a reduced mean free path, the ``tree``'s
    smallest cluster distance (§8.3)."""
    return hierarchy.CLUSTER_MEAN_FREE_PATHS / float(np.min(medium.sigma_t_reduced))


def operator_bytes(
    geometry, medium, model: str, tol: float, near_radius: float, far_on_gpu: bool = False, within=None
) -> tuple[float, dict]:
    """Memory (bytes) the operators of ``geometry`` (the spatially ordered surface) would take, counted
    before they are made: the far field's dense blocks exactly, its crosses by finding those of a sample of its far
    blocks (:func:`~translucency.scatter.crosses.sampled_count`, which follows the medium, the model and ``tol``),
    the near field's lists by the near triangles' corners; ``(bytes, counts)``, the counts with the fits the far field
    would evaluate (none, and no far bytes, where the far field is summed on a GPU per light: ``far_on_gpu``).

    ``within(bytes, counts) -> bool``: the crosses of :data:`FIRST_BLOCKS` blocks are counted first, and where that
    count is not within it even at :data:`FIRST_UNDER` of itself, it is returned without the larger sample (on a large
    surface that sample takes seconds)."""
    n = geometry.n_vertices
    n_c = medium.n_channels
    offsets, ids = nearfield.lists_of(geometry, np.arange(n), near_radius)
    near_entries = int(nearfield.near_vertex_counts(geometry.triangles, np.arange(n), offsets, ids).sum())
    near_bytes = near_entries * (n_c * NEAR_ENTRY_BYTES + INDEX_BYTES) + 40 * n
    if far_on_gpu:
        return float(near_bytes), {"far_fits": 0.0, "near_entries": near_entries, "eps": 0.0}
    tree = _block_tree(geometry)
    far_pairs, dense_pairs = lowrank.partition(tree, _gap(medium))
    sizes = tree.end - tree.start
    whole = n_c * float(np.sum(sizes[dense_pairs[:, 0]] * sizes[dense_pairs[:, 1]]))  # pairs and channels
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta, model)
    fit = fit_directions(medium.eta, AFFINE_TERMS)

    def total(blocks):
        counted = crosses.sampled_count(
            kernels.MODELS[model],
            *(tree, geometry.points, geometry.normals, params, fit, far_eps(tol), far_pairs),
            lambda r: cutoff.pair_bound(medium, model, r),
            blocks=blocks,
        )
        size = near_bytes + (whole + counted["dense_entries"]) * AFFINE_TERMS * DENSE_ENTRY_BYTES
        size += counted["cross_bytes"] + counted["row_scales"] * ROW_SCALE_BYTES
        return float(size), {"far_fits": counted["fits"] + whole, "near_entries": near_entries, "eps": far_eps(tol)}

    if within is not None:
        first, first_counts = total(FIRST_BLOCKS)
        if not within(FIRST_UNDER * first, {**first_counts, "far_fits": FIRST_UNDER * first_counts["far_fits"]}):
            return first, first_counts
    return total(crosses.SAMPLED_BLOCKS)


#: Blocks whose crosses are counted first (:func:`operator_bytes`), and the share of that count a surface must be over
#: the budget at to be refused on it: the spread of a count of 48 blocks is about three times that of 384
#: (bench/README.md, "Relighting's budget").
FIRST_BLOCKS = 48
FIRST_UNDER = 0.75


def prepare(
    geometry,
    medium,
    model: str,
    tol: float,
    near_radius: float,
    beta: float,
    progress=None,
    far_on_gpu: bool = False,
    tree_far=None,
    degree3: dict | None = None,
) -> RelightOperator:
    """The operators of ``geometry`` (the solver's spatially ordered surface, mm) for the medium (1/mm),
    model and tolerance: the far field's hierarchical matrix over every vertex (fitted coefficients, cross
    approximations to :func:`far_eps`), or with ``far_on_gpu`` every pair summed per light on the GPU
    (:class:`~translucency.scatter.gpu.pairs.RelitFarField`), and the near field's operator within ``near_radius``
    (mm; quadrature refinement ratio ``beta``). ``tree_far(w12, flux) -> (B, evaluations)``: a light's far field by
    ``tree`` on the GPU, which a surface too large for every pair per light sums instead (:func:`_with_far_on_gpu`).

    ``progress(stage, fraction)`` is called with the stage ``"relight operators"``. ``degree3``: where the near field
    takes the degree-3 rule (:func:`~translucency.scatter.solve.degree3_rule`'s keywords; None: nowhere).
    """
    report = progress or (lambda stage, fraction: None)
    start = time.perf_counter()
    n = geometry.n_vertices
    n_c = medium.n_channels
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta, model)
    model_code = kernels.MODELS[model]
    report("relight operators", 0.0)
    receivers = np.arange(n)
    offsets, ids = nearfield.lists_of(geometry, receivers, near_radius)
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
        fit_directions(medium.eta, QUADRATIC_TERMS),
        tables=nearfield.tables_of(geometry),
        progress=lambda fraction: report("relight operators", 0.5 * fraction),
        **(degree3 or {}),
    )
    near_seconds = time.perf_counter() - start
    report("relight operators", 0.5)
    start = time.perf_counter()
    if far_on_gpu:
        return _with_far_on_gpu(
            geometry, medium, model, tol, params, (near_starts, near_columns, near_coefs), near_seconds, tree_far
        )
    far = lowrank.build(
        model_code,
        geometry.points,
        geometry.normals,
        params,
        fit_directions(medium.eta, AFFINE_TERMS),
        far_eps(tol),
        _gap(medium),
        lambda r: cutoff.pair_bound(medium, model, r),
        (near_starts, near_columns),
        tree=_block_tree(geometry),
        progress=lambda fraction: report("relight operators", 0.5 + 0.5 * fraction),
    )
    # a near vertex's own pair is held whole in the near field (§8.7): where a low-rank block holds it too, the
    # near row takes off what the block holds, so that the two cancel exactly as the product sums them
    far.take_low_rank_entries(near_starts, near_columns, near_coefs, QUADRATIC_TERMS)
    report("relight operators", 1.0)
    operator = RelightOperator(
        operator_key(medium, model, tol), far, near_starts, near_columns.astype(np.int32), near_coefs
    )
    operator.stats = {
        **{f"far_{key}": value for key, value in far.stats.items() if key != "bytes"},
        "far_entries": int((far.stats["far_floats"] + far.stats["dense_floats"]) // (AFFINE_TERMS * n_c)),
        "near_entries": int(near_starts[-1]),
        "bytes": operator.nbytes,
        "seconds": {"far": time.perf_counter() - start, "near": near_seconds},
    }
    return operator


def _with_far_on_gpu(geometry, medium, model, tol, params, near, near_seconds, tree_far) -> RelightOperator:
    """The operators of :func:`prepare` with the far field summed per light on the GPU: the near field's, and the
    lists of the pairs it holds given to the GPU's far field, which leaves them out. The far field is every pair of
    a light up to :data:`~translucency.scatter.gpu.pairs.ALL_PAIRS_UP_TO` pairs, ``tree_far`` beyond (where
    given)."""
    from .gpu.pairs import ALL_PAIRS_UP_TO, RelitFarField

    near_starts, near_columns, near_coefs = near
    n = geometry.n_vertices
    walked = tree_far is not None and float(n) * n > ALL_PAIRS_UP_TO
    far = RelitFarField(
        kernels.MODELS[model],
        geometry.points,
        geometry.normals,
        params,
        near_starts,
        near_columns,
        near_coefs,
        far_sum=tree_far if walked else None,
    )
    operator = RelightOperator(
        operator_key(medium, model, tol, "gpu"), far, near_starts, near_columns.astype(np.int32), near_coefs
    )
    operator.stats = {
        "far_entries": 0,  # per light (RelightOperator.apply)
        "far_on_gpu": "tree" if walked else "every pair",
        "near_entries": int(near_starts[-1]),
        "near_on_gpu": far.holds_near,
        "bytes": operator.nbytes,
        "seconds": {"far": 0.0, "near": near_seconds},
    }
    return operator


@numba.njit(cache=True, error_model="numpy")
def _inputs(areas, phi, w12, values, lit):
    """Per vertex and channel the ten inputs of the near field's quadratic fit, ``Phi, Psi (3), Xi (6)``
    (``Phi = phi A``, ``Psi = Phi w12``, ``Xi = Phi (w_x^2, w_y^2, w_z^2, w_x w_y, w_x w_z, w_y w_z)``; the far
    field reads the first four), written to ``values (n, C x 10)``, and to ``lit (n,)`` whether any channel's flux
    enters at the vertex."""
    n, n_c = phi.shape
    for i in range(n):
        x, y, z = w12[i, 0], w12[i, 1], w12[i, 2]
        terms = (1.0, x, y, z, x * x, y * y, z * z, x * y, x * z, y * z)
        lit[i] = False
        for c in range(n_c):
            flux = phi[i, c] * areas[i]
            lit[i] = lit[i] or flux != 0.0
            for t in range(QUADRATIC_TERMS):
                values[i, c * QUADRATIC_TERMS + t] = flux * terms[t]


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _apply_rows(worker, lo, hi, starts, counts, columns, offsets, coefs, values, lit, out):
    """``out[r, c] += sum_k coefs[offsets[r] + k, c] . values[columns[starts[r] + k], c]`` over ``k <
    counts[r]`` for receivers ``lo .. hi - 1`` (each channel's terms contiguous: ``a Phi + b . Psi (+ Q : Xi)``),
    the columns without light (``lit`` false) skipped."""
    n_c = out.shape[1]
    width = coefs.shape[1] // n_c
    terms = np.zeros(coefs.shape[1])  # every channel's terms summed apart, over the row's entries: one vector loop
    for r in range(lo, hi):
        terms[:] = 0.0
        at = offsets[r]
        first = starts[r]
        for k in range(counts[r]):
            column = columns[first + k]
            if not lit[column]:
                continue
            row = coefs[at + k]
            value = values[column]
            for t in range(terms.shape[0]):
                terms[t] += row[t] * value[t]
        for c in range(n_c):
            s = 0.0
            for t in range(c * width, (c + 1) * width):
                s += terms[t]
            out[r, c] += s


#: The compiled kernels of the relighting operators' fill and products: numba compiles each on first use; the set-up
#: compiles them ahead
#: (:mod:`translucency.app.warmup`).
RELIGHT_KERNELS = (_inputs, _apply_rows, *lowrank.LOW_RANK_KERNELS)
