"""What the viewer shows, without a window: the settings, the Scene that solves again, the colours, the status.

:class:`ViewerState` holds every choice the controls change (light angles, material, model, scale,
exposure, the two view-dependent layers) and one persistent :class:`~translucency.app.shading.scene.Scene`.
Its ``set_*`` methods solve again when the change needs it and say whether the picture changed; it
hands out the per-vertex display colours ``sRGB(exposure L)`` and a status text. It never imports
PyVista or VTK: a window (:mod:`translucency.app.viewer.widgets`) or a test drives it the same way,
passing the camera position as a plain array when a view-dependent layer needs it.

Parts. The state is one object over its parts, each in a module of its own: the scan at the scale chosen
(:class:`~translucency.app.viewer.scaled_scan.ScaledScan`, ``state.scan``), the solve's settings
(:class:`~translucency.app.viewer.solve_settings.SolveSettings`, ``state.solver``), the lights
(:class:`~translucency.app.viewer.light_rig.LightRig`, ``state.rig``) and the display settings with the camera
(:class:`~translucency.app.viewer.appearance.Appearance`, ``state.appearance``). Their attributes are the state's
too (``state.model`` is ``state.solver.model``). A change that solves replaces a part and puts the old one back
when the solve fails; a display change changes the appearance and needs no solve. The view-dependent layers, the
status text and the bake are :mod:`~translucency.app.viewer.view_layers`, :mod:`~translucency.app.viewer.status`
and :mod:`~translucency.app.viewer.saving`.

By default ``L`` is the radiance toward the normal, ``T21(eta, 1) B`` (docs/physics.md §5.3), exactly
what a bake stores. Two optional layers depend on the view (recomputed when the camera moves; no new
solve; :mod:`translucency.app.viewer.view_layers`): the transmission toward the camera,
``T21(eta, n . w_o) B``, darker at grazing angles, and the specular highlight of every directional light and
environment sample (GGX, roughness ``alpha``, with the solve's shadows; point lights give none).

Interactive resolution. By default (:data:`VIEWER_METHOD`, :data:`VIEWER_TOL`) every change relights every
vertex with the operators the ``Scene``'s surface keeps (prepared on the first solve and after a change of
material or model, with a note in the status while that runs; a proxy only where they would not fit the
memory budget; by ``tree`` on every vertex where their first light was far off, as the status says). With
another method, every change re-solves on the one ``Scene`` (geometry, Embree scene and
visibility are reused) on a proxy of about :data:`INTERACTIVE_VERTICES` vertices
(:func:`interactive_edge_length`), interpolated back to every vertex: small enough to answer in a
fraction of a second, fine enough that the error stays at a few percent away from the shadow
terminator, which the proxy moves by up to an edge (single vertices just past it can be many times
too bright). The measurements behind the default are in bench/README.md ("Interactive proxy").
:meth:`ViewerState.solve_full` solves what is shown on every vertex (with ``relight``: by ``tree`` at the
default tolerance, the accurate answer).

False colour. Instead of ``sRGB(exposure L)`` the viewer can show one number per vertex in physical
units, W/(m² sr) per W/m² of irradiance (:class:`~translucency.app.viewer.appearance.Appearance`, which
holds the display settings): the luminance ``Y`` of what is shown (or one channel), on a
log or a linear scale whose top is the radiance the sRGB view shows as white, ``1 / exposure``
(:func:`translucency.app.display.false_colour_range`). :meth:`ViewerState.set_false_colour` and
:meth:`ViewerState.set_false_colour_scale` choose it; :meth:`ViewerState.false_colour_values` and
:meth:`ViewerState.false_colour_range` are what a window maps through the colour map.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ...scatter.names import DEFAULT_TOL
from ..shading.settings import ShadeSettings, settings_with, viewer_settings
from .appearance import Appearance
from .forwarding import attribute_of, method_of
from .light_rig import LightRig, light_angles, light_direction
from .rollback import put_back_on_failure
from .saving import file_stem, write_bake
from .scaled_scan import ScaledScan
from .solve_settings import INTERACTIVE_VERTICES, SolveSettings, interactive_edge_length
from .status import preparing_note, status_text
from .view_layers import Highlights, radiance_toward

__all__ = [
    "ViewerState",
    "INTERACTIVE_VERTICES",
    "interactive_edge_length",
    "diffusive_materials",
    "light_direction",
    "light_angles",
]


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

    # the appearance: display settings and camera
    exposure = attribute_of("appearance", "exposure")
    view_dependent = attribute_of("appearance", "view_dependent")
    specular = attribute_of("appearance", "specular")
    roughness = attribute_of("appearance", "roughness")
    false_colour = attribute_of("appearance", "false_colour")
    false_colour_quantity = attribute_of("appearance", "false_colour_quantity")
    false_colour_scale = attribute_of("appearance", "false_colour_scale")
    false_colour_title = attribute_of("appearance", "false_colour_title", Appearance.false_colour_title.__doc__)
    false_colour_range = method_of("appearance", Appearance.false_colour_range)
    # display changes: the appearance's, then the status again; no solve
    set_exposure = method_of("appearance", Appearance.set_exposure, then="update_status")
    set_view_dependent = method_of("appearance", Appearance.set_view_dependent, then="update_status")
    set_specular = method_of("appearance", Appearance.set_specular, then="update_status")
    set_false_colour = method_of("appearance", Appearance.set_false_colour, then="update_status")
    set_false_colour_scale = method_of("appearance", Appearance.set_false_colour_scale, then="update_status")
    set_eye = method_of("appearance", Appearance.set_eye)
    eye = attribute_of("appearance", "eye")
    # the solve's settings
    medium = attribute_of("solver", "medium")
    model = attribute_of("solver", "model")
    method = attribute_of("solver", "method")
    tol = attribute_of("solver", "tol")
    resolution = attribute_of("solver", "resolution")
    per_direction = attribute_of("solver", "per_direction")
    bounces = attribute_of("solver", "bounces")
    albedo = attribute_of("solver", "albedo")
    limits = attribute_of("solver", "limits")
    shadows = attribute_of("solver", "shadows")
    # the scan
    base_mesh = attribute_of("scan", "base_mesh")
    name = attribute_of("scan", "name")
    up_axis = attribute_of("scan", "up_axis")
    up = attribute_of("scan", "up")
    front = attribute_of("scan", "front")
    mm_per_unit = attribute_of("scan", "mm_per_unit")
    scene = attribute_of("scan", "scene")
    # the lights
    lights = attribute_of("rig", "lights")
    key_light = attribute_of("rig", "key", "The rig's ``key``: the index of the light :meth:`set_light` steers.")
    azimuth = attribute_of("rig", "azimuth")
    elevation = attribute_of("rig", "elevation")

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
        # every setting checked once, before the scan is loaded ("interactive" is the viewer's own resolution)
        if material is not None:
            changes["material"] = material
        if resolution != "interactive":
            changes["resolution"] = resolution
        settings = settings_with(viewer_settings() if settings is None else settings, **changes)
        #: The mesh, its name and up, and the Scene at the scale chosen.
        self.scan = ScaledScan.load(mesh, settings, unit=unit, name=name)
        #: What the solves use besides the scan and the lights (material, model, method, tolerance, ...).
        self.solver = SolveSettings.of(settings, resolution)
        #: The lights and the key light :meth:`set_light` steers, with its angles (degrees around :attr:`up`).
        self.rig = LightRig.of(lights if lights is not None else self.scan.front_light(), self.up)
        #: The display settings (exposure, view-dependent layers, false colour); their attributes are the state's.
        self.appearance = Appearance(settings.exposure, view_dependent, specular, roughness)
        self.result, self.solve_seconds, self.n_solves, self.status = None, 0.0, 0, ""
        #: Called with no argument when :attr:`status` changes during a solve (a window redraws it).
        self.notify = None
        #: Called with ``(stage, fraction)`` as a solve progresses (a window's progress bar; it may raise to stop
        #: the solve, which then leaves the state as it was before the change).
        self.on_progress = None
        self._highlights = Highlights()
        if solve:
            self.solve()

    # ------------------------------------------------------------------------------------------------
    # changes; each returns whether the picture changed

    def set_light(self, azimuth, elevation) -> bool:
        """Move the first directional light to ``azimuth``, ``elevation`` (degrees around ``up``) and solve.

        The new direction is :func:`light_direction` of the angles; its irradiance stays. Returns False
        (and does nothing) when the angles are the current ones.
        """
        return self._solve_with(self.solve, rig=self.rig.steered(azimuth, elevation, self.up))

    def set_lights(self, lights, *, moving: bool = False) -> bool:
        """Replace every light (a light or a sequence; directions in the scan's coordinates) and solve.

        The first directional light becomes the one :meth:`set_light` steers (none: the angles are None).
        ``moving``: a frame while a window's light is dragged, solved without the light that re-enters the
        surface (no bounce; the status says so); the next call without it solves the same lights whole.
        Returns False when the lights are the current ones and already solved so.
        """
        rig = LightRig.of(lights, self.up)
        if self.rig.holds(rig.lights) and (moving or not self.shows_moving_frame):
            return False
        return self._solve_with((lambda: self.solve(bounces=0)) if moving else self.solve, rig=rig)

    @property
    def shows_moving_frame(self) -> bool:
        """Whether what is shown is a frame while the light moved (solved with fewer bounces than the state's)."""
        return self.result is not None and self.result.metadata.get("bounces", self.bounces) != self.bounces

    def set_material(self, material, *, preview: bool = False) -> bool:
        """Change the material (catalogue name, entry or Medium, 1/mm) and solve (with ``preview``: the quick
        first picture of :meth:`solve_preview`); False if it is the same."""
        return self._solve_with(self._solver(preview), solver=self.solver.with_material(material))

    def set_model(self, model: str, *, preview: bool = False) -> bool:
        """Change the scattering model (``directional``, ``standard``, ``better``) and solve (``preview`` as in
        :meth:`set_material`); False if the same."""
        return self._solve_with(self._solver(preview), solver=self.solver.with_model(model))

    def set_tol(self, tol, *, preview: bool = False) -> bool:
        """Change the solver's tolerance (relative error per vertex, docs/physics.md §8.4) and solve; False if
        the same. With ``relight`` a new tolerance prepares new operators (``preview`` as in :meth:`set_material`)."""
        return self._solve_with(self._solver(preview), solver=self.solver.with_tol(tol))

    def set_bounces(self, bounces) -> bool:
        """Change how many times light re-enters the surface (0: none, docs/physics.md §9) and solve; False if
        the same."""
        return self._solve_with(self.solve, solver=self.solver.with_bounces(bounces))

    def set_scale(self, mm_per_unit, *, preview: bool = False) -> bool:
        """Size of one unit of the mesh's file in mm: scale the mesh, make a new Scene and solve.

        The points become ``p * mm_per_unit / m0`` with ``m0`` the mesh's own mm per unit; False if the
        scale is the current one.
        """
        return self._solve_with(self._solver(preview), scan=self.scan.scaled(mm_per_unit, shadows=self.shadows))

    # ------------------------------------------------------------------------------------------------
    # solving

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

    def _solve_with(self, solve, **changes) -> bool:
        """Set the attributes ``changes`` and call ``solve()``; False (and nothing done) when a change is None (the
        value is the current one). If the solve raises (an error, or a window's cancel through :attr:`on_progress`),
        the attributes are put back as they were."""
        if any(value is None for value in changes.values()):
            return False
        with put_back_on_failure(self, changes, after_undo=self.update_status):
            solve()
        return True

    def solve(self, resolution=None, *, method=None, tol=None, bounces=None) -> None:
        """Solve the current settings on :attr:`scene`, at ``resolution`` (default: the state's own); ``method``,
        ``tol`` and ``bounces`` replace the state's for this solve only (what was used is in the result's metadata,
        which the status reads).

        Sets :attr:`result`, :attr:`solve_seconds` (wall time) and :attr:`status`, counts
        :attr:`n_solves`, and fixes the exposure from the first solve when none was given.
        """
        if resolution is None:
            resolution = self.solver.resolution_on(self.scene.mesh)
        start = time.perf_counter()
        self.result = self.solver.shade(
            self.scene, self.lights, resolution, self.exposure, self._progress, method=method, tol=tol, bounces=bounces
        )
        self.solve_seconds = time.perf_counter() - start
        self.n_solves += 1
        if self.exposure is None:
            self.exposure = self.result.exposure
        self.update_status()

    def _progress(self, stage: str, fraction: float) -> None:
        """A solve's progress: a note while the relighting operators are prepared (:attr:`notify` shows it), and
        :attr:`on_progress`."""
        if self.on_progress is not None:
            self.on_progress(stage, fraction)
        if stage == "relight operators" and fraction == 0.0:
            self.add_note(preparing_note(self))
            if self.notify is not None:
                self.notify()

    # ------------------------------------------------------------------------------------------------
    # what is shown

    def radiance_shown(self, eye=None) -> np.ndarray:
        """Linear radiance per vertex as displayed, W/(m² sr), (n, 3): ``T21 B`` plus the layers that are on.

        ``T21(eta, 1) B`` (the bake's), or ``T21(eta, n . w_o) B`` with the view-dependent layer, plus
        the GGX highlight with the specular one (docs/physics.md §5.3, §5.5;
        :mod:`~translucency.app.viewer.view_layers`). ``eye`` (camera position, mm) is kept as :meth:`set_eye`
        does; with no camera position known yet the layers are left out.
        """
        if eye is not None:
            self.set_eye(eye)
        if not self.appearance.sees_the_camera:
            return self.result.radiance
        highlights = self._highlights.of(self.scene, self.medium, self.lights, self.result) if self.specular else ()
        return radiance_toward(self.result, self.base_mesh.points, self.medium.eta, self.appearance, highlights)

    def colors(self, eye=None) -> np.ndarray:
        """Display colours per vertex, (n, 3) uint8: ``sRGB(exposure L)`` of :meth:`radiance_shown`."""
        return self.appearance.colors(self.radiance_shown(eye))

    def false_colour_values(self, eye=None) -> np.ndarray:
        """The false colour's number per vertex, (n,), in W/(m² sr) per W/m²: the luminance (or the
        channel) of :meth:`radiance_shown`, whether or not false colour is on."""
        return self.appearance.false_colour_values(self.radiance_shown(eye))

    def update_status(self) -> None:
        """Write :attr:`status` from the current state (three lines: material and size, light, last solve;
        :func:`~translucency.app.viewer.status.status_text`); nothing before the first solve."""
        if self.result is not None:
            self.status = status_text(self)

    def add_note(self, line: str) -> None:
        """Append one line to :attr:`status` (it replaces an earlier note and lasts until the next change)."""
        self.update_status()
        self.status += f"\n{line}"

    # ------------------------------------------------------------------------------------------------
    # output

    @property
    def file_stem(self) -> str:
        """Stem of saved files: ``<name>_<material>_<model>``."""
        return file_stem(self.name, self.medium.name, self.model)

    def write_bake(self, path) -> Path:
        """Write the current result as a baked PLY with colours at the current exposure; returns the path.

        A bake holds the radiance toward the normal, ``T21(eta, 1) B`` (docs/physics.md §5.3): it does
        not depend on the view.
        """
        return write_bake(self.result, self.exposure, path)
