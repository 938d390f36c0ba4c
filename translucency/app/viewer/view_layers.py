"""The two layers of the viewer's picture that depend on the view; they need no new solve.

* **view-dependent transmission** -- ``L = T21(eta, n . w_o) B`` with ``w_o`` toward the camera
  (darker at grazing angles, :func:`translucency.scatter.outgoing.subsurface_radiance`, docs/physics.md §5.3);
* **specular highlight** -- the boundary's reflection of every directional light and environment
  sample (GGX, roughness ``alpha``; :func:`translucency.scatter.outgoing.specular_radiance`, §5.5), with
  the same Embree shadows as the solve. Point lights give no highlight.
"""

from __future__ import annotations

import numpy as np


def highlight_inputs(scene, medium, lights, normals) -> list:
    """Per directional sample of ``lights`` on ``scene``'s mesh: (vertices it reaches, direction, irradiance on
    the surface ``E cos V``, W/m² per channel); ``normals`` are the result's, per vertex."""
    from ...scatter.fresnel import fresnel_transmittance

    incident, _ = scene.light_cache.incident_on_mesh(medium, lights, per_direction=True)
    inputs = []
    for part in incident.contributions:
        if part.direction is None:  # a point light: no highlight
            continue
        cos_i = normals[part.vertices] @ part.direction
        # phi = T12 E cos V (irradiance.py), so E cos V = phi / T12
        inputs.append((part.vertices, part.direction, part.phi_rgb / fresnel_transmittance(cos_i, medium.eta)[:, None]))
    return inputs


class Highlights:
    """The specular highlight's inputs (:func:`highlight_inputs`) for one solve's result, traced when first asked
    for and kept until the result changes."""

    def __init__(self):
        self._result, self._inputs = None, None

    def of(self, scene, medium, lights, result) -> list:
        """:func:`highlight_inputs` of ``lights`` on ``scene`` for ``result`` (traced again after a new result)."""
        if self._inputs is None or self._result is not result:
            self._result, self._inputs = result, highlight_inputs(scene, medium, lights, result.normals)
        return self._inputs


def radiance_toward(result, points, eta, appearance, highlights=()) -> np.ndarray:
    """Radiance per vertex toward the camera at ``appearance.eye`` (mm), W/(m² sr), (n, 3).

    ``T21(eta, n . w_o) B`` with the appearance's view-dependent layer, else the result's ``T21(eta, 1) B``;
    plus the GGX highlight (the appearance's ``roughness`` = ``alpha``) of each of ``highlights``
    (:func:`highlight_inputs`; none: no highlight). ``points`` are the mesh's vertices (mm), ``eta`` the
    medium's relative index.
    """
    from ...scatter.outgoing import specular_radiance, subsurface_radiance, view_directions

    w_o = view_directions(points, np.asarray(appearance.eye, dtype=np.float64))
    if appearance.view_dependent:
        radiance = subsurface_radiance(result.B, result.normals, w_o, eta)
    else:
        radiance = result.radiance.copy()
    for vertices, direction, irradiance in highlights:
        radiance[vertices] += specular_radiance(
            result.normals[vertices], w_o[vertices], direction, irradiance, eta, appearance.roughness
        )
    return radiance
