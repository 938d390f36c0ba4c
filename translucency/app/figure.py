"""The picture a scientist keeps: one result's sRGB view and false-colour view side by side, labelled.

:func:`figure_image` renders the mesh twice with one camera (off-screen, :mod:`translucency.app.render`)
and lays the two views out with matplotlib:

* left, the display colours ``sRGB(exposure L)`` of the result (what a bake stores);
* right, the same radiance in physical units: the luminance ``Y`` (or one channel) through a colour map,
  log or linear (:func:`translucency.app.display.false_colour_values`), with a colour bar in
  W/(m² sr) per W/m² of irradiance whose top is what the left view shows as white;
* in both a scale bar in mm, and under them every directional light as the views see it, an arrow
  travelling toward the object (:func:`light_compass`; beside the scan, never over it);
* above, the scan (name, vertices, size), the material, the model, the method and its tolerance, and
  the lights.

The views are parallel projections, so the scale bar holds at every depth of the object (a perspective
view, as in the viewer, has no single scale). The main job, ``bake --preview`` and anyone with a
:class:`~translucency.app.shading.result.ShadeResult` write it with :func:`write_figure`.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

__all__ = ["figure_image", "figure_title", "write_figure", "render_views", "light_compass", "nice_length"]

#: Narrowest picture, inches at 100 dpi: the title and the colour bar's label fit in it.
FIGURE_MIN_WIDTH = 11.6


def nice_length(span: float) -> float:
    """The largest of 1, 2 or 5 times a power of ten that is at most ``span`` (mm; ``span`` > 0)."""
    power = 10.0 ** math.floor(math.log10(span))
    return max(step * power for step in (1.0, 2.0, 5.0) if step * power <= span * (1 + 1e-12))


def _method_words(metadata: dict) -> str:
    """The method as the title says it: ``auto`` with the method it chose for this light (``auto method: tree``)."""
    method, used = metadata.get("method", "?"), metadata.get("method_used")
    return f"{method} method: {used}" if used and used != method else f"{method} method"


def _light_words(light: dict) -> str:
    if light["type"] == "directional":
        d = np.asarray(light["direction"], dtype=float)
        e = np.asarray(light["irradiance_rgb_W_m2"], dtype=float)
        irradiance = f"{e[0]:.3g}" if np.all(e == e[0]) else "(" + ", ".join(f"{v:.3g}" for v in e) + ")"
        return f"directional, toward the light ({d[0]:.2f}, {d[1]:.2f}, {d[2]:.2f}), E = {irradiance} W/m²"
    if light["type"] == "point":
        p = light["position_mm"]
        return f"point at ({p[0]:.3g}, {p[1]:.3g}, {p[2]:.3g}) mm"
    return f"environment {light.get('name') or ''} ({light.get('n_directions')} directions)".replace("  ", " ")


def render_views(mesh, result, values, clim, scale, camera_direction, up_axis, panel):
    """The two views as one (panel, 2 panel, 3) image with one parallel camera framing the scan; returns (image,
    mm per pixel). Nothing but the scan is drawn (the light is shown beside the views, :func:`light_compass`)."""
    from ..io.upright import up_vector
    from .framing import camera_position, front_direction
    from .render import add_colored_mesh, add_false_colour_mesh, new_plotter

    plotter = new_plotter((2 * panel, panel), shape=(1, 2), border=False)
    plotter.link_views()  # before the meshes: the outline of the false colour follows the camera it is made with
    try:
        for column in (0, 1):
            plotter.subplot(0, column)
            if column == 0:
                poly = add_colored_mesh(plotter, mesh, result.colors)
            else:
                poly, _, _ = add_false_colour_mesh(plotter, mesh, values, clim, scale, outline=True)
        plotter.subplot(0, 0)
        direction = front_direction(mesh, up_vector(up_axis)) if camera_direction is None else camera_direction
        plotter.camera_position = camera_position(poly.center, poly.length, direction, tuple(up_vector(up_axis)))
        plotter.enable_parallel_projection()
        plotter.reset_camera()
        mm_per_pixel = 2.0 * float(plotter.camera.parallel_scale) / panel
        image = plotter.screenshot(return_img=True)
    finally:
        plotter.close()
    return image, mm_per_pixel


def light_compass(ax, lights, camera_direction, up) -> None:
    """Draw each directional light in ``ax`` as the camera sees it: a disc, and an arrow from its rim toward
    its centre along the light's travel projected on the picture (solid: the light comes from the camera's
    side of the object; dashed: from behind it). Point and environment lights are not drawn.

    ``lights`` are a result's light records (``metadata["lights"]``); ``camera_direction`` points from the
    object toward the camera and ``up`` is the view-up, both in the scan's coordinates.
    """
    from matplotlib.patches import Circle, FancyArrowPatch

    from .render import LIGHT_GLYPH_COLOR

    toward_camera = np.asarray(camera_direction, dtype=float)
    toward_camera /= np.linalg.norm(toward_camera)
    view_up = np.asarray(up, dtype=float) - (np.asarray(up, dtype=float) @ toward_camera) * toward_camera
    view_up /= np.linalg.norm(view_up)
    right = np.cross(view_up, toward_camera)  # the picture's x: right-handed (right, up, toward the camera)
    ax.set_xlim(-1.3, 1.3)
    ax.set_ylim(-1.3, 1.3)
    ax.set_aspect("equal")
    ax.set_axis_off()
    ax.add_patch(Circle((0.0, 0.0), 1.0, fill=False, color="grey", linewidth=0.8))
    ax.plot([0.0], [0.0], marker="o", markersize=2, color="grey")
    for light in lights:
        if "direction" not in light:
            continue
        d = np.asarray(light["direction"], dtype=float)
        d /= np.linalg.norm(d)
        x, y = float(d @ right), float(d @ view_up)
        behind = float(d @ toward_camera) < 0.0
        ax.add_patch(
            FancyArrowPatch(
                (x, y),
                (0.0, 0.0),
                arrowstyle="-|>",
                mutation_scale=10,
                color=LIGHT_GLYPH_COLOR,
                linewidth=1.6,
                linestyle="--" if behind else "-",
            )
        )


def figure_title(mesh, metadata: dict, name: str | None = None) -> str:
    """The picture's title: the scan (``name``, else its file name), its size, where ``B`` was solved
    when on a proxy, the material, model and method, then the lights (from a result's ``metadata``)."""
    name = name or (Path(mesh.source).stem if getattr(mesh, "source", None) is not None else "scan")
    method = metadata.get("method", "?")
    tolerance = "every pair" if method == "exact" else f"tol {metadata.get('tolerance', float('nan')):g}"
    lights = "; ".join(_light_words(light) for light in metadata.get("lights", ())) or "none"
    shadows = "with shadows" if metadata.get("shadows", True) else "no shadows"
    bounces = metadata.get("bounces")
    if bounces:
        tolerance += f", {bounces} bounce" + ("s" if bounces > 1 else "")
    material = metadata.get("material", "?")
    if metadata.get("albedo", "material") != "material":
        material += " with the scan's colours"
    proxy = re.fullmatch(r"proxy, (\d+) vertices, edge (\S+) mm", str(metadata.get("resolution", "full")))
    solved = (
        f"solved on a proxy of {int(proxy[1]):,} vertices ({proxy[2]} mm edges), interpolated to every vertex\n"
        if proxy
        else ""
    )
    return (
        f"{name}: {mesh.n_points:,} vertices, {mesh.extent:.4g} mm across — {material}, "
        f"{metadata.get('model', '?')} dipole, {_method_words(metadata)} ({tolerance})\n{solved}light: {lights}, "
        f"{shadows}"
    )


def figure_image(
    mesh,
    result,
    *,
    name: str | None = None,
    quantity: str = "luminance",
    scale: str = "log",
    camera_direction=None,
    panel: int = 560,
) -> np.ndarray:
    """The labelled two-view picture of a result (module docstring) as an (h, w, 3) uint8 image.

    Parameters
    ----------
    mesh : TriangleMesh
        The mesh the result belongs to, mm.
    result : ShadeResult
        Its radiance, display colours, exposure and settings (``metadata``).
    name : str, optional
        The scan's name in the title (default: the mesh's file name, or ``scan``).
    quantity : {"luminance", "red", "green", "blue"}
        What the false colour shows.
    scale : {"log", "linear"}
        The false colour's scale.
    camera_direction : sequence of 3 float, optional
        From the centre toward the camera, scan coordinates (default: the scan's front, a little above,
        :func:`~translucency.app.framing.front_direction`).
    panel : int
        Side of each rendered view, pixels.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import LogNorm, Normalize
    from matplotlib.figure import Figure
    from matplotlib.font_manager import FontProperties
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    from .display import FALSE_COLOUR_MAP, false_colour_label, false_colour_range, false_colour_values

    metadata = result.metadata
    values = false_colour_values(result.radiance, quantity)
    clim = false_colour_range(values, scale, result.exposure)
    from ..io.upright import up_vector
    from .framing import front_direction

    up = up_vector(metadata.get("up", "+y"))
    if camera_direction is None:
        camera_direction = front_direction(mesh, up)
    image, mm_per_pixel = render_views(
        mesh, result, values, clim, scale, camera_direction, metadata.get("up", "+y"), int(panel)
    )
    views = (image[:, :panel], image[:, panel:])

    dpi = 100
    width = max(2 * panel / dpi + 0.4, FIGURE_MIN_WIDTH)  # the labels need this much, whatever the panels
    figure = Figure(figsize=(width, (width - 0.4) / 2 + 2.4), dpi=dpi, layout="constrained")
    FigureCanvasAgg(figure)
    grid = figure.add_gridspec(2, 2, height_ratios=[panel, 80])
    figure.suptitle(figure_title(mesh, metadata, name), fontsize=10)
    bar_mm = nice_length(0.25 * panel * mm_per_pixel)
    for column, (view, title) in enumerate(
        zip(
            views,
            (
                f"sRGB display, exposure {result.exposure:.3g} (white = {1.0 / result.exposure:.3g} {_unit()})",
                f"false colour: {false_colour_label(quantity, scale).split(',')[0]}, {scale} scale",
            ),
        )
    ):
        ax = figure.add_subplot(grid[0, column])
        ax.imshow(view, interpolation="nearest")
        ax.set_axis_off()
        ax.set_title(title, fontsize=9)
        ax.add_artist(
            AnchoredSizeBar(
                ax.transData,
                bar_mm / mm_per_pixel,
                f"{bar_mm:g} mm",
                "lower left",
                pad=0.6,
                color="white",
                frameon=False,
                size_vertical=max(2.0, 0.006 * panel),
                fontproperties=FontProperties(size=8),
            )
        )
    norm = LogNorm(*clim) if scale == "log" else Normalize(*clim)
    bar = figure.colorbar(
        ScalarMappable(norm=norm, cmap=FALSE_COLOUR_MAP),
        cax=figure.add_subplot(grid[1, 1]),
        orientation="horizontal",
        extend="min" if scale == "log" else "neither",
    )
    bar.set_label(false_colour_label(quantity, scale), fontsize=8)
    bar.ax.tick_params(labelsize=8)
    note = figure.add_subplot(grid[1, 0])
    note.set_axis_off()
    compass = note.inset_axes((0.0, 0.0, 0.16, 1.0))
    light_compass(compass, metadata.get("lights", ()), camera_direction, up)
    note.text(
        0.18,
        0.5,
        "blue arrow: the light as the views see it, travelling toward the object\n(dashed: from behind the "
        "object); parallel projection: the scale bar holds at every depth",
        fontsize=8,
        va="center",
    )
    canvas = figure.canvas
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].copy()


def _unit() -> str:
    from .display import RADIANCE_UNIT

    return RADIANCE_UNIT


def write_figure(path, mesh, result, **options) -> Path:
    """Write :func:`figure_image` of a result as a PNG, atomically; ``options`` as there. Returns the path."""
    from .outputs import write_png

    return write_png(path, figure_image(mesh, result, **options))
