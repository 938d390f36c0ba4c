"""Models against a path-traced reference, vertex by vertex: ``compare --reference REF``.

A reference (``translucency reference``, :mod:`translucency.io.reference_file`) holds the radiance leaving
each vertex of a repaired scan along its normal, path traced for one material and one directional light
(docs/physics.md §9.5), the same quantity the models give as ``T21(eta, 1) B`` (§5.3), in W/(m² sr) per
W/m² of irradiance. :func:`~translucency.app.compare.compare` with ``reference=`` shades exactly those
vertices, in that material and light, and measures each model against it per region of the surface.

Regions, by ``c = n . w_L`` (the vertex normal and the direction toward the light) and the direct light
the models see at the vertex (their incident flux, shadow rays included):

================ ==================================================================
region           vertices
================ ==================================================================
``lit``          ``c > 0.2`` and directly lit
``grazing``      ``0 < c <= 0.2`` and directly lit
``shadowed``     ``c > 0`` but no direct light (a cast shadow)
``far -0.3..0``  the far side, ``-0.3 <= c <= 0``
``far -0.6..-0.3`` ``-0.6 <= c < -0.3``
``far -1..-0.6`` ``c < -0.6``
``all``          every traced vertex
================ ==================================================================

Every vertex is in exactly one of the first six. Per region, model and channel (:func:`region_rows`):
the vertex count; the **ratio of the means**, mean model / mean reference (vertices count alike, not
weighted by area), with its standard error from the reference's per-vertex standard errors (the models
are deterministic); the share of the reference's radiance that left the surface and entered it again
(``radiance_reentered``, which the models leave out); and the median and 90th percentile of the
per-vertex relative error ``|model - reference| / reference`` over the vertices whose reference standard
error is below :data:`PRECISE_STDERR` of their radiance. Those per-vertex figures include the
reference's own noise; the ratios of means average it away. Vertices the reference did not trace (NaN)
are left out of everything.

Files (beside compare's own): ``reference.csv`` (the rows), ``reference.json`` (the rows, the regions,
the settings, the reference's metadata, the models' solve times next to the path tracer's time and its
median relative standard error) and ``reference_errors.png`` (:func:`reference_errors_image`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError
from .display import REC709_LUMINANCE, luminance

__all__ = [
    "REGIONS",
    "ALL_REGION",
    "LIT_COSINE",
    "PRECISE_STDERR",
    "RATIO_RANGE",
    "ReferenceSetup",
    "load_reference",
    "reference_setup",
    "assign_regions",
    "region_rows",
    "luminance_ratio",
    "reference_errors_image",
    "reference_figure_size",
    "reference_table_text",
]

#: The regions of the surface, in table order, with what puts a vertex in each (module docstring).
REGIONS = (
    ("lit", "c > 0.2, directly lit"),
    ("grazing", "0 < c <= 0.2, directly lit"),
    ("shadowed", "c > 0, no direct light"),
    ("far -0.3..0", "far side, -0.3 <= c <= 0"),
    ("far -0.6..-0.3", "far side, -0.6 <= c < -0.3"),
    ("far -1..-0.6", "far side, c < -0.6"),
)
#: The last row of every table: every traced vertex.
ALL_REGION = "all"
#: ``c = n . w_L`` above which a lit vertex is ``lit`` rather than ``grazing``.
LIT_COSINE = 0.2
#: Lower bounds of ``c`` of the far-side bands after the first (``-0.3 <= c <= 0``, ``-0.6 <= c < -0.3``, below).
FAR_SIDE_BOUNDS = (-0.3, -0.6)
#: Per-vertex relative errors count only where the reference's standard error is below this fraction of it ...
PRECISE_STDERR = 0.2
#: ... and are given only over at least this many such vertices (a few paths per vertex leave most of a dark
#: region at 0 or with a standard error estimated from a handful of paths).
MIN_PRECISE_VERTICES = 30
#: Range of the per-vertex ratio map (model / reference, log scale).
RATIO_RANGE = (0.5, 2.0)
#: Range of the map of the reference's relative standard error.
STDERR_RANGE = (0.0, 0.5)
#: Positions of a given mesh's vertices may differ from the reference's by this fraction of its extent.
POSITION_TOLERANCE = 1e-6
#: The reference's normals may differ from its mesh's vertex normals by this much (length of the difference).
NORMAL_TOLERANCE = 1e-6
#: Zoom after fitting the object and the light's arrow into a view (the arrow's tail may touch the border).
VIEW_ZOOM = 1.3
#: sRGB colour of the vertices a reference did not trace (NaN), in every view.
UNTRACED_GREY = 128
#: Pixels of the band below the views that holds the colour bars and the note.
FIGURE_BAND = 190
#: Narrowest figure, pixels: the titles and the note fit in it.
FIGURE_MIN_WIDTH = 1000


@dataclass(frozen=True)
class ReferenceSetup:
    """What a reference fixes for a comparison (:func:`reference_setup`).

    Attributes
    ----------
    reference : ReferenceFile
        The file read back (:class:`~translucency.io.reference_file.ReferenceFile`).
    path : str
        Where it was read from (``"in memory"`` for a ReferenceFile given as such).
    mesh : TriangleMesh
        Its points (mm) and triangles, shaded as they are (no cleaning).
    medium : Medium
        The material it was traced in, from its coefficients (1/mm).
    light : DirectionalLight
        The light it was traced with (direction toward the light, irradiance in W/m²).
    """

    reference: object
    path: str
    mesh: object
    medium: object
    light: object


def load_reference(reference):
    """A :class:`~translucency.io.reference_file.ReferenceFile` from a path or as it is; ``(file, path text)``."""
    from ..io.reference_file import ReferenceFile, read_reference_file

    if isinstance(reference, ReferenceFile):
        return reference, "in memory"
    return read_reference_file(reference), str(reference)


def reference_setup(reference, mesh=None, materials=None, lights=None, unit=None) -> ReferenceSetup:
    """Read a reference and check what the caller gave against it; everything the comparison uses.

    Parameters
    ----------
    reference : path-like or ReferenceFile
        The path-traced reference.
    mesh : TriangleMesh or pyvista.PolyData, optional
        Must be the mesh it was traced on (same vertex count, positions within
        :data:`POSITION_TOLERANCE` of its extent); None: the reference's own.
    materials : sequence of str, optional
        Each must be the reference's material (same coefficients); None: the reference's.
    lights : light or sequence of lights, optional
        Must be the reference's one directional light; None: that light.
    unit
        A PolyData's length unit, as for :func:`~translucency.app.compare.compare`.

    Raises
    ------
    InvalidParameterError
        One sentence naming what disagrees with the reference.
    """
    from ..geometry.mesh import TriangleMesh
    from ..scatter.lights import DirectionalLight, as_light_list
    from ..scatter.medium import Medium
    from .shading.scan import mesh_for_shading
    from .shading.settings import resolve_medium

    ref, path = load_reference(reference)
    meta = ref.metadata
    missing = [
        k for k in ("material", "sigma_a_per_mm", "sigma_s_per_mm", "g", "eta", "light_direction") if k not in meta
    ]
    if missing:
        raise InvalidParameterError(
            f"the reference {path} records no {', '.join(missing)}; trace it again with 'translucency reference'."
        )
    medium = Medium(meta["sigma_a_per_mm"], meta["sigma_s_per_mm"], meta["g"], meta["eta"], name=str(meta["material"]))
    own = TriangleMesh(ref.points, ref.triangles, source=None if path == "in memory" else Path(path))
    normals = own.vertex_normals()
    gap = np.linalg.norm(normals - ref.normals, axis=1)
    if np.nanmax(gap, initial=0.0) > NORMAL_TOLERANCE:
        raise InvalidParameterError(
            f"the normals stored in the reference {path} differ from its mesh's vertex normals by up to "
            f"{np.nanmax(gap):.2g}; trace it again with 'translucency reference'."
        )
    if mesh is not None:
        given = mesh_for_shading(mesh, unit, entry="compare")
        if given.n_points != own.n_points:
            raise InvalidParameterError(
                f"the mesh has {given.n_points} vertices but the reference {path} was traced on {own.n_points}; "
                "give the mesh it was traced on, or leave the mesh out to use the reference's."
            )
        offset = float(np.max(np.abs(given.points - own.points), initial=0.0))
        if offset > POSITION_TOLERANCE * own.extent:
            raise InvalidParameterError(
                f"the mesh's vertices lie up to {offset:.3g} mm from those of the reference {path}; "
                "give the mesh it was traced on, or leave the mesh out to use the reference's."
            )
    if materials is not None:
        if isinstance(materials, str):
            materials = [m.strip() for m in materials.split(",") if m.strip()]
        for name in materials:
            if not _same_medium(resolve_medium(name), medium):
                raise InvalidParameterError(
                    f"the reference {path} was traced in {medium.name}, not {name}; leave out the materials "
                    f"(--materials/--material) or give {medium.name}."
                )
    direction = np.asarray(meta["light_direction"], dtype=np.float64)
    light = DirectionalLight(direction / np.linalg.norm(direction), float(meta.get("irradiance_w_per_m2", 1.0)))
    if lights is not None:
        given_lights = as_light_list(lights)
        if not (len(given_lights) == 1 and _same_light(given_lights[0], light, DirectionalLight)):
            d = light.direction
            raise InvalidParameterError(
                f"the reference {path} was traced with one directional light toward ({d[0]:.4g}, {d[1]:.4g}, "
                f"{d[2]:.4g}) of {float(np.mean(light.irradiance_rgb)):.4g} W/m^2; leave out the lights "
                "(--light-dir, --light, --env) to use it."
            )
    return ReferenceSetup(ref, path, own, medium, light)


def _same_medium(a, b) -> bool:
    return all(
        np.allclose(getattr(a, name), getattr(b, name), rtol=1e-9, atol=0.0) for name in ("sigma_a", "sigma_s", "g")
    ) and np.isclose(a.eta, b.eta, rtol=1e-12)


def _same_light(light, reference_light, directional) -> bool:
    if not isinstance(light, directional):
        return False
    d = np.asarray(light.direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    return bool(
        np.linalg.norm(d - reference_light.direction) < 1e-6
        and np.allclose(light.irradiance_rgb, reference_light.irradiance_rgb, rtol=1e-9)
    )


def assign_regions(normals, light_direction, lit) -> np.ndarray:
    """The region of every vertex, an index into :data:`REGIONS`, (n,) int.

    Parameters
    ----------
    normals : (n, 3) array_like
        Unit vertex normals.
    light_direction : sequence of 3 float
        Toward the light (any length).
    lit : (n,) array_like of bool
        Whether the vertex gets direct light (the models' incident flux is above 0).
    """
    d = np.asarray(light_direction, dtype=np.float64)
    c = np.asarray(normals, dtype=np.float64) @ (d / np.linalg.norm(d))
    lit = np.asarray(lit, dtype=bool)
    first, second = FAR_SIDE_BOUNDS
    return np.select(
        [(c > LIT_COSINE) & lit, (c > 0) & lit, c > 0, c >= first, c >= second],
        [0, 1, 2, 3, 4],
        default=5,
    ).astype(np.int64)


def region_rows(model: str, radiance, reference, regions, time_s: float) -> list:
    """One row per (region, channel) of one model against the reference (module docstring); the regions of
    :data:`REGIONS`, then :data:`ALL_REGION`.

    Parameters
    ----------
    model : str
        The model's name (the rows' ``model``).
    radiance : (n, 3) array_like
        The model's radiance toward the normal, W/(m² sr) per W/m².
    reference : ReferenceFile
        Its ``radiance``, ``radiance_stderr`` and ``radiance_reentered``, same unit (NaN: not traced).
    regions : (n,) array_like of int
        :func:`assign_regions`.
    time_s : float
        The model's solve time, s.

    Returns
    -------
    list of dict
        ``model, region, channel, n_vertices, mean_model, mean_reference, ratio, ratio_stderr,
        reentered_share, ratio_without_reentered`` (mean model / mean of the reference less its re-entered
        part, which the models leave out), ``n_precise, relative_error_median, relative_error_p90, time_s``;
        a figure that cannot be formed (no vertex, a zero mean) is None.
    """
    model_radiance = np.asarray(radiance, dtype=np.float64)
    ref, stderr = reference.radiance, reference.radiance_stderr
    regions = np.asarray(regions)
    rows = []
    masks = [(name, regions == k) for k, (name, _) in enumerate(REGIONS)] + [(ALL_REGION, np.ones(len(regions), bool))]
    for region, mask in masks:
        for c, channel in enumerate("RGB"):
            use = mask & np.isfinite(ref[:, c]) & np.isfinite(stderr[:, c])
            m, r, s = model_radiance[use, c], ref[use, c], stderr[use, c]
            e = reference.radiance_reentered[use, c]
            n = int(use.sum())
            mean_model = float(m.mean()) if n else None
            mean_ref = float(r.mean()) if n else None
            ratio = ratio_se = share = direct = None
            if n and mean_ref > 0:
                ratio = mean_model / mean_ref
                ratio_se = ratio * float(np.sqrt(np.sum(s**2))) / n / mean_ref
                share = float(np.nanmean(e)) / mean_ref
                direct = mean_model / (mean_ref * (1.0 - share)) if share < 1 else None
            precise = (r > 0) & (s < PRECISE_STDERR * r)
            error = np.abs(m[precise] - r[precise]) / r[precise]
            if error.size < MIN_PRECISE_VERTICES:
                error = error[:0]
            rows.append(
                {
                    "model": model,
                    "region": region,
                    "channel": channel,
                    "n_vertices": n,
                    "mean_model": mean_model,
                    "mean_reference": mean_ref,
                    "ratio": ratio,
                    "ratio_stderr": ratio_se,
                    "reentered_share": share,
                    "ratio_without_reentered": direct,
                    "n_precise": int(error.size),
                    "relative_error_median": float(np.median(error)) if error.size else None,
                    "relative_error_p90": float(np.percentile(error, 90)) if error.size else None,
                    "time_s": float(time_s),
                }
            )
    return rows


def luminance_ratio(radiance, reference) -> np.ndarray:
    """Per vertex, luminance of the model over the reference's, (n,); NaN where the reference is not traced
    or dark."""
    y = luminance(radiance)
    y_ref = luminance(reference.radiance)
    out = np.full(len(y), np.nan)
    good = np.isfinite(y_ref) & (y_ref > 0)
    out[good] = y[good] / y_ref[good]
    return out


def _relative_stderr(reference) -> np.ndarray:
    """Relative standard error of the reference's luminance per vertex (channels traced apart), NaN where dark."""
    y = luminance(reference.radiance)
    se = np.sqrt(luminance(reference.radiance_stderr**2 * np.asarray(REC709_LUMINANCE)))
    out = np.full(len(y), np.nan)
    good = np.isfinite(y) & (y > 0)
    out[good] = se[good] / y[good]
    return out


def reference_figure_size(n_models: int, cell_size) -> tuple[int, int]:
    """``(width, height)`` in pixels of ``reference_errors.png`` for ``n_models`` models and views of ``cell_size``."""
    width, height = (int(v) for v in cell_size)
    return max((n_models + 1) * width, FIGURE_MIN_WIDTH), 2 * height + FIGURE_BAND


def reference_errors_image(setup, results, models, exposure, camera_direction, up, cell_size) -> np.ndarray:
    """The picture of ``reference_errors.png`` as an (h, w, 3) uint8 image (size: :func:`reference_figure_size`).

    Columns: the reference, then one per model. Top row: each in sRGB at one exposure (the reference's), so
    brightness compares. Bottom row: under the reference, its relative standard error per vertex (where
    its noise is); under each model, the ratio of luminance model / reference per vertex on a log scale
    over :data:`RATIO_RANGE` (red: the model is brighter, blue: darker); grey in every view: not traced
    (and in the bottom row, dark). Every view
    shows the light as an arrow travelling toward the object.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import LogNorm, Normalize
    from matplotlib.figure import Figure

    from .display import display_colors
    from .framing import camera_position
    from .render import LIGHT_GLYPH_COLOR, add_colored_mesh, light_glyph, new_plotter

    ref = setup.reference
    mesh = setup.mesh
    columns = len(models) + 1
    cell_w, cell_h = (int(v) for v in cell_size)
    plotter = new_plotter((columns * cell_w, 2 * cell_h), shape=(2, columns), border=False)
    try:
        for row in range(2):
            for column in range(columns):
                plotter.subplot(row, column)
                if row == 0:
                    radiance = np.nan_to_num(ref.radiance) if column == 0 else results[models[column - 1]].radiance
                    colors = display_colors(radiance, exposure)[0]
                    if column == 0:
                        colors[~np.all(np.isfinite(ref.radiance), axis=1)] = UNTRACED_GREY
                    poly = add_colored_mesh(plotter, mesh, colors)
                else:
                    poly = _scalar_mesh(plotter, mesh, ref, results, models, column)
                plotter.add_mesh(
                    light_glyph(poly.center, 0.5 * poly.length, setup.light.direction), color=LIGHT_GLYPH_COLOR
                )
        plotter.subplot(0, 0)
        plotter.camera_position = camera_position(poly.center, poly.length, camera_direction, up)
        plotter.reset_camera()  # the light's arrow in view too ...
        plotter.camera.zoom(VIEW_ZOOM)  # ... the object no smaller than it must be
        plotter.link_views()
        image = plotter.screenshot(return_img=True)
    finally:
        plotter.close()

    width, height = reference_figure_size(len(models), cell_size)
    figure = Figure(figsize=(width / 100, height / 100), dpi=100, layout="constrained")
    FigureCanvasAgg(figure)
    grid = figure.add_gridspec(3, columns, height_ratios=[cell_h, cell_h, FIGURE_BAND - 50])
    meta = ref.metadata
    titles = [f"path-traced reference ({meta.get('spp', '?')} paths per vertex)"] + [
        f"{model} dipole" for model in models
    ]
    for row in range(2):
        for column in range(columns):
            ax = figure.add_subplot(grid[row, column])
            ax.imshow(image[row * cell_h : (row + 1) * cell_h, column * cell_w : (column + 1) * cell_w])
            ax.set_axis_off()
            if row == 0:
                ax.set_title(f"{titles[column]}: sRGB", fontsize=9)
            elif column == 0:
                ax.set_title("reference: relative standard error", fontsize=9)
            else:
                ax.set_title(f"{models[column - 1]} / reference, luminance", fontsize=9)
    bars = figure.add_subplot(grid[2, :])
    bars.set_axis_off()
    ratio_ax = bars.inset_axes([0.52, 0.62, 0.46, 0.16])
    ratio_bar = figure.colorbar(
        ScalarMappable(norm=LogNorm(*RATIO_RANGE), cmap="RdBu_r"), cax=ratio_ax, orientation="horizontal", extend="both"
    )
    ticks = [0.5, 0.67, 0.8, 1.0, 1.25, 1.5, 2.0]
    ratio_bar.set_ticks(ticks, labels=[f"{t:g}" for t in ticks])
    ratio_bar.ax.minorticks_off()
    ratio_bar.set_label("model / reference, luminance per vertex (log scale; red: model brighter)", fontsize=8)
    stderr_ax = bars.inset_axes([0.02, 0.62, 0.40, 0.16])
    stderr_bar = figure.colorbar(
        ScalarMappable(norm=Normalize(*(100 * v for v in STDERR_RANGE)), cmap="viridis"),
        cax=stderr_ax,
        orientation="horizontal",
        extend="max",
    )
    stderr_bar.set_label("reference's standard error, % of its luminance", fontsize=8)
    for bar in (ratio_bar, stderr_bar):
        bar.ax.tick_params(labelsize=8)
    median = meta.get("median_relative_stderr")
    noise = f"median {100 * median:.0f} %" if isinstance(median, (int, float)) else "see left"
    bars.text(
        0.0,
        0.05,
        f"{setup.medium.name}, one directional light of {float(np.mean(setup.light.irradiance_rgb)):.3g} W/m² "
        f"(blue arrow, travelling toward the object); radiance toward the normal; sRGB exposure {exposure:.3g} "
        "for all (the reference's).\nPer-vertex ratios include the reference's noise "
        f"({noise}); grey: not traced or dark. The tables (reference.csv) average the noise away per region.",
        fontsize=8,
        va="bottom",
        transform=bars.transAxes,
    )
    figure.suptitle(
        f"models against a path-traced reference on {mesh.n_points:,} vertices ({mesh.extent:.4g} mm across)",
        fontsize=10,
    )
    figure.canvas.draw()
    return np.asarray(figure.canvas.buffer_rgba())[..., :3].copy()


def _scalar_mesh(plotter, mesh, ref, results, models, column):
    """The bottom row's view of one column: the reference's relative standard error, or a model's ratio."""
    from ..io.polydata import to_pyvista

    poly = to_pyvista(mesh)
    if column == 0:
        poly.point_data["value"] = _relative_stderr(ref)
        style = {"cmap": "viridis", "clim": list(STDERR_RANGE)}
    else:
        poly.point_data["value"] = luminance_ratio(results[models[column - 1]].radiance, ref)
        style = {"cmap": "RdBu_r", "clim": list(RATIO_RANGE), "log_scale": True}
    plotter.add_mesh(
        poly, scalars="value", lighting=False, show_scalar_bar=False, nan_color=[UNTRACED_GREY / 255] * 3, **style
    )
    return poly


#: Columns of ``reference.csv``.
CSV_COLUMNS = (
    "model",
    "region",
    "channel",
    "n_vertices",
    "mean_model",
    "mean_reference",
    "ratio",
    "ratio_stderr",
    "reentered_share",
    "ratio_without_reentered",
    "n_precise",
    "relative_error_median",
    "relative_error_p90",
    "time_s",
)


def reference_document(setup, rows, times) -> dict:
    """What ``reference.json`` holds besides compare's settings: the regions, the reference, the times, the rows."""
    meta = {k: v for k, v in setup.reference.metadata.items() if k != "stats"}
    return {
        "reference_file": setup.path,
        "quantity": "radiance toward the normal, W/(m^2 sr) per W/m^2 of irradiance",
        "regions": {
            "c": "n . w_L, the vertex normal and the direction toward the light",
            "lit": "the models' incident flux is above 0 (direct light, shadow rays included)",
            **dict(REGIONS),
            ALL_REGION: "every traced vertex",
        },
        "figures": (
            "ratio = mean model / mean reference over the region's vertices (not area weighted), ratio_stderr "
            "from the reference's per-vertex standard errors; reentered_share = the reference's re-entered "
            "radiance over its radiance; ratio_without_reentered = mean model / mean of the reference less its "
            "re-entered part (which the models leave out); relative_error_* = |model - reference| / reference "
            "per vertex, over "
            f"the n_precise vertices whose reference standard error is below {PRECISE_STDERR:g} of it: they "
            "include the reference's noise"
        ),
        "vertices": int(len(setup.reference.points)),
        "untraced_vertices": int(np.count_nonzero(~np.all(np.isfinite(setup.reference.radiance), axis=1))),
        "reference": meta,
        "times_s": {
            "path_tracer": meta.get("seconds"),
            "path_tracer_median_relative_stderr": meta.get("median_relative_stderr"),
            "models": dict(times),
        },
        "rows": rows,
    }


def reference_table_text(rows, models, times) -> list:
    """The printed tables, one per model (region by channel ratios), each line at most 100 columns."""
    lines = [
        "regions by c = n.w_L (vertex normal . direction toward the light): lit c > 0.2 and directly lit,",
        "grazing 0 < c <= 0.2 and lit, shadowed c > 0 without direct light, far sides c <= 0 in three bands.",
        "ratio = mean model / mean reference of the radiance toward the normal, W/(m^2 sr) per W/m^2,",
        f"+- its standard error; |m-r|/r: median per vertex where the reference's error < {100 * PRECISE_STDERR:.0f} %",
        "(it includes the reference's noise); re-ent.: reference's re-entered share (green).",
    ]
    for model in models:
        lines.append(f"{model} dipole against the reference (solve {times[model]:.2f} s):")
        lines.append(
            f"  {'region':<15}{'vertices':>8}  {'R':<12} {'G':<12} {'B':<12} {'|m-r|/r R/G/B':<16}{'re-ent.':>7}"
        )
        own = [row for row in rows if row["model"] == model]
        for region in [name for name, _ in REGIONS] + [ALL_REGION]:
            cells = {row["channel"]: row for row in own if row["region"] == region}
            ratios = " ".join(f"{_ratio_text(cells[c]):<12}" for c in "RGB")
            errors = "/".join(_percent_text(cells[c]["relative_error_median"]) for c in "RGB")
            share = cells["G"]["reentered_share"]
            share = "-" if share is None else f"{100 * share:.1f} %"
            n = max(cells[c]["n_vertices"] for c in "RGB")
            lines.append(f"  {region:<15}{n:>8}  {ratios} {errors + ' %':<16}{share:>7}")
    return lines


#: The largest median error a table prints (in %): beyond it the reference's noise or a dark region's tiny mean
#: decides the figure, and ">999" keeps the column aligned.
LARGEST_PRINTED_PERCENT = 999


def _percent_text(fraction) -> str:
    """A median relative error as a whole percentage, "-" when there is none, ">999" beyond
    :data:`LARGEST_PRINTED_PERCENT`."""
    if fraction is None:
        return "-"
    percent = 100 * fraction
    return f"{percent:.0f}" if percent < LARGEST_PRINTED_PERCENT + 0.5 else f">{LARGEST_PRINTED_PERCENT}"


def _ratio_text(row) -> str:
    if row["ratio"] is None:
        return "-"
    return f"{row['ratio']:.3f}+-{row['ratio_stderr']:.3f}" if row["ratio"] < 10 else f"{row['ratio']:.3g}"
