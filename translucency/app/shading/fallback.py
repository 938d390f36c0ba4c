"""The budget's fallback: a solve over its memory or time budget goes to a coarser proxy that fits, said in one line.

Every solve is planned before the work (:mod:`translucency.scatter.budget`); a plan over a budget raises a
:class:`~translucency.errors.BudgetError` with its estimate. The Scene then tries a proxy whose solve should fit
(:func:`coarser_edge`), up to :data:`COARSER_ATTEMPTS` times, and says which proxy it took with the error expected
of it (:func:`coarsened_line`), or lets the sentence of the last refusal through when even the coarsest proxy would
keep too few vertices. A scan far over its time budget is refused before any shadow ray is traced
(:data:`EARLY_PLAN_VERTICES`), and a refusal over time is remembered (:func:`refusal_key`).
"""

from __future__ import annotations

import json

from ...errors import option
from ...scatter.transport import about, bounce_phrase, format_bytes, format_seconds
from .resolution import expected_proxy_error

__all__ = [
    "COARSER_ATTEMPTS",
    "EARLY_PLAN_VERTICES",
    "EARLY_REFUSAL_FACTOR",
    "budget_phrase",
    "coarsened_line",
    "coarser_edge",
    "proxy_seconds",
    "refusal_key",
]

#: Over budget: attempts at a coarser proxy, the fraction of the budget the proxy aims at (the estimate's
#: margin), and the fewest vertices a proxy may keep (below: stop with a sentence instead).
COARSER_ATTEMPTS = 3
COARSER_MARGIN = 0.7
MIN_PROXY_VERTICES = 1000
#: How the solve's estimated time grows with the vertex count n: as n^2 for ``exact`` (every pair); for the others
#: more slowly (``tree``'s plans of one scan at several resolutions, bench/README.md, "Memory and time budget";
#: ``cutoff``'s in "Scaling and memory").
COARSER_TIME_EXPONENT = {"exact": 2.0, "tree": 1.1, "cutoff": 1.4}
#: From this many vertices on, the solve at the resolution asked for is planned with every vertex that faces a
#: light lit before the light's shadows are traced, and refused at once when that plan is over
#: EARLY_REFUSAL_FACTOR times a budget (:func:`translucency.scatter.transport.check_unshadowed`): no Embree scene of
#: a full mesh that is then not solved is built. The factor allows for the light the shadows take away; a scan whose
#: shadows take away more than a fifth of its light may be solved on a proxy where its full solve would have fitted.
EARLY_PLAN_VERTICES = 1_000_000
EARLY_REFUSAL_FACTOR = 1.25
#: Thread-seconds per vertex of the full mesh that making a proxy takes: its decimation (in parts, side by side), the
#: map from the full mesh onto it and the light traced at every vertex of the full mesh. A calibration on scans of
#: 2-10M vertices (bench/README.md, "Memory and time budget"); a proxy over time is sized to fit what is left of
#: the time limit after it.
PROXY_SECONDS_PER_VERTEX = 2e-5
#: Over time, a proxy aims at least at this share of the time limit, however much of it is spent.
LEAST_TIME_SHARE = 0.5


def proxy_seconds(mesh_vertices: int, threads: int) -> float:
    """Seconds that making a proxy of a mesh of ``mesh_vertices`` should take on ``threads`` threads
    (:data:`PROXY_SECONDS_PER_VERTEX`)."""
    return PROXY_SECONDS_PER_VERTEX * mesh_vertices / max(1, threads)


def coarser_edge(
    solver_vertices: int, mesh_vertices: int, mean_edge: float, exc, attempt: int, method: str, spent: float = 0.0
) -> float:
    """The edge length (mm) of a proxy of the full mesh (``mesh_vertices``, mean edge ``mean_edge`` mm) whose solve
    should fit the budget that the solve at ``solver_vertices`` was over (``exc``, a
    :class:`~translucency.errors.BudgetError`), in the time left of the limit once ``spent`` seconds are gone (the
    proxies' making, :func:`proxy_seconds`); ``exc`` is raised again when that proxy
    would keep fewer than :data:`MIN_PROXY_VERTICES` or the attempts are spent.

    Memory grows linearly with the vertex count and time as ``n^COARSER_TIME_EXPONENT``, so the share kept is
    ``COARSER_MARGIN * budget / estimate`` to the power 1 or ``1 / exponent`` (the time budget: what is left of the
    limit, at least :data:`LEAST_TIME_SHARE` of it); the edge is ``mean_edge * sqrt(mesh_vertices / target)``."""
    plan = exc.estimate
    shares = [COARSER_MARGIN * plan.budget_bytes / plan.peak_bytes] if plan.over_memory else []
    if plan.over_time:
        exponent = COARSER_TIME_EXPONENT.get(method, COARSER_TIME_EXPONENT["tree"])
        left = max(plan.time_limit - spent, LEAST_TIME_SHARE * plan.time_limit)
        shares.append((COARSER_MARGIN * left / plan.seconds) ** (1.0 / exponent))
    target = int(solver_vertices * min(shares or [COARSER_MARGIN]))
    if attempt >= COARSER_ATTEMPTS or target < MIN_PROXY_VERTICES:
        raise exc
    return mean_edge * (mesh_vertices / target) ** 0.5


def refusal_key(settings, lights) -> str:
    """What decides whether a solve fits its time limit: every setting but the exposure (the material's
    coefficients, model, method, tolerance, resolution, bounces, the limits ...) and the lights, as one string.
    (Whether it fits the memory budget also depends on what the machine holds at the time.)"""
    described = settings.metadata(lights, str(settings.resolution))
    described["limits"] = [settings.memory_limit, settings.time_limit]
    return json.dumps(described, sort_keys=True, default=str)


def budget_phrase(plan) -> str:
    """``"would need about 25 GB of memory (budget 3.6 GB)"`` or the same for time, from an estimate (over time, a
    light's estimate says the bounces it holds)."""
    if plan.over_memory:
        return (
            f"would need {about(plan)} {format_bytes(plan.peak_bytes)} of memory ({option('memory_limit')} budget "
            f"{format_bytes(plan.budget_bytes)})"
        )
    limit = format_seconds(plan.time_limit)
    return (
        f"would take {about(plan)} {format_seconds(plan.seconds)}{bounce_phrase(plan.bounces)} "
        f"({option('time_limit')} {limit})"
    )


def coarsened_line(reason: str, medium, proxy_vertices: int, vertices: int, edge: float, carried: bool) -> str:
    """The line that says a proxy was taken because the resolution asked for was over budget (``reason``, a
    :func:`budget_phrase`), with the per-vertex error expected of it
    (:func:`~translucency.app.shading.resolution.expected_proxy_error`)."""
    given = ", given the light traced at every vertex" if carried else ""
    return (
        f"solving on a proxy of {proxy_vertices:,} of the {vertices:,} vertices (edge {edge:.3g} mm), since the "
        f"resolution asked for {reason}; expected up to about {expected_proxy_error(medium, edge)} at the 99th "
        f"percentile of vertices{given}; raise the limit to solve every vertex."
    )
