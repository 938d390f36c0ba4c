"""The per-vertex solver: B(x_o) = integral of S_d(x, w12(x); x_o) phi(x) dA(x) at every receiver vertex.

``B`` is the diffuse radiance factor of DESIGN.md: outgoing radiance is ``L = T21(eta, w_o) B``.
It is computed as a sum over source vertices (the far field, by one of the methods below) plus a
near-field correction that integrates the triangles around each receiver with adaptive sub-vertex
quadrature (:mod:`translucency.scatter.nearfield`), so the answer is the surface integral and does
not depend on the tessellation.

Methods for the far field (each with a tolerance where it has one):

``exact``
    every (source, receiver) pair, numba-parallel, blocked; the reference.
``cutoff``
    pairs farther apart than a radius are skipped: first ``R(tol)``, where the tail of a
    geometry-independent bound of ``S_d`` holds less than ``tol`` of the total reflectance, then, for
    every receiver whose own ``B`` is too small for what ``R(tol)`` may drop, the radius that bound
    allows it (docs/physics.md §8.4).
``tree``
    a hierarchy over the sources (:mod:`translucency.scatter.hierarchy`): a cluster that is small
    seen from the receiver, farther than a reduced mean free path, and whose aggregate's error bound is
    small next to the receiver's own ``B`` (as a first, coarser walk estimates it), is replaced by one
    aggregated source (Jensen & Buhler 2002; the relative opening criterion, docs/physics.md §8.3). Nothing
    is skipped by distance: far clusters are cheap, and the far side of an object gets all its ``B`` from them.
``relight``
    the ``tree``'s sums and the near field written once as linear operators on the incident flux
    (:mod:`translucency.scatter.relight`, docs/physics.md §8.7), kept on the surface
    (:func:`relight_operator`) and applied to every later light: slow to prepare, then
    a sparse product per light.
``auto``
    ``tree`` here; over a surface's lights, :func:`translucency.scatter.transport.transport` turns it to
    ``relight`` once the lights have taken as long as preparing would (:mod:`translucency.scatter.method_choice`,
    docs/physics.md §8.10).

``tol`` bounds the relative error of ``B`` per receiver against ``exact`` at the 99th percentile over the
receivers whose ``B`` is at least :data:`TOL_FLOOR` of the largest in its channel (docs/physics.md §8.5).

Skipped work is reported in :attr:`Solution.stats`: sources with no flux, pairs beyond the cutoff or
inside accepted clusters, channels with identical coefficients (computed once).

========= ========================================================= ======================
symbol    meaning                                                   unit
========= ========================================================= ======================
phi       incident flux density after the boundary, T12 E cos V    W/m^2 (any flux/area)
A         barycentric vertex area                                   mm^2
Phi       source flux phi A                                         W mm^2 / m^2
S_d       diffusive BSSRDF                                          1/(mm^2 sr)
B         diffuse radiance factor sum S_d Phi (+ near field)        W/(m^2 sr)
========= ========================================================= ======================
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .. import memory
from ..errors import BudgetError, InvalidParameterError, option, warn_user
from . import budget, cutoff, hierarchy, kernels, nearfield
from .gpu.probe import pair_device
from .medium import CHANNELS, Medium
from .names import DEFAULT_DEVICE, DEFAULT_MODEL, METHODS, MODELS, check_device, check_method, check_model, check_tol
from .surface import SurfaceGeometry, checked_array, ordered_bytes, ordered_light, spatial_order
from .treewalk import GROUP_RECEIVERS

__all__ = ["SurfaceGeometry", "Solution", "solve", "local_reach_floor", "METHODS", "MODELS"]


#: ``tol`` bounds the relative error of ``B`` at every receiver whose ``B`` is at least TOL_FLOOR of the
#: largest in its channel (darker receivers: tol x TOL_FLOOR of that largest, absolute).
TOL_FLOOR = 1e-4
#: Near field: the triangles with a vertex within :func:`near_radius` of the receiver are integrated with sub-triangle
#: quadrature (:mod:`translucency.scatter.nearfield`); its reach in mean edges, in mean free paths, in diffusion
#: coefficients ``D``, and the share of ``tol`` the vertex rule may miss where it stops short of a mean free path.
NEAR_EDGES = 3.0
NEAR_MEAN_FREE_PATHS = 1.0
NEAR_ROUGH_PER_TOL = 1.0
NEAR_DIFFUSION_LENGTHS = 1.0
#: Refinement ratio of the adaptive quadrature (piece diameter over its distance to the receiver; also
#: the fan rule's radial scale, NEAR_BETA * D_min). A piece is accepted once it is this many times smaller
#: than its distance: a smaller ratio gives the same B with more pieces, a larger one accepts the piece that
#: holds the receiver before the peak of S_d there is resolved.
NEAR_BETA = 1.5
#: Whole triangles with diameter <= NEAR_DEGREE3_RATIO * distance get the degree-3 rule of shared points
#: instead of Dunavant's degree-5 rule (``cutoff`` and ``tree``; ``exact`` uses Dunavant's everywhere).
#: Beyond its diameter a triangle sees S_d vary slowly enough for degree 3, whose points are shared with
#: the neighbouring triangles; its error against degree 5 is well below the tolerances
#: (bench/README.md, "Kernel throughput").
NEAR_DEGREE3_RATIO = 1.0
#: ... and only for triangles no wider than NEAR_DEGREE3_DECAY / max sigma_tr: across a wider one S_d
#: changes by more than exp(NEAR_DEGREE3_DECAY) (docs/physics.md §8.2).
NEAR_DEGREE3_DECAY = 0.5


def degree3_rule(medium, method: str) -> dict:
    """Where the near field takes the degree-3 rule of shared points (:data:`NEAR_DEGREE3_RATIO`,
    :data:`NEAR_DEGREE3_DECAY`): ``degree3_ratio`` (0 for ``exact``: Dunavant's rule everywhere) and
    ``degree3_diameter`` (mm), the keywords of :func:`~translucency.scatter.nearfield.near_field_correction` and
    :func:`~translucency.scatter.nearfield.near_field_operator`."""
    return {
        "degree3_ratio": 0.0 if method == "exact" else NEAR_DEGREE3_RATIO,
        "degree3_diameter": NEAR_DEGREE3_DECAY / max(float(np.max(medium.sigma_tr)), 1e-300),
    }


@dataclass
class Solution:
    """What :func:`solve` returns.

    Attributes
    ----------
    B : (n_receivers, C) float64
        Diffuse radiance factor per receiver and channel, W/(m^2 sr) for phi in W/m^2.
    receivers : (n_receivers,) int64
        Vertex index of each row of ``B``.
    stats : dict
        What was computed and what was skipped (pairs, sources, channels, clamps, near-field points).
    timings : dict
        Seconds per stage.
    settings : dict
        Model, method, tolerance and the medium's description.
    """

    B: np.ndarray
    receivers: np.ndarray
    stats: dict
    timings: dict
    settings: dict


def _exact_far_field(model, geometry, medium, lit, w12, flux, params, channel_of, tol, device="cpu"):
    """Method ``exact``: every (lit source, receiver) pair, on the CPU or, where ``device`` is ``gpu``, on the GPU
    (:mod:`translucency.scatter.gpu.pairs`: the lit sources copied to the device once)."""
    model_code = kernels.MODELS[model]
    sources = (geometry.points[lit], geometry.normals[lit], w12[lit], flux[lit])
    if device == "gpu":
        from .gpu.pairs import PairSums

        summed = PairSums(model_code, *sources, params, channel_of)
    else:

        def summed(rcv_points, rcv_normals):
            return kernels.vertex_sum(model_code, *sources, rcv_points, rcv_normals, params, channel_of)

    def evaluate(rcv_points, rcv_normals):
        B, clamped = summed(rcv_points, rcv_normals)
        pairs = int(lit.size) * int(rcv_points.shape[0])
        return B, {"pairs_evaluated": pairs, "pairs_skipped": 0, "clamped_values": int(clamped.sum())}

    return evaluate


def _cutoff_far_field(model, geometry, medium, lit, w12, flux, params, channel_of, tol, reach=None):
    """Method ``cutoff``: pairs within the radius of :func:`translucency.scatter.cutoff.cutoff_radius`, or
    within ``reach`` (mm) when it is given (the local part of ``B``: no receiver's radius widened)."""
    radius = cutoff.cutoff_radius(medium, tol, model) if reach is None else float(reach)
    diagonal = geometry.diagonal
    if not radius < diagonal:  # the radius covers the object: every pair
        every_pair = _exact_far_field(model, geometry, medium, lit, w12, flux, params, channel_of, tol)

        def evaluate(rcv_points, rcv_normals):
            B, stats = every_pair(rcv_points, rcv_normals)
            return B, {**stats, "cutoff_radius_mm": radius}

        return evaluate
    model_code = kernels.MODELS[model]
    sources = (geometry.points[lit], geometry.normals[lit], w12[lit], flux[lit])
    total_flux = flux[lit].sum(axis=0)

    def within(r, rcv_points, rcv_normals):
        if not r < diagonal:
            B, _ = kernels.vertex_sum(model_code, *sources, rcv_points, rcv_normals, params, channel_of)
            return B, np.full(rcv_points.shape[0], lit.size, dtype=np.int64)
        grid = cutoff.grid_of(geometry, lit, r)
        return cutoff.cutoff_sum(
            model_code,
            grid.order,
            grid.start,
            grid.origin,
            grid.cell,
            grid.dims,
            r,
            *sources,
            rcv_points,
            rcv_normals,
            params,
            channel_of,
        )

    def evaluate(rcv_points, rcv_normals):
        B, evaluated = within(radius, rcv_points, rcv_normals)
        widened = 0
        if reach is None:  # receivers whose own B is too small for what the radius may skip get a larger one (§8.4)
            radii = cutoff.receiver_radii(medium, model, tol, B, total_flux, radius, diagonal, TOL_FLOOR)
            for r in np.unique(radii[radii > radius]):
                these = np.flatnonzero(radii == r)
                B[these], evaluated[these] = within(float(r), rcv_points[these], rcv_normals[these])
            widened = int(np.count_nonzero(radii > radius))
        pairs = int(lit.size) * int(rcv_points.shape[0])
        return B, {
            "cutoff_radius_mm": radius,
            "receivers_widened": widened,
            "pairs_evaluated": int(evaluated.sum()),
            "pairs_skipped": pairs - int(evaluated.sum()),
        }

    return evaluate


def _tree_far_field(model, geometry, medium, lit, w12, flux, params, channel_of, tol, device="cpu"):
    """Method ``tree``: clusters whose aggregate errs little next to the receiver's ``B`` replaced by their
    aggregated source (docs/physics.md §8.3), the tree walked and summed on the CPU or, where ``device`` is ``gpu``,
    on the GPU (:mod:`translucency.scatter.gpu.tree`). The aggregates and the allowance's floor (:data:`TOL_FLOOR`
    of the largest first estimate at the most brightly lit vertices) are made once here, for every block of
    receivers (relighting's far field on a GPU calls it per light: :func:`_tree_per_light`). Returns
    ``evaluate(rcv_points mm, rcv_normals) -> (B (n_rcv, C), statistics)``; ``lit`` (the vertices with flux) counts
    the pairs it skipped."""
    model_code = kernels.MODELS[model]
    tree = hierarchy.tree_of(geometry)
    rule = hierarchy.opening(medium, model, tol)
    sources = hierarchy.aggregated_sources(tree, geometry.points, geometry.normals, w12, flux)
    if device == "gpu":
        from .gpu.tree import WalkedSums as walk
    else:
        walk = hierarchy.ListedWalk
    walked = walk(model_code, tree, sources, params, channel_of, rule)
    floor = _allowance_floor(
        geometry,
        flux,
        lambda bright: hierarchy.first_estimate(walked, geometry.points[bright], geometry.normals[bright]),
    )

    def evaluate(rcv_points, rcv_normals):
        B, direct, clustered = hierarchy.tree_sum(walked, rcv_points, rcv_normals, floor)
        pairs = int(lit.size) * int(rcv_points.shape[0])
        return B, {
            "theta": rule.theta,
            "eps": rule.eps,
            "cluster_min_distance_mm": rule.min_distance,
            "tree_nodes": tree.n_nodes,
            "pairs_evaluated": int(direct.sum() + clustered.sum()),
            "pairs_direct": int(direct.sum()),
            "cluster_evaluations": int(clustered.sum()),
            "pairs_skipped": max(pairs - int(direct.sum()), 0),
        }

    return evaluate


def _allowance_floor(geometry, flux, estimate) -> np.ndarray:
    """The least ``B`` (per channel, W/(m^2 sr)) the tree's allowance assumes: :data:`TOL_FLOOR` of the largest
    first estimate (``estimate(vertices)``) at the vertices with the most incident flux density, which do not
    depend on the receivers asked for, so a block of receivers solved alone gets the same ``B``."""
    bright = hierarchy.brightest(flux, geometry.vertex_areas)
    return TOL_FLOOR * np.max(estimate(bright), axis=0)


#: Each method prepares once per solve what does not depend on the receivers and returns a function
#: ``(receiver points mm, receiver normals) -> (B, statistics)`` called on every block of receivers.
_FAR_FIELD = {"exact": _exact_far_field, "cutoff": _cutoff_far_field, "tree": _tree_far_field}


#: Reduced albedo below which the diffusion models are outside their range (README, "Models"): a solve
#: warns once per material and process (:func:`warn_low_albedo`).
LOW_ALBEDO = 0.5
#: The warnings about a material's range already given in this process, by (kind, material, size).
_WARNED: set = set()


def _warn_channels(kind: str, medium: Medium, channels, values, text: str, size_mm: float | None = None) -> None:
    """Once per ``kind``, material (name and coefficients) and object size per process: a
    :class:`~translucency.errors.TranslucencyWarning` ``text`` with ``{which}`` replaced by the named ``channels``
    and their ``values`` (formatted text)."""
    key = (kind, medium.name, medium.sigma_a.tobytes(), medium.sigma_s.tobytes(), medium.g.tobytes(), size_mm)
    if not len(channels) or key in _WARNED:
        return
    _WARNED.add(key)
    names = CHANNELS if medium.n_channels == len(CHANNELS) else [f"channel {c}" for c in range(medium.n_channels)]
    which = ", ".join(f"{names[c]} {values[c]}" for c in channels)
    warn_user(text.format(which=which))


def _shown_below(value: float, limit: float) -> str:
    """``value`` with as few significant digits as keep it visibly below ``limit`` (0.4996 as "0.4996", not "0.5")."""
    for digits in (2, 3, 4, 6):
        text = f"{value:.{digits}g}"
        if float(text) < limit:
            return text
    return repr(float(value))


def warn_low_albedo(medium: Medium) -> None:
    """A :class:`~translucency.errors.TranslucencyWarning` (one sentence, once per material per process)
    when a channel's reduced albedo is below :data:`LOW_ALBEDO`."""
    _warn_channels(
        "low albedo",
        medium,
        np.flatnonzero(medium.alpha_reduced < LOW_ALBEDO),
        [_shown_below(value, LOW_ALBEDO) for value in medium.alpha_reduced],
        f"{medium.name}: reduced albedo below {LOW_ALBEDO} ({{which}}), where the diffusion models are outside "
        "their range; treat its subsurface light there as a rough estimate.",
    )


def warn_transparent(medium: Medium, size_mm: float) -> None:
    """A :class:`~translucency.errors.TranslucencyWarning` (once per material and size per process) when a
    channel's reduced mean free path ``1 / sigma_t'`` is longer than the object (``size_mm``, its bounding box's
    diagonal): light then crosses it without diffusing, and the diffusion models' ``B`` means little."""
    _warn_channels(
        "transparent",
        medium,
        np.flatnonzero(medium.mean_free_path > size_mm),
        [f"{value:.3g} mm" for value in medium.mean_free_path],
        f"{medium.name}: a mean free path longer than the object ({{which}}; the object is {size_mm:.3g} mm "
        "across): light crosses it without diffusing, and the diffusion models' answer means little; trace it "
        "instead (translucency reference).",
        round(size_mm, 6),
    )


def unique_channels(medium: Medium):
    """Distinct coefficient sets of the medium's channels: ``(rows, channel_of)`` (identical channels once)."""
    table = np.stack([medium.sigma_a, medium.sigma_s, medium.g], axis=1)
    rows, channel_of = np.unique(table, axis=0, return_inverse=True)
    return rows, channel_of.astype(np.int64).ravel()


def near_radius(geometry: SurfaceGeometry, medium: Medium, tol: float | None = None) -> float:
    """Radius (mm) inside which triangles get the near-field quadrature (docs/physics.md §8.2).

    ``NEAR_EDGES`` mean edges ``h``, and at least ``NEAR_MEAN_FREE_PATHS / min sigma_t'`` for ``exact`` and
    relighting (``tol`` None: relighting's far field fits each pair in the refracted direction, which nearer pairs
    do not follow, docs/physics.md §8.7) and for ``tree`` and ``cutoff`` where the vertex rule's relative error on
    the largest triangle, about ``(L sigma_tr)^2`` with ``L`` the longest edge for a channel that decays as
    ``exp(-sigma_tr r)``, may reach ``NEAR_ROUGH_PER_TOL * tol``. On a mesh fine for every channel's decay, at least
    ``NEAR_DIFFUSION_LENGTHS * max D`` (nearer than ``D`` the directional dipole follows the angles between the
    normals and the refracted direction, which the vertex rule does not resolve) and ``L`` (a triangle larger than
    the mesh's others is listed by the receivers beside it), and never beyond the mean free path."""
    edges = NEAR_EDGES * geometry.mean_edge_length
    mean_free_path = NEAR_MEAN_FREE_PATHS / float(np.min(medium.sigma_t_reduced))
    roughness = (geometry.longest_edge * float(np.max(medium.sigma_tr))) ** 2
    if tol is not None and roughness <= NEAR_ROUGH_PER_TOL * float(tol):
        short = max(NEAR_DIFFUSION_LENGTHS * float(np.max(medium.D)), geometry.longest_edge)
        return max(edges, min(short, mean_free_path))
    return max(edges, mean_free_path)


def solve(
    geometry: SurfaceGeometry,
    phi: np.ndarray,
    w12: np.ndarray,
    medium: Medium,
    *,
    model: str = DEFAULT_MODEL,
    method: str = "exact",
    tol: float = 1e-3,
    receivers: np.ndarray | None = None,
    reach_mm: float | None = None,
    device: str = DEFAULT_DEVICE,
    progress: Callable[[str, float], None] | None = None,
    memory_limit: float | None = None,
    time_limit: float | None = None,
) -> Solution:
    """Diffuse radiance factor ``B`` at the receiver vertices (DESIGN.md; docs/physics.md §5.3, integrated as in §8).

    This is the low-level reference: its own defaults are ``method="exact"`` and ``tol=1e-3``, not
    the shading defaults of :mod:`translucency.scatter.names` (``auto``, 1e-2) that
    :class:`~translucency.app.shading.settings.ShadeSettings` and the pipeline use. The steps: the inputs are
    checked, moved onto the spatially ordered surface, the memory and time of the solve are estimated
    against the budget, then the far field (``method``) and the near-field correction are summed and
    clamped at 0.

    Parameters
    ----------
    geometry : SurfaceGeometry
        The mesh (mm) with outward unit vertex normals.
    phi : (n, C) array_like
        Incident flux density per vertex and channel after the boundary: ``T12 E cos(theta) V``
        (W/m^2, or any flux per area unit; ``B`` comes out in the same unit per sr). ``C`` must equal
        the medium's channel count.
    w12 : (n, 3) array_like
        Refracted direction of the incident light at each vertex (unit, into the medium);
        ignored where ``phi`` is 0.
    medium : Medium
        Coefficients in 1/mm.
    model : {"directional", "standard", "better"}
        The BSSRDF (FHK14, Jensen 2001, d'Eon 2012).
    method : {"exact", "cutoff", "tree", "relight", "auto"}
        How the far field is summed (module docstring); ``exact`` by default (the reference). ``auto`` is ``tree``
        here (it turns to relighting over a surface's lights: :mod:`translucency.scatter.method_choice`).
    tol : float
        Relative error of ``B`` allowed per receiver against ``exact`` (``cutoff``, ``tree``, ``relight``;
        docs/physics.md §8.5: at the 99th percentile over the receivers whose ``B`` is at least :data:`TOL_FLOOR` of the
        largest in its channel), in (0, 1); ignored by ``exact``; 1e-3 by default.
    receivers : array_like of int, optional
        Vertices to compute ``B`` at (all by default).
    reach_mm : float, optional
        With ``method="cutoff"`` only: the local part of ``B``, from the sources within this distance (mm)
        of each receiver, with no receiver's radius widened (docs/physics.md §8.8; what a proxy solve
        corrects at full resolution). At least :func:`local_reach_floor` (the near-field radius plus the
        longest edge, so that every vertex the near field weighs is in the sum).
    device : {"auto", "cpu", "gpu"}
        Where ``exact`` and ``tree`` sum their pairs, and relighting its far field (``gpu.probe.pair_device``).
    progress : callable, optional
        Called as ``progress(stage, fraction)`` while the solver runs: stages ``far field`` and
        ``near field``, each from 0 to 1, many times per stage (after every block of receivers).
    memory_limit : float, optional
        GB (2**30 bytes) the process may hold; the solve's memory budget is the smaller of this (less
        what the process holds already) and the available memory less head-room
        (:func:`translucency.scatter.budget.memory_budget`).
    time_limit : float, optional
        Seconds the solve may take (by the estimate; None: no limit).

    Returns
    -------
    Solution

    Raises
    ------
    BudgetError
        Before any large allocation, when the estimated memory or time
        (:func:`translucency.scatter.budget.estimate`) is over its budget.
    """
    timings: dict[str, float] = {}
    stats: dict[str, object] = {}
    report, limits = progress or (lambda stage, fraction: None), (memory_limit, time_limit)
    method = _one_light_method(method)
    phi, w12, receivers = _checked_inputs(geometry, phi, w12, medium, model, method, tol, receivers, *limits)
    _check_reach(reach_mm, method, tol, geometry, medium)
    warn_low_albedo(medium)
    warn_transparent(medium, geometry.diagonal)
    used_device, stats["device"] = pair_device(check_device(device), "cutoff" if reach_mm is not None else method)

    start = time.perf_counter()
    memory_at_start = _memory_at_start(geometry)
    work = _ordered_work(geometry, phi, w12, medium, model, receivers, stats)
    work.reach, work.device = reach_mm, used_device
    timings["setup"] = time.perf_counter() - start
    if method == "relight":
        return _relit(work, receivers, tol, memory_limit, time_limit, report, stats, timings)

    start = time.perf_counter()
    plan, near_args, radius, far_field = _plan(work, method, tol, memory_limit, time_limit, stats, memory_at_start)
    timings["budget"] = time.perf_counter() - start
    if not plan.fits:
        raise BudgetError(over_budget_sentence(plan, geometry.n_vertices), plan)

    report("far field", 0.0)
    start = time.perf_counter()
    B, far_stats = _far_field(work, far_field, method, tol, report)
    stats.update(far_stats)
    timings["far_field"] = time.perf_counter() - start
    report("far field", 1.0)

    report("near field", 0.0)
    start = time.perf_counter()
    correction, near_triangles, near_points, list_seconds = _near_field(near_args, work.inner, radius, plan, report)
    stats["near_radius_mm"] = radius
    stats["near_triangles"] = near_triangles
    stats["near_points"] = near_points
    stats["near_lists_kept"] = plan.keep_lists
    B = _assembled(B, correction, work.visit, stats)
    timings["near_lists"] = list_seconds
    timings["near_field"] = time.perf_counter() - start - list_seconds
    report("near field", 1.0)
    settings = {"model": model, "method": method, "tol": tol, "medium": medium.describe()}
    return Solution(B=B, receivers=receivers, stats=stats, timings=timings, settings=settings)


def plan(
    geometry: SurfaceGeometry,
    phi: np.ndarray,
    w12: np.ndarray,
    medium: Medium,
    *,
    model: str = DEFAULT_MODEL,
    method: str = "exact",
    tol: float = 1e-3,
    device: str = DEFAULT_DEVICE,
    memory_limit: float | None = None,
    time_limit: float | None = None,
) -> budget.SolveEstimate:
    """The plan :func:`solve` makes before it starts (its memory and time against the budgets, from the same
    sample), for these arguments, without solving. The spatially ordered surface and the source tree it makes
    stay cached on ``geometry``, so a solve that follows does not make them again. Not for ``method="relight"``,
    whose operators are planned by :func:`relight_operator`.

    The arguments are :func:`solve`'s: ``phi`` (n, C) W/m², ``w12`` (n, 3) unit, ``tol`` relative, ``device``,
    ``memory_limit`` GB (2**30 bytes) and ``time_limit`` s (None: no limit). Returns the
    :class:`~translucency.scatter.budget.SolveEstimate` (``fits``, ``seconds``, ``peak_bytes``, ...)."""
    if method == "relight":
        raise InvalidParameterError(
            "plan() estimates the solves of exact, cutoff and tree; relight plans its operators."
        )
    method = _one_light_method(method)
    phi, w12, receivers = _checked_inputs(
        geometry, phi, w12, medium, model, method, tol, None, memory_limit, time_limit
    )
    memory_at_start = _memory_at_start(geometry)
    work = _ordered_work(geometry, phi, w12, medium, model, receivers, {})
    work.device, _ = pair_device(check_device(device), method)
    estimate, *_ = _plan(work, method, tol, memory_limit, time_limit, {}, memory_at_start)
    return estimate


def _memory_at_start(geometry: SurfaceGeometry) -> tuple[float | None, float]:
    """``(available, resident)`` bytes before a solve allocates anything. The plan's base counts the ordered copy,
    the tree and the sample's grid, so the budget is measured before they are made, and where an earlier plan or
    solve made them already (:func:`~translucency.scatter.surface.ordered_bytes`), as if they were not held (they
    were counted twice: a solve after :func:`plan`, or a viewer's next one, had a smaller budget than the first)."""
    held = ordered_bytes(geometry)
    available = memory.available_memory()
    return (None if available is None else available + held), memory.resident_memory() - held


def relight_operator(
    geometry: SurfaceGeometry, medium, model, tol, *, device="cpu", memory_limit=None, time_limit=None, progress=None
):
    """The relighting operators of ``geometry`` (the spatially ordered surface) for the medium, model and ``tol``
    (:func:`translucency.scatter.relight.prepare`; their far field summed per light on the GPU where ``device`` is
    ``gpu``): ``(operator, reused)``, the operator a
    :class:`~translucency.scatter.relight.TreeInstead` where a first light found them far off. Relighting keeps one
    set per surface (:func:`translucency.scatter.relight.kept_operator`): another medium, model or ``tol`` replaces
    it (its memory is freed before the new one is made).

    Raises :class:`~translucency.errors.BudgetError` before preparing when the operators' memory
    (counted by :func:`~translucency.scatter.relight.operator_bytes`) or time is over budget."""
    from . import relight

    held = relight.kept_operator(geometry, relight.operator_key(medium, model, tol, device))
    given_up = isinstance(held, relight.TreeInstead)
    if held is not None and (not given_up or held.stats["checked_p99"] >= relight.fallback_tols() * tol):
        return held, True
    relight.release_operator(geometry)
    plan, counts = relight_estimate(geometry, medium, model, tol, device, memory_limit, time_limit)
    if not plan.fits:
        raise BudgetError(over_budget_sentence(plan, geometry.n_vertices), plan)
    tree_far = _tree_per_light(geometry, medium, model, tol) if device == "gpu" else None
    radius = near_radius(geometry, medium)  # a mean free path: the far field's fits in the direction need it
    operator = relight.prepare(
        geometry,
        medium,
        model,
        tol,
        radius,
        NEAR_BETA,
        progress,
        far_on_gpu=device == "gpu",
        tree_far=tree_far,
        degree3=degree3_rule(medium, "relight"),
    )
    operator.stats["budget"] = {**plan.as_dict(), "counts": counts}
    relight.keep_operator(geometry, operator)
    return operator, False


def relight_estimate(geometry: SurfaceGeometry, medium, model, tol, device="cpu", memory_limit=None, time_limit=None):
    """The plan of preparing relighting's operators of ``geometry`` (the spatially ordered surface) for the medium,
    model and ``tol``, against ``memory_limit`` (GB) and ``time_limit`` (s), before anything is prepared: ``(plan,
    counts)``, the :class:`~translucency.scatter.budget.SolveEstimate` (``seconds``, ``peak_bytes``, ``fits``) and the
    counts behind it (the far field's fits, the near field's entries; :func:`relight.operator_bytes`,
    :func:`relight_plan`). ``device`` is where the far field would be summed (``cpu`` or ``gpu``)."""
    from . import relight

    radius = near_radius(geometry, medium)  # a mean free path: the far field's fits in the direction need it
    size, counts = relight.operator_bytes(
        geometry,
        medium,
        model,
        tol,
        radius,
        far_on_gpu=device == "gpu",
        within=lambda size, counted: relight_plan(size, counted, memory_limit, time_limit).fits,
    )
    return relight_plan(size, counts, memory_limit, time_limit), counts


def _tree_per_light(geometry, medium, model, tol):
    """``tree_far(w12, flux) -> (B (n, C), evaluations)``: a light's far field at every vertex of ``geometry`` by
    ``tree`` at ``tol`` on the GPU (:func:`_tree_far_field`; ``flux = phi A (n, C)``, every channel of ``medium``),
    which relighting sums per light where every pair would be too many (:mod:`translucency.scatter.relight`)."""
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta, model)
    channel_of = np.arange(medium.n_channels)

    def tree_far(w12, flux):
        lit = np.flatnonzero(flux.max(axis=1) > 0)
        evaluate = _tree_far_field(model, geometry, medium, lit, w12, flux, params, channel_of, tol, device="gpu")
        B, far_stats = evaluate(geometry.points, geometry.normals)
        return B, far_stats["pairs_evaluated"]

    return tree_far


def _relit(work, receivers, tol, memory_limit, time_limit, report, stats, timings) -> Solution:
    """Method ``relight``: the surface's prepared operators (made on first use, kept for later calls with the
    same medium, model and ``tol``) applied to this light; nothing is prepared when no light enters. Operators whose
    first light is far off ``tree`` are not kept, and that light and every later one are solved by ``tree``
    (:class:`~translucency.scatter.relight.TreeInstead`)."""
    from . import relight

    settings = {"model": work.model, "method": "relight", "tol": tol, "medium": work.medium.describe()}
    stats["pairs_skipped"] = 0
    if work.lit.size == 0:
        stats["pairs_evaluated"] = 0
        held = relight.kept_operator(work.geometry, relight.operator_key(work.medium, work.model, tol, work.device))
        if isinstance(held, relight.TreeInstead):
            stats["relight_fallback"] = "tree"
        return Solution(np.zeros((work.inner.size, work.medium.n_channels)), receivers, stats, timings, settings)
    start = time.perf_counter()
    operator, reused = relight_operator(
        work.geometry,
        work.medium,
        work.model,
        tol,
        device=work.device,
        memory_limit=memory_limit,
        time_limit=time_limit,
        progress=report,
    )
    timings["prepare"] = 0.0 if reused else time.perf_counter() - start
    start = time.perf_counter()
    if isinstance(operator, relight.TreeInstead):
        solved = _tree_of(work, tol, memory_limit, time_limit, report)
        B = solved.B
        pairs = {"relight_fallback": "tree", **_far_stats(solved)}
    else:
        light = {}
        B = operator.apply(work.geometry.vertex_areas, work.phi, work.w12, light)[work.inner]
        pairs = {"pairs_evaluated": light["far_entries"] + operator.stats["near_entries"], **light}
    timings["apply"] = time.perf_counter() - start
    if not reused:  # the operators' first light, checked against a tree solve of it (once per preparation)
        start = time.perf_counter()
        checked = _tree_of(work, tol / RELIGHT_CHECK_TOL_FACTOR, None, None, None)
        operator.stats.update(_relight_error(B, checked.B, tol))
        timings["check"] = time.perf_counter() - start
        gave_way = operator.stats["checked_p99"] >= relight.fallback_tols() * tol
        if gave_way:  # the check's answer; nothing is kept
            operator.stats["bytes"] = 0
            relight.keep_operator(work.geometry, relight.TreeInstead(operator.key, dict(operator.stats)))
            B = checked.B
            pairs = {"relight_fallback": "tree", **_far_stats(checked)}
        _warn_relight_check(work.medium.name, operator.stats, tol, work.inner.size, gave_way)
    stats.update(operator.stats)
    stats.update(pairs)
    if "relight_fallback" in pairs:  # tree's near field ran on the CPU, its far field was tree's
        stats.pop("near_on_gpu", None)
        stats.pop("far_on_gpu", None)
    stats["operators_reused"] = reused
    B = _assembled(B, np.zeros_like(B), work.visit, stats)
    return Solution(B=B, receivers=receivers, stats=stats, timings=timings, settings=settings)


def _tree_of(work, tol, memory_limit, time_limit, progress) -> Solution:
    """``tree`` at ``tol`` for the light and receivers of ``work`` (rows in ``work.inner``'s order), on its device."""
    return solve(
        work.geometry,
        work.phi,
        work.w12,
        work.medium,
        model=work.model,
        method="tree",
        tol=tol,
        receivers=work.inner,
        progress=progress,
        memory_limit=memory_limit,
        time_limit=time_limit,
        device=work.device,
    )


def _far_stats(solved: Solution) -> dict:
    """What a ``tree`` solve in relighting's place says of its far field: the pairs it evaluated and skipped, and
    where."""
    return {key: solved.stats[key] for key in ("pairs_evaluated", "pairs_skipped", "device")}


#: The check of freshly prepared relighting operators solves their first light by ``tree`` at ``tol`` over this.
RELIGHT_CHECK_TOL_FACTOR = 4.0
#: ... and says so when a vertex is more than this many ``tol`` off the tree's, even where the 99th percentile holds.
RELIGHT_OUTLIER_TOLS = 10.0


def _relight_error(B, reference, tol) -> dict:
    """``{"checked_p99", "checked_outliers", "checked_worst"}``: the per-vertex error (docs/physics.md §8.5) of relit
    ``B`` against ``reference`` (``tree`` at ``tol / RELIGHT_CHECK_TOL_FACTOR`` for the same light and receivers) at the
    99th percentile, how many vertices are more than :data:`RELIGHT_OUTLIER_TOLS` ``tol`` off it, and the largest
    error (below :data:`TOL_FLOOR` of the largest ``B``, relative to that floor)."""
    floor = TOL_FLOOR * reference.max(axis=0)
    keep = reference >= floor
    if not np.any(keep):
        return {"checked_p99": 0.0, "checked_outliers": 0, "checked_worst": 0.0}
    # relative to B, and below the floor relative to the floor (the absolute error tol allows there)
    relative = np.abs(B - reference) / np.maximum(reference, np.where(floor > 0, floor, 1.0))
    worst = relative.max(axis=1)
    return {
        "checked_p99": float(np.percentile(relative[keep], 99)),
        "checked_outliers": int(np.count_nonzero(worst > RELIGHT_OUTLIER_TOLS * tol)),
        "checked_worst": float(worst.max()),
    }


def _warn_relight_check(name: str, checked: dict, tol: float, vertices: int, gave_way: bool) -> None:
    """One sentence on the first light's check (:func:`_relight_error`) where it found what ``tol`` does not hold:
    the operators given up for ``tree`` (``gave_way``: :data:`~translucency.scatter.relight.FALLBACK_TOLS` ``tol`` off
    or more; nothing where method ``auto`` gave them up nearer, :func:`~translucency.scatter.relight.fallback_tols`),
    off at the 99th percentile (the direction fits of §8.7 follow ``S_d`` less closely for some materials, low
    albedo, than ``tol`` asks, and on large scans the far field's large blocks miss the darkest vertices, §8.9), or
    a few vertices far off while the percentile holds (where a scan's normals turn against each other within a mean
    free path)."""
    from .relight import FALLBACK_TOLS

    error = checked["checked_p99"]
    if gave_way and error < FALLBACK_TOLS * tol:  # method auto's own choice, which holds tol (its tally says so)
        return
    if gave_way:
        percent = f"{100 * error:,.0f}" if error >= 0.1 else f"{100 * error:.2g}"
        warn_user(
            f"{name}: the relighting operators are {percent} % off a tree solve of the first light at the "
            f"99th percentile, {FALLBACK_TOLS:g} times the tolerance of {100 * tol:.2g} % or more (their fit to the "
            "refracted direction, docs/physics.md §8.7, fails here: an index of refraction near 1, or a surface "
            "smaller than a mean free path); every light of this surface and material is solved by tree instead."
        )
    elif error > tol:
        warn_user(
            f"{name}: the relighting operators are {100 * error:.3g} % off a tree solve of the first light at the "
            f"99th percentile, over the tolerance of {100 * tol:.2g} % (their fit to the refracted direction, "
            "docs/physics.md §8.7, or their far field at dark vertices, §8.9); solve with method tree where that "
            "matters."
        )
    elif checked["checked_outliers"]:
        warn_user(
            f"{name}: the relighting operators are up to {100 * checked['checked_worst']:.0f} % off a tree solve of "
            f"the first light at {checked['checked_outliers']} of {vertices} vertices (their fit to the refracted "
            "direction misses where neighbouring normals turn against each other, as on a crumpled patch of a scan, "
            "docs/physics.md §8.7); solve with method tree where that matters."
        )


def relight_plan(size: float, counts: dict, memory_limit, time_limit) -> budget.SolveEstimate:
    """The budget plan of preparing relighting operators of ``size`` bytes (``counts``: the far field's fits and
    the near field's entries), whose peak is :data:`~translucency.scatter.relight.PEAK_SHARE` more."""
    import numba

    from .relight import FIT_SECONDS, NEAR_ENTRY_SECONDS, PEAK_SHARE

    threads = max(1, numba.get_num_threads())
    seconds = (counts["far_fits"] * FIT_SECONDS + counts["near_entries"] * NEAR_ENTRY_SECONDS) / threads
    budget_bytes = budget.memory_budget(memory_limit, memory.available_memory(), memory.resident_memory())
    peak = (1.0 + PEAK_SHARE) * size
    fits = (budget_bytes is None or peak <= budget_bytes) and (time_limit is None or seconds <= time_limit)
    return budget.SolveEstimate(
        base_bytes=0.0,
        far_bytes=size,
        lists_bytes=0.0,
        receiver_bytes=0.0,
        keep_lists=True,
        block_receivers=0,
        block_bytes=0.0,
        own_points=0.0,
        peak_bytes=peak,
        seconds=seconds,
        budget_bytes=budget_bytes,
        time_limit=time_limit,
        fits=fits,
    )


def size_floor_plan(geometry: SurfaceGeometry, n_channels: int, method: str, memory_limit, time_limit):
    """:func:`translucency.scatter.budget.size_floor` of a solve at every vertex of ``geometry``: when it does
    not fit, no solve of that size does (checked before the incident light and the solve's set-up are paid for
    at a size that cannot be solved)."""
    import numba

    counts = budget.SolveCounts(
        n_vertices=geometry.n_vertices,
        n_triangles=len(geometry.triangles),
        n_receivers=geometry.n_vertices,
        n_lit=0,
        n_channels=int(n_channels),
        threads=max(1, numba.get_num_threads()),
        method="exact" if method == "relight" else _one_light_method(method),
        near_triangles=0.0,
        near_points=0.0,
        own_points=0.0,
        far_evaluations=0.0,
    )
    budget_bytes = budget.memory_budget(memory_limit, memory.available_memory(), memory.resident_memory())
    return budget.size_floor(counts, budget_bytes, time_limit)


def _one_light_method(method: str) -> str:
    """``tree`` for ``auto``, any other method as it is: a solve sees one light, and ``auto`` changes to relighting
    only over a surface's lights (:mod:`translucency.scatter.method_choice`, through
    :func:`translucency.scatter.transport.transport`)."""
    return "tree" if method == "auto" else method


def _checked_inputs(geometry, phi, w12, medium, model, method, tol, receivers, memory_limit, time_limit):
    """Validation at the solver's boundary: ``(phi, w12, receivers)`` as float64 / int64 arrays, checked."""
    check_model(model)
    check_method(method)
    check_tol(tol)
    budget.check_limits(memory_limit, time_limit)
    n = geometry.n_vertices
    phi = checked_array(phi, np.float64, (n, medium.n_channels), "phi")
    w12 = checked_array(w12, np.float64, (n, 3), "w12")
    if not np.all(np.isfinite(phi)) or np.any(phi < 0):
        raise InvalidParameterError("phi (incident flux density) must be finite and >= 0.")
    if receivers is None:
        receivers = np.arange(n, dtype=np.int64)
    else:
        receivers = np.asarray(receivers, dtype=np.int64).ravel()
        if receivers.size and (receivers.min() < 0 or receivers.max() >= n):
            raise InvalidParameterError(f"receivers must be vertex indices in 0..{n - 1}.")
    return phi, w12, receivers


def local_reach_floor(geometry: SurfaceGeometry, medium: Medium, tol: float) -> float:
    """The smallest ``reach_mm`` of :func:`solve` (mm) at ``tol``: the near-field radius plus the longest edge, so
    that every vertex of a triangle the near field integrates is among the sources summed."""
    return near_radius(geometry, medium, tol) + geometry.longest_edge


def _check_reach(reach_mm, method, tol, geometry, medium) -> None:
    """``reach_mm`` is None, or positive with ``method="cutoff"`` and at least :func:`local_reach_floor`."""
    if reach_mm is None:
        return
    if method != "cutoff":
        raise InvalidParameterError(
            f"reach_mm limits the cutoff method's sum; pass method='cutoff' with it, not {method!r}."
        )
    floor = local_reach_floor(geometry, medium, tol)
    try:
        reach = float(reach_mm)
    except (TypeError, ValueError):
        reach = math.nan
    if not (math.isfinite(reach) and reach >= floor):
        raise InvalidParameterError(
            f"reach_mm must be a distance of at least {floor:.4g} mm on this mesh (its near-field radius plus its "
            f"longest edge), not {reach_mm!r}."
        )


@dataclass
class _Work:
    """A solve's inputs on the spatially ordered surface (:meth:`SurfaceGeometry.spatial_order`).

    ``inner`` are the receivers in that surface's numbering, sorted; ``visit`` puts the rows of ``B``
    back in the caller's order (``B[visit] = B_inner``). ``params`` and ``channel_of`` are the kernels'
    coefficients of the distinct channels and each channel's row among them; ``flux = phi A`` and
    ``lit`` the vertices with any flux.
    """

    model: str
    medium: Medium
    geometry: SurfaceGeometry
    phi: np.ndarray
    w12: np.ndarray
    flux: np.ndarray
    lit: np.ndarray
    inner: np.ndarray
    visit: np.ndarray
    params: np.ndarray
    channel_of: np.ndarray
    reach: float | None = None
    device: str = "cpu"

    def far_field(self, method: str, tol: float):
        """The far-field ``method`` prepared for these sources (see :data:`_FAR_FIELD`; ``cutoff`` within
        :attr:`reach` when it is set; ``exact`` and ``tree`` on the GPU where :attr:`device` is ``gpu``)."""
        args = (
            self.model,
            self.geometry,
            self.medium,
            self.lit,
            self.w12,
            self.flux,
            self.params,
            self.channel_of,
            tol,
        )
        if self.reach is not None:
            return _cutoff_far_field(*args, reach=self.reach)
        if self.device == "gpu":
            return _FAR_FIELD[method](*args, device="gpu")
        return _FAR_FIELD[method](*args)


def _ordered_work(geometry, phi, w12, medium, model, receivers, stats) -> _Work:
    """The inputs moved onto the spatially ordered surface, identical channels merged, sources with flux."""
    # work on the spatially ordered copy, receivers in its order; B goes back to the caller's order
    n = geometry.n_vertices
    geometry, order, rank = spatial_order(geometry)
    phi, w12, flux, lit = ordered_light(phi, w12, geometry.vertex_areas, order)
    if receivers.size == n and np.array_equal(receivers, np.arange(n)):  # every vertex: the order is the tree's
        inner, visit = np.arange(n), order
    else:
        inner = rank[receivers]
        visit = np.argsort(inner, kind="stable")
        inner = inner[visit]
    rows, channel_of = unique_channels(medium)
    params = kernels.channel_parameters(rows[:, 0], rows[:, 1], rows[:, 2], medium.eta, model)
    stats["channels_computed"] = int(rows.shape[0])
    stats["channels_skipped_identical"] = int(medium.n_channels - rows.shape[0])

    stats["sources"] = int(lit.size)
    stats["sources_skipped_no_flux"] = int(n - lit.size)
    stats["receivers"] = int(receivers.size)
    return _Work(model, medium, geometry, phi, w12, flux, lit, inner, visit, params, channel_of)


def _plan(work: _Work, method, tol, memory_limit, time_limit, stats, memory_at_start=None):
    """The memory and time plan (:func:`translucency.scatter.budget.estimate`) from a sample of receivers:
    ``(plan, near_args, near radius in mm, the prepared far field or None)``; the plan goes into
    ``stats["budget"]``. ``memory_at_start``: ``(available, resident)`` bytes before the solve allocated
    anything (measured now when not given).

    Nothing of the whole surface's size is made for the plan but the source tree and, for a moment, its nodes'
    aggregates: the far field's sample evaluates a table of the columns its walks list, and the near field's is
    taken on the triangles around the sampled receivers (:func:`_around`), so that a solve the plan refuses has
    not already held the surface's near grid, triangle tables and the tree's table of every source and node,
    which grow with the scan."""
    geometry = work.geometry
    radius = near_radius(geometry, work.medium, None if method == "exact" else tol)
    near_args = dict(
        model_code=kernels.MODELS[work.model],
        geometry=geometry,
        w12=work.w12,
        phi=work.phi,
        params=work.params,
        channel_of=work.channel_of,
        medium=work.medium,
        **degree3_rule(work.medium, method),
        device=work.device,
    )
    available, resident = memory_at_start or (memory.available_memory(), memory.resident_memory())
    budget_bytes = budget.memory_budget(memory_limit, available, resident)
    # cutoff's evaluations depend on B (its widened radii): it is prepared and run; tree's are its walk's
    far_field = work.far_field(method, tol) if work.lit.size and method == "cutoff" else None
    counts = sample_counts(work, far_field, near_args, radius, method, tol)
    plan = budget.estimate(counts, budget_bytes, time_limit)
    stats["budget"] = {**plan.as_dict(), "counts": dataclasses.asdict(counts)}
    return plan, near_args, radius, far_field


def _far_field(work: _Work, far_field, method, tol, report):
    """The far field of every receiver by ``method`` (``far_field``: already prepared, or None), in chunks
    of :data:`FAR_CHUNK` multiples (with progress): ``(B in the ordered receivers' rows, statistics)``."""
    inner, n_channels = work.inner, work.medium.n_channels
    if work.lit.size == 0:
        return np.zeros((inner.size, n_channels)), {"pairs_evaluated": 0, "pairs_skipped": 0}
    far_field = far_field or work.far_field(method, tol)
    rcv_points = work.geometry.points[inner]
    rcv_normals = work.geometry.normals[inner]
    B, far_stats = np.zeros((inner.size, n_channels)), {}
    step = FAR_CHUNK * max(1, -(-inner.size // (budget.PROGRESS_STEPS * FAR_CHUNK)))
    if work.device == "gpu":
        step = max(step, GPU_FAR_CHUNK)
    for first in range(0, inner.size, step):
        part = slice(first, min(inner.size, first + step))
        B[part], part_stats = far_field(rcv_points[part], rcv_normals[part])
        far_stats = _merge_stats(far_stats, part_stats)
        report("far field", part.stop / inner.size)
    return B, far_stats


def _assembled(far, correction, visit, stats):
    """``B = far field + near-field correction``, negative sums clamped to 0 (counted in
    ``stats["negative_clamped"]``), rows back in the caller's order of receivers."""
    B = far + correction
    negative = B < 0
    stats["negative_clamped"] = int(negative.sum())
    B[negative] = 0.0
    B[visit] = B.copy()  # rows back in the order of ``receivers``
    return B


#: Receivers per far-field call are a multiple of this (the tree's block: its groups, and so ``B``,
#: are the same as in one call).
FAR_CHUNK = 4096
#: ... and on a GPU at least this many (a multiple of FAR_CHUNK): a call gives the device a thread per receiver, and
#: a sixteenth of a scan's receivers would leave most of a data-centre GPU idle.
GPU_FAR_CHUNK = 1 << 20
#: Receivers sampled for the budget's counts: groups of GROUP_RECEIVERS neighbours (the tree's groups).
SAMPLE_GROUPS = 64
#: Most near-triangle entries the near-field sample may list (bounds its memory: ~170 bytes each).
SAMPLE_NEAR_ENTRIES = 500_000


def _merge_stats(total: dict, part: dict) -> dict:
    """Far-field statistics of receiver chunks: counters add up, settings (radius, theta) stay."""
    counters = (
        "pairs_evaluated",
        "pairs_skipped",
        "receivers_widened",
        "pairs_direct",
        "cluster_evaluations",
        "clamped_values",
    )
    merged = dict(total)
    for key, value in part.items():
        merged[key] = merged.get(key, 0) + value if key in counters else value
    return merged


def _near_call(args, receivers, offsets, triangle_ids, own=None, maps=None):
    """:func:`translucency.scatter.nearfield.near_field_correction` on some receivers with their lists; on the GPU
    where the solve's device is (:mod:`translucency.scatter.gpu.nearfield`, ``exact``'s rules), except for the
    budget's sample, which counts each receiver's own points (``own``). ``maps``: the light's
    :func:`~translucency.scatter.nearfield.column_maps`, shared by the blocks of a solve."""
    g = args["geometry"]
    common = (
        args["model_code"],
        g.points,
        g.triangles,
        g.triangle_areas,
        g.normals,
        args["w12"],
        args["phi"],
        receivers,
        offsets,
        triangle_ids,
        args["params"],
        args["channel_of"],
        NEAR_BETA,
        float(np.min(args["medium"].D)),
    )
    if args.get("device") == "gpu" and own is None:
        from .gpu import nearfield as on_the_gpu

        return on_the_gpu.near_field_correction(*common, nearfield.tables_of(g))
    return nearfield.near_field_correction(
        *common,
        tables=nearfield.tables_of(g),
        degree3_ratio=args["degree3_ratio"],
        degree3_diameter=args["degree3_diameter"],
        refined_out=own,
        maps=maps,
    )


def _sample_receivers(inner: np.ndarray) -> np.ndarray:
    """The budget's sample of the receivers ``inner``: :data:`SAMPLE_GROUPS` random groups of
    :data:`GROUP_RECEIVERS` neighbours (the tree's groups), every receiver when there are few."""
    n_r, size = inner.size, GROUP_RECEIVERS
    groups = -(-n_r // size)
    if groups <= SAMPLE_GROUPS:
        return inner
    chosen = np.sort(np.random.default_rng(0).choice(groups, SAMPLE_GROUPS, replace=False))
    return inner[np.unique(np.minimum((size * chosen[:, None] + np.arange(size)).ravel(), n_r - 1))]


def sample_counts(work: _Work, far_field, near_args, radius, method, tol) -> budget.SolveCounts:
    """The budget's counts on the sample of receivers (:func:`_sample_receivers`): far-field evaluations
    (:func:`_far_evaluations`) and the near field's (:func:`_near_counts`, on the triangles around the sample,
    :func:`_around`), per receiver."""
    import numba

    geometry = work.geometry
    rcv = _sample_receivers(work.inner)
    near, points, own = _near_counts(*_around(work, near_args, rcv, radius))
    return budget.SolveCounts(
        geometry.n_vertices,
        int(geometry.triangles.shape[0]),
        int(work.inner.size),
        int(work.lit.size),
        int(work.flux.shape[1]),
        numba.get_num_threads(),
        method,
        near,
        points,
        own,
        _far_evaluations(work, far_field, rcv, method, tol),
        device=work.device,
    )


def _far_evaluations(work: _Work, far_field, rcv, method, tol) -> float:
    """Far-field evaluations per receiver of the sample ``rcv``: ``exact`` every lit source, ``cutoff`` by its
    prepared ``far_field``, ``tree`` by its walks with the nodes' aggregates and a table of the columns they list
    alone (:func:`~translucency.scatter.hierarchy.sampled_evaluations`)."""
    geometry, lit = work.geometry, work.lit
    if lit.size == 0 or rcv.size == 0:
        return 0.0
    if method == "exact":
        return float(lit.size)
    if method == "tree":
        rule = hierarchy.opening(work.medium, work.model, tol)
        evaluations = hierarchy.sampled_evaluations(
            kernels.MODELS[work.model],
            hierarchy.tree_of(geometry),
            geometry.points,
            geometry.normals,
            work.w12,
            work.flux,
            rcv,
            hierarchy.brightest(work.flux, geometry.vertex_areas),
            work.params,
            work.channel_of,
            rule,
            TOL_FLOOR,
        )
        return float(evaluations.mean())
    _, far_stats = (far_field or work.far_field(method, tol))(geometry.points[rcv], geometry.normals[rcv])
    return far_stats["pairs_evaluated"] / rcv.size


#: The near field's sample is taken on the surface around the sampled receivers when that keeps at most this
#: share of the triangles (else on the whole surface, whose grid the solve then reuses).
SAMPLE_SURFACE_SHARE = 0.25


def _around(work: _Work, near_args, rcv, radius):
    """``(near_args, grid, rcv)`` for the near field's sample at the receivers ``rcv``: on the triangles with a
    vertex within ``radius`` (mm) of one of them, as a surface of their own (the near grid lists a receiver's
    triangles by that test, so their lists and quadrature are the same), or on the whole surface."""
    geometry = work.geometry
    if rcv.size == 0:
        return near_args, nearfield.grid_of(geometry, radius), rcv
    near = nearfield.vertices_near(geometry.points, geometry.points[rcv], radius * (1.0 + 1e-9))
    triangles = geometry.triangles[np.any(near[geometry.triangles], axis=1)]
    if triangles.shape[0] > SAMPLE_SURFACE_SHARE * geometry.triangles.shape[0]:
        return near_args, nearfield.grid_of(geometry, radius), rcv
    vertices, local = np.unique(triangles, return_inverse=True)
    surface = SurfaceGeometry(geometry.points[vertices], local.reshape(-1, 3), geometry.normals[vertices])
    args = {**near_args, "geometry": surface, "w12": near_args["w12"][vertices], "phi": near_args["phi"][vertices]}
    return args, nearfield.grid_of(surface, radius), np.searchsorted(vertices, rcv)


def _near_counts(near_args, grid, rcv) -> tuple[float, float, float]:
    """The near field's counts per receiver of the sample ``rcv``: near triangles (by ``grid``), and quadrature
    points and of those the receivers' own (on as many as :data:`SAMPLE_NEAR_ENTRIES` allows)."""
    near = grid.counts(rcv) if rcv.size else np.zeros(0)
    take = min(rcv.size, max(8, int(SAMPLE_NEAR_ENTRIES // max(1.0, float(near.mean()) if near.size else 1.0))))
    near_rcv = rcv[np.unique(np.linspace(0, rcv.size - 1, take).astype(np.int64))] if take else rcv
    points = own = np.zeros(0)
    if near_rcv.size:
        offsets, ids = grid.lists(near_rcv)
        own = np.zeros(near_rcv.size, dtype=np.int64)
        _, points = _near_call(near_args, near_rcv, offsets, ids, own)
    mean = lambda a: float(a.mean()) if a.size else 0.0  # noqa: E731
    return mean(near), mean(points), mean(own)


def over_budget_sentence(plan: budget.SolveEstimate, n_vertices: int) -> str:
    """One sentence saying which budget a solve of ``n_vertices`` is over and what to change (over time, a light's
    estimate says the bounces it holds, ``plan.bounces``)."""
    if plan.over_memory:
        what = (
            f"needs {budget.about(plan)} {budget.format_bytes(plan.peak_bytes)} of memory beyond what the process "
            f"holds, over the budget of {budget.format_bytes(plan.budget_bytes)}"
        )
        more = option("memory_limit")
    else:
        what = (
            f"would take {budget.about(plan)} {budget.format_seconds(plan.seconds)}"
            f"{budget.bounce_phrase(plan.bounces)}, over the limit of {budget.format_seconds(plan.time_limit)}"
        )
        more = option("time_limit") + (f", pass {option('bounces', 0)}" if plan.bounces else "")
    return (
        f"solving at {n_vertices:,} vertices {what}; pass {option('resolution')} with a proxy edge length in mm "
        f"(coarser), raise {more}, or check the scan's {option('unit')}."
    )


def _near_field(args, inner, radius, plan, report):
    """Near-field correction of every receiver, in blocks of the plan: ``(correction, near triangles,
    near points, seconds spent listing)``; the same result whatever the blocks. On a GPU the mesh and the light are
    copied there once for the blocks, and given back after them."""
    if args.get("device") != "gpu":
        return _near_blocks(args, inner, radius, plan, report)
    from .gpu import nearfield as on_the_gpu

    try:
        return _near_blocks(args, inner, radius, plan, report)
    finally:
        on_the_gpu.release()


def _near_blocks(args, inner, radius, plan, report):
    """:func:`_near_field`'s blocks."""
    geometry = args["geometry"]
    n_r = inner.size
    correction = np.zeros((n_r, args["phi"].shape[1]))
    total_triangles = total_points = 0
    list_seconds = 0.0
    tables = nearfield.tables_of(geometry)
    maps = nearfield.column_maps(args["phi"], geometry.triangles.shape[0], tables.n_edges)
    start = time.perf_counter()
    if plan.keep_lists:
        offsets, triangle_ids = nearfield.lists_of(geometry, inner, radius)
        list_seconds += time.perf_counter() - start
        bounds = list(range(0, n_r, plan.block_receivers)) + [n_r]
        total_triangles = int(triangle_ids.size)
        for lo, hi in zip(bounds[:-1], bounds[1:]):
            correction[lo:hi], points = _near_call(args, inner[lo:hi], offsets[lo : hi + 1], triangle_ids, maps=maps)
            total_points += int(points.sum())
            report("near field", hi / n_r)
        return correction, total_triangles, total_points, list_seconds
    # blocks with their own lists, cut where their memory reaches what the plan gives a block
    grid = nearfield.grid_of(geometry, radius)
    counts = grid.counts(inner)
    table_per_receiver, rim = budget.block_table_bytes(
        budget.SAMPLE_SAFETY * float(np.mean(counts)) if counts.size else 0.0
    )
    own = budget.BYTES_PER_OWN_POINT * budget.SAMPLE_SAFETY * plan.own_points + table_per_receiver
    cost = np.cumsum((budget.BYTES_PER_NEAR_ROOM + budget.BYTES_PER_NEAR_TRIANGLE) * counts + own)
    cap = max(plan.block_bytes - rim, 1.0)
    list_seconds += time.perf_counter() - start
    lo = 0
    while lo < n_r:
        hi = int(np.searchsorted(cost, (cost[lo - 1] if lo else 0.0) + cap, side="right"))
        hi = min(n_r, max(hi, lo + 1))
        start = time.perf_counter()
        offsets, triangle_ids = grid.lists(inner[lo:hi], counts[lo:hi])
        list_seconds += time.perf_counter() - start
        correction[lo:hi], points = _near_call(args, inner[lo:hi], offsets, triangle_ids, maps=maps)
        total_triangles += int(triangle_ids.size)
        total_points += int(points.sum())
        del offsets, triangle_ids
        report("near field", hi / n_r)
        lo = hi
    return correction, total_triangles, total_points, list_seconds
