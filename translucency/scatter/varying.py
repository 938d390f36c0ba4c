"""A solve whose albedo changes from vertex to vertex: the colour of a scan read as its diffuse reflectance
(docs/physics.md §6.5).

Each vertex has a diffuse reflectance per channel (linear, in (0, 1)); the material keeps its reduced mean
free path ``1 / sigma_t'``, its ``g`` and ``eta``, and each vertex's reduced albedo is the one whose total
reflectance is that vertex's (:func:`~translucency.scatter.appearance.reduced_albedo`). A pair of vertices
then has two sets of coefficients; the sum at a receiver uses the receiver's,

    B(x_o) = sum_i S_{alpha(x_o)}(x_o, x_i) Phi_i,

as pbrt and Cycles do at their shading point. docs/physics.md §6.5 compares it with the source's and with
their mean against a two-media random walk, and says why the receiver's.

The solver takes one medium. The reflectances are covered by levels ``R_k`` at most :data:`REFLECTANCE_STEP`
apart; each level is solved at the receivers with a channel between its neighbours, and a receiver's ``B``
is interpolated between the two levels around its reflectance, linearly in ``log B`` (``B`` falls off
nearly exponentially with the albedo's transport coefficient; linear in ``B`` it takes more levels for
the same error). One reflectance everywhere is the homogeneous solve.
"""

from __future__ import annotations

import math
import time
import warnings

import numpy as np

from ..errors import InvalidParameterError, TranslucencyWarning
from .appearance import reduced_albedo
from .medium import Medium

__all__ = [
    "REFLECTANCE_STEP",
    "REFLECTANCE_RANGE",
    "reflectance_levels",
    "level_weights",
    "checked_reflectance",
    "solve_varying",
]

#: Largest step (in reflectance) between two levels: ``B`` is interpolated between the levels, so a
#: smaller step lowers the interpolation error at the cost of more levels to solve, each a solve with one
#: albedo (bench/README.md, "Colour from the scan").
REFLECTANCE_STEP = 0.025
#: Reflectances are clamped to this range: 0 and 1 have no albedo (a colour of pure black or white).
REFLECTANCE_RANGE = (0.01, 0.95)


def reflectance_levels(reflectance, step: float | None = None) -> np.ndarray:
    """Evenly spaced reflectance levels from the smallest to the largest value of ``reflectance`` (any shape),
    at most ``step`` (default :data:`REFLECTANCE_STEP`) apart; one level when every value is the same."""
    step = REFLECTANCE_STEP if step is None else step
    low, high = float(np.min(reflectance)), float(np.max(reflectance))
    count = 1 if high - low <= 1e-12 else max(2, math.ceil((high - low) / step - 1e-9) + 1)
    return np.linspace(low, high, count)


def level_weights(reflectance: np.ndarray, levels: np.ndarray, k: int) -> np.ndarray:
    """The hat weight of level ``k`` at each reflectance: 1 at ``levels[k]``, falling linearly to 0 at its
    neighbours (the weights of all levels sum to 1 inside their range)."""
    if levels.size == 1:
        return np.ones_like(reflectance)
    step = levels[1] - levels[0]
    return np.clip(1.0 - np.abs(reflectance - levels[k]) / step, 0.0, 1.0)


def _level_medium(medium: Medium, reflectance_level: float) -> Medium:
    """The material at one reflectance level: its reduced mean free path, ``g`` and ``eta`` kept, the reduced
    albedo from the level."""
    alpha = reduced_albedo(np.full(medium.n_channels, reflectance_level), medium.eta)
    sigma_t_reduced = medium.sigma_t_reduced
    sigma_s = alpha * sigma_t_reduced / (1.0 - medium.g)
    sigma_a = sigma_t_reduced - alpha * sigma_t_reduced
    return Medium(
        sigma_a,
        sigma_s,
        medium.g,
        medium.eta,
        f"{medium.name} at reflectance {reflectance_level:.3g}",
    )


def checked_reflectance(reflectance, n_vertices: int, n_channels: int) -> tuple[np.ndarray, int]:
    """``reflectance`` as an ``(n, C)`` float64 array clamped to :data:`REFLECTANCE_RANGE`, and how many
    values were clamped; a sentence when its shape or values are wrong."""
    try:
        values = np.asarray(reflectance, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError("the per-vertex reflectance must be numbers in (0, 1).") from None
    if values.shape != (n_vertices, n_channels):
        raise InvalidParameterError(
            f"the per-vertex reflectance must have one row per vertex and one column per channel "
            f"({n_vertices} x {n_channels}), got shape {values.shape}."
        )
    if not np.all(np.isfinite(values)):
        raise InvalidParameterError(
            "the per-vertex reflectance has values that are not finite; give numbers in (0, 1)."
        )
    low, high = REFLECTANCE_RANGE
    clamped = int(np.count_nonzero((values < low) | (values > high)))
    return np.clip(values, low, high), clamped


def solve_varying(geometry, phi, w12, medium: Medium, *, reflectance, solver=None, progress=None, **options):
    """``B`` with a reduced albedo per vertex, the receiver's (module docstring; docs/physics.md §6.5): a
    :class:`~translucency.scatter.solve.Solution` like :func:`~translucency.scatter.solve.solve`'s.

    Parameters
    ----------
    geometry, phi, w12, medium
        As in :func:`~translucency.scatter.solve.solve`; the medium gives the reduced mean free path, ``g``
        and ``eta`` (its own albedo is replaced).
    reflectance : (n, C) array_like
        Diffuse reflectance per vertex and channel (linear), clamped to :data:`REFLECTANCE_RANGE`.
    solver : callable, optional
        Stands in for :func:`~translucency.scatter.solve.solve` (the same arguments).
    progress : callable, optional
        ``progress(stage, fraction)``, the levels' solves in turn.
    **options
        ``model``, ``method``, ``tol``, ``device``, ``receivers``, ``memory_limit``, ``time_limit`` of the solve;
        ``relight`` is solved by ``tree`` on the device asked for (operators per level would replace each other).
    """
    from .solve import Solution, solve, warn_low_albedo

    solver = solver or solve
    n, C = geometry.n_vertices, medium.n_channels
    values, clamped = checked_reflectance(reflectance, n, C)
    if options.get("method") == "relight":
        options["method"] = "tree"
    receivers = options.pop("receivers", None)
    receivers = np.arange(n) if receivers is None else np.asarray(receivers, dtype=np.int64).ravel()
    levels = reflectance_levels(values)
    warn_low_albedo(_level_medium(medium, float(levels[0])))  # the darkest colour, said once (solve's own check)
    at_receivers = values[receivers]
    log_sum = np.zeros((receivers.size, C))
    linear_sum = np.zeros((receivers.size, C))
    dark = np.zeros((receivers.size, C), dtype=bool)  # a level gave 0: interpolated linearly there
    stats = {"levels": levels.tolist(), "reflectance_clamped": clamped, "solves": 0, "receiver_solves": 0}
    timings: dict[str, float] = {}
    settings = None
    start = time.perf_counter()
    for k, level in enumerate(levels):
        weights = level_weights(at_receivers, levels, k)
        rows = np.flatnonzero(np.any(weights > 0.0, axis=1))
        if rows.size == 0:
            continue
        inner = None if progress is None else (lambda stage, f, k=k: progress(stage, (k + f) / levels.size))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", TranslucencyWarning)  # said once above, not once per level
            solution = solver(
                geometry,
                phi,
                w12,
                _level_medium(medium, float(level)),
                receivers=receivers[rows],
                progress=inner,
                **options,
            )
        w = weights[rows]
        B = solution.B
        linear_sum[rows] += w * B
        log_sum[rows] += w * np.log(np.maximum(B, np.finfo(float).tiny))
        dark[rows] |= (w > 0.0) & (B <= 0.0)
        stats["solves"] += 1
        stats["receiver_solves"] += int(rows.size)
        for key in ("pairs_evaluated", "pairs_skipped", "near_points"):
            stats[key] = stats.get(key, 0) + int(solution.stats.get(key, 0))
        for key in ("pairs_direct", "cluster_evaluations"):  # tree's, where the levels were solved by tree
            if key in solution.stats:
                stats[key] = stats.get(key, 0) + int(solution.stats[key])
        if "device" in solution.stats:
            stats["device"] = solution.stats["device"]
        for key, value in solution.timings.items():
            timings[key] = timings.get(key, 0.0) + value
        settings = settings or solution.settings
    timings["total"] = time.perf_counter() - start
    B = np.where(dark, linear_sum, np.exp(log_sum))
    settings = {
        **settings,
        "medium": medium.describe(),
        "albedo": f"per vertex (the receiver's), {levels.size} reflectance levels, {levels[0]:.3g} to {levels[-1]:.3g}",
    }
    return Solution(B=B, receivers=receivers, stats=stats, timings=timings, settings=settings)
