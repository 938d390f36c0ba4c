"""What a viewer solves with, besides the scan and the lights: material, model, solver, tolerance, resolution, bounces.

:class:`SolveSettings` is taken once from a :class:`~translucency.app.shading.settings.ShadeSettings`; each change
the viewer offers is checked here (``with_*``: new settings, or None when the value is the current one), and
:meth:`SolveSettings.shade` asks a :class:`~translucency.app.shading.scene.Scene` for one solve with them.
"""

from __future__ import annotations

import dataclasses
import math

from ..shading.resolution import coarsest_proxy_edge, proxy_edge_length
from ..shading.settings import ShadeSettings, resolve_medium

#: Vertices of the interactive proxy (the measurements behind it: bench/README.md, "Interactive proxy").
INTERACTIVE_VERTICES = 7500


def interactive_edge_length(mesh, medium, vertices: int = INTERACTIVE_VERTICES) -> float:
    """Proxy edge length (mm) that answers interactively: a proxy of about ``vertices`` vertices.

    A closed mesh has about two triangles per vertex; the edge is that of equilateral triangles covering
    the surface, ``l = sqrt(4 A / (sqrt(3) 2 N))`` for area ``A`` (mm²) and ``N`` vertices. It is never
    finer than :func:`~translucency.app.shading.resolution.proxy_edge_length` of the medium (the detail the light
    can show after diffusing, docs/physics.md §8.6), and never coarser than
    :func:`~translucency.app.shading.resolution.coarsest_proxy_edge` (an object only a few diffusion lengths
    across still gets a proxy of some triangles).
    """
    triangle_area = mesh.surface_area / (2.0 * vertices)
    budget = math.sqrt(triangle_area / (math.sqrt(3.0) / 4.0))  # area of an equilateral triangle: sqrt(3)/4 l²
    return min(max(budget, proxy_edge_length(medium)), coarsest_proxy_edge(mesh.surface_area))


@dataclasses.dataclass(eq=False)
class SolveSettings:
    """The settings of a viewer's solves (the scan's scale and the lights are kept apart).

    Attributes
    ----------
    medium : Medium
        The material, 1/mm coefficients.
    model, method : str
        The scattering model and the solver's method.
    device : str
        Where the far field is summed (``cpu``, ``gpu`` or ``auto``:
        :func:`translucency.scatter.gpu.probe.pair_device`), the preview by ``tree`` too.
    tol : float
        The solver's tolerance, relative error per vertex.
    resolution : "interactive", "full", "auto" or float
        Where ``B`` is computed (``"interactive"`` is the viewer's own, :meth:`resolution_on`; a number is a proxy
        edge, mm).
    per_direction, albedo, shadows
        The shading settings' own (:class:`~translucency.app.shading.settings.ShadeSettings`).
    bounces : int
        How many times light re-enters the surface.
    limits : dict
        ``memory_limit`` and ``time_limit`` of each solve.
    """

    medium: object
    model: str
    method: str
    device: str
    tol: float
    resolution: object
    per_direction: bool
    bounces: int
    albedo: object
    limits: dict
    shadows: bool

    @classmethod
    def of(cls, settings: ShadeSettings, resolution) -> SolveSettings:
        """The solve settings of ``settings``, with the viewer's ``resolution`` (it may be ``"interactive"``)."""
        return cls(
            medium=settings.material,
            model=settings.model,
            method=settings.method,
            device=settings.device,
            tol=float(settings.tol),
            resolution=resolution,
            per_direction=bool(settings.per_direction),
            bounces=settings.bounces,
            albedo=settings.albedo,
            limits={"memory_limit": settings.memory_limit, "time_limit": settings.time_limit},
            shadows=bool(settings.shadows),
        )

    def with_material(self, material) -> SolveSettings | None:
        """These settings with ``material`` (catalogue name, entry or Medium, 1/mm); None if it is the same."""
        medium = resolve_medium(material)
        return None if medium.describe() == self.medium.describe() else dataclasses.replace(self, medium=medium)

    def with_model(self, model: str) -> SolveSettings | None:
        """These settings with the scattering ``model`` (checked); None if it is the same."""
        from ...scatter.names import check_model

        return self._with("model", check_model(model))

    def with_tol(self, tol) -> SolveSettings | None:
        """These settings with the solver's tolerance ``tol`` (checked); None if it is the same."""
        from ...scatter.names import check_tol

        return self._with("tol", check_tol(tol))

    def with_bounces(self, bounces) -> SolveSettings | None:
        """These settings with ``bounces`` re-entries of the light (checked); None if it is the same."""
        from ...scatter.names import check_bounces

        return self._with("bounces", check_bounces(bounces))

    def _with(self, name: str, value) -> SolveSettings | None:
        """These settings with ``name`` set to ``value``; None when that is its value already."""
        return None if value == getattr(self, name) else dataclasses.replace(self, **{name: value})

    def resolution_on(self, mesh):
        """Where a solve on ``mesh`` computes ``B`` at these settings' resolution: ``"interactive"`` is every vertex
        with ``relight`` and otherwise the proxy edge (mm) of :func:`interactive_edge_length`; any other is as it is."""
        if self.resolution != "interactive":
            return self.resolution
        return "full" if self.method == "relight" else interactive_edge_length(mesh, self.medium)

    def shade(self, scene, lights, resolution, exposure, progress, *, method=None, tol=None, bounces=None):
        """One solve on ``scene`` with ``lights`` at ``resolution`` (not ``"interactive"``), display ``exposure``
        (None: automatic) and ``progress``; ``method``, ``tol`` and ``bounces`` replace these settings' for this
        solve only. Returns the :class:`~translucency.app.shading.result.ShadeResult`."""
        method = self.method if method is None else method
        return scene.shade(
            self.medium,
            lights,
            model=self.model,
            method=method,
            device=self.device,
            tol=self.tol if tol is None else tol,
            resolution=resolution,
            exposure=exposure,
            per_direction=self.per_direction,
            bounces=self.bounces if bounces is None else bounces,
            albedo=self.albedo,
            progress=progress,
            **self.limits,
        )
