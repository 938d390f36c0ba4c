"""The control strip of the viewer's PyVista window: its layout, and the compass, status, check boxes and sliders.

The scan has the window's left part to itself; the strip on the right (:data:`CONTROL_STRIP` of the width)
holds at the top the light compass (:mod:`translucency.app.viewer.compass`), then the status, the check
boxes and the sliders. No control covers the scan. Each control calls one of the window's ``set_*`` methods
(:class:`~translucency.app.viewer.widgets.Viewer`), and :meth:`ControlStrip.follow` puts them back where the
state is after a change made from code.
"""

from __future__ import annotations

import math
import textwrap

import numpy as np

from ..render import new_plotter
from .compass import LightCompass
from .state import diffusive_materials

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
#: Height of a slider's title, as a fraction of the strip's renderer.
TITLE_HEIGHT = 0.018


def strip_plotter(window_size, *, off_screen: bool):
    """A plotter laid out for the strip: the scan on the left (both rows, the current renderer on return), the
    compass (top) and the controls in a strip on the right. ``window_size`` in pixels."""
    plotter = new_plotter(
        window_size,
        off_screen=off_screen,
        shape=(2, 2),
        col_weights=[1.0 - CONTROL_STRIP, CONTROL_STRIP],
        row_weights=[COMPASS_HEIGHT, 1.0 - COMPASS_HEIGHT],
        groups=[(np.s_[:], 0)],
        border=False,
    )
    plotter.subplot(0, 0)
    return plotter


class ControlStrip:
    """The compass, the status and the controls of ``viewer``'s window (a plotter of :func:`strip_plotter`).

    Attributes
    ----------
    widgets : dict
        The VTK widgets by name: ``false_colour``, ``log_scale``, ``view_dependent``, ``specular`` (check boxes),
        ``material``, ``model``, ``azimuth``, ``elevation`` (without a directional light: none), ``exposure``,
        ``scale`` (sliders).
    materials : list of str
        The material slider's choices, in order.
    compass : LightCompass or None
        The light compass (None when the lights hold no directional light).
    compass_arrow : pyvista.PolyData or None
        The compass's arrow, from the key light toward the object.
    """

    def __init__(self, viewer):
        self.viewer, self.plotter = viewer, viewer.plotter
        self.widgets, self.materials, self.compass = {}, [], None
        state = viewer.state
        self.plotter.subplot(0, 1)
        self.plotter.renderer.set_background(STRIP_BACKGROUND)
        if state.key_light is not None:
            self.compass = LightCompass(self.plotter, state.base_mesh, state.lights[state.key_light].direction)
            self.compass.turn(viewer.renderer.camera)
        self.compass_arrow = self.compass.arrow if self.compass is not None else None
        self.plotter.subplot(1, 1)
        self.plotter.renderer.set_background(STRIP_BACKGROUND)
        strip_height = int(round((1.0 - COMPASS_HEIGHT) * self.plotter.window_size[1]))
        self._status = self.plotter.add_text(" ", position=(8, 0), font_size=6, color="white", name="status")
        self._status.GetTextProperty().SetVerticalJustificationToTop()
        self._status.SetPosition(8, strip_height - 6)
        self.show_status(state.status)
        self._add_check_boxes(strip_height)
        self._add_choices()
        self._add_sliders()
        self.plotter.subplot(0, 0)  # back to the scan's renderer

    def show_status(self, text: str) -> None:
        """``text`` in the status, each line wrapped to the strip's width (no render)."""
        width = max(20, int(self.plotter.window_size[0] * CONTROL_STRIP / 7.5))
        lines = [textwrap.fill(line, width, subsequent_indent="  ") for line in text.split("\n")]
        self._status.SetInput("\n".join(lines))

    def turn_compass(self, camera) -> None:
        """The compass seen from where the scan's ``camera`` looks (no render)."""
        if self.compass is not None:
            self.compass.turn(camera)

    def follow(self, state) -> None:
        """The status, the controls and the compass's arrow where ``state`` is (after a change made from code)."""
        from ...scatter.names import MODELS

        self.show_status(state.status)
        values = {
            "scale": state.mm_per_unit,
            "exposure": math.log2(state.exposure),
            "azimuth": state.azimuth,
            "elevation": state.elevation,
        }
        if state.medium.name in self.materials:
            values["material"] = self.materials.index(state.medium.name)
        values["model"] = list(MODELS).index(state.model)
        for key, value in values.items():
            widget = self.widgets.get(key)
            if widget is not None and value is not None:
                widget.GetRepresentation().SetValue(value)
        if "material" in values and "material" in self.widgets:
            self.widgets["material"].GetRepresentation().SetTitleText(state.medium.name)
        if "model" in self.widgets:
            self.widgets["model"].GetRepresentation().SetTitleText(state.model)
        checked = {
            "view_dependent": state.view_dependent,
            "specular": state.specular,
            "false_colour": state.false_colour,
            "log_scale": state.false_colour_scale == "log",
        }
        for key, on in checked.items():
            if key in self.widgets:
                self.widgets[key].GetRepresentation().SetState(int(on))
        if self.compass is not None and state.key_light is not None:
            self.compass.point(state.lights[state.key_light].direction)

    def _add_check_boxes(self, strip_height: int) -> None:
        """The false colour, its scale and the two view-dependent layers, under the status (pixels from the
        bottom of the window, where the strip starts)."""
        viewer, state = self.viewer, self.viewer.state
        width, height = self.plotter.window_size
        strip_px = int(round((1.0 - CONTROL_STRIP) * width))
        boxes = (
            ("false_colour", "false colour (key y)", viewer.set_false_colour, state.false_colour),
            (
                "log_scale",
                "log scale (key l)",
                lambda on: viewer.set_false_colour_scale("log" if on else "linear"),
                state.false_colour_scale == "log",
            ),
            ("view_dependent", "T21 toward the camera", viewer.set_view_dependent, state.view_dependent),
            ("specular", "specular highlight", viewer.set_specular, state.specular),
        )
        box = max(14, min(22, height // 35))
        step = box + 8
        first = int(strip_height * 0.66 + 2 * step)
        for k, (key, label, callback, value) in enumerate(boxes):
            y = first - k * step
            self.widgets[key] = self.plotter.add_checkbox_button_widget(
                callback, value=value, position=(strip_px + 8, y), size=box, border_size=2, color_off="grey"
            )
            self.plotter.add_text(
                label, position=(box + 16, y + box // 4), font_size=6, color="white", name=f"{key}_label"
            )

    @staticmethod
    def _row(row: int) -> dict:
        """Where the slider of ``row`` (0 at the bottom) goes in the strip's normalised viewport (PyVista places
        sliders in the current renderer's): below the compass."""
        y = 0.06 + row * 0.098
        return {"pointa": (0.06, y), "pointb": (0.94, y)}

    def _add_choices(self) -> None:
        """The material and model sliders (top rows), each titled by its choice."""
        from ...scatter.names import MODELS

        viewer, state = self.viewer, self.viewer.state
        style = {"style": "modern", "interaction_event": "end"}
        choices = {key: key for key in diffusive_materials()}
        if state.medium.name not in choices:  # a medium of its own: offer it first
            choices = {state.medium.name: state.medium, **choices}
        self.materials = list(choices)
        self.widgets["material"] = self.plotter.add_text_slider_widget(
            lambda name: viewer.set_material(choices[name]),
            self.materials,
            value=self.materials.index(state.medium.name),
            **self._row(5),
            **style,
        )
        self.widgets["model"] = self.plotter.add_text_slider_widget(
            viewer.set_model, list(MODELS), value=list(MODELS).index(state.model), **self._row(4), **style
        )
        for key in ("material", "model"):  # the title names the choice; the index is no use
            self.widgets[key].GetRepresentation().SetTitleHeight(TITLE_HEIGHT)
            self.widgets[key].GetRepresentation().ShowSliderLabelOff()

    def _add_sliders(self) -> None:
        """The light's azimuth and elevation (degrees; with a directional light), the exposure (log2) and the scale
        (mm per unit)."""
        viewer, state = self.viewer, self.viewer.state
        titled = {"style": "modern", "interaction_event": "end", "title_height": TITLE_HEIGHT}
        # relighting answers while the slider moves; a full solve when it is let go
        light_style = {**titled, "interaction_event": "always" if state.method == "relight" else "end"}
        if state.key_light is not None:
            self.widgets["azimuth"] = self.plotter.add_slider_widget(
                lambda a: viewer.set_light(a, viewer.elevation),
                [-180.0, 180.0],
                value=state.azimuth,
                title="light azimuth (deg)",
                fmt="%.0f",
                **self._row(3),
                **light_style,
            )
            self.widgets["elevation"] = self.plotter.add_slider_widget(
                lambda e: viewer.set_light(viewer.azimuth, e),
                [-90.0, 90.0],
                value=state.elevation,
                title="light elevation (deg)",
                fmt="%.0f",
                **self._row(2),
                **light_style,
            )
        stops = math.log2(state.exposure)
        self.widgets["exposure"] = self.plotter.add_slider_widget(
            lambda v: viewer.set_exposure(2.0**v),
            [stops - EXPOSURE_STOPS, stops + EXPOSURE_STOPS],
            value=stops,
            title="exposure (log2)",
            fmt="%.1f",
            **self._row(1),
            **titled,
        )
        base = float(state.base_mesh.mm_per_unit)
        self.widgets["scale"] = self.plotter.add_slider_widget(
            viewer.set_scale,
            [base * SCALE_RANGE[0], base * SCALE_RANGE[1]],
            value=state.mm_per_unit,
            title="scale (mm per unit)",
            fmt="%.3g",
            **self._row(0),
            **titled,
        )
