"""The viewer's window: a PyVista plotter drawing what a :class:`~translucency.app.viewer.state.ViewerState` computes.

The mesh is drawn with its per-vertex display colours and no lighting of PyVista's own
(``rgb=True``): what you see is the solver's radiance after the display transform, ``sRGB(exposure L)``
(:meth:`ViewerState.colors <translucency.app.viewer.state.ViewerState.colors>`; what ``L`` is, and
how fast a change answers, is said in :mod:`translucency.app.viewer.state`). Without the
view-dependent layers the picture equals :func:`~translucency.app.render.render_colors` of the same
colours.

Layout: the scan has the window's left part to itself; the controls live in a strip on the right
(:data:`CONTROL_STRIP` of the width): at the top a light compass (a small copy of the scan turned with
the camera, and the light's arrow, :func:`~translucency.app.render.light_glyph`, following the light
sliders), then the status, the check boxes and the sliders. No control covers the scan.

False colour: check box (or key ``y``) swaps the sRGB view for the luminance in W/(m² sr) per W/m²
through a colour map, with its colour bar under the scan; a second check box (or key ``l``) chooses a
log or a linear scale (:mod:`translucency.app.viewer.state`).

Pictures: :meth:`Viewer.screenshot` and key ``s`` save the scan's part of the window only -- what
the scan looks like, with the colour bar in false colour, never a slider or a check box.

Controls (each calls a method, so the viewer can be driven from code the same way): sliders for
the light's azimuth and elevation (degrees, around the ``up`` axis; they steer the first directional
light, other lights stay as they are), the material (the catalogue's diffusive materials), the model,
the scale (mm per unit of the file: the mesh is scaled and a new :class:`~translucency.app.shading.scene.Scene`
made; the picture keeps its framing) and the exposure (log2, display only: no solve); check boxes for
the two view-dependent layers; key ``s`` saves a screenshot and the current bake (PLY) into the output
folder, ``Return`` solves the current state on every vertex (``resolution="full"``), so that ``s`` then
saves that.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..framing import scan_camera
from ..render import (
    LIGHT_GLYPH_COLOR,
    light_glyph,
    new_plotter,
)
from .layers import ScanLayers
from .state import ViewerState, diffusive_materials

#: Range of the scale slider, as factors of the mesh's own mm per unit.
SCALE_RANGE = (0.25, 4.0)
#: Half-range of the exposure slider, in stops (log2) around the first exposure.
EXPOSURE_STOPS = 8.0
#: Fraction of the window's width the control strip takes (right); the scan has the rest.
CONTROL_STRIP = 0.3
#: Fraction of the window's height the light compass takes (top of the strip).
COMPASS_HEIGHT = 0.22
#: Background of the control strip.
STRIP_BACKGROUND = "#202020"


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
        :func:`~translucency.app.shading.scan.mesh_for_shading`); default: the embedded default scan, cleaned.
    material : str or Material or Medium, optional
        Shortcut for the starting material (catalogue name, 1/mm coefficients).
    lights : light or sequence of lights, optional
        Directions in the scan's own coordinates. Default: one white directional light of 1 W/m²
        above and in front of the scan (:func:`~translucency.app.shading.settings.default_light_direction` of
        ``up``). The light sliders steer the first directional light; without one they are not shown.
    settings : ShadeSettings, optional
        The starting settings (default :func:`~translucency.app.shading.settings.viewer_settings`), as in
        :class:`~translucency.app.viewer.state.ViewerState`; ``up`` is also the camera's view-up and where the
        default camera is (above and in front).
    **changes
        Any field of the settings by name (``tol=0.05``, ``up="z"``, ...), replacing the one of ``settings``.
    resolution : "interactive", "full", "auto" or float
        Where ``B`` is computed while controls change: ``"interactive"`` (default) is a proxy of about
        :data:`~translucency.app.viewer.state.INTERACTIVE_VERTICES` vertices
        (:func:`~translucency.app.viewer.state.interactive_edge_length`); the others are the
        shading policy's (a number is a proxy edge length in mm).
    view_dependent, specular : bool
        Show ``T21(eta, n . w_o) B`` instead of ``T21(eta, 1) B``; add the specular highlight.
    roughness : float
        GGX ``alpha`` of the highlight.
    camera_direction : sequence of 3 float, optional
        From the mesh's centre toward the camera at the start, in the scan's coordinates (default: the scan's
        front, :func:`~translucency.app.framing.front_direction`); the whole scan is framed
        (:func:`~translucency.app.framing.scan_camera`).
    window_size : (int, int)
        Window size, pixels.
    off_screen : bool
        Render without a window (screenshots, tests).
    widgets : bool
        Show the control strip (sliders, check boxes, status, light compass) beside the scan.
    output : path-like
        Folder for the files the ``s`` key saves (default: the current folder).
    name : str, optional
        Stem of the saved files (default: the mesh's file name, or ``scan``).
    unit : {"mm", "cm", "m", "in"} or float, optional
        A PolyData's length unit (None: its ``field_data["length_unit"]``, else inferred from its size).
    plotter : pyvista.Plotter, optional
        Draw into this plotter's current renderer instead of a window of the viewer's own (the
        ``window_size`` and ``off_screen`` arguments are then the plotter's). The host owns the window:
        no control strip and no keys are added (drive the viewer by its ``set_*`` methods), and
        :meth:`close` leaves the plotter open.
    """

    base_mesh = _state_attribute("base_mesh")
    name = _state_attribute("name")
    medium = _state_attribute("medium")
    model = _state_attribute("model")
    method = _state_attribute("method")
    tol = _state_attribute("tol")
    resolution = _state_attribute("resolution")
    per_direction = _state_attribute("per_direction")
    bounces = _state_attribute("bounces")
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
        material=None,
        lights=None,
        *,
        settings=None,
        resolution="interactive",
        view_dependent=False,
        specular=False,
        roughness=0.25,
        camera_direction=None,
        window_size=(1024, 768),
        off_screen=False,
        widgets=True,
        output=".",
        name=None,
        unit=None,
        plotter=None,
        **changes,
    ):
        # settings checked and the scan loaded first; the window before the (slower) first solve
        self.state = ViewerState(
            mesh,
            material,
            lights,
            settings=settings,
            resolution=resolution,
            view_dependent=view_dependent,
            specular=specular,
            roughness=roughness,
            name=name,
            solve=False,
            unit=unit,
            **changes,
        )
        self.output = Path(output)
        self.widgets = {}
        self._window_shown = False  # set by show() and by screenshot(); a window never shown has no picture yet
        self._own_plotter = plotter is None
        widgets = bool(widgets) and self._own_plotter
        if plotter is not None:
            self.plotter = plotter
        elif widgets:  # the scan on the left (both rows), the compass and the controls in a strip on the right
            self.plotter = new_plotter(
                window_size,
                off_screen=off_screen,
                shape=(2, 2),
                col_weights=[1.0 - CONTROL_STRIP, CONTROL_STRIP],
                row_weights=[COMPASS_HEIGHT, 1.0 - COMPASS_HEIGHT],
                groups=[(np.s_[:], 0)],
                border=False,
            )
            self.plotter.subplot(0, 0)
        else:
            self.plotter = new_plotter(window_size, off_screen=off_screen)
        #: The renderer that draws the scan (screenshots are its part of the window).
        self.renderer = self.plotter.renderer
        self._status_actor = None
        self.state.notify = self._notify
        self.state.solve()
        self.layers = ScanLayers(
            self.plotter,
            self.base_mesh,
            scalar_bar={
                "color": "white",
                "position_x": 0.15,
                "position_y": 0.01,
                "width": 0.7,
                "height": 0.09,
                "fmt": "%.3g",
                "title_font_size": 12,
                "label_font_size": 11,
            },
        )
        #: The display-colour and false-colour layers' meshes (their arrays are what is shown).
        self.poly, self.false_colour_poly = self.layers.poly, self.layers.false_colour_poly
        width, height = self.renderer.GetSize() if self.renderer.GetSize()[1] else self.plotter.window_size
        self.renderer.camera_position = scan_camera(
            self.base_mesh,
            self.up,
            width / max(height, 1),
            self.state.front if camera_direction is None else camera_direction,
        )
        self._compass = self.compass_arrow = None
        if widgets:
            self._add_widgets()
            self.plotter.subplot(0, 0)
        self.renderer.camera.AddObserver("ModifiedEvent", self._on_camera)
        if self._own_plotter:
            self.plotter.add_key_event("s", self.save)
            self.plotter.add_key_event("Return", self.solve_full)
            self.plotter.add_key_event("y", lambda: self.set_false_colour(not self.state.false_colour))
            self.plotter.add_key_event(
                "l", lambda: self.set_false_colour_scale("linear" if self.state.false_colour_scale == "log" else "log")
            )
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

    def set_false_colour(self, on: bool, quantity: str | None = None) -> None:
        """Show the false colour (on: luminance, or ``quantity``, in physical units) or the sRGB view; no solve."""
        if self.state.set_false_colour(on, quantity):
            self._redisplay()

    def set_false_colour_scale(self, scale: str) -> None:
        """``log`` or ``linear`` scale of the false colour; no solve."""
        self.state.set_false_colour_scale(scale)
        self._redisplay()

    def solve_full(self) -> None:
        """Solve the current state on every vertex of the mesh (slow; see :mod:`translucency.app.viewer.state`)."""
        self.state.solve_full()
        self._redisplay()

    # ------------------------------------------------------------------------------------------------
    # output

    def screenshot(self, path=None, *, widgets: bool = False) -> np.ndarray:
        """The current picture as an (h, w, 3) uint8 image, written as a PNG when ``path`` is given.

        Without ``widgets`` (default) the picture is the scan's renderer only -- the scan, and the colour
        bar in false colour -- cropped from the window, so no control is in it; with ``widgets`` it is the
        whole window.
        """
        from ..outputs import write_png

        if not (self._window_shown or self.plotter.off_screen):  # a window never shown has no picture yet
            self.plotter.show(interactive=False, auto_close=False)
            self._window_shown = True
        self.plotter.render()
        image = np.asarray(self.plotter.screenshot(return_img=True))
        if not widgets:
            image = self._crop_to_scan(image)
        if path is not None:
            write_png(path, image)
        return image

    def _crop_to_scan(self, image) -> np.ndarray:
        """The scan renderer's pixels of a window image (rows from the top, VTK's origin at the bottom)."""
        x0, x1, y0, y1 = (float(v) for v in np.asarray(self.renderer.GetViewport())[[0, 2, 1, 3]])
        height, width = image.shape[:2]
        left, right = round(x0 * width), round(x1 * width)
        bottom, top = round(y0 * height), round(y1 * height)
        return np.ascontiguousarray(image[height - top : height - bottom, left:right])

    def save(self, folder=None) -> tuple[Path, Path]:
        """Save a screenshot (PNG, the scan's part of the window, :meth:`screenshot`) and the current bake
        (PLY) into ``folder``.

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
        self.screenshot(png)
        self.state.write_bake(ply)
        self.state.add_note(f"saved {png.name} and {ply.name}")
        self._show_status()
        return png, ply

    def show(self, **kwargs) -> None:
        """Open the window and hand control to the user (returns when it is closed)."""
        self._window_shown = True
        self.plotter.show(**kwargs)

    def close(self) -> None:
        """Close the window and free the renderer (a plotter passed in stays open: it is the host's)."""
        if self._own_plotter:
            self.plotter.close()

    # ------------------------------------------------------------------------------------------------
    # internals

    def _redisplay(self) -> None:
        """Draw what the state computes: colours or false colour from the current camera, status, widgets."""
        self.state.set_eye(self.renderer.camera.position)
        self._recolour()
        self._show_status()
        self._sync_widgets()
        self._point_compass()
        self.plotter.render()

    def _recolour(self) -> None:
        """New colours or false colour from the state (no render)."""
        self.layers.recolour(self.state)

    def _notify(self) -> None:
        """The state's status changed during a solve: show it now (a window that exists already)."""
        if self._status_actor is not None:
            self._show_status()
            self.plotter.render()

    def _show_status(self) -> None:
        """The status, wrapped to the strip's width."""
        if self._status_actor is None:
            return
        import textwrap

        width = max(20, int(self.plotter.window_size[0] * CONTROL_STRIP / 7.5))
        lines = [textwrap.fill(line, width, subsequent_indent="  ") for line in self.status.split("\n")]
        self._status_actor.SetInput("\n".join(lines))

    def _on_camera(self, camera, _event) -> None:
        """Camera moved: recompute the view-dependent layers (no solve, no render here), turn the compass."""
        if self.state.set_eye(camera.GetPosition()):
            self._recolour()
        self._turn_compass()

    def _point_compass(self) -> None:
        """The compass's arrow along the current key light."""
        if self._compass is None or self.state.key_light is None:
            return
        arrow, radius = self._compass
        arrow.copy_from(light_glyph((0.0, 0.0, 0.0), radius, self.lights[self.state.key_light].direction))

    def _turn_compass(self) -> None:
        """The compass's camera looks from where the scan's camera looks (same direction and view-up)."""
        if self._compass is None:
            return
        camera, compass = self.renderer.camera, self._compass_renderer.camera
        offset = np.asarray(camera.GetPosition()) - np.asarray(camera.GetFocalPoint())
        offset = offset / np.linalg.norm(offset)
        compass.SetFocalPoint(0.0, 0.0, 0.0)
        compass.SetPosition(*(offset * 6.0 * self._compass[1]))
        compass.SetViewUp(*camera.GetViewUp())
        compass.SetParallelProjection(True)
        compass.SetParallelScale(1.7 * self._compass[1])
        self._compass_renderer.ResetCameraClippingRange()
        self._compass_renderer.camera_set = True  # PyVista must not reset it on the first render

    def _add_widgets(self) -> None:
        """The control strip: compass (top), status, check boxes and sliders, none over the scan."""
        from ...scatter.names import MODELS

        plotter = self.plotter
        width, height = plotter.window_size
        strip_x0 = 1.0 - CONTROL_STRIP
        strip_px = int(round(strip_x0 * width))

        # the light compass: the scan, scaled to a unit radius, and the light's arrow, turned with the camera
        plotter.subplot(0, 1)
        plotter.renderer.set_background(STRIP_BACKGROUND)
        self._compass_renderer = plotter.renderer
        if self.state.key_light is not None:
            points = self.base_mesh.points - 0.5 * (
                self.base_mesh.points.min(axis=0) + self.base_mesh.points.max(axis=0)
            )
            radius = 1.0
            small = self.base_mesh.replace(points=points / (0.5 * float(self.base_mesh.extent)))
            from ...io.polydata import to_pyvista

            plotter.add_mesh(to_pyvista(small), color="lightgrey", name="compass_scan")
            arrow = light_glyph((0.0, 0.0, 0.0), radius, self.lights[self.state.key_light].direction)
            plotter.add_mesh(arrow, color=LIGHT_GLYPH_COLOR, name="compass_arrow")
            plotter.add_text("light", position="upper_left", font_size=8, color="white", name="compass_label")
            self._compass = (arrow, radius)
            #: The compass's arrow (PolyData): from the key light toward the object.
            self.compass_arrow = arrow
            self._turn_compass()

        # the status, the check boxes and the sliders
        plotter.subplot(1, 1)
        plotter.renderer.set_background(STRIP_BACKGROUND)
        self._status_actor = plotter.add_text(" ", position=(8, 0), font_size=6, color="white", name="status")
        self._status_actor.GetTextProperty().SetVerticalJustificationToTop()
        strip_height = int(round((1.0 - COMPASS_HEIGHT) * height))
        self._status_actor.SetPosition(8, strip_height - 6)
        self._show_status()
        toggles = (
            ("false_colour", "false colour (key y)", self.set_false_colour, self.state.false_colour),
            (
                "log_scale",
                "log scale (key l)",
                lambda on: self.set_false_colour_scale("log" if on else "linear"),
                self.state.false_colour_scale == "log",
            ),
            ("view_dependent", "T21 toward the camera", self.set_view_dependent, self.view_dependent),
            ("specular", "specular highlight", self.set_specular, self.specular),
        )
        box = max(14, min(22, height // 35))
        step = box + 8
        first = int(strip_height * 0.66 + 2 * step)  # from the bottom of the window (the strip starts there)
        for k, (key, label, callback, value) in enumerate(toggles):
            y = first - k * step
            self.widgets[key] = plotter.add_checkbox_button_widget(
                callback, value=value, position=(strip_px + 8, y), size=box, border_size=2, color_off="grey"
            )
            plotter.add_text(label, position=(box + 16, y + box // 4), font_size=6, color="white", name=f"{key}_label")

        style = {"style": "modern", "interaction_event": "end"}
        titled = {**style, "title_height": 0.018}
        # PyVista places sliders in the current renderer's normalised viewport: the strip, below the compass
        rows = [0.06 + k * 0.098 for k in range(6)]  # bottom to top
        x0, x1 = 0.06, 0.94

        def at(row):
            return {"pointa": (x0, rows[row]), "pointb": (x1, rows[row])}

        choices = {key: key for key in diffusive_materials()}
        if self.medium.name not in choices:  # a medium of its own: offer it first
            choices = {self.medium.name: self.medium, **choices}
        self._materials = list(choices)
        self.widgets["material"] = plotter.add_text_slider_widget(
            lambda name: self.set_material(choices[name]),
            self._materials,
            value=self._materials.index(self.medium.name),
            **at(5),
            **style,
        )
        self.widgets["model"] = plotter.add_text_slider_widget(
            self.set_model, list(MODELS), value=list(MODELS).index(self.model), **at(4), **style
        )
        for key in ("material", "model"):  # the title names the choice; the index is no use
            self.widgets[key].GetRepresentation().SetTitleHeight(titled["title_height"])
            self.widgets[key].GetRepresentation().ShowSliderLabelOff()
        # relighting answers while the slider moves; a full solve when it is let go
        light_style = {**titled, "interaction_event": "always" if self.state.method == "relight" else "end"}
        if self.state.key_light is not None:
            self.widgets["azimuth"] = plotter.add_slider_widget(
                lambda a: self.set_light(a, self.elevation),
                [-180.0, 180.0],
                value=self.azimuth,
                title="light azimuth (deg)",
                fmt="%.0f",
                **at(3),
                **light_style,
            )
            self.widgets["elevation"] = plotter.add_slider_widget(
                lambda e: self.set_light(self.azimuth, e),
                [-90.0, 90.0],
                value=self.elevation,
                title="light elevation (deg)",
                fmt="%.0f",
                **at(2),
                **light_style,
            )
        stops = math.log2(self.exposure)
        self.widgets["exposure"] = plotter.add_slider_widget(
            lambda v: self.set_exposure(2.0**v),
            [stops - EXPOSURE_STOPS, stops + EXPOSURE_STOPS],
            value=stops,
            title="exposure (log2)",
            fmt="%.1f",
            **at(1),
            **titled,
        )
        base = float(self.base_mesh.mm_per_unit)
        self.widgets["scale"] = plotter.add_slider_widget(
            self.set_scale,
            [base * SCALE_RANGE[0], base * SCALE_RANGE[1]],
            value=self.mm_per_unit,
            title="scale (mm per unit)",
            fmt="%.3g",
            **at(0),
            **titled,
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
        states = {
            "view_dependent": self.view_dependent,
            "specular": self.specular,
            "false_colour": self.state.false_colour,
            "log_scale": self.state.false_colour_scale == "log",
        }
        for key, on in states.items():
            if key in self.widgets:
                self.widgets[key].GetRepresentation().SetState(int(on))
