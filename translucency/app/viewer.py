"""Interactive viewer: a scan shown by its translucent radiance, with controls that solve again.

The mesh is drawn with its per-vertex display colours and no lighting of PyVista's own
(``rgb=True``): what you see is the solver's radiance after the display transform, ``sRGB(exposure L)``.
By default ``L`` is the radiance toward the normal, ``T21(eta, 1) B``, exactly what a bake stores, so the
picture equals :func:`~translucency.app.render.render_colors` of the same colours. Two optional
layers depend on the view (recomputed when the camera moves; no new solve):

* **view-dependent transmission** -- ``L = T21(eta, n . w_o) B`` with ``w_o`` toward the camera
  (darker at grazing angles, :func:`translucency.scatter.outgoing.subsurface_radiance`);
* **specular highlight** -- the boundary's reflection of every directional light and environment
  sample (GGX, roughness ``alpha``; :func:`translucency.scatter.outgoing.specular_radiance`), with the
  same Embree shadows as the solve. Point lights give no highlight.

Controls (each calls a method, so the viewer can be driven from code the same way): sliders for
the light's azimuth and elevation (degrees, around the ``up`` axis; they steer the first directional
light, other lights stay as they are), the material (the catalogue's diffusive materials), the model,
the scale (mm per unit of the file: the mesh is scaled and a new :class:`~translucency.app.pipeline.Scene`
made; the picture keeps its framing) and the exposure (log2, display only: no solve); check boxes for
the two view-dependent layers; key ``s`` saves a screenshot and the current bake (PLY) into the output
folder, ``Return`` solves the current state on every vertex (``resolution="full"``).

Interactive resolution. Every change re-solves on one persistent ``Scene`` (geometry, Embree scene and
visibility are reused) on a proxy of about :data:`INTERACTIVE_VERTICES` vertices
(:func:`interactive_edge_length`), interpolated back to every vertex. Measured on the embedded default
scan (28,088 vertices after cleaning, 155 mm across) on the 2-core machine at a load of about 1, warm,
``tree`` at tolerance 0.01, a new light direction per change (new visibility and solve); the reference
is the full solve with the default settings (every vertex), which takes 0.58 s per change there.
Errors are over marble, skim milk and ketchup under three lights (elevations 10-60 deg):

============ ========= ================ ============== =====================
proxy edge   vertices  time per change  relative RMS   median relative error,
                                        error of B     lit vertices
============ ========= ================ ============== =====================
2 mm         16,449    0.35-0.45 s      1.0-1.9 %      0.8 %
2.5 mm       10,528    0.23-0.39 s      1.8-3.0 %      1.6 %
3 mm         7,312     0.17-0.23 s      2.4-3.8 %      2.3 %
4 mm         4,114     0.11-0.20 s      3.8-5.5 %      3.5 %
5.1 mm       2,531     0.07-0.15 s      5.3-7.3 %      5.4 %
============ ========= ================ ============== =====================

The default, about 7,500 vertices (3 mm on the default scan), answers in about 0.2 s. Its error sits
at the shadow terminator, which the proxy moves by up to an edge: single vertices just past it can be
many times too bright (ketchup, whose light fades within 1-5 mm, most), while the lit and the far side
stay within a few percent. ``Return`` solves what is on screen on every vertex; ``s`` then saves that.
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError
from ..scatter.budget import DEFAULT_TIME_LIMIT_S
from ..scatter.names import DEFAULT_METHOD, DEFAULT_MODEL, DEFAULT_TOL
from .pipeline import (Scene, coarsest_proxy_edge, default_light_direction, display_colors, proxy_edge_length,
                       resolve_medium, write_result)
from .render import DEFAULT_UP, add_colored_mesh, camera_position, default_camera_direction, new_plotter
from .settings import DEFAULT_MATERIAL, ShadeSettings

#: Vertices of the interactive proxy (see the module docstring for the measurements behind it).
INTERACTIVE_VERTICES = 7500

#: Range of the scale slider, as factors of the mesh's own mm per unit.
SCALE_RANGE = (0.25, 4.0)
#: Half-range of the exposure slider, in stops (log2) around the first exposure.
EXPOSURE_STOPS = 8.0


def interactive_edge_length(mesh, medium, vertices: int = INTERACTIVE_VERTICES) -> float:
    """Proxy edge length (mm) that answers interactively: a proxy of about ``vertices`` vertices.

    A closed mesh has about two triangles per vertex; the edge is that of equilateral triangles covering
    the surface. It is never finer than :func:`~translucency.app.pipeline.proxy_edge_length` of the
    medium (the detail the light can show after diffusing), and never coarser than
    :func:`~translucency.app.pipeline.coarsest_proxy_edge` (an object only a few diffusion lengths
    across still gets a proxy of some triangles).
    """
    triangle_area = mesh.surface_area / (2.0 * vertices)
    budget = math.sqrt(triangle_area / (math.sqrt(3.0) / 4.0))
    return min(max(budget, proxy_edge_length(medium)), coarsest_proxy_edge(mesh.surface_area))


def _frame(up):
    """Unit ``up`` and two unit axes ``e1, e2`` perpendicular to it (``e1``: +z made orthogonal, or +x)."""
    up = np.asarray(up, dtype=np.float64)
    up = up / np.linalg.norm(up)
    seed = np.array([0.0, 0.0, 1.0]) if abs(up[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    e1 = seed - (seed @ up) * up
    e1 /= np.linalg.norm(e1)
    return up, e1, np.cross(up, e1)


def light_direction(azimuth, elevation, up=DEFAULT_UP) -> np.ndarray:
    """Unit direction toward a light at ``azimuth``, ``elevation`` (degrees) around ``up``.

    Elevation is the angle above the plane perpendicular to ``up``; azimuth 0 is the world +z made
    perpendicular to ``up`` (+x when ``up`` is along z) and 90 is ``up x`` that (+x for ``up`` = +y).
    """
    up, e1, e2 = _frame(up)
    a, e = math.radians(azimuth), math.radians(elevation)
    return math.cos(e) * (math.cos(a) * e1 + math.sin(a) * e2) + math.sin(e) * up


def light_angles(direction, up=DEFAULT_UP) -> tuple[float, float]:
    """``(azimuth, elevation)`` in degrees of a direction (inverse of :func:`light_direction`)."""
    up, e1, e2 = _frame(up)
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    elevation = math.degrees(math.asin(float(np.clip(d @ up, -1.0, 1.0))))
    azimuth = math.degrees(math.atan2(float(d @ e2), float(d @ e1)))
    return azimuth, elevation


def diffusive_materials() -> list[str]:
    """Keys of the catalogue entries every diffusion model can represent (they scatter in every channel)."""
    from ..scatter.materials import catalogue

    return [entry.key for entry in catalogue() if entry.is_diffusive]


class Viewer:
    """A scan shaded by its translucent radiance in a PyVista window, re-solved when a control changes.

    Every control calls one of the ``set_*`` methods; call them from code to drive the viewer the same
    way (the widgets follow). See the module docstring for what is shown and how fast it answers.

    Parameters
    ----------
    mesh : TriangleMesh, optional
        A cleaned mesh in mm (default: the embedded default scan, cleaned).
    material : str or Material or Medium
        The starting material (catalogue name, 1/mm coefficients).
    lights : light or sequence of lights, optional
        Directions in the scan's own coordinates. Default: one white directional light of 1 W/m²
        above and in front of the scan (:func:`~translucency.app.pipeline.default_light_direction` of
        ``up``). The light sliders steer the first directional light; without one they are not shown.
    model, method, tol, per_direction, memory_limit, time_limit
        Passed to :meth:`Scene.shade <translucency.app.pipeline.Scene.shade>` (GB, seconds).
    resolution : "interactive", "full", "auto" or float
        Where ``B`` is computed while controls change: ``"interactive"`` (default) is a proxy of about
        :data:`INTERACTIVE_VERTICES` vertices (:func:`interactive_edge_length`); the others are the
        pipeline's (a number is a proxy edge length in mm).
    shadows : bool
        Embree shadow rays.
    exposure : float, optional
        Display exposure (linear factor); automatic from the first solve by default, then kept, so that
        brightness changes between materials and lights stay visible.
    view_dependent, specular : bool
        Show ``T21(eta, n . w_o) B`` instead of ``T21(eta, 1) B``; add the specular highlight.
    roughness : float
        GGX ``alpha`` of the highlight.
    up : str
        The scan's up axis, ``"x"`` ... ``"-z"`` or ``"auto"`` (inferred from the mesh, see
        :mod:`translucency.io.upright`): the camera's view-up, the axis of the light's azimuth, and
        where the default camera and light are (above and in front).
    camera_direction : sequence of 3 float, optional
        From the mesh's centre toward the camera at the start, in the scan's coordinates (default:
        :func:`~translucency.app.render.default_camera_direction` of ``up``).
    window_size : (int, int)
        Window size, pixels.
    off_screen : bool
        Render without a window (screenshots, tests).
    widgets : bool
        Show the sliders, check boxes and status line.
    output : path-like
        Folder for the files the ``s`` key saves (default: the current folder).
    name : str, optional
        Stem of the saved files (default: the mesh's file name, or ``scan``).
    """

    def __init__(self, mesh=None, material=DEFAULT_MATERIAL, lights=None, *, model=DEFAULT_MODEL, method=DEFAULT_METHOD,
                 tol=DEFAULT_TOL,
                 resolution="interactive", shadows=True, per_direction=False, exposure=None, memory_limit=None,
                 time_limit=DEFAULT_TIME_LIMIT_S, view_dependent=False, specular=False, roughness=0.25, up="auto",
                 camera_direction=None,
                 window_size=(1024, 768), off_screen=False, widgets=True, output=".", name=None):
        from ..io.upright import up_vector
        from ..scatter.lights import DirectionalLight, as_light_list
        from .pipeline import load_scan

        # every setting checked once, before the scan is loaded ("interactive" is the viewer's own resolution)
        settings = ShadeSettings(material, model, method, tol, "full" if resolution == "interactive" else resolution,
                                 shadows, per_direction, exposure, memory_limit, time_limit, up)
        if mesh is None:
            mesh, _, default_name = load_scan(None)
            name = name or default_name
        self.base_mesh = mesh
        self.name = name or (Path(mesh.source).stem if mesh.source is not None else "scan")
        self.medium = settings.material
        self.model, self.method, self.tol = model, method, float(tol)
        self.resolution = resolution
        self.per_direction = bool(per_direction)
        self.limits = {"memory_limit": memory_limit, "time_limit": time_limit}
        self.shadows = bool(shadows)
        self.scene = Scene(mesh, shadows=self.shadows, up=up)
        self.up_axis = self.scene.up
        self.up = tuple(float(u) for u in up_vector(self.up_axis))
        self.lights = as_light_list(lights if lights is not None
                                    else DirectionalLight(default_light_direction(self.up_axis), 1.0))
        self._key_light = next((i for i, light in enumerate(self.lights) if isinstance(light, DirectionalLight)), None)
        self.azimuth, self.elevation = (light_angles(self.lights[self._key_light].direction, self.up)
                                        if self._key_light is not None else (None, None))
        self.mm_per_unit = float(mesh.mm_per_unit)
        self.exposure = exposure
        self.view_dependent, self.specular, self.roughness = bool(view_dependent), bool(specular), float(roughness)
        self.output = Path(output)
        self.result = None
        self.solve_seconds = 0.0
        self.n_solves = 0
        self.status = ""
        self._full_next = False
        self._resolution_used = None
        self._highlight_inputs = None
        self._eye = None
        self.widgets = {}

        self.plotter = new_plotter(window_size, off_screen=off_screen)
        self._solve()
        self.poly = add_colored_mesh(self.plotter, self.base_mesh, display_colors(self.result.radiance, self.exposure)[0])
        if camera_direction is None:
            camera_direction = default_camera_direction(self.up_axis)
        self.plotter.camera_position = camera_position(self.poly.center, self.poly.length, camera_direction, self.up)
        self._status_actor = self.plotter.add_text(self.status, position="upper_left", font_size=10, color="white",
                                                   name="status")
        self._overlays = [self._status_actor]
        if widgets:
            self._add_widgets()
        else:
            self._status_actor.SetVisibility(False)
        self.plotter.camera.AddObserver("ModifiedEvent", self._on_camera)
        self.plotter.add_key_event("s", self.save)
        self.plotter.add_key_event("Return", self.solve_full)
        self._redisplay()

    # ------------------------------------------------------------------------------------------------
    # state changes (the widgets call these)

    def set_light(self, azimuth, elevation) -> None:
        """Move the first directional light to ``azimuth``, ``elevation`` (degrees around ``up``) and solve."""
        from ..scatter.lights import DirectionalLight

        if self._key_light is None:
            raise InvalidParameterError("the lights hold no directional light to steer; add one (--light-dir X,Y,Z).")
        azimuth, elevation = float(azimuth), float(elevation)
        if not (np.isfinite(azimuth) and np.isfinite(elevation) and -90.0 <= elevation <= 90.0):
            raise InvalidParameterError(f"light angles must be finite with elevation in [-90, 90] degrees, "
                                        f"got azimuth {azimuth!r}, elevation {elevation!r}.")
        if (azimuth, elevation) == (self.azimuth, self.elevation):
            return
        self.azimuth, self.elevation = azimuth, elevation
        lights = list(self.lights)
        old = lights[self._key_light]
        lights[self._key_light] = DirectionalLight(light_direction(azimuth, elevation, self.up), old.irradiance_rgb)
        self.lights = tuple(lights)
        self._refresh()

    def set_material(self, material) -> None:
        """Change the material (catalogue name, entry or Medium) and solve."""
        medium = resolve_medium(material)
        if medium.describe() == self.medium.describe():
            return
        self.medium = medium
        self._refresh()

    def set_model(self, model: str) -> None:
        """Change the scattering model (``directional``, ``standard``, ``better``) and solve."""
        from ..scatter.names import check_model

        check_model(model)
        if model == self.model:
            return
        self.model = model
        self._refresh()

    def set_scale(self, mm_per_unit) -> None:
        """Size of one unit of the mesh's file in mm: scale the mesh, make a new Scene and solve."""
        mm_per_unit = float(mm_per_unit)
        if not (np.isfinite(mm_per_unit) and mm_per_unit > 0):
            raise InvalidParameterError(f"the scale must be a positive number of mm per unit, got {mm_per_unit!r}.")
        if mm_per_unit == self.mm_per_unit:
            return
        factor = mm_per_unit / float(self.base_mesh.mm_per_unit)
        mesh = self.base_mesh.replace(points=self.base_mesh.points * factor, mm_per_unit=mm_per_unit)
        self.mm_per_unit = mm_per_unit
        self.scene = Scene(mesh, shadows=self.shadows, up=self.up_axis)
        self._refresh()

    def set_exposure(self, exposure) -> None:
        """Display exposure (linear factor): new colours from the same solution, no solve."""
        exposure = float(exposure)
        if not (np.isfinite(exposure) and exposure > 0):
            raise InvalidParameterError(f"exposure must be a positive number, got {exposure!r}.")
        self.exposure = exposure
        self._redisplay()

    def set_view_dependent(self, on: bool) -> None:
        """Show ``T21(eta, n . w_o) B`` (on) or ``T21(eta, 1) B`` (off); no solve."""
        self.view_dependent = bool(on)
        self._redisplay()

    def set_specular(self, on: bool) -> None:
        """Add (on) or remove the specular highlight; no solve."""
        self.specular = bool(on)
        self._redisplay()

    def solve_full(self) -> None:
        """Solve the current state on every vertex of the mesh (slow; see the module docstring)."""
        self._full_next = True
        self._refresh()

    # ------------------------------------------------------------------------------------------------
    # output

    def screenshot(self, path=None, *, widgets: bool = False) -> np.ndarray:
        """The current picture as an (h, w, 3) uint8 image, written as a PNG when ``path`` is given.

        Without ``widgets`` the sliders, check boxes and status line are hidden for the picture.
        """
        from .outputs import write_png

        if self.plotter._first_time and not self.plotter.off_screen:  # a window never shown has no picture yet
            self.plotter.show(interactive=False, auto_close=False)
        hidden = [] if widgets else [w for w in self.widgets.values() if w.GetEnabled()]
        overlays = [] if widgets else [actor for actor in self._overlays if actor.GetVisibility()]
        for widget in hidden:
            widget.Off()
        for actor in overlays:
            actor.SetVisibility(False)
        self.plotter.render()
        image = np.asarray(self.plotter.screenshot(return_img=True))
        for widget in hidden:
            widget.On()
        for actor in overlays:
            actor.SetVisibility(True)
        self.plotter.render()
        if path is not None:
            write_png(path, image)
        return image

    def save(self, folder=None) -> tuple[Path, Path]:
        """Save a screenshot (PNG, with the controls) and the current bake (PLY) into ``folder``.

        The bake holds the radiance toward the normal and colours at the current exposure (a bake does
        not depend on the view). File names are ``<name>_<material>_<model>_<n>`` with the first free
        ``n``. Returns ``(png, ply)``.
        """
        folder = Path(folder) if folder is not None else self.output
        folder.mkdir(parents=True, exist_ok=True)
        stem = f"{Path(self.name).stem}_{self.medium.name}_{self.model}"
        index = 0
        while (folder / f"{stem}_{index:03d}.png").exists() or (folder / f"{stem}_{index:03d}.ply").exists():
            index += 1
        png, ply = folder / f"{stem}_{index:03d}.png", folder / f"{stem}_{index:03d}.ply"
        self.screenshot(png, widgets=True)
        result = self.result
        colors, _ = display_colors(result.radiance, self.exposure)
        write_result(dataclasses.replace(result, colors=colors, exposure=self.exposure,
                                         metadata=dict(result.metadata, exposure=self.exposure)), ply)
        self.status = self.status.split("\nsaved")[0] + f"\nsaved {png.name} and {ply.name}"
        self._status_actor.set_text("upper_left", self.status)
        return png, ply

    def show(self, **kwargs) -> None:
        """Open the window and hand control to the user (returns when it is closed)."""
        self.plotter.show(**kwargs)

    def close(self) -> None:
        """Close the window and free the renderer."""
        self.plotter.close()

    # ------------------------------------------------------------------------------------------------
    # internals

    def _solver_resolution(self):
        if self._full_next:
            return "full"
        if self.resolution == "interactive":
            return interactive_edge_length(self.scene.mesh, self.medium)
        return self.resolution

    def _solve(self) -> None:
        resolution = self._solver_resolution()
        self._full_next = False
        start = time.perf_counter()
        self.result = self.scene.shade(self.medium, self.lights, model=self.model, method=self.method, tol=self.tol,
                                       resolution=resolution, exposure=self.exposure, per_direction=self.per_direction,
                                       **self.limits)
        self.solve_seconds = time.perf_counter() - start
        self.n_solves += 1
        if self.exposure is None:
            self.exposure = self.result.exposure
        self._highlight_inputs = None
        self._update_status()

    def _refresh(self) -> None:
        self._solve()
        self._redisplay()

    def _update_status(self) -> None:
        result = self.result
        size = float(self.scene.mesh.extent)
        light = ("" if self.azimuth is None else
                 f"light azimuth {self.azimuth:.0f} deg, elevation {self.elevation:.0f} deg; ")
        tolerance = "exact sum" if self.method == "exact" else f"tolerance {self.tol:.3g}"
        self.status = (f"{self.medium.name}, {self.model} dipole, {size:.3g} mm ({self.mm_per_unit:.4g} mm per unit), "
                       f"up {self.up_axis}\n"
                       f"{light}exposure {self.exposure:.3g}\n"
                       f"solved in {self.solve_seconds:.2f} s: {self.method}, {tolerance}, "
                       f"{result.stats['solver_vertices']} of {result.stats['vertices']} vertices")
        if hasattr(self, "_status_actor"):
            self._status_actor.set_text("upper_left", self.status)

    def _radiance_shown(self) -> np.ndarray:
        """Linear radiance per vertex as displayed (with the view-dependent layers that are on)."""
        from ..scatter.outgoing import specular_radiance, subsurface_radiance, view_directions

        result = self.result
        if not (self.view_dependent or self.specular):
            return result.radiance
        eye = np.asarray(self.plotter.camera.position, dtype=np.float64)
        w_o = view_directions(self.base_mesh.points, eye)
        radiance = subsurface_radiance(result.B, result.normals, w_o, self.medium.eta) if self.view_dependent \
            else result.radiance.copy()
        if self.specular:
            for vertices, direction, irradiance in self._highlights():
                radiance[vertices] += specular_radiance(result.normals[vertices], w_o[vertices], direction, irradiance,
                                                        self.medium.eta, self.roughness)
        return radiance

    def _highlights(self) -> list:
        """Per directional sample: (vertices it reaches, direction, irradiance on the surface E cos V)."""
        from ..scatter.fresnel import fresnel_transmittance

        if self._highlight_inputs is None:
            incident, _ = self.scene.incident_on_mesh(self.medium, self.lights, per_direction=True)
            normals = self.result.normals
            inputs = []
            for part in incident.contributions:
                if part.direction is None:  # a point light: no highlight
                    continue
                cos_i = normals[part.vertices] @ part.direction
                # phi = T12 E cos V (irradiance.py), so E cos V = phi / T12
                inputs.append((part.vertices, part.direction,
                               part.phi_rgb / fresnel_transmittance(cos_i, self.medium.eta)[:, None]))
            self._highlight_inputs = inputs
        return self._highlight_inputs

    def _display_colors(self) -> np.ndarray:
        colors, _ = display_colors(self._radiance_shown(), self.exposure)
        return colors

    def _redisplay(self) -> None:
        self.poly.point_data["colors"][:] = self._display_colors()
        self._eye = tuple(self.plotter.camera.position)
        self._update_status()
        self._sync_widgets()
        self.plotter.render()

    def _on_camera(self, camera, _event) -> None:
        """Camera moved: recompute the view-dependent layers (no solve, no render here)."""
        if not (self.view_dependent or self.specular):
            return
        eye = tuple(camera.GetPosition())
        if eye == self._eye:
            return
        self._eye = eye
        self.poly.point_data["colors"][:] = self._display_colors()

    def _add_widgets(self) -> None:
        from ..scatter.names import MODELS

        plotter = self.plotter
        style = {"style": "modern", "interaction_event": "end"}
        titled = {**style, "title_height": 0.02}
        row_low, row_high = 0.08, 0.21
        columns = [(0.03, 0.31), (0.36, 0.64), (0.69, 0.97)]

        def at(column, row):
            (x0, x1), y = columns[column], row
            return {"pointa": (x0, y), "pointb": (x1, y)}

        choices = {key: key for key in diffusive_materials()}
        if self.medium.name not in choices:  # a medium of its own: offer it first
            choices = {self.medium.name: self.medium, **choices}
        self._materials = list(choices)
        self.widgets["material"] = plotter.add_text_slider_widget(
            lambda name: self.set_material(choices[name]), self._materials,
            value=self._materials.index(self.medium.name), **at(0, row_low), **style)
        self.widgets["model"] = plotter.add_text_slider_widget(
            self.set_model, list(MODELS), value=list(MODELS).index(self.model), **at(1, row_low), **style)
        for key in ("material", "model"):
            self.widgets[key].GetRepresentation().SetTitleHeight(titled["title_height"])
        base = float(self.base_mesh.mm_per_unit)
        self.widgets["scale"] = plotter.add_slider_widget(
            self.set_scale, [base * SCALE_RANGE[0], base * SCALE_RANGE[1]], value=self.mm_per_unit,
            title="scale (mm per unit)", fmt="%.3g", **at(2, row_low), **titled)
        if self._key_light is not None:
            self.widgets["azimuth"] = plotter.add_slider_widget(
                lambda a: self.set_light(a, self.elevation), [-180.0, 180.0], value=self.azimuth,
                title="light azimuth (deg)", fmt="%.0f", **at(0, row_high), **titled)
            self.widgets["elevation"] = plotter.add_slider_widget(
                lambda e: self.set_light(self.azimuth, e), [-90.0, 90.0], value=self.elevation,
                title="light elevation (deg)", fmt="%.0f", **at(1, row_high), **titled)
        stops = math.log2(self.exposure)
        self.widgets["exposure"] = plotter.add_slider_widget(
            lambda v: self.set_exposure(2.0 ** v), [stops - EXPOSURE_STOPS, stops + EXPOSURE_STOPS], value=stops,
            title="exposure (log2)", fmt="%.1f", **at(2, row_high), **titled)
        width, height = plotter.window_size
        for k, (key, label, callback, value) in enumerate(
                (("view_dependent", "T21 toward the camera", self.set_view_dependent, self.view_dependent),
                 ("specular", "specular highlight", self.set_specular, self.specular))):
            y = height - 40 - 36 * k
            self.widgets[key] = plotter.add_checkbox_button_widget(callback, value=value, position=(width - 40, y),
                                                                   size=26, border_size=2)
            self._overlays.append(plotter.add_text(label, position=(width - 250, y + 4), font_size=8, color="white",
                                                   name=f"{key}_label"))

    def _sync_widgets(self) -> None:
        """Put the widgets where the state is (after a change made from code)."""
        from ..scatter.names import MODELS

        values = {"scale": self.mm_per_unit, "exposure": math.log2(self.exposure),
                  "azimuth": self.azimuth, "elevation": self.elevation}
        if self.medium.name in getattr(self, "_materials", ()):
            values["material"] = self._materials.index(self.medium.name)
        values["model"] = list(MODELS).index(self.model)
        for key, value in values.items():
            widget = self.widgets.get(key)
            if widget is not None and value is not None:
                widget.GetRepresentation().SetValue(value)
        if "material" in values and "material" in self.widgets:
            self.widgets["material"].GetRepresentation().SetTitleText(self.medium.name)
        if "model" in self.widgets:
            self.widgets["model"].GetRepresentation().SetTitleText(self.model)
        for key in ("view_dependent", "specular"):
            if key in self.widgets:
                self.widgets[key].GetRepresentation().SetState(int(getattr(self, key)))
