"""The incident light a :class:`~translucency.app.shading.scene.Scene` keeps, under one typed key.

A light is traced (Embree shadow rays, :func:`translucency.scatter.transport.incident_flux`) at the vertices of a
solver surface, or at every vertex of the full mesh; a fine proxy is given the full mesh's light carried onto its
vertices with the flux kept (:func:`translucency.scatter.transport.carried_light`, docs/physics.md §8.6). Each is
kept under a :class:`LightKey` that says which of those it is, so that another material with the same ``eta``, or a
light that comes back, traces no ray again; the visibility of every light sample is kept apart in the Scene's
:class:`~translucency.scatter.transport.VisibilityCache`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...scatter import transport

__all__ = ["LightKey", "LightCache", "light_key"]

#: Light set-ups kept at once; the oldest is dropped first.
KEPT_LIGHTS = 8


@dataclass(frozen=True)
class LightKey:
    """What a kept incident light is, and what it depends on.

    Attributes
    ----------
    where : str
        ``"solver surface"`` (traced at the vertices of the solver surface ``surface``), ``"carried"`` (the full
        mesh's light carried onto the proxy ``surface``; kept with the full mesh's flux density), ``"full mesh"``
        (traced at every vertex of the full mesh against itself; ``surface`` None) or ``"full mesh against
        proxy"`` (traced at every vertex of the full mesh against the proxy ``surface``).
    surface : int or None
        The ``id`` of the solver surface.
    lights : str
        The lights, described.
    eta : float
        The relative index of refraction, 1.
    per_direction : bool
        Whether each light sample is kept apart.
    """

    where: str
    surface: int | None
    lights: str
    eta: float
    per_direction: bool

    @property
    def on_full_mesh(self) -> bool:
        """Whether the light is at every vertex of the full mesh (the largest arrays kept)."""
        return self.where in ("full mesh", "full mesh against proxy")


def light_key(where: str, surface, lights, eta, per_direction) -> LightKey:
    """The :class:`LightKey` of ``lights`` (a sequence of lights) with ``eta`` on ``surface`` (a solver surface,
    or None for the full mesh)."""
    described = repr([light.to_dict() for light in lights])
    return LightKey(where, None if surface is None else id(surface), described, float(eta), bool(per_direction))


class LightCache:
    """The incident lights of one full mesh and its solver surfaces, traced once and kept.

    Parameters
    ----------
    mesh : TriangleMesh
        The full mesh (mm).
    shadows : bool
        Cast Embree shadow rays (off: every front-facing vertex is lit).
    normals, areas : callable
        The full mesh's unit vertex normals and barycentric vertex areas (mm²), computed once by their owner.
    """

    def __init__(self, mesh, shadows: bool, normals, areas):
        self.mesh = mesh
        self.shadows = bool(shadows)
        self.visibility = transport.VisibilityCache()
        self._normals = normals
        self._areas = areas
        self._kept: dict = {}

    def incident(self, geometry, triangles, lights, eta, per_direction=False):
        """Incident light traced at the vertices of a solver surface, kept per (surface, lights, eta);
        ``(light, reused)``."""
        key = light_key("solver surface", geometry, lights, eta, per_direction)
        if key in self._kept:
            return self._kept[key], True
        light = transport.incident_flux(
            geometry.points,
            geometry.normals,
            geometry.vertex_areas,
            lights,
            eta,
            triangles=triangles if self.shadows else None,
            cache=self.visibility,
            per_direction=per_direction,
        )
        self._remember(key, light)
        return light, False

    def incident_on_mesh(self, medium, lights, per_direction=False):
        """Incident light at every vertex of the full mesh for ``medium``'s ``eta``, kept across proxies;
        ``(light, reused)``."""
        from ...scatter.lights import as_light_list

        return self._on_full_mesh(as_light_list(lights), medium.eta, per_direction)

    def solver_light(self, geometry, solver_mesh, decimation, lights, eta, per_direction=False):
        """Incident light on the solver mesh, ``(light, reused)``.

        With a ``decimation`` (a fine proxy, :func:`~translucency.app.shading.resolution.carries_full_light`) it is
        the light at every vertex of the full mesh (:meth:`full_light_for_proxy`: its own normals and relief) carried
        onto the proxy's vertices with its flux kept (docs/physics.md §8.6). Kept with it is only the full mesh's
        flux density (:meth:`flux_on_full_mesh`), not the whole light, which is let go.
        """
        if solver_mesh is self.mesh:
            return self._on_full_mesh(lights, eta, per_direction)
        if decimation is None:
            return self.incident(geometry, solver_mesh.triangles, lights, eta, per_direction)
        key = light_key("carried", geometry, lights, eta, per_direction)
        if key in self._kept:
            return self._kept[key][0], True
        full, _ = self.full_light_for_proxy(geometry, solver_mesh, decimation, lights, eta, per_direction)
        light = transport.carried_light(full, decimation.gather, geometry.normals, geometry.vertex_areas)
        self.drop_full_mesh_lights()  # the whole light: its flux density is kept with the carried light
        self._remember(key, (light, full.phi_rgb))
        return light, False

    def flux_on_full_mesh(self, geometry, lights, eta, per_direction=False) -> np.ndarray:
        """The flux density (n, 3), W/m², at every vertex of the full mesh of the light carried onto the proxy
        ``geometry`` by :meth:`solver_light` (which must have run for it)."""
        return self._kept[light_key("carried", geometry, lights, eta, per_direction)][1]

    def full_light_for_proxy(self, geometry, solver_mesh, decimation, lights, eta, per_direction=False):
        """The light at every vertex of the full mesh that a proxy is given, ``(light, reused)``: the one traced
        against the full mesh when a refused resolution traced it, else traced now from every vertex of the full
        mesh (its own normals) against the proxy's surface, whose Embree scene is far smaller. Each ray starts off
        its vertex along the vertex normal by the vertex's distance from the proxy (``decimation``'s mapping), so
        that no vertex under the proxy's surface is shadowed by it; a point light's distance and direction are
        measured from there too."""
        key = light_key("full mesh against proxy", geometry, lights, eta, per_direction)
        for known in (light_key("full mesh", None, lights, eta, per_direction), key):
            if known in self._kept:
                return self._kept[known], True
        if not self.shadows:
            light = self._traced(self.mesh.points, lights, eta, per_direction)
        else:
            light = self._traced(
                self.mesh.points + decimation.mapping.distance[:, None] * self._normals(),
                lights,
                eta,
                per_direction,
                occluder=self.visibility.occluder(geometry.points, solver_mesh.triangles)[0],
            )
        self._remember(key, light)
        return light, False

    def drop_full_mesh_lights(self) -> None:
        """Let go of every light traced at every vertex of the full mesh (against it, or against a proxy)."""
        for key in [key for key in self._kept if key.on_full_mesh]:
            del self._kept[key]

    def forget(self, geometry) -> None:
        """Let go of every light of the solver surface ``geometry``, and of the Embree scenes and visibility."""
        for key in [key for key in self._kept if key.surface == id(geometry)]:
            del self._kept[key]
        self.visibility.clear()

    def _on_full_mesh(self, lights, eta, per_direction=False):
        """Incident light traced at every vertex of the full mesh against itself, ``(light, reused)``."""
        key = light_key("full mesh", None, lights, eta, per_direction)
        if key in self._kept:
            return self._kept[key], True
        light = self._traced(
            self.mesh.points, lights, eta, per_direction, triangles=self.mesh.triangles if self.shadows else None
        )
        self._remember(key, light)
        return light, False

    def _traced(self, origins, lights, eta, per_direction, **visibility):
        """:func:`~translucency.scatter.transport.incident_flux` at every vertex of the full mesh (its normals and
        areas), the rays from ``origins`` (mm) against ``visibility``'s ``triangles`` or ``occluder``."""
        return transport.incident_flux(
            origins,
            self._normals(),
            self._areas(),
            lights,
            eta,
            cache=self.visibility,
            per_direction=per_direction,
            **visibility,
        )

    def _remember(self, key: LightKey, light) -> None:
        """Keep an incident light for its key: a few recent light set-ups, the oldest dropped first."""
        while len(self._kept) >= KEPT_LIGHTS:
            self._kept.pop(next(iter(self._kept)))
        self._kept[key] = light
