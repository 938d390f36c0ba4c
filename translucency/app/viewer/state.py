"""What the viewer shows, without a window: the settings, the Scene that solves again, the colours, the status.

:class:`ViewerState` holds every choice the controls change (light angles, material, model, scale,
exposure, the two view-dependent layers) and one persistent :class:`~translucency.app.shading.scene.Scene`.
Its ``set_*`` methods solve again when the change needs it and say whether the picture changed; it
hands out the per-vertex display colours ``sRGB(exposure L)`` and a status text. It never imports
PyVista or VTK: a window (:mod:`translucency.app.viewer.widgets`) or a test drives it the same way,
passing the camera position as a plain array when a view-dependent layer needs it.

By default ``L`` is the radiance toward the normal, ``T21(eta, 1) B`` (docs/physics.md §5.3), exactly
what a bake stores. Two optional layers depend on the view (recomputed when the camera moves; no new
solve):

* **view-dependent transmission** -- ``L = T21(eta, n . w_o) B`` with ``w_o`` toward the camera
  (darker at grazing angles, :func:`translucency.scatter.outgoing.subsurface_radiance`, §5.3);
* **specular highlight** -- the boundary's reflection of every directional light and environment
  sample (GGX, roughness ``alpha``; :func:`translucency.scatter.outgoing.specular_radiance`, §5.5), with
  the same Embree shadows as the solve. Point lights give no highlight.

Interactive resolution. By default (:data:`VIEWER_METHOD`, :data:`VIEWER_TOL`) every change relights every
vertex with the operators the ``Scene``'s surface keeps (prepared on the first solve and after a change of
material or model, with a note in the status while that runs; a proxy only where they would not fit the
memory budget). With another method, every change re-solves on the one ``Scene`` (geometry, Embree scene and
visibility are reused) on a proxy of about :data:`INTERACTIVE_VERTICES` vertices
(:func:`interactive_edge_length`), interpolated back to every vertex: small enough to answer in a
fraction of a second, fine enough that the error stays at a few percent away from the shadow
terminator, which the proxy moves by up to an edge (single vertices just past it can be many times
too bright). The measurements behind the default are in bench/README.md ("Interactive proxy").
:meth:`ViewerState.solve_full` solves what is shown on every vertex (with ``relight``: by ``tree`` at the
default tolerance, the accurate answer).

False colour. Instead of ``sRGB(exposure L)`` the viewer can show one number per vertex in physical
units, W/(m² sr) per W/m² of irradiance: the luminance ``Y`` of what is shown (or one channel), on a
log or a linear scale whose top is the radiance the sRGB view shows as white, ``1 / exposure``
(:func:`translucency.app.display.false_colour_range`). :meth:`ViewerState.set_false_colour` and
:meth:`ViewerState.set_false_colour_scale` choose it; :meth:`ViewerState.false_colour_values` and
:meth:`ViewerState.false_colour_range` are what a window maps through the colour map.
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import numpy as np

from ...errors import InvalidParameterError
from ...scatter.names import DEFAULT_TOL
from ..display import (
    FALSE_COLOUR_QUANTITIES,
    FALSE_COLOUR_SCALES,
    display_colors,
    false_colour_label,
    false_colour_range,
    false_colour_values,
)
from ..framing import DEFAULT_UP, frame_axes, front_direction, turned_to_front
from ..shading.resolution import coarsest_proxy_edge, proxy_edge_length
from ..shading.result import write_result
from ..shading.scan import mesh_for_shading
from ..shading.scene import Scene, scene_for
from ..shading.settings import (
    ShadeSettings,
    default_light_direction,
    resolve_medium,
    settings_with,
    viewer_settings,
)

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


def light_direction(azimuth, elevation, up=DEFAULT_UP) -> np.ndarray:
    """Unit direction toward a light at ``azimuth``, ``elevation`` (degrees) around ``up``.

    ``d = cos(e) (cos(a) e1 + sin(a) e2) + sin(e) up``: elevation is the angle above the plane
    perpendicular to ``up``; azimuth 0 is the world +z made perpendicular to ``up`` (+x when ``up`` is
    along z) and 90 is ``up x`` that (+x for ``up`` = +y).
    """
    up, e1, e2 = frame_axes(up)
    a, e = math.radians(azimuth), math.radians(elevation)
    return math.cos(e) * (math.cos(a) * e1 + math.sin(a) * e2) + math.sin(e) * up


def light_angles(direction, up=DEFAULT_UP) -> tuple[float, float]:
    """``(azimuth, elevation)`` in degrees of a direction (inverse of :func:`light_direction`)."""
    up, e1, e2 = frame_axes(up)
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    elevation = math.degrees(math.asin(float(np.clip(d @ up, -1.0, 1.0))))
    azimuth = math.degrees(math.atan2(float(d @ e2), float(d @ e1)))
    return azimuth, elevation


def diffusive_materials() -> list[str]:
    """Keys of the catalogue entries every diffusion model can represent (they scatter in every channel)."""
    from ...scatter.materials import catalogue

    return [entry.key for entry in catalogue() if entry.is_diffusive]


class ViewerState:
    """The viewer's settings and solution, with no window: what to show and how to change it.

    Every ``set_*`` method checks its value (a sentence on a bad one), solves again on the persistent
    :attr:`scene` when the change needs it, and returns whether the picture changed; :meth:`colors`
    and :attr:`status` are then what to draw. See the module docstring for what is shown.

    Parameters
    ----------
    mesh : TriangleMesh or pyvista.PolyData, optional
        A cleaned mesh in mm, or a PolyData in ``unit`` (converted and repaired,
        :func:`~translucency.app.shading.scan.mesh_for_shading`); default: the embedded default scan, cleaned.
    material : str or Material or Medium, optional
        Shortcut for the starting material (catalogue name, 1/mm coefficients).
    lights : light or sequence of lights, optional
        Directions in the scan's own coordinates. Default: one white directional light of 1 W/m²
        above and in front of the scan (:func:`~translucency.app.shading.settings.default_light_direction` of
        ``up``, turned about ``up`` with the camera to the scan's front, :mod:`translucency.app.framing`).
        :meth:`set_light` steers the first directional light.
    settings : ShadeSettings, optional
        The starting settings (default :func:`viewer_settings`: the viewer's method and tolerance), passed to
        :meth:`Scene.shade_with <translucency.app.shading.scene.Scene.shade_with>`; ``exposure`` is the display
        exposure (linear factor; automatic from the first solve by default, then kept, so that brightness changes
        between materials and lights stay visible), ``up`` the axis of the light's azimuth and where the default
        light is. With the scan's colours as its albedo, ``relight`` is solved by ``tree`` (one solve per
        reflectance level each change).
    **changes
        Any field of the settings by name (``tol=0.05``, ``up="z"``, ...), replacing the one of ``settings``.
    resolution : "interactive", "full", "auto" or float
        Where ``B`` is computed on a change: ``"interactive"`` (default) is every vertex with ``relight``
        (a proxy where its operators would not fit the memory budget), otherwise a proxy of about
        :data:`INTERACTIVE_VERTICES` vertices (:func:`interactive_edge_length`); the others are the
        shading policy's (a number is a proxy edge length in mm); it replaces the settings' resolution.
    view_dependent, specular : bool
        Show ``T21(eta, n . w_o) B`` instead of ``T21(eta, 1) B``; add the specular highlight.
    roughness : float
        GGX ``alpha`` of the highlight.
    name : str, optional
        Stem of saved files (default: the mesh's file name, or ``scan``).
    solve : bool
        Solve now (default); with ``False`` call :meth:`solve` before reading :attr:`result` or colours.
    unit : {"mm", "cm", "m", "in"} or float, optional
        A PolyData's length unit (None: its ``field_data["length_unit"]``, else inferred from its size).
    """

    def __init__(
        self,
        mesh=None,
        material=None,
        lights=None,
        *,
        settings: ShadeSettings | None = None,
        resolution="interactive",
        view_dependent=False,
        specular=False,
        roughness=0.25,
        name=None,
        solve=True,
        unit=None,
        **changes,
    ):
        from ...io.upright import up_vector
        from ...scatter.lights import DirectionalLight, as_light_list
        from ..shading.scan import load_scan

        # every setting checked once, before the scan is loaded ("interactive" is the viewer's own resolution)
        if material is not None:
            changes["material"] = material
        if resolution != "interactive":
            changes["resolution"] = resolution
        settings = settings_with(viewer_settings() if settings is None else settings, **changes)
        model, method, tol = settings.model, settings.method, settings.tol
        per_direction, shadows, exposure = settings.per_direction, settings.shadows, settings.exposure
        if mesh is None:
            mesh, _, default_name = load_scan(None)
            name = name or default_name
        else:
            mesh = mesh_for_shading(mesh, unit, entry="Viewer")
        self.base_mesh = mesh
        self.name = name or (Path(mesh.source).stem if mesh.source is not None else "scan")
        self.medium = settings.material
        self.model, self.method, self.tol = model, method, float(tol)
        self.resolution = resolution
        self.per_direction = bool(per_direction)
        self.bounces = settings.bounces
        self.albedo = settings.albedo
        self.limits = {"memory_limit": settings.memory_limit, "time_limit": settings.time_limit}
        self.shadows = bool(shadows)
        self.scene = scene_for(mesh, settings)
        self.up_axis = self.scene.up
        self.up = tuple(float(u) for u in up_vector(self.up_axis))
        #: Toward the camera that sees the scan's front (:func:`~translucency.app.framing.front_direction`).
        self.front = front_direction(mesh, self.up)
        default_light = DirectionalLight(
            turned_to_front(default_light_direction(self.up_axis), self.up, self.front), 1.0
        )
        self.lights = as_light_list(lights if lights is not None else default_light)
        #: Index in :attr:`lights` of the directional light :meth:`set_light` steers, or None.
        self.key_light = next((i for i, light in enumerate(self.lights) if isinstance(light, DirectionalLight)), None)
        self.azimuth, self.elevation = (
            light_angles(self.lights[self.key_light].direction, self.up) if self.key_light is not None else (None, None)
        )
        self.mm_per_unit = float(mesh.mm_per_unit)
        self.exposure = exposure
        self.view_dependent, self.specular, self.roughness = bool(view_dependent), bool(specular), float(roughness)
        #: False colour instead of sRGB (:meth:`set_false_colour`), its quantity and scale.
        self.false_colour, self.false_colour_quantity, self.false_colour_scale = False, "luminance", "log"
        #: Camera position (mm, scan coordinates) the view-dependent layers use; None: not known yet.
        self.eye = None
        self.result = None
        self.solve_seconds = 0.0
        self.n_solves = 0
        self.status = ""
        #: Called with no argument when :attr:`status` changes during a solve (a window redraws it).
        self.notify = None
        #: Called with ``(stage, fraction)`` as a solve progresses (a window's progress bar; it may raise to stop
        #: the solve, which then leaves the state as it was before the change).
        self.on_progress = None
        self._highlight_inputs = None
        if solve:
            self.solve()

    # ------------------------------------------------------------------------------------------------
    # changes; each returns whether the picture changed

    def set_light(self, azimuth, elevation) -> bool:
        """Move the first directional light to ``azimuth``, ``elevation`` (degrees around ``up``) and solve.

        The new direction is :func:`light_direction` of the angles; its irradiance stays. Returns False
        (and does nothing) when the angles are the current ones.
        """
        from ...scatter.lights import DirectionalLight

        if self.key_light is None:
            raise InvalidParameterError("the lights hold no directional light to steer; add one (--light-dir X,Y,Z).")
        azimuth, elevation = float(azimuth), float(elevation)
        if not (np.isfinite(azimuth) and np.isfinite(elevation) and -90.0 <= elevation <= 90.0):
            raise InvalidParameterError(
                f"light angles must be finite with elevation in [-90, 90] degrees, "
                f"got azimuth {azimuth!r}, elevation {elevation!r}."
            )
        if (azimuth, elevation) == (self.azimuth, self.elevation):
            return False
        lights = list(self.lights)
        old = lights[self.key_light]
        lights[self.key_light] = DirectionalLight(light_direction(azimuth, elevation, self.up), old.irradiance_rgb)
        self._solve_with(self.solve, azimuth=azimuth, elevation=elevation, lights=tuple(lights))
        return True

    def set_lights(self, lights, *, moving: bool = False) -> bool:
        """Replace every light (a light or a sequence; directions in the scan's coordinates) and solve.

        The first directional light becomes the one :meth:`set_light` steers (none: the angles are None).
        ``moving``: a frame while a window's light is dragged, solved without the light that re-enters the
        surface (no bounce; the status says so); the next call without it solves the same lights whole.
        Returns False when the lights are the current ones and already solved so.
        """
        from ...scatter.lights import DirectionalLight, as_light_list

        lights = as_light_list(lights)
        same = [light.to_dict() for light in lights] == [light.to_dict() for light in self.lights]
        if same and (moving or not self.shows_moving_frame):
            return False
        key = next((i for i, light in enumerate(lights) if isinstance(light, DirectionalLight)), None)
        angles = light_angles(lights[key].direction, self.up) if key is not None else (None, None)
        solve = (lambda: self.solve(bounces=0)) if moving else self.solve
        self._solve_with(solve, lights=lights, key_light=key, azimuth=angles[0], elevation=angles[1])
        return True

    @property
    def shows_moving_frame(self) -> bool:
        """Whether what is shown is a frame while the light moved (solved with fewer bounces than the state's)."""
        return self.result is not None and self.result.metadata.get("bounces", self.bounces) != self.bounces

    def set_material(self, material, *, preview: bool = False) -> bool:
        """Change the material (catalogue name, entry or Medium, 1/mm) and solve (with ``preview``: the quick
        first picture of :meth:`solve_preview`); False if it is the same."""
        medium = resolve_medium(material)
        if medium.describe() == self.medium.describe():
            return False
        self._solve_with(self._solver(preview), medium=medium)
        return True

    def set_model(self, model: str, *, preview: bool = False) -> bool:
        """Change the scattering model (``directional``, ``standard``, ``better``) and solve (``preview`` as in
        :meth:`set_material`); False if the same."""
        from ...scatter.names import check_model

        check_model(model)
        if model == self.model:
            return False
        self._solve_with(self._solver(preview), model=model)
        return True

    def set_tol(self, tol, *, preview: bool = False) -> bool:
        """Change the solver's tolerance (relative error per vertex, docs/physics.md §8.4) and solve; False if
        the same. With ``relight`` a new tolerance prepares new operators (``preview`` as in :meth:`set_material`)."""
        from ...scatter.names import check_tol

        tol = check_tol(tol)
        if tol == self.tol:
            return False
        self._solve_with(self._solver(preview), tol=tol)
        return True

    def set_bounces(self, bounces) -> bool:
        """Change how many times light re-enters the surface (0: none, docs/physics.md §9) and solve; False if
        the same."""
        from ...scatter.names import check_bounces

        bounces = check_bounces(bounces)
        if bounces == self.bounces:
            return False
        self._solve_with(self.solve, bounces=bounces)
        return True

    def set_scale(self, mm_per_unit, *, preview: bool = False) -> bool:
        """Size of one unit of the mesh's file in mm: scale the mesh, make a new Scene and solve.

        The points become ``p * mm_per_unit / m0`` with ``m0`` the mesh's own mm per unit; False if the
        scale is the current one.
        """
        mm_per_unit = float(mm_per_unit)
        if not (np.isfinite(mm_per_unit) and mm_per_unit > 0):
            raise InvalidParameterError(f"the scale must be a positive number of mm per unit, got {mm_per_unit!r}.")
        if mm_per_unit == self.mm_per_unit:
            return False
        factor = mm_per_unit / float(self.base_mesh.mm_per_unit)
        mesh = self.base_mesh.replace(points=self.base_mesh.points * factor, mm_per_unit=mm_per_unit)
        self._solve_with(
            self._solver(preview), mm_per_unit=mm_per_unit, scene=Scene(mesh, shadows=self.shadows, up=self.up_axis)
        )
        return True

    def set_exposure(self, exposure) -> bool:
        """Display exposure (linear factor on ``L`` before sRGB): new colours from the same solution, no solve."""
        exposure = float(exposure)
        if not (np.isfinite(exposure) and exposure > 0):
            raise InvalidParameterError(f"exposure must be a positive number, got {exposure!r}.")
        changed = exposure != self.exposure
        self.exposure = exposure
        self.update_status()
        return changed

    def set_view_dependent(self, on: bool) -> bool:
        """Show ``T21(eta, n . w_o) B`` (on) or ``T21(eta, 1) B`` (off; docs/physics.md §5.3); no solve."""
        changed = bool(on) != self.view_dependent
        self.view_dependent = bool(on)
        self.update_status()
        return changed

    def set_specular(self, on: bool) -> bool:
        """Add (on) or remove the specular highlight (docs/physics.md §5.5); no solve."""
        changed = bool(on) != self.specular
        self.specular = bool(on)
        self.update_status()
        return changed

    def set_false_colour(self, on: bool, quantity: str | None = None) -> bool:
        """Show false colour (on) or sRGB (off); ``quantity`` is ``luminance`` (kept when None) or a channel
        name (``red``, ``green``, ``blue``). No solve."""
        quantity = self.false_colour_quantity if quantity is None else quantity
        if quantity not in FALSE_COLOUR_QUANTITIES:
            raise InvalidParameterError(
                f"the false colour shows one of {', '.join(FALSE_COLOUR_QUANTITIES)}, got {quantity!r}."
            )
        changed = (bool(on), quantity) != (self.false_colour, self.false_colour_quantity)
        self.false_colour, self.false_colour_quantity = bool(on), quantity
        self.update_status()
        return changed

    def set_false_colour_scale(self, scale: str) -> bool:
        """Scale of the false colour: ``log`` (:data:`~translucency.app.display.LOG_DECADES` decades) or
        ``linear``; no solve. Returns whether the picture changed (only when false colour is on)."""
        if scale not in FALSE_COLOUR_SCALES:
            raise InvalidParameterError(f"the false colour's scale is one of log, linear; got {scale!r}.")
        changed = scale != self.false_colour_scale
        self.false_colour_scale = scale
        self.update_status()
        return changed and self.false_colour

    def set_eye(self, eye) -> bool:
        """Camera position (3 floats, mm, scan coordinates) for the view-dependent layers; no solve.

        Returns True when a view-dependent layer is on and the position moved (the colours change).
        """
        eye = tuple(float(v) for v in eye)
        moved = eye != self.eye
        self.eye = eye
        return moved and (self.view_dependent or self.specular)

    def solve_preview(self) -> None:
        """A quick first picture: ``tree`` on the interactive proxy (:func:`interactive_edge_length`, about
        :data:`INTERACTIVE_VERTICES` vertices), shown while the state's own method prepares (a window calls it
        before :meth:`solve` on a new scan)."""
        self.solve(interactive_edge_length(self.scene.mesh, self.medium), method="tree")

    def solve_full(self) -> None:
        """Solve the current state on every vertex of the mesh (slow; see the module docstring): with
        ``relight``, by ``tree`` at the default tolerance."""
        if self.method == "relight":
            self.solve("full", method="tree", tol=DEFAULT_TOL)
        else:
            self.solve("full")

    def _solver(self, preview: bool):
        """:meth:`solve_preview` or :meth:`solve`."""
        return self.solve_preview if preview else self.solve

    def _solve_with(self, solve, **changes) -> None:
        """Set the attributes ``changes`` and call ``solve()``; if it raises (an error, or a window's cancel through
        :attr:`on_progress`), the attributes are put back as they were."""
        before = {name: getattr(self, name) for name in changes}
        for name, value in changes.items():
            setattr(self, name, value)
        try:
            solve()
        except BaseException:
            for name, value in before.items():
                setattr(self, name, value)
            self.update_status()
            raise

    def solve(self, resolution=None, *, method=None, tol=None, bounces=None) -> None:
        """Solve the current settings on :attr:`scene`, at ``resolution`` (default: the state's own); ``method``,
        ``tol`` and ``bounces`` replace the state's for this solve only (what was used is in the result's metadata,
        which the status reads).

        Sets :attr:`result`, :attr:`solve_seconds` (wall time) and :attr:`status`, counts
        :attr:`n_solves`, and fixes the exposure from the first solve when none was given.
        """
        if resolution is None:
            resolution = self.resolution
            if resolution == "interactive":
                resolution = (
                    "full" if self.method == "relight" else interactive_edge_length(self.scene.mesh, self.medium)
                )
        start = time.perf_counter()
        self.result = self.scene.shade(
            self.medium,
            self.lights,
            model=self.model,
            method=self.method if method is None else method,
            tol=self.tol if tol is None else tol,
            resolution=resolution,
            exposure=self.exposure,
            per_direction=self.per_direction,
            bounces=self.bounces if bounces is None else bounces,
            albedo=self.albedo,
            progress=self._progress,
            **self.limits,
        )
        self.solve_seconds = time.perf_counter() - start
        self.n_solves += 1
        if self.exposure is None:
            self.exposure = self.result.exposure
        self._highlight_inputs = None
        self.update_status()

    # ------------------------------------------------------------------------------------------------
    # what is shown

    def radiance_shown(self, eye=None) -> np.ndarray:
        """Linear radiance per vertex as displayed, W/(m² sr), (n, 3): ``T21 B`` plus the layers that are on.

        ``T21(eta, 1) B`` (the bake's), or ``T21(eta, n . w_o) B`` with the view-dependent layer, plus
        the GGX highlight with the specular one (docs/physics.md §5.3, §5.5). ``eye`` (camera position,
        mm) is kept as :meth:`set_eye` does; with no camera position known yet the layers are left out.
        """
        from ...scatter.outgoing import specular_radiance, subsurface_radiance, view_directions

        if eye is not None:
            self.set_eye(eye)
        result = self.result
        if not (self.view_dependent or self.specular) or self.eye is None:
            return result.radiance
        w_o = view_directions(self.base_mesh.points, np.asarray(self.eye, dtype=np.float64))
        radiance = (
            subsurface_radiance(result.B, result.normals, w_o, self.medium.eta)
            if self.view_dependent
            else result.radiance.copy()
        )
        if self.specular:
            for vertices, direction, irradiance in self._highlights():
                radiance[vertices] += specular_radiance(
                    result.normals[vertices], w_o[vertices], direction, irradiance, self.medium.eta, self.roughness
                )
        return radiance

    def colors(self, eye=None) -> np.ndarray:
        """Display colours per vertex, (n, 3) uint8: ``sRGB(exposure L)`` of :meth:`radiance_shown`."""
        colors, _ = display_colors(self.radiance_shown(eye), self.exposure)
        return colors

    def false_colour_values(self, eye=None) -> np.ndarray:
        """The false colour's number per vertex, (n,), in W/(m² sr) per W/m²: the luminance (or the
        channel) of :meth:`radiance_shown`, whether or not false colour is on."""
        return false_colour_values(self.radiance_shown(eye), self.false_colour_quantity)

    def false_colour_range(self) -> tuple[float, float]:
        """``(low, high)`` of the false colour, W/(m² sr) per W/m²: ``high = 1 / exposure`` (white in sRGB)."""
        return false_colour_range(np.zeros(0), self.false_colour_scale, self.exposure)

    @property
    def false_colour_title(self) -> str:
        """Title of the false colour's colour bar: quantity, unit and scale."""
        return false_colour_label(self.false_colour_quantity, self.false_colour_scale)

    def _progress(self, stage: str, fraction: float) -> None:
        """A solve's progress: a note while the relighting operators are prepared (:attr:`notify` shows it), and
        :attr:`on_progress`."""
        if self.on_progress is not None:
            self.on_progress(stage, fraction)
        if stage == "relight operators" and fraction == 0.0:
            self.add_note(
                f"preparing the relighting operators for {self.medium.name} on {self.scene.mesh.n_points:,} vertices "
                "(once per material and model; the time grows with the vertices)..."
            )
            if self.notify is not None:
                self.notify()

    def update_status(self) -> None:
        """Write :attr:`status` from the current state (three lines: material and size, light, last solve)."""
        result = self.result
        if result is None:  # nothing solved yet
            return
        size = float(self.scene.mesh.extent)
        light = (
            ""
            if self.azimuth is None
            else f"light azimuth {self.azimuth:.0f} deg, elevation {self.elevation:.0f} deg; "
        )
        # what the last solve used (solve_full and the preview solve by tree, whatever the state's method is)
        method, tol = result.metadata.get("method", self.method), result.metadata.get("tolerance", self.tol)
        tolerance = "exact sum" if method == "exact" else f"tolerance {tol:.3g}"
        prepared = result.timings.get("solve_prepare", 0.0)
        if self.shows_moving_frame:
            tolerance += "; no bounce while the light moves"
        if method == "relight" and prepared:
            tolerance += f" (operators prepared in {prepared:.0f} s, once)"
        self.status = (
            f"{self.medium.name}, {self.model} dipole, {size:.3g} mm ({self.mm_per_unit:.4g} mm per unit), "
            f"up {self.up_axis}\n"
            f"{light}display exposure {self.exposure:.3g}"
            + (f"; false colour: {self.false_colour_quantity}, {self.false_colour_scale}" if self.false_colour else "")
            + "\n"
            f"solved in {self.solve_seconds:.2f} s (wall time) on {result.stats['solver_vertices']} of "
            f"{result.stats['vertices']} vertices: {method}, {tolerance}"
        )

    def add_note(self, line: str) -> None:
        """Append one line to :attr:`status` (it replaces an earlier note and lasts until the next change)."""
        self.update_status()
        self.status += f"\n{line}"

    # ------------------------------------------------------------------------------------------------
    # output

    @property
    def file_stem(self) -> str:
        """Stem of saved files: ``<name>_<material>_<model>``."""
        return f"{Path(self.name).stem}_{self.medium.name}_{self.model}"

    def write_bake(self, path) -> Path:
        """Write the current result as a baked PLY with colours at the current exposure; returns the path.

        A bake holds the radiance toward the normal, ``T21(eta, 1) B`` (docs/physics.md §5.3): it does
        not depend on the view.
        """
        result = self.result
        colors, _ = display_colors(result.radiance, self.exposure)
        return write_result(
            dataclasses.replace(
                result, colors=colors, exposure=self.exposure, metadata=dict(result.metadata, exposure=self.exposure)
            ),
            path,
        )

    def _highlights(self) -> list:
        """Per directional sample: (vertices it reaches, direction, irradiance on the surface E cos V)."""
        from ...scatter.fresnel import fresnel_transmittance

        if self._highlight_inputs is None:
            incident, _ = self.scene.light_cache.incident_on_mesh(self.medium, self.lights, per_direction=True)
            normals = self.result.normals
            inputs = []
            for part in incident.contributions:
                if part.direction is None:  # a point light: no highlight
                    continue
                cos_i = normals[part.vertices] @ part.direction
                # phi = T12 E cos V (irradiance.py), so E cos V = phi / T12
                inputs.append(
                    (
                        part.vertices,
                        part.direction,
                        part.phi_rgb / fresnel_transmittance(cos_i, self.medium.eta)[:, None],
                    )
                )
            self._highlight_inputs = inputs
        return self._highlight_inputs
