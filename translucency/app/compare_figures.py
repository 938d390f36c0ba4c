"""The pictures of a comparison: the image grid of every (material, model) cell, the difference maps against the
first model, and the profile plot along the cut through the light (:mod:`translucency.app.compare`).
"""

from __future__ import annotations

import numpy as np

from ..io.polydata import to_pyvista
from .display import display_colors
from .framing import camera_position, scan_camera
from .render import add_colored_mesh, new_plotter

__all__ = ["grid_image", "difference_image", "profile_figure"]

#: Height of the band under the difference maps that holds the colour bar, in cell heights.
COLOUR_BAR_BAND = 0.3
#: The profile's log axis spans this fraction of the largest radiance and up (darker values sit on the floor).
PROFILE_RANGE = 1e-6


def _cells(plotter, rows, columns):
    """Make every subplot current in turn; yields (row, column)."""
    for row in range(rows):
        for column in range(columns):
            plotter.subplot(row, column)
            yield row, column


def grid_image(mesh, comparison, camera_direction, up, cell_size) -> np.ndarray:
    rows, columns = len(comparison.models), len(comparison.materials)
    plotter = new_plotter((columns * cell_size[0], rows * cell_size[1]), shape=(rows, columns))
    camera = None
    for row, column in _cells(plotter, rows, columns):
        material, model = comparison.materials[column], comparison.models[row]
        colors, _ = display_colors(comparison.results[material, model].radiance, comparison.exposure)
        add_colored_mesh(plotter, mesh, colors)
        camera = camera or scan_camera(mesh, up, cell_size[0] / cell_size[1], camera_direction)
        plotter.camera_position = camera
        plotter.add_text(f"{material}, {model}", position="upper_left", font_size=10, color="white")
    plotter.subplot(0, 0)
    plotter.add_text(
        f"exposure {comparison.exposure:.3g} (all cells)", position="lower_left", font_size=7, color="white"
    )
    image = plotter.screenshot(return_img=True)
    plotter.close()
    return image


def difference_image(mesh, comparison, relative, camera_direction, up, cell_size) -> np.ndarray:
    """Relative-difference maps, one row per model after the first, and one colour bar in a band below."""
    rows, columns = len(comparison.models) - 1, len(comparison.materials)
    reference = comparison.models[0]
    limit = max(float(np.percentile(np.abs(np.concatenate(list(relative.values()))), 99)), 1e-3)
    band = COLOUR_BAR_BAND
    plotter = new_plotter(
        (columns * cell_size[0], int(round((rows + band) * cell_size[1]))),
        shape=(rows + 1, columns),
        row_weights=[1.0] * rows + [band],
        groups=[(rows, np.s_[:])],
    )
    camera, actor = None, None
    for row, column in _cells(plotter, rows, columns):
        material, model = comparison.materials[column], comparison.models[row + 1]
        poly = to_pyvista(mesh)
        poly.point_data["relative difference"] = relative[material, model]
        actor = plotter.add_mesh(
            poly,
            scalars="relative difference",
            cmap="RdBu_r",
            clim=(-limit, limit),
            lighting=False,
            show_scalar_bar=False,
        )
        camera = camera or camera_position(poly.center, poly.length, camera_direction, up)
        plotter.camera_position = camera
        plotter.add_text(f"{material}: {model} vs {reference}", position="upper_left", font_size=10, color="white")
    plotter.subplot(rows, 0)
    font = int(np.clip(columns * cell_size[0] / 40, 8, 14))  # the title fits the band's width
    title = f"(Y - Y_{reference}) / Y_{reference}"
    # the title at the band's top, apart from the bar: VTK puts a horizontal bar's title among its tick labels
    plotter.add_text(title, position="upper_edge", font_size=max(font // 2, 5), color="white")
    bar = plotter.add_scalar_bar(
        title=title,
        mapper=actor.mapper,
        color="white",
        fmt="%.2f",
        position_x=0.1,
        position_y=0.05,
        width=0.8,
        height=0.6,
        title_font_size=font,
        label_font_size=font - 2,
    )
    bar.SetTitle("")
    image = plotter.screenshot(return_img=True)
    plotter.close()
    return image


def profile_figure(comparison):
    """Radiance along the cut, one panel per channel, legend beside the panels (a matplotlib Figure,
    no global state)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(12, 4), dpi=100, layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.subplots(1, 3, sharex=True)
    styles = ["-", "--", ":", "-."]
    colours = [f"C{k % 10}" for k in range(len(comparison.materials))]
    top = max([float(radiance.max()) for _, radiance in comparison.profiles.values() if radiance.size] + [0.0]) or 1.0
    plane = comparison.profile_plane
    for c, (ax, channel) in enumerate(zip(axes, ("red", "green", "blue"))):
        for (material, model), (position, radiance) in comparison.profiles.items():
            ax.plot(
                position,
                np.maximum(radiance[:, c], PROFILE_RANGE * top),
                styles[comparison.models.index(model) % len(styles)],
                color=colours[comparison.materials.index(material)],
                lw=1.0,
                label=f"{material}, {model}",
            )
        if comparison.reference_profile is not None:  # the path-traced reference, with two standard errors
            position, radiance, stderr = comparison.reference_profile
            low = np.maximum(radiance[:, c] - 2.0 * stderr[:, c], PROFILE_RANGE * top)
            ax.fill_between(position, low, radiance[:, c] + 2.0 * stderr[:, c], color="0.75", lw=0)
            ax.plot(
                position,
                np.maximum(radiance[:, c], PROFILE_RANGE * top),
                color="black",
                lw=1.4,
                label="reference (path traced; band: 2 standard errors)",
            )
        for x in plane["light_boundaries_mm"]:
            ax.axvline(x, color="0.6", lw=0.6, ls=":")
        ax.set_yscale("log")
        ax.set_ylim(bottom=PROFILE_RANGE * top)
        ax.set_xlabel("position along the cut (mm; 0 faces the light)")
        ax.set_title(f"{channel} channel")
    axes[0].set_ylabel("radiance toward the normal, W/(m² sr) per W/m²")
    handles, labels = axes[0].get_legend_handles_labels()
    # under the panels, off the data and off the title
    figure.legend(handles, labels, fontsize=7, loc="outside lower center", ncols=min(len(labels), 4))
    figure.suptitle(
        f"profile across the light boundary: the plane through the centre containing the light cuts the "
        f"surface in a line of {plane['length_mm']:.0f} mm; dotted: where the direct light ends",
        fontsize=9,
    )
    return figure
