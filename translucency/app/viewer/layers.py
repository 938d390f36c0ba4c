"""The scan as a viewer draws it: one renderer, two layers (display colours and false colour), recoloured from a state.

Both windows use it: the PyVista window (:mod:`translucency.app.viewer.widgets`) and the desktop application
(:mod:`translucency.app.desktop`). Until the first solve the scan is shown unshaded, in grey with the
renderer's own lighting (:meth:`ScanLayers.show_unshaded`), so that a window has something to show at once.
"""

from __future__ import annotations

import numpy as np

from ..render import add_colored_mesh, add_false_colour_mesh
from .state import ViewerState

#: Colour of the scan before its first solve (lit by the renderer's own lights).
UNSHADED_COLOUR = "#b8b8b8"


#: Where a corner annotation (PyVista's ``add_text`` at ``"lower_edge"``) keeps the text of the lower edge.
LOWER_EDGE = 4


class ScanLayers:
    """The scan drawn in ``plotter``'s current renderer as sRGB display colours or as false colour.

    Parameters
    ----------
    plotter : pyvista.Plotter or pyvistaqt.QtInteractor
        Where to draw (its current renderer).
    mesh : TriangleMesh
        The scan, mm.
    scalar_bar : dict, optional
        Keywords of PyVista's ``add_scalar_bar`` for the false colour's bar in the same renderer; None: no
        bar (a host draws its own, outside the scan's pixels).

    Attributes
    ----------
    poly : pyvista.PolyData
        The display-colour layer; its ``"colors"`` array (uint8) is what is shown.
    false_colour_poly : pyvista.PolyData
        The false-colour layer; its ``"false colour"`` array is in W/(m² sr) per W/m².
    """

    def __init__(self, plotter, mesh, *, scalar_bar=None):
        self.plotter = plotter
        n = mesh.n_points
        self.poly = add_colored_mesh(plotter, mesh, np.zeros((n, 3), np.uint8), name="scan")
        self.rgb_actor = plotter.renderer.actors["scan"]
        self.false_colour_poly, self.false_actor, self.scalar_bar = add_false_colour_mesh(
            plotter,
            mesh,
            np.ones(n),
            (0.1, 1.0),
            "log",
            title="" if scalar_bar is not None else None,
            scalar_bar=scalar_bar,
        )
        #: The bar's title, a text of its own at the window's lower edge, under the tick labels (VTK draws a
        #: horizontal bar's title over them); None without a bar.
        self.bar_title = None
        if self.scalar_bar is not None:
            self.scalar_bar.SetTextPositionToPrecedeScalarBar()  # tick labels under the bar
            self.bar_title = plotter.add_text(
                " ",
                position="lower_edge",
                font_size=scalar_bar.get("title_font_size", 12) * 0.75,
                color=scalar_bar.get("color", "white"),
                name="false colour title",
            )
            self.bar_title.SetMaximumFontSize(int(scalar_bar.get("title_font_size", 12)) + 2)
            self.bar_title.SetVisibility(False)
        self.unshaded_actor = plotter.add_mesh(
            self.poly.copy(deep=False), color=UNSHADED_COLOUR, smooth_shading=True, name="scan unshaded"
        )
        self.show_unshaded()

    def show_unshaded(self) -> None:
        """Show the scan in plain grey, lit by the renderer (before its first solve)."""
        self.unshaded_actor.SetVisibility(True)
        self.rgb_actor.SetVisibility(False)
        self.false_actor.SetVisibility(False)
        if self.scalar_bar is not None:
            self.scalar_bar.SetVisibility(False)
            self.bar_title.SetVisibility(False)

    def recolour(self, state: ViewerState) -> None:
        """New colours, or new false-colour values, range, scale and title, from ``state`` (no render).

        ``state`` must hold a result (:meth:`ViewerState.solve`); its camera position (:meth:`ViewerState.set_eye`)
        is what the view-dependent layers use.
        """
        false_colour = state.false_colour
        self.unshaded_actor.SetVisibility(False)
        self.rgb_actor.SetVisibility(not false_colour)
        self.false_actor.SetVisibility(false_colour)
        if self.scalar_bar is not None:
            self.scalar_bar.SetVisibility(false_colour)
            self.bar_title.SetVisibility(false_colour)
        if not false_colour:
            self.poly.point_data["colors"][:] = state.colors()
            return
        low, high = state.false_colour_range()
        self.false_colour_poly.point_data["false colour"][:] = np.maximum(state.false_colour_values(), low)
        table = self.false_actor.mapper.lookup_table
        table.log_scale = state.false_colour_scale == "log"
        self.false_actor.mapper.scalar_range = (low, high)
        table.scalar_range = (low, high)
        if self.scalar_bar is not None:
            self.bar_title.SetText(LOWER_EDGE, state.false_colour_title)
