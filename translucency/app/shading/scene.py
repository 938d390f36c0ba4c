"""One mesh prepared for repeated shading: :class:`Scene`, and :func:`shade`, its one-call form.

A shade is a short sequence: pick the solver's surface for the resolution asked for
(:mod:`~translucency.app.shading.resolution`), give it the incident light
(:mod:`~translucency.app.shading.light_cache`),
carry that light through it behind the solver's one door (:func:`translucency.scatter.transport.transport`), and
over a budget try a coarser proxy (:mod:`~translucency.app.shading.fallback`); then assemble the result
(:func:`~translucency.app.shading.result.shade_result`). The Scene keeps every piece of that work a later shade can
reuse.
"""

from __future__ import annotations

import dataclasses
import time

from ...errors import BudgetError, InvalidParameterError
from ...scatter import transport
from ...scatter.names import DEFAULT_TOL
from ...threads import thread_count
from .fallback import (
    COARSER_ATTEMPTS,
    EARLY_PLAN_VERTICES,
    EARLY_REFUSAL_FACTOR,
    budget_phrase,
    coarsened_line,
    coarser_edge,
    proxy_seconds,
    refusal_key,
)
from .light_cache import LightCache
from .resolution import carries_full_light, proxy_edge, proxy_line, solver_mesh_for
from .result import ShadeResult, Solved, shade_result
from .scan import load_scan, mesh_for_shading, scan_reflectance
from .settings import ShadeSettings, default_light_direction, settings_table, settings_with

__all__ = ["Scene", "shade", "shade_scan", "scene_for", "RELEASE_SCENE_VERTICES"]

#: From a scan of this many vertices on, the Embree scenes (the scan's, or its proxy's) are let go once the incident
#: light is traced, so that they are not held through the solve's set-up and plan, where a scan's bake peaks; the
#: bounce builds the solver mesh's again. Below, a viewer's next light reuses them.
RELEASE_SCENE_VERTICES = 1_000_000


class _SaidBeforeWork:
    """The progress callback of one attempt, which says a proxy's line (the budget forced it) once, when the
    solve reports its first stage: after its plan has accepted the proxy, before its heavy work."""

    def __init__(self, line, warn, progress):
        self.line, self.warn, self.progress = line, warn, progress

    def say(self) -> None:
        """Say the line, once."""
        if self.line is not None:
            self.warn(self.line)
            self.line = None

    def __call__(self, stage, fraction):
        self.say()
        if self.progress is not None:
            self.progress(stage, fraction)


class Scene:
    """One mesh prepared for repeated shading, keeping every piece of work that a new call can reuse.

    What is kept, and when it is reused (reported in ``ShadeResult.stats["reused"]``):

    * the solver mesh (full, or a proxy per edge length) with its geometry caches -- vertex areas,
      near-triangle lists (per near radius), the source tree -- reused whatever the light and the
      material;
    * the Embree scene and the visibility of every light sample, reused when only the material changes (or when a
      light comes back);
    * the incident light per (lights, eta, shadows), reused when only the coefficients change
      (:attr:`light_cache`);
    * that the resolution asked for would take longer than the time limit, per settings and lights: the same
      shade asked again goes straight to the proxy (its line said again).

    A viewer keeps one ``Scene`` and calls :meth:`shade` on every change; :func:`shade` is the one-call form.

    Parameters
    ----------
    mesh : TriangleMesh or pyvista.PolyData
        A cleaned mesh in mm with outward orientation, or a PolyData (any PyVista dataset) in ``unit``,
        converted and repaired (:func:`~translucency.app.shading.scan.mesh_for_shading`); :attr:`mesh` is the
        mesh shaded.
    shadows : bool
        Cast Embree shadow rays (off: every front-facing vertex is lit).
    up : str
        The scan's up axis, ``"x"`` ... ``"-z"``, or ``"auto"`` (inferred from the mesh, see
        :mod:`translucency.io.upright`); it places the default light (above and in front) and is
        recorded in the metadata. The solver does not use it.
    unit : {"mm", "cm", "m", "in"} or float, optional
        A PolyData's length unit (None: its ``field_data["length_unit"]``, else inferred from its size);
        refused with a TriangleMesh, which is in mm.
    """

    def __init__(self, mesh, *, shadows: bool = True, up: str = "auto", unit=None):
        from ...io.upright import parse_up

        self.mesh = mesh_for_shading(mesh, unit, entry="Scene")
        self.shadows = bool(shadows)
        self.up_requested = parse_up(up)
        self._up = None if self.up_requested == "auto" else self.up_requested
        self._normals = self._areas = self._mean_edge = None
        self.light_cache = LightCache(self.mesh, self.shadows, self.full_normals, self.full_areas)
        self._solver_meshes: dict = {}
        self._refused: dict = {}

    @property
    def up(self) -> str:
        """The up axis, ``"+x"`` ... ``"-z"`` (inferred on first use when it was ``"auto"``)."""
        if self._up is None:
            from ...io.upright import resolve_up

            self._up = resolve_up("auto", self.mesh.points, self.mesh.triangles)
        return self._up

    @property
    def visibility(self):
        """The Embree scenes and the visibility of every light sample traced (the light cache's)."""
        return self.light_cache.visibility

    @property
    def mean_edge(self) -> float:
        """The full mesh's mean edge length (mm), measured once."""
        if self._mean_edge is None:
            self._mean_edge = self.mesh.mean_edge_length  # kept with the mesh (the cleaning measures it on the way)
        return self._mean_edge

    def full_normals(self):
        """The full mesh's unit vertex normals, computed once (the solver's at full resolution and the result's)."""
        if self._normals is None:
            # the mesh's own array (not a view), read-only: shared with the full-resolution surface and the light's
            # cache key, which hashes it once
            self._normals = self.mesh.vertex_normals(copy=False)
        return self._normals

    def full_areas(self):
        """The full mesh's barycentric vertex areas (mm²), computed once (the solver's at full resolution and the
        light's at every vertex)."""
        if self._areas is None:
            self._areas = self.mesh.vertex_areas(copy=False)  # read-only: shared with the full-resolution surface
        return self._areas

    def solver_mesh(self, medium, resolution="full", tol=DEFAULT_TOL, memory_limit=None):
        """``(solver mesh, Decimation or None, edge or None, SurfaceGeometry, reused)`` for a resolution (``tol``: the
        per-vertex tolerance that sets the edge of "auto",
        :func:`~translucency.app.shading.resolution.auto_proxy_edge`; ``memory_limit``, GB: what a proxy's
        decimation may hold)."""
        edge = proxy_edge(self.mean_edge, medium, resolution, tol, self.mesh)
        key = None if edge is None else round(edge, 9)  # decided before decimating: a cache hit costs nothing
        if key in self._solver_meshes:
            return (*self._solver_meshes[key], True)
        mesh, decimation, edge = solver_mesh_for(self.mesh, edge, memory_limit)
        full = decimation is None
        geometry = transport.SurfaceGeometry(
            mesh.points,
            mesh.triangles,
            self.full_normals() if full else mesh.vertex_normals(),
            mean_edge_mm=self.mean_edge if full else None,
            vertex_areas_mm2=self.full_areas() if full else None,
        )
        self._solver_meshes[key] = (mesh, decimation, edge, geometry)
        return mesh, decimation, edge, geometry, False

    def shade(
        self, material=None, lights=None, *, settings: ShadeSettings | None = None, progress=None, warn=None, **changes
    ) -> ShadeResult:
        """Translucent shading: ``B``, radiance toward the normal and display colours (see :func:`shade`).

        ``settings`` (default: the defaults) with ``material`` and the fields of ``changes`` replaced; their
        ``shadows`` and ``up`` are this Scene's."""
        if {"shadows", "up"} & set(changes):
            raise InvalidParameterError(
                "shadows and up belong to the Scene: pass them to Scene(mesh, shadows=..., up=...)."
            )
        if material is not None:
            changes["material"] = material
        settings = settings_with(settings, **changes, shadows=self.shadows, up=self.up_requested)
        return self.shade_with(settings, lights, progress=progress, warn=warn)

    def shade_with(
        self, settings: ShadeSettings, lights=None, *, progress=None, warn=None, note=None, solver=None
    ) -> ShadeResult:
        """:meth:`shade` with validated :class:`~translucency.app.shading.settings.ShadeSettings` (their ``shadows``
        and ``up`` are this Scene's, see :func:`scene_for`). ``note(line)``, when given, hears which proxy the
        resolution asked for chose and its expected error (a proxy forced by the budget goes to ``warn``).
        ``solver`` stands in for :func:`translucency.scatter.transport.solve` (the same arguments; a
        :class:`~translucency.app.shading.distributed.BlockSolver` solves on a Dask cluster)."""
        from ...scatter.lights import DirectionalLight, as_light_list

        lights = as_light_list(
            lights if lights is not None else DirectionalLight(default_light_direction(self.up), 1.0)
        )
        solved = self._solve_within_budget(settings, lights, progress, solver, warn or _warn)
        if solved.coarsened is None and solved.decimation is not None and note is not None:
            auto_tol = _auto_tol(settings)
            note(
                proxy_line(
                    settings.resolution,
                    auto_tol,
                    settings.material,
                    solved.solver_mesh.n_points,
                    self.mesh.n_points,
                    solved.edge,
                )
            )
        return shade_result(self, settings, lights, solved)

    def _solve_within_budget(self, settings: ShadeSettings, lights, progress, solver, warn) -> Solved:
        """The solve at the resolution asked for, or on a coarser proxy while it is over a budget
        (:mod:`~translucency.app.shading.fallback`); the same solve asked again after a refusal over time goes
        straight to its proxy. A proxy the budget forces is said to ``warn`` before it is solved."""
        refusal = None if solver is not None else refusal_key(settings, lights)
        resolution, reason, first = settings.resolution, None, 0
        if refusal in self._refused:
            (reason, resolution), first = self._refused[refusal], 1
        timings, proxies = {"geometry": 0.0}, 0
        for attempt in range(first, COARSER_ATTEMPTS + 1):
            start = time.perf_counter()
            solver_mesh, decimation, edge, geometry, geometry_reused = self.solver_mesh(
                settings.material, resolution, _auto_tol(settings), settings.memory_limit
            )
            timings["geometry"] += time.perf_counter() - start
            proxies += decimation is not None and not geometry_reused
            line = None
            if reason is not None:
                carried = carries_full_light(settings.material, edge)
                line = coarsened_line(
                    reason, settings.material, solver_mesh.n_points, self.mesh.n_points, edge, carried
                )
            said = _SaidBeforeWork(line, warn, progress)
            try:
                solved = self._attempt(
                    settings,
                    lights,
                    attempt,
                    resolution,
                    (solver_mesh, decimation, edge, geometry),
                    said,
                    solver,
                    timings,
                )
            except BudgetError as exc:
                reason = reason or budget_phrase(exc.estimate)  # of the resolution asked for
                # estimated, not measured, so that a scan gets the same proxy however busy the machine: the proxies
                # made so far and the next
                spent = (proxies + 1) * proxy_seconds(self.mesh.n_points, thread_count())
                resolution = coarser_edge(
                    solver_mesh.n_points, self.mesh.n_points, self.mean_edge, exc, attempt, settings.method, spent
                )
                if attempt == 0 and refusal is not None and not exc.estimate.over_memory:
                    # over time only: that estimate depends on the settings and lights alone
                    self._refused[refusal] = (reason, resolution)
                # what the resolution that did not fit built is freed before the proxy is made
                self._forget(geometry)
                continue
            solved.geometry_reused, solved.refusal_reused = geometry_reused, first > 0
            said.say()  # a solver that reports no progress: said now
            solved.coarsened = line
            return solved
        raise AssertionError("unreachable: coarser_edge raises when the attempts are spent")

    def _attempt(self, settings, lights, attempt, resolution, solver_surface, progress, solver, timings) -> Solved:
        """One solve on the solver surface of ``resolution`` (``(mesh, decimation, edge, geometry)``), checked
        against the budget before the light is traced, then the light and the solver's transport; a
        :class:`~translucency.errors.BudgetError` when over a budget."""
        solver_mesh, decimation, edge, geometry = solver_surface
        medium = settings.material
        reflectance = scan_reflectance(solver_mesh) if settings.albedo == "vertex_colors" else None
        # a proxy "auto" chose spends the tolerance on its own error: its far field is held to the default (a proxy
        # the budget forced is solved at the tolerance asked for)
        solve_tol = min(settings.tol, DEFAULT_TOL) if decimation is not None and resolution == "auto" else settings.tol
        options = transport.TransportOptions(
            model=settings.model,
            method=settings.method,
            device=settings.device,
            tol=solve_tol,
            per_direction=settings.per_direction,
            bounces=settings.bounces,
            shadows=self.shadows,
            memory_limit=settings.memory_limit,
            time_limit=settings.time_limit,
        )
        if solver is None:  # a size no solve fits: no light traced for it
            transport.check_size(geometry, medium.n_channels, options)
            if attempt == 0 and geometry.n_vertices >= EARLY_PLAN_VERTICES:  # a proxy is sized to fit
                early = dataclasses.replace(options, tol=settings.tol)
                transport.check_unshadowed(geometry, lights, medium, early, EARLY_REFUSAL_FACTOR)
        start = time.perf_counter()
        carried = carries_full_light(medium, edge)
        if decimation is not None and not carried:  # a refused resolution's light: not held beside the proxy's
            self.light_cache.drop_full_mesh_lights()
        incident, incident_reused = self.light_cache.solver_light(
            geometry, solver_mesh, decimation if carried else None, lights, medium.eta, settings.per_direction
        )
        timings["incident_light"] = timings.get("incident_light", 0.0) + time.perf_counter() - start
        if self.mesh.n_points >= RELEASE_SCENE_VERTICES:  # not held through the solve's set-up
            self.visibility.release_scenes()
        carried_through = transport.transport(
            geometry,
            incident,
            medium,
            options,
            lights=lights,
            visibility=self.visibility,
            reflectance=reflectance,
            progress=progress,
            solver=solver,
        )
        full_flux = (
            self.light_cache.flux_on_full_mesh(geometry, lights, medium.eta, settings.per_direction)
            if decimation is not None and carried
            else None
        )
        return Solved(
            solver_mesh,
            decimation,
            edge,
            carried,
            incident,
            carried_through,
            full_flux,
            timings=timings,
            incident_reused=incident_reused,
        )

    def _forget(self, geometry) -> None:
        """Drop the solver mesh of ``geometry``, its incident light and the Embree scenes and visibility."""
        for key, kept in list(self._solver_meshes.items()):
            if kept[3] is geometry:
                del self._solver_meshes[key]
        self.light_cache.forget(geometry)


def _auto_tol(settings: ShadeSettings) -> float:
    """The tolerance that sets the edge of resolution "auto": the settings', or the default for ``exact``, which
    has none."""
    return DEFAULT_TOL if settings.method == "exact" else settings.tol


def _warn(message: str) -> None:
    from ...errors import warn_user

    warn_user(message)


def shade(
    mesh,
    material=None,
    lights=None,
    *,
    settings: ShadeSettings | None = None,
    unit=None,
    progress=None,
    warn=None,
    **changes,
) -> ShadeResult:
    """Translucent shading of one mesh (mm): ``B``, radiance toward the normal and display colours.

    The one-call form of :class:`Scene` (nothing is kept between calls; keep a ``Scene`` to reuse work).

    Parameters
    ----------
    mesh : TriangleMesh or pyvista.PolyData
        A cleaned mesh in mm with outward orientation, or a PolyData (any PyVista dataset) in ``unit``,
        converted and repaired first (:func:`~translucency.app.shading.scan.mesh_for_shading`; ``result.mesh`` is
        the mesh shaded).
    material : str or Material or Medium, optional
        Shortcut for the ``material`` setting: catalogue name, catalogue entry or a
        :class:`~translucency.scatter.medium.Medium` (1/mm).
    lights : light or sequence of lights, optional
        Default: one white directional light of 1 W/m² from
        :func:`~translucency.app.shading.settings.default_light_direction` of ``up`` (above and in front of the
        scan). Directions are in the scan's own coordinates.
    settings : ShadeSettings, optional
        Every setting of the solve (default: the defaults, table below).
    **changes
        Any field of :class:`~translucency.app.shading.settings.ShadeSettings` by name (``tol=0.05``,
        ``bounces=0``, ...), replacing the one of ``settings``; an unknown name is a sentence.
    unit : {"mm", "cm", "m", "in"} or float, optional
        A PolyData's length unit (None: its ``field_data["length_unit"]``, else inferred from its size).
    progress : callable, optional
        ``progress(stage, fraction)``, many times per stage during the solve.
    warn : callable, optional
        ``warn(line)`` receives the line that says a solve over its budget went to a coarser proxy, with the error
        expected of it (default: a :class:`~translucency.errors.TranslucencyWarning`); when even that proxy would
        be too coarse, a :class:`~translucency.errors.BudgetError` says what to change.

    Returns
    -------
    ShadeResult
        ``result.reentered`` holds the part of ``B`` that left and entered again (``bounces``), and
        ``result.stats["bounces"]`` its rays, seconds and share.
    """
    if material is not None:
        changes["material"] = material
    settings = settings_with(settings, **changes)
    mesh = mesh_for_shading(mesh, unit, entry="shade")
    return scene_for(mesh, settings).shade_with(settings, lights, progress=progress, warn=warn)


shade.__doc__ += (
    "\n    Settings\n    --------\n" + "\n".join("    " + line for line in settings_table().splitlines()) + "\n"
)


def scene_for(mesh, settings: ShadeSettings) -> Scene:
    """A :class:`Scene` of ``mesh`` with the settings' shadows and up axis."""
    return Scene(mesh, shadows=settings.shadows, up=settings.up)


def shade_scan(
    scan,
    settings: ShadeSettings | None = None,
    lights=None,
    *,
    unit=None,
    progress=None,
    warn=None,
    note=None,
    solver=None,
) -> ShadeResult:
    """A scan shaded with every setting of ``settings``: the pipeline's first half
    (:func:`~translucency.app.shading.result.write_result` is the second).

    Parameters
    ----------
    scan : path-like, TriangleMesh, pyvista.PolyData or None
        A scan file in ``unit`` (None: inferred from its size), loaded and cleaned by
        :func:`~translucency.app.shading.scan.load_scan`; None for the embedded default scan; a PolyData in
        ``unit``, converted and cleaned; or a TriangleMesh already cleaned, in mm, used as it is.
    settings : ShadeSettings, optional
        Every setting of the solve (default: the defaults).
    lights : light or sequence of lights, optional
        Default: the white directional light above and in front.
    progress, warn
        As in :func:`shade`; ``warn`` also receives the loader's warnings, and ``note`` the line that
        says which unit was inferred (default: ``warn``) and the one that says which proxy the resolution
        chose (:meth:`Scene.shade_with`; default: none).
    solver : callable, optional
        Stands in for :func:`translucency.scatter.transport.solve` (:meth:`Scene.shade_with`).

    Returns
    -------
    ShadeResult
        ``result.mesh`` is the cleaned mesh in mm.
    """
    from ...geometry.mesh import TriangleMesh
    from ...io.polydata import is_pyvista_mesh

    settings = settings_with(settings)
    if isinstance(scan, TriangleMesh) or is_pyvista_mesh(scan):
        mesh = mesh_for_shading(scan, unit, entry="shade_scan")
    else:
        mesh = load_scan(scan, unit, warn=warn, note=note)[0]
    return scene_for(mesh, settings).shade_with(
        settings, lights, progress=progress, warn=warn, note=note, solver=solver
    )
