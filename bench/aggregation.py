"""How far aggregating the light samples per vertex moves ``B``: per-direction summation as reference.

:func:`~translucency.scatter.irradiance.incident_flux` gives the solver one source per vertex, the
flux ``Phi_i`` with the flux-weighted refracted direction ``w12_i``; the exact input would be one
source per vertex and light sample, ``(Phi_ik, w12_ik)`` (docs/physics.md §7.2). For one directional
light the two agree; for several, :func:`aggregation_error` measures the difference with the float64
reference dipole (:func:`~translucency.scatter.dipoles.directional_dipole`), as a plain vertex sum on
a small mesh, so that it measures the aggregation and not the solver's quadrature.

========== ==================================================== ==============
symbol     meaning                                              unit
========== ==================================================== ==============
Phi_i      aggregated flux entering at vertex i                 W mm²/m²
w12_i      flux-weighted unit refracted direction at vertex i   1
Phi_ik     flux of light sample k entering at vertex i          W mm²/m²
w12_ik     refracted direction of sample k at vertex i          1
S_d        directional dipole (FHK14)                           1/(mm² sr)
B          sum_i S_d Phi at a receiver                          W/(m² sr)
========== ==================================================== ==============

Run as a script, it prints the error on a marble sphere (radius 5 mm) lit by one, two and three
directional lights::

    .venv/bin/python bench/aggregation.py
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from translucency.errors import InvalidParameterError  # noqa: E402
from translucency.scatter.dipoles import directional_dipole  # noqa: E402

__all__ = ["aggregation_error"]


def aggregation_error(points, normals, incident, medium, receivers) -> dict:
    """Error of the aggregated sources against per-direction summation, with the reference dipole.

    Evaluates ``B(x_o) = sum_i S_d(x_i, w12; x_o) Phi`` at the receiver vertices twice, with the
    float64 :func:`~translucency.scatter.dipoles.directional_dipole`: once per source vertex with
    the aggregated ``(Phi_i, w12_i)``, once per source vertex and light sample with
    ``(Phi_ik, w12_ik)``. The receiver's own vertex is left out of both sums (r = 0). It is a plain
    vertex sum, so it measures the aggregation, not the solver's quadrature. Cost: receivers x
    sources x samples dipole evaluations; meant for small meshes and benchmarks.

    Parameters
    ----------
    points, normals : array_like, shape (n, 3)
        The vertices and unit normals given to :func:`~translucency.scatter.irradiance.incident_flux`.
    incident : ~translucency.scatter.irradiance.IncidentLight
        Result of :func:`~translucency.scatter.irradiance.incident_flux` with ``per_direction=True``.
    medium : Medium
        Optical coefficients (:class:`~translucency.scatter.medium.Medium`).
    receivers : array_like of int
        Vertex indices where ``B`` is compared.

    Returns
    -------
    dict
        ``B_aggregated``, ``B_per_direction`` (receivers x 3, W/(m² sr) for E in W/m²),
        ``max_relative_error`` and ``rms_relative_error`` over receivers and channels with
        ``B_per_direction > 0``.
    """
    if incident.contributions is None:
        raise InvalidParameterError("aggregation_error needs incident_flux(..., per_direction=True).")
    points = np.asarray(points, dtype=np.float64)
    normals = np.asarray(normals, dtype=np.float64)
    receivers = np.asarray(receivers, dtype=np.int64)
    lit = np.flatnonzero(incident.flux_rgb.sum(axis=1) > 0.0)
    vertices = np.concatenate([c.vertices for c in incident.contributions])
    flux = np.concatenate([c.flux_rgb for c in incident.contributions])
    w12 = np.concatenate([c.w12 for c in incident.contributions])

    def sum_at(receiver, sources, source_w12, source_flux, channel):
        keep = sources != receiver
        s = sources[keep]
        S_d = directional_dipole(
            points[s],
            normals[s],
            source_w12[keep],
            points[receiver],
            normals[receiver],
            medium.sigma_a[channel],
            medium.sigma_s[channel],
            medium.g[channel],
            medium.eta,
        )
        return float(S_d @ source_flux[keep, channel])

    aggregated = np.zeros((len(receivers), 3))
    per_direction = np.zeros((len(receivers), 3))
    for j, receiver in enumerate(receivers):
        for channel in range(3):
            aggregated[j, channel] = sum_at(receiver, lit, incident.w12[lit], incident.flux_rgb[lit], channel)
            per_direction[j, channel] = sum_at(receiver, vertices, w12, flux, channel)
    positive = per_direction > 0.0
    relative = np.abs(aggregated[positive] - per_direction[positive]) / per_direction[positive]
    return {
        "B_aggregated": aggregated,
        "B_per_direction": per_direction,
        "max_relative_error": float(relative.max()) if relative.size else 0.0,
        "rms_relative_error": float(np.sqrt(np.mean(relative**2))) if relative.size else 0.0,
    }


def main() -> None:
    """Print the aggregation error on a marble sphere under one, two and three directional lights."""
    from translucency.geometry.measure import barycentric_vertex_areas, triangle_areas, vertex_normals
    from translucency.geometry.synthetic import icosphere
    from translucency.scatter.irradiance import incident_flux
    from translucency.scatter.lights import DirectionalLight
    from translucency.scatter.materials import material

    points, triangles = icosphere(2, radius=5.0)
    normals = vertex_normals(points, triangles)
    areas = barycentric_vertex_areas(triangles, triangle_areas(points, triangles), len(points))
    medium = material("marble").medium()
    receivers = np.arange(0, len(points), 7)
    directions = [(0.0, 0.0, 1.0), (1.0, 0.0, 0.2), (0.0, -1.0, 0.5)]
    print(f"{'lights':>6}  {'max relative error':>18}  {'rms relative error':>18}")
    for count in range(1, len(directions) + 1):
        lights = [DirectionalLight(d) for d in directions[:count]]
        incident = incident_flux(points, normals, areas, lights, medium.eta, per_direction=True)
        report = aggregation_error(points, normals, incident, medium, receivers)
        print(f"{count:>6}  {report['max_relative_error']:>18.3e}  {report['rms_relative_error']:>18.3e}")


if __name__ == "__main__":
    main()
