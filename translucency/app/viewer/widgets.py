"""The viewer's window: a PyVista plotter drawing what a :class:`~translucency.app.viewer.state.ViewerState` computes.

The mesh is drawn with its per-vertex display colours and no lighting of PyVista's own
(``rgb=True``): what you see is the solver's radiance after the display transform, ``sRGB(exposure L)``
(:meth:`ViewerState.colors <translucency.app.viewer.state.ViewerState.colors>`; what ``L`` is, and
how fast a change answers, is said in :mod:`translucency.app.viewer.state`). Without the
view-dependent layers the picture equals :func:`~translucency.app.render.render_colors` of the same
colours.

Layout: the scan has the window's left part to itself; the controls live in a strip on the right
(:data:`~translucency.app.viewer.controls.CONTROL_STRIP` of the width; :mod:`translucency.app.viewer.controls`):
at the top a light compass (a small copy of the scan turned with the camera, and the light's arrow,
:func:`~translucency.app.render.light_glyph`, following the light sliders; :mod:`translucency.app.viewer.compass`),
then the status, the check boxes and the sliders. No control covers the scan.

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

from pathlib import Path

import numpy as np

from ..framing import PYVISTA_BAR_ROOM, scan_camera
from ..render import new_plotter
from .controls import ControlStrip, strip_plotter
from .forwarding import attribute_of
from .layers import ScanLayers
from .saving import numbered_paths
from .state import ViewerState

#: The false colour's bar, under the scan (keywords of PyVista's ``add_scalar_bar``).
SCALAR_BAR = {
    "color": "white",
    "position_x": 0.15,
    "position_y": 0.05,
    "width": 0.7,
    "height": 0.1,
    "fmt": "%.3g",
    "title_font_size": 12,
    "label_font_size": 11,
}


def framings(mesh, up, renderer, window_size, direction) -> tuple[list, list]:
    """The scan framed whole from ``direction`` (:func:`~translucency.app.framing.scan_camera`), without and with
    room under it for the false colour's bar (PyVista camera positions)."""
    width, height = renderer.GetSize() if renderer.GetSize()[1] else window_size
    aspect = width / max(height, 1)
    return scan_camera(mesh, up, aspect, direction), scan_camera(mesh, up, aspect, direction, PYVISTA_BAR_ROOM)


def reframe_for_bar(renderer, framed, bar_shown: bool) -> None:
    """Frame the scan with room for the false colour's bar under it (``bar_shown``) or without, when the camera is
    at the other of the two ``framed`` positions (:func:`framings`); a camera the user has moved stays."""
    before, after = (framed[0], framed[1]) if bar_shown else (framed[1], framed[0])

    def flat(position):
        return np.concatenate([np.ravel(np.asarray(part, dtype=float)) for part in position])

    if np.allclose(flat(renderer.camera_position), flat(before)):
        renderer.camera_position = after


def renderer_pixels(image, renderer) -> np.ndarray:
    """The pixels of ``renderer``'s viewport in an image of its whole window, (h, w, 3) (rows from the top, VTK's
    origin at the bottom)."""
    x0, x1, y0, y1 = (float(v) for v in np.asarray(renderer.GetViewport())[[0, 2, 1, 3]])
    height, width = image.shape[:2]
    left, right = round(x0 * width), round(x1 * width)
    bottom, top = round(y0 * height), round(y1 * height)
    return np.ascontiguousarray(image[height - top : height - bottom, left:right])


def _state_attribute(name: str):
    """A viewer attribute that is its state's: read from and written to ``viewer.state``."""
    return attribute_of("state", name, f"The state's ``{name}`` (:class:`~translucency.app.viewer.state.ViewerState`).")


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
        :data:`~translucency.app.viewer.solve_settings.INTERACTIVE_VERTICES` vertices
        (:func:`~translucency.app.viewer.solve_settings.interactive_edge_length`); the others are the
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
        self._window_shown = False  # set by show() and by screenshot(); a window never shown has no picture yet
        self._own_plotter = plotter is None
        widgets = bool(widgets) and self._own_plotter
        if plotter is not None:
            self.plotter = plotter
        elif widgets:  # the scan on the left (both rows), the compass and the controls in a strip on the right
            self.plotter = strip_plotter(window_size, off_screen=off_screen)
        else:
            self.plotter = new_plotter(window_size, off_screen=off_screen)
        #: The renderer that draws the scan (screenshots are its part of the window).
        self.renderer = self.plotter.renderer
        #: The control strip (compass, status, check boxes, sliders); None without one.
        self.controls = None
        self.state.notify = self._notify
        self.state.solve()
        self.layers = ScanLayers(self.plotter, self.base_mesh, scalar_bar=SCALAR_BAR)
        #: The display-colour and false-colour layers' meshes (their arrays are what is shown).
        self.poly, self.false_colour_poly = self.layers.poly, self.layers.false_colour_poly
        direction = self.state.front if camera_direction is None else camera_direction
        self._framings = framings(self.base_mesh, self.up, self.renderer, self.plotter.window_size, direction)
        self.renderer.camera_position = self._framings[0]
        if widgets:
            self.controls = ControlStrip(self)
        #: The VTK widgets of the control strip by name (:class:`~translucency.app.viewer.controls.ControlStrip`).
        self.widgets = self.controls.widgets if self.controls is not None else {}
        #: The compass's arrow (PolyData): from the key light toward the object; None without a compass.
        self.compass_arrow = self.controls.compass_arrow if self.controls is not None else None
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
            reframe_for_bar(self.renderer, self._framings, self.state.false_colour)
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
            image = renderer_pixels(image, self.renderer)
        if path is not None:
            write_png(path, image)
        return image

    def save(self, folder=None) -> tuple[Path, Path]:
        """Save a screenshot (PNG, the scan's part of the window, :meth:`screenshot`) and the current bake
        (PLY) into ``folder``.

        The bake holds the radiance toward the normal and colours at the current exposure (a bake does
        not depend on the view). File names are ``<name>_<material>_<model>_<n>`` with the first free
        ``n``. Returns ``(png, ply)``.
        """
        folder = Path(folder) if folder is not None else self.output
        folder.mkdir(parents=True, exist_ok=True)
        png, ply = numbered_paths(folder, self.state.file_stem, (".png", ".ply"))
        self.screenshot(png)
        self.state.write_bake(ply)
        self.state.add_note(f"saved {png.name} and {ply.name}")
        if self.controls is not None:
            self.controls.show_status(self.status)
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
        if self.controls is not None:
            self.controls.follow(self.state)
        self.plotter.render()

    def _recolour(self) -> None:
        """New colours or false colour from the state (no render)."""
        self.layers.recolour(self.state)

    def _notify(self) -> None:
        """The state's status changed during a solve: show it now (a window that exists already)."""
        if self.controls is not None:
            self.controls.show_status(self.status)
            self.plotter.render()

    def _on_camera(self, camera, _event) -> None:
        """Camera moved: recompute the view-dependent layers (no solve, no render here), turn the compass."""
        if self.state.set_eye(camera.GetPosition()):
            self._recolour()
        if self.controls is not None:
            self.controls.turn_compass(self.renderer.camera)
