"""The one door from the shading policy into the solver: light on a surface gives ``B`` and its re-entered part,
planned against the budget (docs/physics.md §5.3, §7.4, §8).

:mod:`translucency.app.shading` reaches the solver only through this module. What goes in is plain data: the
surface record (:class:`SurfaceGeometry`: points in mm, triangles, unit vertex normals; the algorithms keep their
prepared work on it), the incident light (:class:`IncidentLight`, from :func:`incident_flux` or
:func:`carried_light`), the medium (1/mm) and one :class:`TransportOptions`; what comes back is a
:class:`Transport`. Behind the door, in order:

1. :func:`check_size`: the least any solve of the surface's size needs, against the budgets, before the light
   is traced;
2. :func:`check_unshadowed`: at scan size, the plan with every vertex that faces a light lit, before any shadow
   ray (shadows only take light away);
3. :func:`transport`: the solve (:func:`translucency.scatter.solve.solve`; once per light sample with
   ``per_direction``; with a reflectance per vertex through :func:`translucency.scatter.varying.solve_varying`),
   then the light that leaves the surface and enters again (:func:`translucency.scatter.bounces.solve_bounces`);
   with the method ``auto``, by the method :mod:`translucency.scatter.method_choice` chooses for this light, the
   bounces' solves included.

========= ============================================================ ==============
symbol    meaning                                                      unit
========= ============================================================ ==============
phi       incident flux density after the boundary                     W/m²
B         diffuse radiance factor, first solve plus re-entered light   W/(m² sr)
T21       Fresnel transmittance out of the medium along the normal      1
========= ============================================================ ==============
"""

from __future__ import annotations

import dataclasses
import functools
import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import BudgetError, DeviceError, TranslucencyError, option, warn_user
from . import relight
from .budget import about, bounce_phrase, format_bytes, format_seconds
from .irradiance import IncidentLight, carried_light, incident_flux
from .method_choice import AUTO, chosen_method, count_light, missed_tol, operators_held, refuse, tally_of
from .names import DEFAULT_DEVICE
from .solve import Solution, over_budget_sentence, solve
from .surface import SurfaceGeometry, spatial_order
from .treewalk import GROUP_RECEIVERS
from .visibility import VisibilityCache

__all__ = [
    "GROUP_RECEIVERS",
    "IncidentLight",
    "Solution",
    "SurfaceGeometry",
    "Transport",
    "TransportOptions",
    "VisibilityCache",
    "about",
    "bounce_phrase",
    "carried_light",
    "check_size",
    "check_unshadowed",
    "format_bytes",
    "format_seconds",
    "incident_flux",
    "light_solves",
    "normal_transmittance",
    "solve",
    "spatial_order",
    "transport",
]


#: A bounce (its gather and its solve) costs about what the light's first solve is planned to take (bench/README.md,
#: "Memory and time budget"): a light's first solve is planned against ``1 + bounces`` times its own time.
BOUNCE_SOLVE_SHARE = 1.0


@dataclass(frozen=True)
class TransportOptions:
    """How a light is carried through a surface: the solver's choices and budgets, built by keyword.

    Attributes
    ----------
    model, method : str
        Names of :mod:`translucency.scatter.names`.
    tol : float
        The relative error allowed per vertex, 1.
    device : str
        Where ``exact`` and relighting's far field sum their pairs: ``cpu``, ``gpu`` or ``auto``
        (:data:`~translucency.scatter.names.DEVICES`).
    per_direction : bool
        One solve per light sample.
    bounces : int
        Times the light leaving the surface enters again (0: never).
    shadows : bool
        Whether the bounces' mirror reflection of the lights is shadowed.
    memory_limit, time_limit : float or None
        GB and seconds (None: no limit).
    """

    model: str
    method: str
    tol: float
    device: str = DEFAULT_DEVICE
    per_direction: bool = False
    bounces: int = 0
    shadows: bool = True
    memory_limit: float | None = None
    time_limit: float | None = None

    @property
    def limits(self) -> dict:
        """``memory_limit`` and ``time_limit`` as the solver's keywords."""
        return {"memory_limit": self.memory_limit, "time_limit": self.time_limit}

    @property
    def solve_keywords(self) -> dict:
        """``model``, ``method``, ``tol``, ``device`` and the limits as the keywords of
        :func:`~translucency.scatter.solve.solve`."""
        return {"model": self.model, "method": self.method, "tol": self.tol, "device": self.device, **self.limits}


@dataclass
class Transport:
    """What :func:`transport` returns, on the surface's vertices.

    Attributes
    ----------
    B : ndarray, shape (n, C)
        The diffuse radiance factor, the first solve's plus the re-entered part, W/(m² sr) per W/m².
    reentered : ndarray, shape (n, C), or None
        The part of ``B`` from light that left the surface and entered again; None with no bounce.
    solutions : list of Solution
        The first solve's, one per light sample with ``per_direction``.
    bounces : dict
        The bounces' statistics (``{"bounces": 0}`` without), with ``share_of_B`` per channel.
    timings : dict
        Seconds per stage: ``solve_<stage>`` summed over the solves, ``bounce_gather`` and ``bounce_solve``.
    method : str
        The method the light was solved by (what ``auto`` chose).
    method_choice : dict or None
        With ``auto``: its tally for these settings (:meth:`~translucency.scatter.method_choice.Tally.as_dict`).
    """

    B: np.ndarray
    reentered: np.ndarray | None
    solutions: list
    bounces: dict
    timings: dict = field(default_factory=dict)
    method: str = ""
    method_choice: dict | None = None

    @property
    def solver_stats(self) -> dict:
        """The first solve's statistics; for several solves their count, summed pairs and points, the first's
        ``device``, and whether relighting gave way to ``tree`` in any (``relight_fallback``)."""
        if len(self.solutions) == 1:
            return self.solutions[0].stats
        summed = ("pairs_evaluated", "pairs_skipped", "near_points")
        stats = {"solves": len(self.solutions), **{k: sum(s.stats.get(k, 0) for s in self.solutions) for k in summed}}
        if "device" in self.solutions[0].stats:
            stats["device"] = self.solutions[0].stats["device"]
        fallback = next((s.stats["relight_fallback"] for s in self.solutions if "relight_fallback" in s.stats), None)
        return stats if fallback is None else {**stats, "relight_fallback": fallback}

    @property
    def operators_reused(self) -> bool:
        """Whether relighting operators prepared by an earlier light were applied."""
        return any(s.stats.get("operators_reused") for s in self.solutions)


def normal_transmittance(eta: float) -> float:
    """``T21(eta, 1)``: the share of ``B`` that leaves toward the normal, ``L = T21 B`` (docs/physics.md §2)."""
    from .fresnel import fresnel_transmittance

    return float(fresnel_transmittance(1.0, eta))


def check_size(surface: SurfaceGeometry, n_channels: int, options: TransportOptions) -> None:
    """A :class:`~translucency.errors.BudgetError` when even the least a solve of the surface's size needs
    (:func:`translucency.scatter.solve.size_floor_plan`) is over the limits; relighting plans its own."""
    from .solve import size_floor_plan

    if options.method == "relight":
        return
    floor = _first_solve(
        surface,
        options,
        lambda first: size_floor_plan(surface, n_channels, first.method, first.memory_limit, first.time_limit),
    )
    if not floor.fits:
        raise _for_the_light(floor, surface, options)


def check_unshadowed(surface: SurfaceGeometry, lights, medium, options: TransportOptions, factor: float) -> None:
    """A :class:`~translucency.errors.BudgetError` when the solve's plan with every vertex that faces a light lit
    (:func:`translucency.scatter.solve.plan`, no shadow ray traced) is over ``factor`` times a budget. Shadows only
    take light away, so the solve with them would most likely be over its budget too, and no Embree scene of the
    surface need be built at a size that is then not solved. The ordered surface and source tree the plan makes
    stay on ``surface`` for the solve."""
    from .solve import plan

    held = options.method == AUTO and operators_held(surface, medium, options.model, options.tol, options.device)
    if options.method == "relight" or held:  # relighting plans its own operators
        return
    facing = incident_flux(surface.points, surface.normals, surface.vertex_areas, lights, medium.eta)
    estimate = _first_solve(
        surface, options, lambda first, lit=facing: plan(surface, lit.phi_rgb, lit.w12, medium, **first.solve_keywords)
    )
    del facing
    over_time = estimate.time_limit is not None and estimate.seconds > factor * estimate.time_limit
    over_memory = estimate.budget_bytes is not None and estimate.peak_bytes > factor * estimate.budget_bytes
    if over_time or over_memory:
        raise _for_the_light(estimate, surface, options)


def light_solves(options: TransportOptions) -> float:
    """How many times its own planned time a light's first solve stands for: ``1 + bounces`` (each bounce about one
    solve more, :data:`BOUNCE_SOLVE_SHARE`), so that ``time_limit`` holds the light's solves together; 1 without a
    bounce or a time limit, and for relighting, whose plan is its operators' preparation (a bounce is then one more
    light through them). ``auto`` is planned as its first lights are solved, by ``tree``."""
    if options.method == "relight" or options.time_limit is None or not options.bounces:
        return 1.0
    return 1.0 + BOUNCE_SOLVE_SHARE * options.bounces


def _first_solve(surface: SurfaceGeometry, options: TransportOptions, call):
    """``call(options)`` for a light's first solve (or its plan), planned against its share of ``time_limit``
    (:func:`light_solves`); a refusal is said for the whole light (:func:`_for_the_light`)."""
    share = light_solves(options)
    if share == 1.0:
        return call(options)
    try:
        return call(dataclasses.replace(options, time_limit=options.time_limit / share))
    except BudgetError as exc:
        if exc.estimate is None:
            raise
        raise _for_the_light(exc.estimate, surface, options) from None


def _for_the_light(plan, surface: SurfaceGeometry, options: TransportOptions) -> BudgetError:
    """The refusal of a light's first solve whose plan is ``plan`` (a
    :class:`~translucency.scatter.budget.SolveEstimate`), said for the whole light: its estimated seconds and the limit
    times :func:`light_solves` (the limit is then ``time_limit`` itself) and the bounces they hold, in the solver's
    sentence."""
    share = light_solves(options)
    if share != 1.0:
        plan = dataclasses.replace(
            plan, seconds=plan.seconds * share, time_limit=plan.time_limit * share, bounces=options.bounces
        )
    return BudgetError(over_budget_sentence(plan, surface.n_vertices), plan)


def transport(
    surface: SurfaceGeometry,
    light: IncidentLight,
    medium,
    options: TransportOptions,
    *,
    lights=(),
    visibility: VisibilityCache | None = None,
    reflectance=None,
    progress=None,
    solver=None,
) -> Transport:
    """``B`` of ``light`` on ``surface`` and its re-entered part (module docstring, steps 3).

    Parameters
    ----------
    surface, light, medium, options
        The surface (mm), the incident light on its vertices, the medium (1/mm) and the solver's choices.
    lights : sequence of lights
        The lights themselves, whose mirror reflection the bounces let in again.
    visibility : VisibilityCache, optional
        Where the bounces' Embree scene of ``surface`` is kept (a new one by default).
    reflectance : (n, C) array_like, optional
        A diffuse reflectance per vertex that replaces the medium's albedo (docs/physics.md §6.5).
    progress : callable, optional
        ``progress(stage, fraction)``, many times per stage.
    solver : callable, optional
        Stands in for :func:`translucency.scatter.solve.solve` (the same arguments).

    Raises
    ------
    BudgetError
        Before the work, when a solve's estimate is over its budget.
    """
    carry = functools.partial(
        _transported, surface, light, medium, lights=lights, visibility=visibility, reflectance=reflectance,
        progress=progress, solver=solver,
    )  # fmt: skip
    if options.method != AUTO:
        return dataclasses.replace(carry(options), method=options.method)
    if solver is not None:  # a solver of its own (a cluster's): its time and relighting's are not the same to weigh
        return dataclasses.replace(carry(dataclasses.replace(options, method="tree")), method="tree")
    return _auto(surface, medium, options, reflectance is not None, carry)


def _auto(surface, medium, options: TransportOptions, varying: bool, carry) -> Transport:
    """The light carried by ``carry(options)`` with the method ``auto`` chooses (:mod:`.method_choice`), counted in
    its tally; where relighting's operators were to be prepared and the budget or the GPU refused them, the light is
    solved by ``tree`` and they are not tried again under the same limits."""
    settings = (surface, medium, options.model, options.tol, options.device)
    limits = (options.memory_limit, options.time_limit)
    chosen = chosen_method(*settings, *limits, varying=varying)
    held_before = operators_held(*settings)
    start = time.perf_counter()
    try:
        # operators prepared here are kept only where their first light holds tol with a margin for the others (they
        # give way to tree otherwise)
        with relight.first_light_held_to(relight.AUTO_KEEP_SHARE):
            carried = carry(dataclasses.replace(options, method=chosen))
    except (BudgetError, DeviceError) as exc:
        if chosen != "relight" or held_before:
            raise
        refuse(*settings, str(exc), limits)
        chosen = "tree"
        start = time.perf_counter()
        carried = carry(dataclasses.replace(options, method=chosen))
    if chosen == "tree":
        tally = count_light(*settings, "tree", time.perf_counter() - start)
    elif not held_before and operators_held(*settings):  # prepared for this light
        tally = count_light(*settings, "prepared", time.perf_counter() - start)
        if "relight_fallback" in carried.solver_stats:  # their first light missed tol: it is the check's tree solve
            # the solve that prepared them (a light per direction may start with a direction that lights nothing)
            p99 = next(s.stats["checked_p99"] for s in carried.solutions if "checked_p99" in s.stats)
            tally = missed_tol(*settings, p99, tally)
            chosen = "tree"
    else:
        tally = tally_of(*settings)
    return dataclasses.replace(carried, method=chosen, method_choice=tally.as_dict())


def _transported(
    surface, light, medium, options: TransportOptions, *, lights, visibility, reflectance, progress, solver
) -> Transport:
    """:func:`transport` by ``options.method``, one of the solver's own (not ``auto``)."""
    solve_one = _solver(solver, reflectance)

    def first(planned: TransportOptions) -> list:
        if planned.per_direction:
            return _solve_per_direction(surface, light, medium, planned, progress, solve_one)
        return [solve_one(surface, light.phi_rgb, light.w12, medium, progress=progress, **planned.solve_keywords)]

    solutions = _first_solve(surface, options, first)
    timings: dict = {}
    for solution in solutions:
        for stage, seconds in solution.timings.items():
            timings[f"solve_{stage}"] = timings.get(f"solve_{stage}", 0.0) + seconds
    B = sum(solution.B for solution in solutions)
    if not options.bounces:
        return Transport(B, None, solutions, {"bounces": 0}, timings)
    from .bounces import solve_bounces

    visibility = VisibilityCache() if visibility is None else visibility
    occluder, _ = visibility.occluder(surface.points, surface.triangles)
    try:
        bounced = solve_bounces(
            surface,
            occluder,
            B,
            lights,
            medium,
            bounces=options.bounces,
            model=options.model,
            method=options.method,
            tol=options.tol,
            device=options.device,
            shadows=options.shadows,
            progress=progress,
            solver=solve_one,
            **options.limits,
        )
    except TranslucencyError as exc:
        # after the first solve's work, at the resolution asked for: keep it and say what is missing (over the
        # budget, a coarser proxy for everything would lose far more than the bounce adds: B at full resolution)
        warn_user(
            f"the light that enters the surface again was not added ({str(exc).rstrip('.')}); the result is the "
            f"first-order light alone ({option('bounces', 0)} asks for that from the start)."
        )
        return Transport(B, None, solutions, {"bounces": 0, "bounce_failed": str(exc)}, timings)
    timings["bounce_gather"] = bounced.stats["seconds"]["gather"] + bounced.stats["seconds"]["specular"]
    timings["bounce_solve"] = bounced.stats["seconds"]["solve"]
    B = B + bounced.B
    return Transport(B, bounced.B, solutions, _bounce_stats(bounced, B), timings)


def _solver(solver, reflectance):
    """The solve to call: ``solver`` (or :func:`~translucency.scatter.solve.solve`) as it is, or wrapped by
    :func:`~translucency.scatter.varying.solve_varying` with a reflectance per vertex."""
    if reflectance is None:
        return solver or solve
    from .varying import solve_varying

    return functools.partial(solve_varying, reflectance=reflectance, solver=solver)


def _solve_per_direction(surface, light, medium, options: TransportOptions, progress, solve_one) -> list:
    """One solve per light sample (each with its own refracted direction); their ``B`` add up."""
    n = surface.n_vertices
    parts = light.contributions
    solutions = []
    for k, part in enumerate(parts):
        phi = np.zeros((n, 3))
        w12 = np.tile((0.0, 0.0, -1.0), (n, 1))
        phi[part.vertices] = part.phi_rgb
        w12[part.vertices] = part.w12
        inner = None if progress is None else (lambda stage, f, k=k: progress(stage, (k + f) / len(parts)))
        solutions.append(
            solve_one(
                surface,
                phi,
                w12,
                medium,
                progress=inner,
                **options.solve_keywords,
            )
        )
    return solutions


def _bounce_stats(bounced, B) -> dict:
    """The bounces' statistics: bounces done, rays, seconds of the gather and of the extra solves, and the share of
    ``B`` (summed over the vertices, per channel) that re-entered."""
    total = np.asarray(B, dtype=np.float64).sum(axis=0)
    share = np.asarray(bounced.B, dtype=np.float64).sum(axis=0) / np.where(total > 0.0, total, np.inf)
    return {**bounced.stats, "share_of_B": share.tolist()}
