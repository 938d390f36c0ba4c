"""The viewer's window: a PyVista plotter drawing what a :class:`~translucency.app.viewer.state.ViewerState` computes.

The mesh is drawn with its per-vertex display colours and no lighting of PyVista's own
(``rgb=True``): what you see is the solver's radiance after the display transform, ``sRGB(exposure L)``
(:meth:`ViewerState.colors <translucency.app.viewer.state.ViewerState.colors>`; what ``L`` is, and
how fast a change answers, is said in :mod:`translucency.app.viewer.state`). Without the
view-dependent layers the picture equals :func:`~translucency.app.render.render_colors` of the same
colours.

Controls (each calls a method, so the viewer can be driven from code the same way): sliders for
the light's azimuth and elevation (degrees, around the ``up`` axis; they steer the first directional
light, other lights stay as they are), the material (the catalogue's diffusive materials), the model,
the scale (mm per unit of the file: the mesh is scaled and a new :class:`~translucency.app.pipeline.Scene`
made; the picture keeps its framing) and the exposure (log2, display only: no solve); check boxes for
the two view-dependent layers; key ``s`` saves a screenshot and the current bake (PLY) into the output
folder, ``Return`` solves the current state on every vertex (``resolution="full"``), so that ``s`` then
saves that.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ...scatter.budget import DEFAULT_TIME_LIMIT_S
from ...scatter.names import DEFAULT_METHOD, DEFAULT_MODEL, DEFAULT_TOL
from ..render import add_colored_mesh, camera_position, default_camera_direction, new_plotter
from ..settings import DEFAULT_MATERIAL
from .state import ViewerState, diffusive_materials

#: Range of the scale slider, as factors of the mesh's own mm per unit.
SCALE_RANGE = (0.25, 4.0)
#: Half-range of the exposure slider, in stops (log2) around the first exposure.
EXPOSURE_STOPS = 8.0


def _state_attribute(name: str):
    """A viewer attribute that is its state's: read from and written to ``viewer.state``."""

    def get(viewer):
        return getattr(viewer.state, name)

    def put(viewer, value):
        setattr(viewer.state, name, value)

    return property(get, put, doc=f"The state's ``{name}`` (:class:`~translucency.app.viewer.state.ViewerState`).")


class Viewer:
    """A scan shaded by its translucent radiance in a PyVista window, re-solved when a control changes.

    Every control calls one of the ``set_*`` methods; call them from code to drive the viewer the same
    way (the widgets follow). The settings and the solution live in :attr:`state`, a
    :class:`~translucency.app.viewer.state.ViewerState`; its attributes (``medium``, ``model``,
    ``exposure``, ``result``, ``status``, ``n_solves``, ...) are the viewer's too. See the module
    docstrings for what is shown and how fast it answers.

    Parameters
    ----------
    mesh : TriangleMesh or pyvista.PolyData, optional
        A cleaned mesh in mm, or a PolyData in ``unit`` (converted and repaired,
        :func:`~translucency.app.pipeline.mesh_for_shading`); default: the embedded default scan, cleaned.
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
        :data:`~translucency.app.viewer.state.INTERACTIVE_VERTICES` vertices
        (:func:`~translucency.app.viewer.state.interactive_edge_length`); the others are the
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
    unit : {"mm", "cm", "m", "in"} or float, optional
        A PolyData's length unit (None: its ``field_data["length_unit"]``, else inferred from its size).
    """

    base_mesh = _state_attribute("base_mesh")
    name = _state_attribute("name")
    medium = _state_attribute("medium")
    model = _state_attribute("model")
    method = _state_attribute("method")
    tol = _state_attribute("tol")
    resolution = _state_attribute("resolution")
    per_direction = _state_attribute("per_direction")
    limits = _state_attribute("limits")
    shadows = _state_attribute("shadows")
    scene = _state_attribute("scene")
    up_axis = _state_attribute("up_axis")
    up = _state_attribute("up")
    lights = _state_attribute("lights")
    azimuth = _state_attribute("azimuth")
    elevation = _state_attribute("elevation")
    mm_per_unit = _state_attribute("mm_per_unit")
    exposure = _state_attribute("exposure")
    view_dependent = _state_attribute("view_dependent")
    specular = _state_attribute("specular")
    roughness = _state_attribute("roughness")
    result = _state_attribute("result")
    solve_seconds = _state_attribute("solve_seconds")
    n_solves = _state_attribute("n_solves")
    status = _state_attribute("status")

    def __init__(
        self,
        mesh=None,
        material=DEFAULT_MATERIAL,
        lights=None,
        *,
        model=DEFAULT_MODEL,
        method=DEFAULT_METHOD,
        tol=DEFAULT_TOL,
        resolution="interactive",
        shadows=True,
        per_direction=False,
        exposure=None,
        memory_limit=None,
        time_limit=DEFAULT_TIME_LIMIT_S,
        view_dependent=False,
        specular=False,
        roughness=0.25,
        up="auto",
        camera_direction=None,
        window_size=(1024, 768),
        off_screen=False,
        widgets=True,
        output=".",
        name=None,
        unit=None,
    ):
        # settings checked and the scan loaded first; the window before the (slower) first solve
        self.state = ViewerState(
            mesh,
            material,
            lights,
            model=model,
            method=method,
            tol=tol,
            resolution=resolution,
            shadows=shadows,
            per_direction=per_direction,
            exposure=exposure,
            memory_limit=memory_limit,
            time_limit=time_limit,
            view_dependent=view_dependent,
            specular=specular,
            roughness=roughness,
            up=up,
            name=name,
            solve=False,
            unit=unit,
        )
        self.output = Path(output)
        self.widgets = {}
        self._window_shown = False  # set by show() and by screenshot(); a window never shown has no picture yet
        self.plotter = new_plotter(window_size, off_screen=off_screen)
        self.state.solve()
        self.poly = add_colored_mesh(self.plotter, self.base_mesh, self.state.colors())
        if camera_direction is None:
            camera_direction = default_camera_direction(self.up_axis)
        self.plotter.camera_position = camera_position(self.poly.center, self.poly.length, camera_direction, self.up)
        self._status_actor = self.plotter.add_text(
            self.status, position="upper_left", font_size=10, color="white", name="status"
        )
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
        if self.state.set_light(azimuth, elevation):
            self._redisplay()

    def set_material(self, material) -> None:
        """Change the material (catalogue name, entry or Medium) and solve."""
        if self.state.set_material(material):
            self._redisplay()

    def set_model(self, model: str) -> None:
        """Change the scattering model (``directional``, ``standard``, ``better``) and solve."""
        if self.state.set_model(model):
            self._redisplay()

    def set_scale(self, mm_per_unit) -> None:
        """Size of one unit of the mesh's file in mm: scale the mesh, make a new Scene and solve."""
        if self.state.set_scale(mm_per_unit):
            self._redisplay()

    def set_exposure(self, exposure) -> None:
        """Display exposure (linear factor): new colours from the same solution, no solve."""
        if self.state.set_exposure(exposure):
            self._redisplay()

    def set_view_dependent(self, on: bool) -> None:
        """Show ``T21(eta, n . w_o) B`` (on) or ``T21(eta, 1) B`` (off); no solve."""
        if self.state.set_view_dependent(on):
            self._redisplay()

    def set_specular(self, on: bool) -> None:
        """Add (on) or remove the specular highlight; no solve."""
        if self.state.set_specular(on):
            self._redisplay()

    def solve_full(self) -> None:
        """Solve the current state on every vertex of the mesh (slow; see :mod:`translucency.app.viewer.state`)."""
        self.state.solve_full()
        self._redisplay()

    # ------------------------------------------------------------------------------------------------
    # output

    def screenshot(self, path=None, *, widgets: bool = False) -> np.ndarray:
        """The current picture as an (h, w, 3) uint8 image, written as a PNG when ``path`` is given.

        Without ``widgets`` the sliders, check boxes and status line are hidden for the picture.
        """
        from ..outputs import write_png

        if not (self._window_shown or self.plotter.off_screen):  # a window never shown has no picture yet
            self.plotter.show(interactive=False, auto_close=False)
            self._window_shown = True
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
        stem = self.state.file_stem
        index = 0
        while (folder / f"{stem}_{index:03d}.png").exists() or (folder / f"{stem}_{index:03d}.ply").exists():
            index += 1
        png, ply = folder / f"{stem}_{index:03d}.png", folder / f"{stem}_{index:03d}.ply"
        self.screenshot(png, widgets=True)
        self.state.write_bake(ply)
        self.state.add_note(f"saved {png.name} and {ply.name}")
        self._status_actor.set_text("upper_left", self.status)
        return png, ply

    def show(self, **kwargs) -> None:
        """Open the window and hand control to the user (returns when it is closed)."""
        self._window_shown = True
        self.plotter.show(**kwargs)

    def close(self) -> None:
        """Close the window and free the renderer."""
        self.plotter.close()

    # ------------------------------------------------------------------------------------------------
    # internals

    def _redisplay(self) -> None:
        """Draw what the state computes: colours from the current camera, status, widget positions."""
        self.state.set_eye(self.plotter.camera.position)
        self.poly.point_data["colors"][:] = self.state.colors()
        self._status_actor.set_text("upper_left", self.status)
        self._sync_widgets()
        self.plotter.render()

    def _on_camera(self, camera, _event) -> None:
        """Camera moved: recompute the view-dependent layers (no solve, no render here)."""
        if self.state.set_eye(camera.GetPosition()):
            self.poly.point_data["colors"][:] = self.state.colors()

    def _add_widgets(self) -> None:
        from ...scatter.names import MODELS

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
            lambda name: self.set_material(choices[name]),
            self._materials,
            value=self._materials.index(self.medium.name),
            **at(0, row_low),
            **style,
        )
        self.widgets["model"] = plotter.add_text_slider_widget(
            self.set_model, list(MODELS), value=list(MODELS).index(self.model), **at(1, row_low), **style
        )
        for key in ("material", "model"):
            self.widgets[key].GetRepresentation().SetTitleHeight(titled["title_height"])
        base = float(self.base_mesh.mm_per_unit)
        self.widgets["scale"] = plotter.add_slider_widget(
            self.set_scale,
            [base * SCALE_RANGE[0], base * SCALE_RANGE[1]],
            value=self.mm_per_unit,
            title="scale (mm per unit)",
            fmt="%.3g",
            **at(2, row_low),
            **titled,
        )
        if self.state.key_light is not None:
            self.widgets["azimuth"] = plotter.add_slider_widget(
                lambda a: self.set_light(a, self.elevation),
                [-180.0, 180.0],
                value=self.azimuth,
                title="light azimuth (deg)",
                fmt="%.0f",
                **at(0, row_high),
                **titled,
            )
            self.widgets["elevation"] = plotter.add_slider_widget(
                lambda e: self.set_light(self.azimuth, e),
                [-90.0, 90.0],
                value=self.elevation,
                title="light elevation (deg)",
                fmt="%.0f",
                **at(1, row_high),
                **titled,
            )
        stops = math.log2(self.exposure)
        self.widgets["exposure"] = plotter.add_slider_widget(
            lambda v: self.set_exposure(2.0**v),
            [stops - EXPOSURE_STOPS, stops + EXPOSURE_STOPS],
            value=stops,
            title="exposure (log2)",
            fmt="%.1f",
            **at(2, row_high),
            **titled,
        )
        width, height = plotter.window_size
        for k, (key, label, callback, value) in enumerate(
            (
                ("view_dependent", "T21 toward the camera", self.set_view_dependent, self.view_dependent),
                ("specular", "specular highlight", self.set_specular, self.specular),
            )
        ):
            y = height - 40 - 36 * k
            self.widgets[key] = plotter.add_checkbox_button_widget(
                callback, value=value, position=(width - 40, y), size=26, border_size=2
            )
            self._overlays.append(
                plotter.add_text(label, position=(width - 250, y + 4), font_size=8, color="white", name=f"{key}_label")
            )

    def _sync_widgets(self) -> None:
        """Put the widgets where the state is (after a change made from code)."""
        from ...scatter.names import MODELS

        values = {
            "scale": self.mm_per_unit,
            "exposure": math.log2(self.exposure),
            "azimuth": self.azimuth,
            "elevation": self.elevation,
        }
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
