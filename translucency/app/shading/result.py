"""What a shade returns: :class:`ShadeResult`, assembled from the solve on the solver's surface, and its file.

:func:`shade_result` takes what the Scene solved (a :class:`Solved`: the solver mesh, the light it was given and the
solver's :class:`~translucency.scatter.transport.Transport`), carries ``B`` from a proxy back to every vertex
(clamped at 0), makes the radiance toward the normal ``L = T21(eta, 1) B`` and the display colours, and records
every setting and what was reused. :func:`write_result` writes it (PLY, VTP/VTK, glTF by the suffix,
:mod:`translucency.app.exports`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...io.units import RADIANCE_UNIT, unit_metadata
from ...scatter.transport import normal_transmittance
from ..display import display_colors

__all__ = ["ShadeResult", "Solved", "shade_result", "write_result"]


@dataclass
class ShadeResult:
    """Everything :func:`~translucency.app.shading.scene.shade` computed for one mesh: per-vertex arrays over
    ``mesh.points``, the settings.

    Radiance and ``B`` are in the solver's unit, W/(m² sr) for lights whose irradiance is given in
    W/m² (per W/m² of the light's irradiance: the default light has 1 W/m²).

    Attributes
    ----------
    mesh : TriangleMesh
        The mesh shaded: points in mm, triangles, ``mesh.mm_per_unit`` the scan file's unit.
    B : ndarray, shape (n, 3)
        The view-independent diffuse radiance factor ``B(x_o)`` per vertex and RGB channel, W/(m² sr)
        per W/m² (linear; interpolated from the proxy on a proxy solve).
    radiance : ndarray, shape (n, 3)
        Linear radiance toward the normal ``L = T21(eta, 1) B``, same unit: what a bake stores.
    colors : ndarray of uint8, shape (n, 3)
        Display colours, ``srgb(exposure * radiance)`` in 8 bits (:func:`translucency.app.display.display_colors`).
    exposure : float
        The display exposure the colours were made with, 1 / (unit of ``radiance``).
    normals : ndarray, shape (n, 3)
        Unit vertex normals of ``mesh`` (area-weighted), 1.
    stats : dict
        What the solve did: ``incident`` (lit vertices, rays), ``solver`` (pairs, ...), ``reused`` (work
        kept from earlier calls of the :class:`~translucency.app.shading.scene.Scene`), ``coarser`` (the proxy line, or
        None),
        ``solver_vertices``, ``vertices``.
    timings : dict
        Seconds per stage (``geometry``, ``incident_light``, ``solve_...``, ``interpolate_to_full``), s.
    metadata : dict
        Every setting of the run, as the outputs record them: material and coefficients (1/mm), lights,
        model, method, tolerance, resolution, shadows, exposure, the units (``length_unit`` = "mm",
        ``source_unit``, ``source_mm_per_unit``, ... of the scan file, ``radiance_unit``), up axis,
        budget, version.
    incident_flux : ndarray, shape (n, 3), optional
        The solver's input: the flux density entering the surface, ``phi = T12 E cos V`` summed over the
        light samples, W/m² per channel (:func:`translucency.scatter.irradiance.incident_flux`). On a proxy
        solve with the full mesh's light carried onto the proxy
        (:func:`~translucency.app.shading.resolution.carries_full_light`) it is that light,
        traced at every vertex; on a coarser proxy, the proxy's own ``phi`` interpolated to every vertex like
        ``B`` (what the solver saw: shadow edges as soft as the proxy's); None on a result made by hand.
    reentered : ndarray, shape (n, 3), optional
        The part of ``B`` from light that left the surface and entered again (``bounces``,
        docs/physics.md §7.4), W/(m² sr) per W/m²; None with ``bounces=0``.
    """

    mesh: object
    B: np.ndarray
    radiance: np.ndarray
    colors: np.ndarray
    exposure: float
    normals: np.ndarray
    stats: dict
    timings: dict
    metadata: dict = field(default_factory=dict)
    incident_flux: np.ndarray | None = None
    reentered: np.ndarray | None = None

    def to_pyvista(self):
        """The result as a ``pyvista.PolyData``: points (mm), triangles, every per-vertex array, the settings.

        ``point_data`` holds ``radiance`` and ``B`` (n, 3) float, ``colors`` (n, 3) uint8 (the active
        scalars), ``luminance`` (n,, the Rec. 709 luminance of the radiance, same unit),
        ``incident_flux`` (n, 3, W/m²), ``reentered`` (n, 3, with bounces) and ``normals`` (n, 3);
        ``field_data`` the settings (:attr:`metadata` flattened to strings and numbers, with
        ``length_unit`` = "mm", ``radiance_unit`` and ``incident_flux_unit``). So
        ``mesh.plot(scalars="colors", rgb=True)`` shows the bake, ``mesh.plot(scalars="luminance")`` the
        luminance in a colour map, and ``mesh.save("x.vtp")`` keeps it all (:func:`write_result` writes the
        same atomically).
        """
        from ..exports import result_polydata

        return result_polydata(self)

    def camera_position(self) -> list:
        """The default view of the result as PyVista takes it (``plotter.camera_position`` or
        ``mesh.plot(cpos=...)``): ``[eye, focal point, view up]`` in mm, from the scan's front and a little
        above, its up axis (``metadata["up"]``) up, the whole scan in PyVista's default window above the room
        its colour bar takes -- the view of the tool's own pictures (:func:`~translucency.app.framing.scan_camera`),
        where PyVista's default camera would take +z as up."""
        from ...io.upright import up_vector
        from ..framing import PYVISTA_ASPECT, PYVISTA_BAR_ROOM, scan_camera

        up = tuple(up_vector(self.metadata.get("up", "+y")))
        return scan_camera(self.mesh, up, PYVISTA_ASPECT, room_below=PYVISTA_BAR_ROOM)


@dataclass
class Solved:
    """What a Scene solved for one shade, on its solver mesh: what :func:`shade_result` needs.

    Attributes
    ----------
    solver_mesh : TriangleMesh
        The full mesh, or a proxy of it (mm).
    decimation : Decimation or None
        The proxy's mapping to the full mesh; None for the full mesh.
    edge : float or None
        The proxy's edge length, mm.
    carried : bool
        Whether the proxy was given the full mesh's light, carried onto its vertices.
    incident : IncidentLight
        The light the solver saw, on the solver mesh's vertices.
    transport : Transport
        The solver's answer (:class:`~translucency.scatter.transport.Transport`).
    full_flux : ndarray, shape (n, 3), optional
        With ``carried``: the flux density at every vertex of the full mesh, W/m².
    coarsened : str or None
        The budget's proxy line, when the resolution asked for was over a budget.
    timings : dict
        Seconds of the geometry and the incident light.
    geometry_reused, incident_reused, refusal_reused : bool
        Which work an earlier shade had done.
    """

    solver_mesh: object
    decimation: object
    edge: float | None
    carried: bool
    incident: object
    transport: object
    full_flux: np.ndarray | None = None
    coarsened: str | None = None
    timings: dict = field(default_factory=dict)
    geometry_reused: bool = False
    incident_reused: bool = False
    refusal_reused: bool = False


def shade_result(scene, settings, lights, solved: Solved) -> ShadeResult:
    """The :class:`ShadeResult` of ``solved`` on ``scene``'s full mesh, with ``settings`` and ``lights``
    recorded."""
    timings = {**solved.timings, **solved.transport.timings}
    B, reentered, phi = solved.transport.B, solved.transport.reentered, solved.incident.phi_rgb
    decimation = solved.decimation
    if decimation is not None:
        start = time.perf_counter()
        B = np.maximum(decimation.interpolate(B), 0.0)
        # what entered, traced at every vertex; or what the proxy's own light saw (ShadeResult.incident_flux)
        phi = solved.full_flux if solved.carried else np.maximum(decimation.interpolate(phi), 0.0)
        if reentered is not None:
            reentered = np.maximum(decimation.interpolate(reentered), 0.0)
        timings["interpolate_to_full"] = time.perf_counter() - start
    medium = settings.material
    radiance = normal_transmittance(medium.eta) * B  # L toward the normal, T21(eta, 1) B
    colors, exposure = display_colors(radiance, settings.exposure)
    mesh, proxy = scene.mesh, solved.solver_mesh
    resolution = "full" if decimation is None else f"proxy, {proxy.n_points} vertices, edge {solved.edge:.3g} mm"
    metadata = {
        **settings.metadata(lights, resolution),
        # what summed the pairs ("cpu" or "gpu (its name)"), where the setting may have been auto
        "device": solved.transport.solver_stats.get("device", settings.device),
        # the method that solved this light, where the setting may have been auto
        "method_used": solved.transport.method or settings.method,
        "shadows": scene.shadows,
        "exposure": exposure,
        **unit_metadata(mesh.mm_per_unit, mesh.unit_inferred),
        "radiance_unit": RADIANCE_UNIT,
        "up": scene.up,
        "up_inferred": scene.up_requested == "auto",
        "budget": {
            "memory_limit_gb": settings.memory_limit,
            "time_limit_s": settings.time_limit,
            "coarser": solved.coarsened,
        },
    }
    stats = {
        "incident": solved.incident.stats.as_dict(),
        "solver": solved.transport.solver_stats,
        "reused": _reused(solved),
        "coarser": solved.coarsened,
        "solver_vertices": proxy.n_points,
        "vertices": mesh.n_points,
        "bounces": solved.transport.bounces,
        "method_choice": solved.transport.method_choice,
    }
    return ShadeResult(
        mesh, B, radiance, colors, exposure, scene.full_normals(), stats, timings, metadata, phi, reentered
    )


def _reused(solved: Solved) -> list:
    """The names of the work a shade reused from earlier ones (``stats["reused"]``)."""
    incident = solved.incident
    reused = [
        name
        for name, flag in (
            ("geometry", solved.geometry_reused),
            ("incident light", solved.incident_reused),
            ("Embree scene", incident.stats.scene == "reused"),
            ("relight operators", solved.transport.operators_reused),
            ("the refusal of the resolution asked for", solved.refusal_reused),
        )
        if flag
    ]
    if incident.stats.n_visibility_reused:
        reused.append(f"visibility of {incident.stats.n_visibility_reused} light samples")
    return reused


def write_result(result: ShadeResult, path) -> Path:
    """Write a result to a file whose suffix names the format, atomically, with every setting; the
    pipeline's second half. Returns the path.

    ``.ply`` (colours, radiance and ``B`` as float properties, ``quality`` = luminance, settings in the
    header), ``.vtp``/``.vtk`` (:meth:`ShadeResult.to_pyvista`: every array as point data, settings as
    field data), ``.glb``/``.gltf`` (linear vertex colours for Blender and web viewers, settings in
    ``extras``); what each holds and which programs read it: :mod:`translucency.app.exports`.

    Raises
    ------
    InvalidParameterError
        Another suffix (one sentence listing the supported ones), a missing folder, the scan itself.
    WriteError
        When the disk refuses the file; nothing is left behind.
    """
    from ..exports import write_result_file

    return write_result_file(result, path)
