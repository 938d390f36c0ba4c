"""Path-traced ground truth on a scan: ``translucency reference`` and :func:`trace_reference`.

The scan is loaded and repaired as for shading (the same vertices, so a reference and a model's result
line up vertex by vertex), then :func:`translucency.reference.pathtrace.trace_radiance` walks ``spp`` paths
from every vertex along its normal (docs/physics.md §9.5), and the result is written with its mesh and
settings (:mod:`translucency.io.reference_file`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

__all__ = ["DEFAULT_SPP", "GroundTruth", "trace_reference", "write_reference"]

#: Paths per vertex and channel when none is given: enough for tables and binned figures, which average many
#: vertices, though single vertices stay noisy (the error falls as 1/sqrt(paths); give more for maps;
#: bench/README.md, "Against the path-traced reference").
DEFAULT_SPP = 16
#: Seconds a reference may trace unless told otherwise (``--time-limit``): an hour, the longest a user waits
#: for a ground truth without planning it.
REFERENCE_TIME_LIMIT_S = 3600


@dataclasses.dataclass(frozen=True)
class GroundTruth:
    """A path-traced reference on a scan's vertices.

    Attributes
    ----------
    mesh : TriangleMesh
        The repaired scan in mm, whose vertices the arrays belong to.
    normals : ndarray, shape (n, 3)
        The vertex normals the radiance was traced along.
    radiance, radiance_stderr, radiance_reentered : ndarray, shape (n, 3)
        W/(m² sr) per W/m² (docs/physics.md §9.5).
    metadata : dict
        Material, coefficients, light direction, spp, seed, time and counters.
    """

    mesh: object
    normals: np.ndarray
    radiance: np.ndarray
    radiance_stderr: np.ndarray
    radiance_reentered: np.ndarray
    metadata: dict


def trace_reference(
    mesh=None,
    material="marble",
    light_direction=None,
    *,
    spp: int = DEFAULT_SPP,
    seed: int = 0,
    unit=None,
    up="auto",
    progress: Callable[[float, str], None] | None = None,
    time_limit: float | None = None,
) -> GroundTruth:
    """Path-traced radiance along the normal at every vertex of a scan (docs/physics.md §9.5).

    Parameters
    ----------
    mesh : TriangleMesh, pyvista.PolyData or None
        The scan (None: the embedded default bunny); a PolyData is converted in ``unit`` and repaired.
    material : str or Medium
        A catalogue name or a :class:`~translucency.scatter.medium.Medium`.
    light_direction : array_like, shape (3,), optional
        Toward the directional light of 1 W/m², scan coordinates (default: above and in front, by ``up``).
    spp : int
        Paths per vertex and channel (>= 2).
    seed : int
        Seed of the random numbers.
    unit, up
        As for :func:`~translucency.app.shading.scene.shade`.
    progress : callable, optional
        ``progress(fraction, message)`` every few seconds.
    time_limit : float, optional
        Seconds the tracing may take: a ``spp`` that would take longer is refused with a
        :class:`~translucency.errors.BudgetError` once the first seconds have told the rate (the command line's
        default is :data:`REFERENCE_TIME_LIMIT_S`).
    """
    from ..io.units import unit_metadata
    from ..io.upright import resolve_up
    from ..reference.pathtrace import trace_radiance
    from ..scatter.medium import Medium
    from .shading.scan import load_default_scan, mesh_for_shading
    from .shading.settings import default_light_direction, resolve_medium

    mesh = load_default_scan() if mesh is None else mesh_for_shading(mesh, unit, entry="trace_reference")
    medium = material if isinstance(material, Medium) else resolve_medium(material)
    if light_direction is None:
        light_direction = default_light_direction(resolve_up(up, mesh.points, mesh.triangles))
    light = np.asarray(light_direction, dtype=np.float64)
    normals = mesh.vertex_normals()
    traced = trace_radiance(
        mesh.points,
        mesh.triangles,
        mesh.points,
        normals,
        medium,
        light,
        spp=spp,
        seed=seed,
        progress=progress,
        time_limit=time_limit,
    )
    metadata = {
        "quantity": "radiance leaving the surface along the vertex normal, subsurface part, path traced",
        "radiance_unit": "W/(m^2 sr) per W/m^2",
        "material": medium.name,
        "sigma_a_per_mm": medium.sigma_a.tolist(),
        "sigma_s_per_mm": medium.sigma_s.tolist(),
        "g": medium.g.tolist(),
        "eta": float(medium.eta),
        "light_direction": (light / np.linalg.norm(light)).tolist(),
        "irradiance_w_per_m2": 1.0,
        "spp": int(spp),
        "seed": int(seed),
        "seconds": traced.seconds,
        "median_relative_stderr": traced.relative_stderr(),
        **unit_metadata(mesh.mm_per_unit, mesh.unit_inferred),
        "stats": traced.stats,
    }
    return GroundTruth(
        mesh=mesh,
        normals=normals,
        radiance=traced.radiance,
        radiance_stderr=traced.radiance_stderr,
        radiance_reentered=traced.radiance_reentered,
        metadata=metadata,
    )


def write_reference(truth: GroundTruth, path):
    """Write a :class:`GroundTruth` as ``.npz`` or ``.vtp`` (:mod:`translucency.io.reference_file`); returns
    the path."""
    from ..io.reference_file import write_reference_file

    arrays = {
        "radiance": truth.radiance,
        "radiance_stderr": truth.radiance_stderr,
        "radiance_reentered": truth.radiance_reentered,
    }
    return write_reference_file(path, truth.mesh.points, truth.mesh.triangles, truth.normals, arrays, truth.metadata)
