"""The false colour's colour bar as a Qt widget under the view, so that it never covers the scan.

Drawn by matplotlib (its Qt canvas), with the same colour map, range and scale as the scan's false colour
(:func:`translucency.app.display.false_colour_range`): log ticks on a log scale.
"""

from __future__ import annotations

from matplotlib.backends.backend_qtagg import FigureCanvasQTAgg
from matplotlib.figure import Figure

#: Height of the bar's widget, pixels.
BAR_HEIGHT = 84


class ColourBar(FigureCanvasQTAgg):
    """A horizontal colour bar: :meth:`show_range` draws it for a range, scale and title."""

    def __init__(self, parent=None):
        figure = Figure(figsize=(6, 0.8), facecolor="black")
        super().__init__(figure)
        self.setParent(parent)
        self.setFixedHeight(BAR_HEIGHT)
        self.axes = figure.add_axes((0.08, 0.42, 0.84, 0.2))
        self.shown = None

    def show_range(self, clim, scale: str, title: str) -> None:
        """Draw the bar for ``clim`` (low, high; W/(m² sr) per W/m²) on a ``log`` or ``linear`` scale."""
        from matplotlib import colormaps
        from matplotlib.cm import ScalarMappable
        from matplotlib.colors import LogNorm, Normalize

        from ..display import FALSE_COLOUR_MAP

        key = (tuple(float(c) for c in clim), scale, title)
        if key == self.shown:
            return
        self.shown = key
        low, high = key[0]
        norm = LogNorm(low, high) if scale == "log" else Normalize(low, high)
        self.axes.clear()
        bar = self.figure.colorbar(
            ScalarMappable(norm=norm, cmap=colormaps[FALSE_COLOUR_MAP]), cax=self.axes, orientation="horizontal"
        )
        bar.ax.tick_params(colors="white", labelsize=8)
        bar.outline.set_edgecolor("white")
        self.axes.set_title(title, color="white", fontsize=9)
        self.draw_idle()
