"""Where ``B`` is computed: the resolution policy that picks the solver's surface, the full mesh or a proxy.

A proxy is the scan decimated to an edge length ``h`` (mm) where the scan is much finer; ``B`` is solved at its
vertices and interpolated back to every vertex of the full mesh (:mod:`translucency.io.decimate`), the near field
still integrated over the proxy's real triangles. ``resolution`` is ``"full"``, ``"auto"`` (the longest edge whose
expected error is within the tolerance, docs/physics.md §8.6) or an edge in mm.

========================= ================================================================ ======
symbol                    meaning                                                          unit
========================= ================================================================ ======
h                         proxy edge length                                                mm
sigma_tr                  effective transport coefficient, per channel                     1/mm
sigma_t'                  reduced extinction coefficient, per channel                      1/mm
rate                      how fast a proxy's expected error grows with h (:func:`error_rate`) 1/mm
========================= ================================================================ ======
"""

from __future__ import annotations

import numpy as np

from ...errors import InvalidParameterError, option
from .settings import parse_resolution

__all__ = [
    "auto_proxy_edge",
    "carries_full_light",
    "coarsest_proxy_edge",
    "error_rate",
    "expected_proxy_error",
    "fine_enough_for",
    "proxy_edge",
    "proxy_edge_length",
    "proxy_line",
    "solver_mesh_for",
]

#: The detail the light can show after diffusing (:func:`proxy_edge_length`, the viewer's interactive proxy and the
#: coarsest "auto" proxy): no edges shorter than min(PROXY_DIFFUSION_FRACTION / max sigma_tr,
#: PROXY_MEAN_FREE_PATHS / max sigma_t'), a fraction of the shortest diffusion length and a few reduced mean free
#: paths, which set how sharp a shadow edge stays. Meshes finer than PROXY_MIN_RATIO times a proxy's edge are
#: decimated to it.
PROXY_DIFFUSION_FRACTION = 0.5
PROXY_MEAN_FREE_PATHS = 5.0
PROXY_MIN_RATIO = 1.5
#: The expected per-vertex error of a proxy (99th percentile of vertices) is AUTO_PROXY_ERROR_SLOPE * rate * h, with
#: rate = max(max sigma_tr, AUTO_RATE_PER_SIGMA_T * max sigma_t', AUTO_RATE_FLOOR_PER_MM): the empirical rule of
#: docs/physics.md §8.6 (its measurements: bench/README.md, "Automatic resolution"). The sigma_t' and floor terms
#: cover light that diffuses little over a reduced mean free path or over the object, where sigma_tr alone
#: undercounts.
AUTO_PROXY_ERROR_SLOPE = 1.25
AUTO_RATE_PER_SIGMA_T = 0.1
AUTO_RATE_FLOOR_PER_MM = 0.1
#: A proxy keeps at least this many triangles. On an object only a few diffusion lengths across (a scan read in the
#: wrong unit, say) the "auto" and the viewer's edge lengths are shortened to it, and a proxy edge length given that
#: leaves fewer is refused with a sentence.
PROXY_MIN_TRIANGLES = 200
#: A proxy whose edge ``h`` is at most this many diffusion lengths (``max sigma_tr * h``) is given the light traced at
#: every vertex of the full mesh, carried onto its vertices with the flux kept; a coarser one traces its own
#: (docs/physics.md §8.6: the carried flux is spread over a proxy edge, which a fine proxy does not see and a coarse
#: one does).
CARRIED_LIGHT_MAX_SIGMA_TR_EDGE = 0.1


def carries_full_light(medium, edge) -> bool:
    """Whether a proxy of edge ``edge`` (mm, None for the full mesh) is given the full mesh's light carried onto it
    (:data:`CARRIED_LIGHT_MAX_SIGMA_TR_EDGE`) rather than the light traced at its own vertices."""
    return edge is not None and float(np.max(medium.sigma_tr)) * edge <= CARRIED_LIGHT_MAX_SIGMA_TR_EDGE


def coarsest_proxy_edge(surface_area: float) -> float:
    """Longest proxy edge (mm) that leaves :data:`PROXY_MIN_TRIANGLES` equilateral triangles on ``surface_area``
    (mm²): ``h = sqrt(A / (N sqrt(3) / 4))``."""
    return float(np.sqrt(surface_area / (PROXY_MIN_TRIANGLES * np.sqrt(3.0) / 4.0)))


def proxy_edge_length(medium) -> float:
    """Edge length (mm) of the detail the light can show in this medium (:data:`PROXY_DIFFUSION_FRACTION`; without
    absorption, where the diffusion length is infinite, the mean free paths' part alone)."""
    sigma_tr = float(np.max(medium.sigma_tr))
    edge = PROXY_MEAN_FREE_PATHS / float(np.max(medium.sigma_t_reduced))
    return edge if sigma_tr == 0 else min(edge, PROXY_DIFFUSION_FRACTION / sigma_tr)


def error_rate(medium) -> float:
    """How fast a proxy's expected error grows with its edge (1/mm): the largest of max sigma_tr, a tenth of max
    sigma_t' and 0.1/mm (:data:`AUTO_PROXY_ERROR_SLOPE`, docs/physics.md §8.6)."""
    return max(
        float(np.max(medium.sigma_tr)),
        AUTO_RATE_PER_SIGMA_T * float(np.max(medium.sigma_t_reduced)),
        AUTO_RATE_FLOOR_PER_MM,
    )


def auto_proxy_edge(medium, tol) -> float:
    """Proxy edge length (mm) of resolution "auto" at the per-vertex tolerance ``tol`` (a fraction): the longest
    edge whose expected error is within it, ``h = tol / (AUTO_PROXY_ERROR_SLOPE rate)`` (:func:`error_rate`,
    docs/physics.md §8.6), and no longer than :func:`proxy_edge_length`."""
    return min(float(tol) / (AUTO_PROXY_ERROR_SLOPE * error_rate(medium)), proxy_edge_length(medium))


def fine_enough_for(edge, mean_edge) -> bool:
    """Whether a mesh of mean edge ``mean_edge`` (mm) is fine enough to be decimated to a proxy of edge ``edge`` (mm)
    by "auto" (:data:`PROXY_MIN_RATIO` times finer)."""
    return edge >= PROXY_MIN_RATIO * mean_edge


def expected_proxy_error(medium, edge) -> str:
    """The per-vertex error (99th percentile) expected of a proxy of edge ``edge`` (mm), in words:
    ``AUTO_PROXY_ERROR_SLOPE * rate * h`` (:func:`error_rate`)."""
    percent = 100 * AUTO_PROXY_ERROR_SLOPE * error_rate(medium) * edge
    return f"{percent:.2g} %" if percent < 100 else f"{percent:.0f} %"


def proxy_line(resolution, tol, medium, proxy_vertices, vertices, edge) -> str:
    """The line that says which proxy ``resolution`` chose (at the tolerance ``tol`` for "auto"), and the error
    expected of it (:func:`expected_proxy_error`)."""
    why = (
        f"which {option('tol', tol)} allows" if resolution == "auto" else f"as {option('resolution', resolution)} asks"
    )
    return (
        f"solving on a proxy of {proxy_vertices:,} of the {vertices:,} vertices (edge {edge:.3g} mm), {why}; expected "
        f"error up to about {expected_proxy_error(medium, edge)} at the 99th percentile of vertices "
        f"({option('resolution', 'full')} solves every vertex)."
    )


def proxy_edge(mean_edge, medium, resolution, tol, mesh):
    """Proxy edge length (mm) for a resolution (at the per-vertex tolerance ``tol`` for "auto") on ``mesh`` of
    ``mean_edge`` (mm), or None for the full mesh; a given edge that leaves too few triangles is a sentence."""
    if resolution == "full":
        return None
    if resolution == "auto":
        edge = min(auto_proxy_edge(medium, tol), coarsest_proxy_edge(mesh.surface_area))
        return edge if fine_enough_for(edge, mean_edge) else None
    edge = parse_resolution(resolution)
    if edge <= mean_edge:
        return None
    coarsest = coarsest_proxy_edge(mesh.surface_area)
    if edge > coarsest:
        raise InvalidParameterError(
            f"a proxy edge of {edge:.3g} mm ({option('resolution', f'{edge:g}')}) would leave fewer than "
            f"{PROXY_MIN_TRIANGLES} triangles on this {mesh.extent:.3g} mm mesh; pass {option('resolution')} "
            f"below {coarsest:.3g} mm, or full (and check {option('unit')} if the mesh should be larger)."
        )
    return edge


def solver_mesh_for(mesh, edge, memory_limit=None):
    """The mesh the solver runs on: ``(mesh or proxy, Decimation or None, proxy edge length or None)``; a proxy's
    decimation holds the process and its children within ``memory_limit`` (GB) when given."""
    from ...io.decimate import decimate_mesh
    from ...scatter.budget import GB

    if edge is None:
        return mesh, None, None
    limit_bytes = None if memory_limit is None else memory_limit * GB
    decimation = decimate_mesh(mesh, target_edge_length=edge, memory_limit_bytes=limit_bytes)
    if decimation.method == "none":
        return mesh, None, None
    return decimation.proxy, decimation, edge
