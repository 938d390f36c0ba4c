"""One scan from mesh to translucent colours: geometry, incident light, solver, display transform.

This is the glue between :mod:`translucency.io` and :mod:`translucency.scatter` that the command line,
the viewer and batch baking share: :func:`shade` takes a cleaned :class:`~translucency.geometry.mesh.TriangleMesh`
in mm, a material and lights, and returns the per-vertex diffuse radiance factor ``B``, the radiance
toward the normal ``L = T21(eta, 1) B`` (linear) and display colours (exposure + sRGB), in a
:class:`ShadeResult`; :meth:`ShadeResult.to_pyvista` and :func:`write_result` (PLY, VTP/VTK, glTF by
the suffix, :mod:`translucency.app.exports`) hand it to other programs.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from ..errors import TranslucencyError, option
from ..geometry.measure import mean_edge_length
from ..io.units import RADIANCE_UNIT, unit_metadata
from ..scatter.budget import DEFAULT_TIME_LIMIT_S
from ..scatter.names import DEFAULT_BOUNCES, DEFAULT_METHOD, DEFAULT_MODEL, DEFAULT_TOL
from .display import display_colors
from .settings import DEFAULT_MATERIAL, ShadeSettings, parse_resolution, resolve_medium  # noqa: F401  (resolve_medium re-exported)

#: The embedded default scan: the watertight Stanford bunny inside the pymeshlab wheel, stored
#: normalised to a unit diagonal; it is scaled to this width (mm), the size of the original figurine.
DEFAULT_SCAN_WIDTH_MM = 155.0
#: From the object toward the default light, in the display frame (right, up, front; see
#: :func:`translucency.io.upright.display_frame`): above, in front and a little to the right. For a
#: scan whose up is +y (the default bunny) this is the direction in the scan's own coordinates too.
DEFAULT_LIGHT_DIRECTION = (0.35, 1.0, 0.45)

#: The detail the light can show after diffusing (:func:`proxy_edge_length`, the viewer's interactive proxy and the
#: coarsest "auto" proxy): no edges shorter than min(PROXY_DIFFUSION_FRACTION / max sigma_tr,
#: PROXY_MEAN_FREE_PATHS / max sigma_t'), a fraction of the shortest diffusion length and a few reduced mean free
#: paths, which set how sharp a shadow edge stays. Meshes finer than PROXY_MIN_RATIO times a proxy's edge are
#: decimated to it; the result is interpolated back to every vertex of the full mesh. The near field is still
#: integrated over the proxy's real triangles, so only where B is computed changes.
PROXY_DIFFUSION_FRACTION = 0.5
PROXY_MEAN_FREE_PATHS = 5.0
PROXY_MIN_RATIO = 1.5
#: Resolution "auto" (the default) takes a proxy only where its error is within the tolerance asked for
#: (:func:`auto_proxy_edge`, docs/physics.md §8.6): a proxy of edge h was off by up to about AUTO_PROXY_ERROR_SLOPE
#: * rate * h at the 99th percentile of vertices, rate = max(max sigma_tr, AUTO_RATE_PER_SIGMA_T * max sigma_t',
#: AUTO_RATE_FLOOR_PER_MM). Measured with the far field at 1 % (bench/README.md, "Proxy error, measured apart",
#: "Scaling and memory", "Automatic resolution"), the ratio of that error to sigma_tr * h was up to 1.22 (the shared
#: Igea in marble, h = 0.42 diffusion lengths, 51 % against the full solve), 0.75-0.99 on the horse and the Igea,
#: 0.54-0.71 on the bunny's 2 mm proxies, 0.4 on the Igea's 0.5 mm proxy (0.13, 5.2 %), 0.65 and 1.06 on the 2.1M-
#: and 10M-vertex Igea's (0.046 and 0.040; 3.0 and 4.3 % against exact). Where the light diffuses little over a
#: reduced mean free path or over the object, sigma_tr alone undercounts: marble at a diffuse reflectance of 0.99 was
#: 13 % off on a 0.9 mm proxy of the Igea (sigma_t' h = 2.7), soy milk (mean free path 12 mm, diffusion length 35 mm)
#: 5 % off exact on a 0.8 mm one and 22 % on a 2.8 mm one, about 8 % per mm of edge: the scan's own relief in the flux.
AUTO_PROXY_ERROR_SLOPE = 1.25
AUTO_RATE_PER_SIGMA_T = 0.1
AUTO_RATE_FLOOR_PER_MM = 0.1
#: A proxy keeps at least this many triangles. On an object only a few diffusion lengths across (a
#: scan read in the wrong unit, say) the "auto" and the viewer's edge lengths are shortened to it,
#: and a proxy edge length given that leaves fewer is refused with a sentence.
PROXY_MIN_TRIANGLES = 200


#: From a scan of this many vertices on, the Embree scenes (the scan's, or its proxy's) are let go once the incident
#: light is traced, so that they are not held through the solve's set-up and plan (where a scan's bake peaks:
#: +360 MB at 2.1M vertices, about 1.7 GB at 10M); the bounce builds the solver mesh's again (4 s at 2.1M, 2 s for
#: the 10M scan's proxy). Below, a viewer's next light reuses them.
RELEASE_SCENE_VERTICES = 1_000_000


#: From this many vertices on, the solve at the resolution asked for is planned with every vertex that faces a
#: light lit before the light's shadows are traced, and refused at once when that plan is over
#: EARLY_REFUSAL_FACTOR times a budget (the 10M-vertex Igea: 10 times the time limit): no Embree scene of the full
#: mesh is built (19.5 s and 3.8 GB at 20M triangles); its proxy's light is traced at every vertex against the
#: proxy's surface (:meth:`Scene.solver_light`). What the plan makes (the ordered surface, the source tree) the
#: solve reuses; the plan's sample costs about 1 s at 1M vertices. A proxy made because that resolution was over
#: budget is sized to fit, and is not planned twice (3 s at 1.1M vertices). The factor allows for the light the
#: shadows take away: on the 10M-vertex Igea under the default light the plan with them was 19 % below (52 min
#: against 64); at 1.25 the 2.1M-vertex Igea (7 min against 5) is refused before the Embree scene of its 4.2M
#: triangles is built, which had taken its bake from a 2.5 GB peak to 3.6 GB. A scan whose shadows take away more
#: than a fifth of its light may be solved on a proxy where its full solve would have fitted.
EARLY_PLAN_VERTICES = 1_000_000
EARLY_REFUSAL_FACTOR = 1.25

#: A proxy whose edge ``h`` is at most this many diffusion lengths (``max σ_tr · h``) is given the light traced at
#: every vertex of the full mesh, carried onto its vertices with the flux kept; a coarser one traces its own
#: (docs/physics.md §8.6). Measured (bench/README.md, "Scaling and memory" and "Proxy error, measured apart"): on
#: the 10M-vertex Igea's proxy (0.04) the per-vertex p99 fell from 19 % to 3.2-4.3 %, on the 2.1M one's from 9.2 % to
#: 2.7-3.0 %; on the Igea's 0.5 mm proxy (0.13) it was 5.7 % against 5.2 %, and on the proxies of proxy_edge_length
#: and the bunny's 2 mm ones (0.42-0.57) 49-68 % against 36-51 %: the carried flux is spread over a proxy edge, which a
#: fine proxy does not see and a coarse one does.
CARRIED_LIGHT_MAX_SIGMA_TR_EDGE = 0.1


def carries_full_light(medium, edge) -> bool:
    """Whether a proxy of edge ``edge`` (mm, None for the full mesh) is given the full mesh's light carried onto it
    (:data:`CARRIED_LIGHT_MAX_SIGMA_TR_EDGE`) rather than the light traced at its own vertices."""
    return edge is not None and float(np.max(medium.sigma_tr)) * edge <= CARRIED_LIGHT_MAX_SIGMA_TR_EDGE


def coarsest_proxy_edge(surface_area: float) -> float:
    """Longest proxy edge (mm) that leaves :data:`PROXY_MIN_TRIANGLES` equilateral triangles on
    ``surface_area`` (mm²)."""
    return float(np.sqrt(surface_area / (PROXY_MIN_TRIANGLES * np.sqrt(3.0) / 4.0)))


def default_light_direction(up: str = "+y") -> np.ndarray:
    """Direction (unit-free, scan coordinates) from the object toward the default light for an up axis.

    :data:`DEFAULT_LIGHT_DIRECTION` turned from the display frame into the scan's frame: above the
    scan along ``up`` (``"+x"`` ... ``"-z"``) and in front of it.
    """
    from ..io.upright import to_scan_frame

    return to_scan_frame(DEFAULT_LIGHT_DIRECTION, up)


#: Over budget: attempts at a coarser proxy, the fraction of the budget the proxy aims at (the estimate's
#: margin), and the fewest vertices a proxy may keep (below: stop with a sentence instead).
COARSER_ATTEMPTS = 3
COARSER_MARGIN = 0.7
#: How the solve's estimated time grows with the vertex count: every pair for ``exact``; for the others the
#: estimate fell 9.8 times from the 10M-vertex Igea to a 1.92M proxy of it (n^1.4: fewer clusters open per
#: receiver on a coarser mesh).
COARSER_TIME_EXPONENT = {"exact": 2.0, "tree": 1.4, "cutoff": 1.4}
MIN_PROXY_VERTICES = 1000
#: Relative RMS error of B on a proxy against ``exact`` on the full mesh, by the fraction of vertices the
#: proxy keeps: the worst of the proxy rows of bench/README.md (bunny, horse, Igea; marble, skim milk,
#: ketchup; tree at 0.01) at that fraction or more. Per vertex it is far larger where B is small (the 99th
#: percentile: 9 % on the 2.1M-vertex Igea kept at 54 %, 30-80 % in marble and more in ketchup on the
#: bunny and the horse), which the proxy's warning says in words.
PROXY_ERRORS = ((0.45, "2 %"), (0.2, "4 %"), (0.09, "6 %"), (0.05, "7 %"), (0.02, "9 %"))


def proxy_edge_length(medium) -> float:
    """Edge length (mm) of the detail the light can show in this medium (:data:`PROXY_DIFFUSION_FRACTION`; without
    absorption, where the diffusion length is infinite, the mean free paths' part alone)."""
    sigma_tr = float(np.max(medium.sigma_tr))
    edge = PROXY_MEAN_FREE_PATHS / float(np.max(medium.sigma_t_reduced))
    return edge if sigma_tr == 0 else min(edge, PROXY_DIFFUSION_FRACTION / sigma_tr)


def auto_proxy_edge(medium, tol) -> float:
    """Proxy edge length (mm) of resolution "auto" at the per-vertex tolerance ``tol`` (a fraction): the longest
    edge whose expected error is within it, ``tol / (AUTO_PROXY_ERROR_SLOPE rate)`` with ``rate`` (1/mm) the largest
    of max σ_tr, a tenth of max σ_t′ and 0.1/mm (:data:`AUTO_PROXY_ERROR_SLOPE`, docs/physics.md §8.6), and no
    longer than :func:`proxy_edge_length`."""
    return min(float(tol) / (AUTO_PROXY_ERROR_SLOPE * _auto_rate(medium)), proxy_edge_length(medium))


def fine_enough_for(edge, mean_edge) -> bool:
    """Whether a mesh of mean edge ``mean_edge`` (mm) is fine enough to be decimated to a proxy of edge ``edge`` (mm)
    by "auto" (:data:`PROXY_MIN_RATIO` times finer)."""
    return edge >= PROXY_MIN_RATIO * mean_edge


def _auto_rate(medium) -> float:
    """How fast a proxy's error grows with its edge (1/mm, :data:`AUTO_PROXY_ERROR_SLOPE`)."""
    return max(
        float(np.max(medium.sigma_tr)),
        AUTO_RATE_PER_SIGMA_T * float(np.max(medium.sigma_t_reduced)),
        AUTO_RATE_FLOOR_PER_MM,
    )


def default_scan_path() -> Path:
    """Path of the embedded default scan (``pymeshlab/tests/sample_meshes/bunny.obj``)."""
    path = resources.files("pymeshlab") / "tests" / "sample_meshes" / "bunny.obj"
    if not path.is_file():
        raise TranslucencyError(
            "the embedded default scan (pymeshlab/tests/sample_meshes/bunny.obj) is missing from the "
            "installed pymeshlab; reinstall it (pip install --force-reinstall 'pymeshlab==2025.7.*') or pass "
            "a mesh file."
        )
    return Path(str(path))


def load_default_scan():
    """The embedded default scan as a :class:`~translucency.geometry.mesh.TriangleMesh`, 155 mm across."""
    from ..io.load import load_mesh, read_mesh_arrays

    path = default_scan_path()
    points, _, _ = read_mesh_arrays(path)
    width = float(np.max(points.max(axis=0) - points.min(axis=0)))
    return load_mesh(path, unit=DEFAULT_SCAN_WIDTH_MM / width)


@dataclass
class ShadeResult:
    """Everything :func:`shade` computed for one mesh: per-vertex arrays over ``mesh.points``, the settings.

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
        kept from earlier calls of the :class:`Scene`), ``coarser`` (the proxy line, or None),
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
        solve with the full mesh's light carried onto the proxy (:func:`carries_full_light`) it is that light,
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
        from .exports import result_polydata

        return result_polydata(self)

    def camera_position(self) -> list:
        """The default view of the result as PyVista takes it (``plotter.camera_position`` or
        ``mesh.plot(cpos=...)``): ``[eye, focal point, view up]`` in mm, in front of the scan and a little
        above, its up axis (``metadata["up"]``) up -- the view of the tool's own pictures, where PyVista's
        default camera would take +z as up."""
        from ..io.upright import up_vector
        from .render import camera_position, default_camera_direction

        up = self.metadata.get("up", "+y")
        points = np.asarray(self.mesh.points)
        low, high = points.min(axis=0), points.max(axis=0)
        return camera_position(
            0.5 * (low + high), float(np.linalg.norm(high - low)), default_camera_direction(up), tuple(up_vector(up))
        )


class Scene:
    """One mesh prepared for repeated shading, keeping every piece of work that a new call can reuse.

    What is kept, and when it is reused (reported in ``ShadeResult.stats["reused"]``):

    * the solver mesh (full, or a proxy per edge length) with its geometry caches -- vertex areas,
      near-triangle lists (per near radius), the source tree -- reused whatever the light and the
      material;
    * the Embree scene and the visibility of every light sample (:class:`VisibilityCache`), reused
      when only the material changes (or when a light comes back);
    * the incident light per (lights, eta, shadows), reused when only the coefficients change;
    * that the resolution asked for would take longer than the time limit, per settings and lights: the same
      shade asked again goes straight to the proxy (its line said again).

    A viewer keeps one ``Scene`` and calls :meth:`shade` on every change; :func:`shade` is the
    one-call form.

    Parameters
    ----------
    mesh : TriangleMesh or pyvista.PolyData
        A cleaned mesh in mm with outward orientation, or a PolyData (any PyVista dataset) in ``unit``,
        converted and repaired (:func:`mesh_for_shading`); :attr:`mesh` is the mesh shaded.
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
        from ..io.upright import parse_up
        from ..scatter.visibility import VisibilityCache

        self.mesh = mesh_for_shading(mesh, unit, entry="Scene")
        self.shadows = bool(shadows)
        self.up_requested = parse_up(up)
        self._up = None if self.up_requested == "auto" else self.up_requested
        self.visibility = VisibilityCache()
        self._solver_meshes: dict = {}
        self._incident: dict = {}
        self._normals = None
        self._areas = None
        self._mean_edge = None
        self._refused: dict = {}

    @property
    def up(self) -> str:
        """The up axis, ``"+x"`` ... ``"-z"`` (inferred on first use when it was ``"auto"``)."""
        if self._up is None:
            from ..io.upright import resolve_up

            self._up = resolve_up("auto", self.mesh.points, self.mesh.triangles)
        return self._up

    def solver_mesh(self, medium, resolution="full", tol=DEFAULT_TOL):
        """``(solver mesh, Decimation or None, edge or None, SurfaceGeometry, reused)`` for a resolution (``tol``: the
        per-vertex tolerance that sets the edge of "auto", :func:`auto_proxy_edge`)."""
        from ..scatter.solve import SurfaceGeometry

        if self._mean_edge is None:
            self._mean_edge = mean_edge_length(self.mesh.points, self.mesh.triangles)
        edge = _proxy_edge(self._mean_edge, medium, resolution, tol, self.mesh)
        key = None if edge is None else round(edge, 9)  # decided before decimating: a cache hit costs nothing
        if key in self._solver_meshes:
            return (*self._solver_meshes[key], True)
        mesh, decimation, edge = _solver_mesh(self.mesh, edge)
        full = decimation is None
        geometry = SurfaceGeometry(
            mesh.points,
            mesh.triangles,
            self._full_normals() if full else mesh.vertex_normals(),
            mean_edge_mm=self._mean_edge if full else None,
            vertex_areas_mm2=self._full_areas() if full else None,
        )
        self._solver_meshes[key] = (mesh, decimation, edge, geometry)
        return mesh, decimation, edge, geometry, False

    def incident(self, geometry, triangles, lights, eta, per_direction=False):
        """Incident light on a solver mesh, memoised per (mesh, lights, eta, shadows); ``(light, reused)``."""
        from ..scatter.irradiance import incident_flux

        key = (id(geometry), *_light_key(lights, eta, per_direction))
        if key in self._incident:
            return self._incident[key], True
        light = incident_flux(
            geometry.points,
            geometry.normals,
            geometry.vertex_areas,
            lights,
            eta,
            triangles=triangles if self.shadows else None,
            cache=self.visibility,
            per_direction=per_direction,
        )
        self._remember_light(key, light)
        return light, False

    def incident_on_mesh(self, medium, lights, per_direction=False):
        """Incident light at every vertex of the full mesh, memoised per (lights, eta, shadows) and kept across
        proxies; ``(light, reused)``."""
        from ..scatter.lights import as_light_list

        return self._light_on_full_mesh(as_light_list(lights), medium.eta, per_direction)

    def solver_light(self, geometry, solver_mesh, decimation, lights, eta, per_direction=False):
        """Incident light on the solver mesh, memoised as :meth:`incident`; ``(light, reused)``.

        With a ``decimation`` (a proxy, see :func:`carries_full_light`) it is the light at every vertex of the full
        mesh (:meth:`full_light_for_proxy`: its own normals and relief) carried onto the proxy's vertices with its flux
        kept (:func:`translucency.scatter.irradiance.carried_light`, docs/physics.md §8.6). Kept with it is only the
        full mesh's flux density (:meth:`flux_on_full_mesh`), not the whole light: at 10M vertices its four arrays are
        1 GB, held through the solve where a bake peaks; another material (another ``eta``) traces it again.
        """
        from ..scatter.irradiance import carried_light

        if solver_mesh is self.mesh:
            return self._light_on_full_mesh(lights, eta, per_direction)
        if decimation is None:
            return self.incident(geometry, solver_mesh.triangles, lights, eta, per_direction)
        key = self._carried_key(geometry, lights, eta, per_direction)
        if key in self._incident:
            return self._incident[key][0], True
        full, _ = self.full_light_for_proxy(geometry, solver_mesh, decimation, lights, eta, per_direction)
        light = carried_light(full, decimation.gather, geometry.normals, geometry.vertex_areas)
        self._drop_full_mesh_lights()  # the whole light: its flux density is kept with the carried light
        self._remember_light(key, (light, full.phi_rgb))
        return light, False

    def flux_on_full_mesh(self, geometry, lights, eta, per_direction=False) -> np.ndarray:
        """The flux density (n, 3), W/m², at every vertex of the full mesh of the light carried onto the proxy
        ``geometry`` by :meth:`solver_light` (which must have run for it)."""
        return self._incident[self._carried_key(geometry, lights, eta, per_direction)][1]

    @staticmethod
    def _carried_key(geometry, lights, eta, per_direction):
        # not the key of :meth:`incident`, which traces on the proxy itself; the first item is the mesh's, as there
        return (id(geometry), *_light_key(lights, eta, per_direction), "carried")

    def full_light_for_proxy(self, geometry, solver_mesh, decimation, lights, eta, per_direction=False):
        """The light at every vertex of the full mesh that a proxy is given, ``(light, reused)``: the one traced
        against the full mesh when a refused resolution traced it, else traced now from every vertex of the full mesh
        (its own normals) against the proxy's surface, whose Embree scene is a ninth of the full mesh's (at 10M
        vertices 2 s to build instead of 19.5 s, and 3.8 GB less at its peak; measured on the 10M-vertex Igea, the
        per-vertex p99 4.0 % instead of 3.7 %). Each ray starts off its vertex along the vertex normal by the vertex's
        distance from the proxy (``decimation``'s mapping), then by the proxy's own offset, so that no vertex under
        the proxy's surface is shadowed by it; a point light's distance and direction are measured from there too
        (a relative change of about twice that distance over the light's). The visibility is kept in the Scene's
        cache, so another material traces no ray again."""
        light_key = _light_key(lights, eta, per_direction)
        key = (id(geometry), *light_key, "full mesh")
        for known in (("full mesh", *light_key), key):  # traced against the full mesh, or against this proxy
            if known in self._incident:
                return self._incident[known], True
        if not self.shadows:
            light = self._traced_on_full_mesh(self.mesh.points, lights, eta, per_direction)
        else:
            normals = self._full_normals()
            light = self._traced_on_full_mesh(
                self.mesh.points + decimation.mapping.distance[:, None] * normals,
                lights,
                eta,
                per_direction,
                occluder=self.visibility.occluder(geometry.points, solver_mesh.triangles)[0],
            )
        self._remember_light(key, light)
        return light, False

    def _light_on_full_mesh(self, lights, eta, per_direction=False):
        """Incident light traced at every vertex of the full mesh, ``(light, reused)``; kept when a resolution is
        refused and across proxies (a solver mesh's own light, :meth:`incident`, is dropped with it)."""
        key = ("full mesh", *_light_key(lights, eta, per_direction))
        if key in self._incident:
            return self._incident[key], True
        light = self._traced_on_full_mesh(
            self.mesh.points, lights, eta, per_direction, triangles=self.mesh.triangles if self.shadows else None
        )
        self._remember_light(key, light)
        return light, False

    def _traced_on_full_mesh(self, origins, lights, eta, per_direction, **visibility):
        """:func:`~translucency.scatter.irradiance.incident_flux` at every vertex of the full mesh (its normals and
        areas), the rays from ``origins`` (mm) against ``visibility``'s ``triangles`` or ``occluder``, the
        visibility kept in the Scene's cache."""
        from ..scatter.irradiance import incident_flux

        return incident_flux(
            origins,
            self._full_normals(),
            self._full_areas(),
            lights,
            eta,
            cache=self.visibility,
            per_direction=per_direction,
            **visibility,
        )

    def _full_normals(self) -> np.ndarray:
        """The full mesh's unit vertex normals, computed once (the solver's at full resolution and the result's)."""
        if self._normals is None:
            self._normals = self.mesh.vertex_normals()
        return self._normals

    def _full_areas(self) -> np.ndarray:
        """The full mesh's barycentric vertex areas (mm²), computed once (the solver's at full resolution and the
        light's at every vertex)."""
        if self._areas is None:
            self._areas = self.mesh.vertex_areas()
            self._areas.flags.writeable = False  # shared with the full-resolution SurfaceGeometry's cache
        return self._areas

    def _drop_full_mesh_lights(self) -> None:
        """Let go of every light traced at every vertex of the full mesh (against it, or against a proxy)."""
        for key in [key for key in self._incident if "full mesh" in (key[0], key[-1])]:
            del self._incident[key]

    def _remember_light(self, key, light) -> None:
        """Keep an incident light for its key: a few recent light set-ups, the oldest dropped first."""
        while len(self._incident) >= 8:
            self._incident.pop(next(iter(self._incident)))
        self._incident[key] = light

    def shade(
        self,
        material=DEFAULT_MATERIAL,
        lights=None,
        *,
        model=DEFAULT_MODEL,
        method=DEFAULT_METHOD,
        tol=DEFAULT_TOL,
        resolution="auto",
        exposure=None,
        per_direction=False,
        bounces=DEFAULT_BOUNCES,
        albedo="material",
        progress=None,
        memory_limit=None,
        time_limit=DEFAULT_TIME_LIMIT_S,
        warn=None,
    ) -> ShadeResult:
        """Translucent shading: ``B``, radiance toward the normal and display colours (see :func:`shade`)."""
        settings = ShadeSettings(
            material,
            model,
            method,
            tol,
            resolution,
            self.shadows,
            per_direction,
            exposure,
            memory_limit,
            time_limit,
            self.up_requested,
            bounces,
            albedo,
        )
        return self.shade_with(settings, lights, progress=progress, warn=warn)

    def shade_with(
        self, settings: ShadeSettings, lights=None, *, progress=None, warn=None, note=None, solver=None
    ) -> ShadeResult:
        """:meth:`shade` with validated :class:`~translucency.app.settings.ShadeSettings` (their ``shadows``
        and ``up`` are this Scene's, see :func:`scene_for`). ``note(line)``, when given, hears which proxy the
        resolution asked for chose and its expected error (a proxy forced by the budget goes to ``warn``).
        ``solver`` stands in for :func:`translucency.scatter.solve.solve` (the same arguments; a
        :class:`~translucency.app.distributed.BlockSolver` solves on a Dask cluster)."""
        from ..errors import BudgetError
        from ..scatter.fresnel import fresnel_transmittance
        from ..scatter.lights import DirectionalLight, as_light_list

        medium, model, method, tol = settings.material, settings.model, settings.method, settings.tol
        resolution, exposure, per_direction = settings.resolution, settings.exposure, settings.per_direction
        memory_limit, time_limit = settings.memory_limit, settings.time_limit
        timings = {}
        lights = as_light_list(
            lights if lights is not None else DirectionalLight(default_light_direction(self.up), 1.0)
        )
        limits = {"memory_limit": memory_limit, "time_limit": time_limit}
        coarsened = reason = None
        # the same solve asked again (a later shade of a script or a viewer) is not planned and refused again at
        # the resolution asked for when its time was over the limit: at 10M vertices that plan takes half a
        # minute and 4 GB beside the last result
        refusal_key = None if solver is not None else _refusal_key(settings, lights)
        auto_tol = DEFAULT_TOL if method == "exact" else tol  # what sets the edge of "auto"; exact has no tolerance
        first_attempt = 0
        if refusal_key in self._refused:
            reason, resolution = self._refused[refusal_key]
            first_attempt = 1
        for attempt in range(first_attempt, COARSER_ATTEMPTS + 1):
            start = time.perf_counter()
            solver_mesh, decimation, edge, geometry, geometry_reused = self.solver_mesh(medium, resolution, auto_tol)
            timings["geometry"] = timings.get("geometry", 0.0) + time.perf_counter() - start
            solve_with = _albedo_solver(solver_mesh, settings.albedo, solver)
            try:
                if solver is None and method != "relight":  # a size no solve fits: no light traced for it
                    _check_size_floor(geometry, medium.n_channels, method, limits)
                    if attempt == 0 and geometry.n_vertices >= EARLY_PLAN_VERTICES:  # a proxy is sized to fit
                        _check_unshadowed_plan(geometry, lights, settings, limits)
                start = time.perf_counter()
                carried = carries_full_light(medium, edge)
                if decimation is not None and not carried:  # a refused resolution's light: not held beside the proxy's
                    self._drop_full_mesh_lights()
                incident, incident_reused = self.solver_light(
                    geometry, solver_mesh, decimation if carried else None, lights, medium.eta, per_direction
                )
                timings["incident_light"] = timings.get("incident_light", 0.0) + time.perf_counter() - start
                if self.mesh.n_points >= RELEASE_SCENE_VERTICES:  # not held through the solve's set-up
                    self.visibility.release_scenes()
                # a proxy "auto" chose spends the tolerance on its own error (AUTO_PROXY_ERROR_SLOPE was measured
                # with the far field at the default tolerance on the proxy): its far field is held to that
                solve_tol = min(tol, DEFAULT_TOL) if decimation is not None and resolution == "auto" else tol
                solutions = _solve(
                    geometry, incident, medium, model, method, solve_tol, progress, per_direction, limits, solve_with
                )
                bounced = self._bounces(
                    geometry, solver_mesh, solutions, lights, settings, solve_tol, progress, limits, solve_with
                )
                break
            except BudgetError as exc:
                reason = reason or budget_phrase(exc.estimate)  # of the resolution asked for
                resolution = self._coarser(solver_mesh, exc, attempt, method)
                if attempt == 0 and refusal_key is not None and not exc.estimate.over_memory:
                    # over time only: that estimate depends on the settings and lights alone (the memory
                    # budget depends on what the machine holds at the time, and is planned again)
                    self._refused[refusal_key] = (reason, resolution)
                # what the resolution that did not fit built (geometry caches, Embree, incident light) is freed
                # before the proxy is made: at scan size it is most of the memory held
                self._forget(geometry)
                solver_mesh = geometry = incident = None
        if reason is not None:
            expected = f"up to about {_expected_proxy_error(medium, edge)} at the 99th percentile of vertices" + (
                ", given the light traced at every vertex"
                if carried
                else f" (relative RMS about {proxy_error(solver_mesh.n_points / self.mesh.n_points)})"
            )
            coarsened = (
                f"solving on a proxy of {solver_mesh.n_points:,} of the {self.mesh.n_points:,} vertices "
                f"(edge {edge:.3g} mm), since the resolution asked for {reason}; expected {expected} (proxy "
                f"measurements in bench/README.md); raise the limit to solve every vertex."
            )
            (warn or _warn)(coarsened)
        elif decimation is not None and note is not None:
            note(_proxy_line(settings.resolution, auto_tol, medium, solver_mesh.n_points, self.mesh.n_points, edge))
        B = sum(solution.B for solution in solutions)
        for solution in solutions:
            for k, v in solution.timings.items():
                timings[f"solve_{k}"] = timings.get(f"solve_{k}", 0.0) + v
        reentered = None
        if bounced is not None:
            reentered = bounced.B
            timings["bounce_gather"] = bounced.stats["seconds"]["gather"] + bounced.stats["seconds"]["specular"]
            timings["bounce_solve"] = bounced.stats["seconds"]["solve"]
            B = B + reentered
        phi = incident.phi_rgb
        if decimation is not None:
            start = time.perf_counter()
            B = np.maximum(decimation.interpolate(B), 0.0)
            phi = (  # what entered, traced at every vertex; or what the proxy's own light saw (ShadeResult)
                self.flux_on_full_mesh(geometry, lights, medium.eta, per_direction)
                if carried
                else np.maximum(decimation.interpolate(phi), 0.0)
            )
            if reentered is not None:
                reentered = np.maximum(decimation.interpolate(reentered), 0.0)
            timings["interpolate_to_full"] = time.perf_counter() - start
        radiance = float(fresnel_transmittance(1.0, medium.eta)) * B  # L toward the normal, T21(eta, 1) B
        colors, exposure = display_colors(radiance, exposure)
        metadata = {
            **settings.metadata(
                lights, "full" if decimation is None else f"proxy, {solver_mesh.n_points} vertices, edge {edge:.3g} mm"
            ),
            "shadows": self.shadows,
            "exposure": exposure,
            **unit_metadata(self.mesh.mm_per_unit, self.mesh.unit_inferred),
            "radiance_unit": RADIANCE_UNIT,
            "up": self.up,
            "up_inferred": self.up_requested == "auto",
            "budget": {"memory_limit_gb": memory_limit, "time_limit_s": time_limit, "coarser": coarsened},
        }
        reused = [
            name
            for name, flag in (
                ("geometry", geometry_reused),
                ("incident light", incident_reused),
                ("Embree scene", incident.stats.scene == "reused"),
                ("relight operators", any(s.stats.get("operators_reused") for s in solutions)),
                ("the refusal of the resolution asked for", first_attempt > 0),
            )
            if flag
        ]
        if incident.stats.n_visibility_reused:
            reused.append(f"visibility of {incident.stats.n_visibility_reused} light samples")
        solver_stats = (
            solutions[0].stats
            if len(solutions) == 1
            else {
                "solves": len(solutions),
                **{
                    k: sum(s.stats.get(k, 0) for s in solutions)
                    for k in ("pairs_evaluated", "pairs_skipped", "near_points")
                },
            }
        )
        stats = {
            "incident": incident.stats.as_dict(),
            "solver": solver_stats,
            "reused": reused,
            "coarser": coarsened,
            "solver_vertices": solver_mesh.n_points,
            "vertices": self.mesh.n_points,
            "bounces": _bounce_stats(bounced, B),
        }
        return ShadeResult(
            self.mesh, B, radiance, colors, exposure, self._full_normals(), stats, timings, metadata, phi, reentered
        )

    def _bounces(self, geometry, solver_mesh, solutions, lights, settings, tol, progress, limits, solver=None):
        """The light that re-enters (:func:`translucency.scatter.bounces.solve_bounces`) after the first
        solve, on the solver mesh with this Scene's Embree scene, at the first solve's ``tol``; None for
        ``bounces=0``."""
        if not settings.bounces:
            return None
        from ..scatter.bounces import solve_bounces

        occluder, _ = self.visibility.occluder(geometry.points, solver_mesh.triangles)
        return solve_bounces(
            geometry,
            occluder,
            sum(solution.B for solution in solutions),
            lights,
            settings.material,
            bounces=settings.bounces,
            model=settings.model,
            method=settings.method,
            tol=tol,
            shadows=self.shadows,
            progress=progress,
            solver=solver,
            **limits,
        )

    def _forget(self, geometry) -> None:
        """Drop the solver mesh of ``geometry``, its incident light and the Embree scenes and visibility."""
        for key, kept in list(self._solver_meshes.items()):
            if kept[3] is geometry:
                del self._solver_meshes[key]
        for key in [key for key in self._incident if key[0] == id(geometry)]:
            del self._incident[key]
        self.visibility.clear()

    def _coarser(self, solver_mesh, exc, attempt, method="tree"):
        """The edge length (mm) of a proxy whose solve should fit the budget ``exc`` was over;
        ``exc`` again when that proxy would keep too few vertices or the attempts are spent."""
        plan = exc.estimate
        # memory grows linearly with the vertex count, time as n^COARSER_TIME_EXPONENT: one decimation should
        # reach a proxy that fits (a square-root law for every method had decimated 10M vertices twice)
        shares = [COARSER_MARGIN * plan.budget_bytes / plan.peak_bytes] if plan.over_memory else []
        if plan.over_time:
            exponent = COARSER_TIME_EXPONENT.get(method, COARSER_TIME_EXPONENT["tree"])
            shares.append((COARSER_MARGIN * plan.time_limit / plan.seconds) ** (1.0 / exponent))
        target = int(solver_mesh.n_points * min(shares or [COARSER_MARGIN]))
        if attempt >= COARSER_ATTEMPTS or target < MIN_PROXY_VERTICES:
            raise exc
        if self._mean_edge is None:
            self._mean_edge = mean_edge_length(self.mesh.points, self.mesh.triangles)
        return self._mean_edge * (self.mesh.n_points / target) ** 0.5


def _light_key(lights, eta, per_direction) -> tuple:
    """What an incident light depends on besides the mesh and its shadows: the lights, ``eta``, per direction."""
    return repr([light.to_dict() for light in lights]), float(eta), per_direction


def _refusal_key(settings: ShadeSettings, lights) -> str:
    """What decides whether a solve fits its time limit: every setting but the exposure (the material's
    coefficients, model, method, tolerance, resolution, bounces, the limits ...) and the lights, as one string.
    (Whether it fits the memory budget also depends on what the machine holds at the time.)"""
    import json

    described = settings.metadata(lights, str(settings.resolution))
    described["limits"] = [settings.memory_limit, settings.time_limit]
    return json.dumps(described, sort_keys=True, default=str)


def _bounce_stats(bounced, B) -> dict:
    """``stats["bounces"]`` of a result: bounces done, rays, seconds of the gather and of the extra
    solves, and the share of ``B`` (summed over the vertices, per channel) that re-entered."""
    if bounced is None:
        return {"bounces": 0}
    total = np.asarray(B, dtype=np.float64).sum(axis=0)
    share = np.asarray(bounced.B, dtype=np.float64).sum(axis=0) / np.where(total > 0.0, total, np.inf)
    return {**bounced.stats, "share_of_B": share.tolist()}


def budget_phrase(plan) -> str:
    """``"would need about 25 GB of memory (budget 3.6 GB)"`` or the same for time, from an estimate."""
    from ..scatter.budget import format_bytes, format_seconds

    if plan.over_memory:
        return (
            f"would need about {format_bytes(plan.peak_bytes)} of memory ({option('memory_limit')} budget "
            f"{format_bytes(plan.budget_bytes)})"
        )
    return f"would take about {format_seconds(plan.seconds)} ({option('time_limit')} {format_seconds(plan.time_limit)})"


def proxy_error(fraction: float) -> str:
    """Expected relative RMS error of ``B`` on a proxy keeping ``fraction`` of the vertices (:data:`PROXY_ERRORS`)."""
    for kept, error in PROXY_ERRORS:
        if fraction >= kept:
            return error
    return f"more than {PROXY_ERRORS[-1][1]} (coarser than measured)"


def _warn(message: str) -> None:
    import warnings

    from ..errors import TranslucencyWarning

    warnings.warn(message, TranslucencyWarning, stacklevel=3)


def _check_unshadowed_plan(geometry, lights, settings: ShadeSettings, limits) -> None:
    """A :class:`~translucency.errors.BudgetError` when the solve's plan with every vertex that faces a light lit
    (:func:`translucency.scatter.solve.plan`, no shadow ray traced) is over :data:`EARLY_REFUSAL_FACTOR` times a
    budget. Shadows only take light away (19 % of the 10M-vertex Igea's plan under the default light), so the solve
    with them would most likely be over its budget too, and no Embree scene of the full mesh need be built at a
    size that is then not solved (19.5 s and 3.8 GB at 10M vertices)."""
    from ..errors import BudgetError
    from ..scatter.irradiance import incident_flux
    from ..scatter.solve import over_budget_sentence, plan

    medium = settings.material
    facing = incident_flux(geometry.points, geometry.normals, geometry.vertex_areas, lights, medium.eta)
    estimate = plan(
        geometry,
        facing.phi_rgb,
        facing.w12,
        medium,
        model=settings.model,
        method=settings.method,
        tol=settings.tol,
        **limits,
    )
    del facing
    over_time = estimate.time_limit is not None and estimate.seconds > EARLY_REFUSAL_FACTOR * estimate.time_limit
    over_memory = (
        estimate.budget_bytes is not None and estimate.peak_bytes > EARLY_REFUSAL_FACTOR * estimate.budget_bytes
    )
    if over_time or over_memory:
        raise BudgetError(over_budget_sentence(estimate, geometry.n_vertices), estimate)


def _check_size_floor(geometry, n_channels, method, limits) -> None:
    """A :class:`~translucency.errors.BudgetError` when even the least a solve of this size needs
    (:func:`translucency.scatter.solve.size_floor_plan`) is over the limits."""
    from ..errors import BudgetError
    from ..scatter.solve import over_budget_sentence, size_floor_plan

    floor = size_floor_plan(geometry, n_channels, method, limits["memory_limit"], limits["time_limit"])
    if not floor.fits:
        raise BudgetError(over_budget_sentence(floor, geometry.n_vertices), floor)


def scan_reflectance(mesh) -> np.ndarray:
    """The scan's colour per vertex as its diffuse reflectance: ``(n, 3)`` linear values in [0, 1], the 8-bit
    sRGB colours decoded (docs/physics.md §6.5); a sentence when the scan has none."""
    from ..errors import InvalidParameterError, command_line_active
    from .display import srgb_decode

    colors = mesh.point_data.get("colors")
    if colors is None:
        name = Path(mesh.source).name if mesh.source is not None else "this mesh"
        flag = "--albedo-from-colors" if command_line_active() else 'albedo="vertex_colors"'
        raise InvalidParameterError(
            f"{name} has no vertex colours or texture to take the albedo from; drop {flag} or give a scan with "
            "colours (PLY red/green/blue, OBJ with a map_Kd texture, VTK 'colors')."
        )
    return srgb_decode(np.asarray(colors, dtype=np.float64)[:, :3] / 255.0)


def _albedo_solver(solver_mesh, albedo: str, solver=None):
    """The solve to call: ``solver`` (or :func:`translucency.scatter.solve.solve`) as it is for the
    material's albedo, or wrapped by :func:`translucency.scatter.varying.solve_varying` with the solver
    mesh's colours for ``"vertex_colors"``."""
    if albedo != "vertex_colors":
        return solver
    import functools

    from ..scatter.varying import solve_varying

    return functools.partial(solve_varying, reflectance=scan_reflectance(solver_mesh), solver=solver)


def _solve(geometry, incident, medium, model, method, tol, progress, per_direction, limits, solver=None):
    """The solver's :class:`Solution` list: one, or one per light sample with ``per_direction`` (``solver``:
    :func:`translucency.scatter.solve.solve` or what stands in for it)."""
    from ..scatter.solve import solve

    solve = solver or solve
    if per_direction:
        return _solve_per_direction(geometry, incident, medium, model, method, tol, progress, limits, solve)
    return [
        solve(
            geometry,
            incident.phi_rgb,
            incident.w12,
            medium,
            model=model,
            method=method,
            tol=tol,
            progress=progress,
            **limits,
        )
    ]


def _solve_per_direction(geometry, incident, medium, model, method, tol, progress, limits=None, solver=None):
    """One solve per light sample (each with its own refracted direction); their ``B`` add up."""
    from ..scatter.solve import solve

    solve = solver or solve
    n = geometry.n_vertices
    solutions = []
    for k, part in enumerate(incident.contributions):
        phi = np.zeros((n, 3))
        w12 = np.tile((0.0, 0.0, -1.0), (n, 1))
        phi[part.vertices] = part.phi_rgb
        w12[part.vertices] = part.w12
        inner = (
            None
            if progress is None
            else (lambda stage, fraction, k=k: progress(stage, (k + fraction) / len(incident.contributions)))
        )
        solutions.append(
            solve(geometry, phi, w12, medium, model=model, method=method, tol=tol, progress=inner, **(limits or {}))
        )
    return solutions


def shade(
    mesh,
    material=DEFAULT_MATERIAL,
    lights=None,
    *,
    model=DEFAULT_MODEL,
    method=DEFAULT_METHOD,
    tol=DEFAULT_TOL,
    shadows=True,
    resolution="auto",
    exposure=None,
    per_direction=False,
    bounces=DEFAULT_BOUNCES,
    albedo="material",
    up="auto",
    unit=None,
    progress=None,
    memory_limit=None,
    time_limit=DEFAULT_TIME_LIMIT_S,
    warn=None,
) -> ShadeResult:
    """Translucent shading of one mesh (mm): ``B``, radiance toward the normal and display colours.

    The one-call form of :class:`Scene` (nothing is kept between calls; keep a ``Scene`` to reuse work).

    Parameters
    ----------
    mesh : TriangleMesh or pyvista.PolyData
        A cleaned mesh in mm with outward orientation, or a PolyData (any PyVista dataset) in ``unit``,
        converted and repaired first (:func:`mesh_for_shading`; ``result.mesh`` is the mesh shaded).
    material : str or Material or Medium
        Catalogue name, catalogue entry or a :class:`~translucency.scatter.medium.Medium` (1/mm).
    lights : light or sequence of lights, optional
        Default: one white directional light of 1 W/m² from :func:`default_light_direction` of ``up``
        (above and in front of the scan). Directions are in the scan's own coordinates.
    model, method, tol
        Passed to :func:`translucency.scatter.solve.solve` (defaults and checks:
        :class:`~translucency.app.settings.ShadeSettings`).
    shadows : bool
        Cast Embree shadow rays (off: every front-facing vertex is lit).
    resolution : "auto", "full" or float
        Where ``B`` is computed: ``"auto"`` (default) on a proxy of :func:`auto_proxy_edge` where the mesh is
        much finer than that, so that the proxy's expected per-vertex error is within ``tol`` (at the default 1 %
        no scan measured is that fine: every vertex); ``"full"`` on every vertex; a number is a proxy edge length
        in mm. Measured on the shared Igea (134k vertices, 0.48 mm edges) in marble: at ``tol=0.45`` a proxy of
        19k vertices, 32 % off ``exact`` at the 99th percentile of vertices in a third of the time of every vertex
        at that ``tol`` (bench/README.md, "Automatic resolution").
    exposure : float, optional
        Display exposure (automatic by default, see :func:`~translucency.app.display.display_colors`).
    per_direction : bool
        Solve once per light sample with its own refracted direction and add the results (exact for
        several lights; the default aggregates the lights per vertex, see
        :mod:`translucency.scatter.irradiance`).
    bounces : int
        Times the light leaving the surface (subsurface exitance, mirror reflection of the lights) that
        reaches it again is let in and solved again (docs/physics.md §7.4; 0 to 8, default
        :data:`~translucency.scatter.names.DEFAULT_BOUNCES`); the rays are traced even with
        ``shadows=False``. ``result.reentered`` holds that part of ``B`` and ``result.stats["bounces"]``
        its rays, seconds and share.
    albedo : {"material", "vertex_colors"}
        ``"vertex_colors"``: the scan's colour per vertex (its texture sampled at the vertices for an OBJ)
        read as the diffuse reflectance, 8-bit sRGB decoded, with the material's mean free path, g and eta
        (:func:`translucency.scatter.varying.solve_varying`, docs/physics.md §6.5); several solves, one
        per reflectance level.
    up : str
        The scan's up axis (``"x"`` ... ``"-z"``, or ``"auto"``: inferred, see :mod:`translucency.io.upright`);
        only the default light and the metadata depend on it.
    unit : {"mm", "cm", "m", "in"} or float, optional
        A PolyData's length unit (None: its ``field_data["length_unit"]``, else inferred from its size).
    progress : callable, optional
        ``progress(stage, fraction)``, many times per stage during the solve.
    memory_limit : float, optional
        GB (2**30 bytes) the process may hold; the budget is the smaller of this and the available
        memory less head-room (:mod:`translucency.scatter.budget`).
    time_limit : float or None
        Seconds the solve may take by its estimate (default :data:`DEFAULT_TIME_LIMIT_S`; None: no limit).
        Over either budget the scan is solved on a coarser proxy that fits, said in one line to ``warn``
        with the expected error, or, when even that would be too coarse, a
        :class:`~translucency.errors.BudgetError` says what to change.
    warn : callable, optional
        ``warn(line)`` receives that line (default: a :class:`~translucency.errors.TranslucencyWarning`).
    """
    mesh = mesh_for_shading(mesh, unit, entry="shade")
    return Scene(mesh, shadows=shadows, up=up).shade(
        material,
        lights,
        model=model,
        method=method,
        tol=tol,
        resolution=resolution,
        exposure=exposure,
        per_direction=per_direction,
        bounces=bounces,
        albedo=albedo,
        progress=progress,
        memory_limit=memory_limit,
        time_limit=time_limit,
        warn=warn,
    )


def load_scan(path, unit=None, *, warn=None, note=None):
    """A mesh file (or the embedded default scan when ``path`` is None), loaded in ``unit`` and cleaned.

    ``unit`` None: inferred from the size (:func:`translucency.io.units.infer_unit`). Returns
    ``(mesh in mm, CleanReport or None, name)``. Warnings from loading (the unit inferred, an
    implausible size for the unit given) go to ``warn(message)`` when given; the line that says
    which unit was inferred goes to ``note(message)`` instead when that is given.
    """
    import warnings

    from ..io.clean import clean_mesh
    from ..io.load import load_mesh
    from ..io.units import UnitInferredWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if path is None:
            mesh, name = load_default_scan(), default_scan_path().stem
        else:
            mesh, name = load_mesh(path, unit=unit), str(path)
    for warning in caught:
        say = note if note is not None and issubclass(warning.category, UnitInferredWarning) else warn
        if say is not None:
            say(str(warning.message))
    mesh, report = clean_mesh(mesh)
    return mesh, report, name


def mesh_for_shading(mesh, unit=None, *, entry: str, stacklevel: int = 3):
    """The mesh an entry point shades: a :class:`~translucency.geometry.mesh.TriangleMesh` as it is (already
    cleaned, in mm), a ``pyvista.PolyData`` (or other PyVista dataset) converted in ``unit``
    (:func:`~translucency.io.polydata.as_triangle_mesh`: None reads its ``field_data["length_unit"]`` or
    infers the unit from the size) and repaired with :func:`~translucency.io.clean.clean_mesh`, as a scan
    file would be. ``stacklevel`` as in :func:`~translucency.io.polydata.as_triangle_mesh`."""
    from ..geometry.mesh import TriangleMesh
    from ..io.clean import clean_mesh
    from ..io.polydata import as_triangle_mesh

    if isinstance(mesh, TriangleMesh):
        return as_triangle_mesh(mesh, unit, entry=entry)
    mesh = as_triangle_mesh(mesh, unit, entry=entry, stacklevel=stacklevel + 1)
    return clean_mesh(mesh)[0]


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
    """A scan shaded with every setting of ``settings``: the pipeline's first half (:func:`write_result`
    is the second).

    Parameters
    ----------
    scan : path-like, TriangleMesh, pyvista.PolyData or None
        A scan file in ``unit`` (None: inferred from its size), loaded and cleaned by :func:`load_scan`;
        None for the embedded default scan; a PolyData in ``unit``, converted and cleaned
        (:func:`mesh_for_shading`); or a TriangleMesh already cleaned, in mm, used as it is.
    settings : ShadeSettings, optional
        Every setting of the solve (default: :class:`~translucency.app.settings.ShadeSettings`'s defaults).
    lights : light or sequence of lights, optional
        Default: the white directional light above and in front (:func:`default_light_direction`).
    progress, warn
        As in :func:`shade`; ``warn`` also receives the loader's warnings, and ``note`` the line that
        says which unit was inferred (default: ``warn``) and the one that says which proxy the resolution
        chose (:meth:`Scene.shade_with`; default: none).
    solver : callable, optional
        Stands in for :func:`translucency.scatter.solve.solve` (:meth:`Scene.shade_with`).

    Returns
    -------
    ShadeResult
        ``result.mesh`` is the cleaned mesh in mm.
    """
    from ..geometry.mesh import TriangleMesh
    from ..io.polydata import is_pyvista_mesh

    settings = ShadeSettings() if settings is None else settings
    if isinstance(scan, TriangleMesh) or is_pyvista_mesh(scan):
        mesh = mesh_for_shading(scan, unit, entry="shade_scan")
    else:
        mesh = load_scan(scan, unit, warn=warn, note=note)[0]
    return scene_for(mesh, settings).shade_with(
        settings, lights, progress=progress, warn=warn, note=note, solver=solver
    )


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
    from .exports import write_result_file

    return write_result_file(result, path)


def _proxy_line(resolution, tol, medium, proxy_vertices, vertices, edge) -> str:
    """The line that says which proxy ``resolution`` chose (at the tolerance ``tol`` for "auto"), and the error
    expected of it (:func:`_expected_proxy_error`)."""
    why = (
        f"which {option('tol', tol)} allows" if resolution == "auto" else f"as {option('resolution', resolution)} asks"
    )
    return (
        f"solving on a proxy of {proxy_vertices:,} of the {vertices:,} vertices (edge {edge:.3g} mm), {why}; expected "
        f"error up to about {_expected_proxy_error(medium, edge)} at the 99th percentile of vertices "
        f"({option('resolution', 'full')} solves every vertex)."
    )


def _expected_proxy_error(medium, edge) -> str:
    """The per-vertex error (99th percentile) expected of a proxy of edge ``edge`` (mm), in words:
    :data:`AUTO_PROXY_ERROR_SLOPE` times the rate of :func:`auto_proxy_edge` times the edge."""
    percent = 100 * AUTO_PROXY_ERROR_SLOPE * _auto_rate(medium) * edge
    return f"{percent:.2g} %" if percent < 100 else f"{percent:.0f} %"


def _proxy_edge(mean_edge, medium, resolution, tol, mesh):
    """Proxy edge length (mm) for a resolution (at the per-vertex tolerance ``tol`` for "auto") on ``mesh`` of
    ``mean_edge`` (mm), or None for the full mesh."""
    from ..errors import InvalidParameterError, option

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


def _solver_mesh(mesh, edge):
    """The mesh the solver runs on: ``(mesh or proxy, Decimation or None, proxy edge length or None)``."""
    from ..io.decimate import decimate_mesh

    if edge is None:
        return mesh, None, None
    decimation = decimate_mesh(mesh, target_edge_length=edge)
    if decimation.method == "none":
        return mesh, None, None
    return decimation.proxy, decimation, edge
