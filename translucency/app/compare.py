"""Scripted comparisons: one scan, view and light in several materials and models.

:func:`compare` solves every (material, model) pair on one :class:`~translucency.app.shading.scene.Scene`
(the geometry, Embree scene and visibility are computed once) and returns the numbers; with an output
folder it also writes

============================ ===========================================================================
file                         content
============================ ===========================================================================
``grid.png``                 one cell per (material, model): rows are models, columns materials, each
                             labelled; all cells share **one exposure** (below), so brightness compares
``differences.png``          with two or more models: per-vertex relative difference of luminance of each
                             model against the first, ``(Y_m - Y_ref) / max(Y_ref, 1e-3 Y_ref,99)``, one
                             row per model, one diverging colour bar with symmetric limits for all cells
``statistics.csv``           per (material, model, vertex subset, channel): mean, median and percentiles
                             5/25/75/95/99 of the radiance toward the normal, and the solve time
``statistics.json``          the same, the differences' statistics, the settings and the profile's plane
``profile.png``              radiance along a cut across the light boundary (below), one panel per channel,
                             the legend under the panels
``reference.csv``, ``.json`` with ``reference=``: every model against a path-traced reference per region
``reference_errors.png``     and channel, and the per-vertex ratio maps (:mod:`.reference_compare`)
============================ ===========================================================================

Statistics are per vertex (not area weighted) over two subsets: ``all`` vertices and ``lit`` ones (those
the lights reach directly: front-facing and not shadowed, i.e. with incident flux). Radiance is the
linear radiance toward the normal ``T21(eta, 1) B`` in W/(m² sr) for irradiance in W/m².

Common exposure: unless one is given, it maps the 99.5th percentile of the brightest channel over the
vertices of *all* cells together to 0.9 (:func:`~translucency.app.display.display_colors`), so the
brightest cell looks as a single render would and darker materials look darker.

Profile: the plane through the centre of the mesh's bounding box that contains the light direction (of
the first directional light; the ``up`` axis without one) and the ``up`` axis (the camera direction when
the light is along ``up``) cuts the surface in closed lines; along the longest, the radiance is
interpolated linearly from the vertices and plotted against the signed arc length, in mm, from the point
that faces the light most (positive toward ``up``). Dotted lines mark where the direct light ends (the
shadow terminator, and cast shadows), so the plot shows how far light bleeds past it in each material.

Default light: its own, :data:`COMPARE_LIGHT_DIRECTION`, not the pipeline's. The main job and the viewer
light a scan from above and in front (:data:`~translucency.app.shading.settings.DEFAULT_LIGHT_DIRECTION`), a
key light that leaves 13 % of the vertices the camera sees of the default bunny in shadow, mostly
under the chin and the haunch; but materials differ most where light crosses a shadow edge and where
it shines through thin parts, so compare lights from the right, above and a little behind: 32 % of
what the camera sees is in shadow, the terminator crosses the body and the ears are lit from behind
(:func:`visible_shadow_fraction` measures it; tests/app/test_compare.py keeps it at 10 % or more).

Files are written into a temporary folder beside the output folder and moved in only when all are
complete (:func:`~translucency.io.atomic.staged_folder`): a failed run leaves the folder as it was.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import __version__
from ..errors import InvalidParameterError, option
from ..io.polydata import to_pyvista
from ..io.units import RADIANCE_UNIT, unit_metadata
from ..scatter.names import DEFAULT_MODEL
from .compare_figures import difference_image, grid_image, profile_figure
from .display import display_colors
from .framing import DEFAULT_CAMERA_DIRECTION, DEFAULT_UP
from .shading.scan import mesh_for_shading
from .shading.scene import Scene, scene_for
from .shading.settings import DEFAULT_MATERIAL, ShadeSettings, resolve_medium, settings_with

__all__ = [
    "COMPARE_LIGHT_DIRECTION",
    "compare_light_direction",
    "visible_vertices",
    "visible_shadow_fraction",
    "Comparison",
    "compare",
    "validate_choices",
    "radiance_statistics",
    "relative_difference",
    "profile_cut",
    "profile_figure",
    "PERCENTILES",
]

#: Percentiles reported besides the mean and the median.
PERCENTILES = (5, 25, 75, 95, 99)
#: Rec. 709 luminance weights of linear RGB (the difference maps compare luminance).
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
#: The difference's denominator is at least this fraction of the reference's 99th percentile.
DIFFERENCE_FLOOR = 1e-3
CHANNELS = ("R", "G", "B")
#: From the object toward compare's default light, in the display frame (right, up, front; turned into the
#: scan's frame by its up axis like the pipeline's default): from the right, above and a little behind, so
#: that the camera (front right, :data:`~translucency.app.framing.DEFAULT_CAMERA_DIRECTION`) sees the shadow
#: edge and the glow through thin parts (module docstring: 32 % of the visible vertices of the default
#: bunny in shadow).
COMPARE_LIGHT_DIRECTION = (0.9, 1.0, -0.2)


@dataclass
class Comparison:
    """What :func:`compare` computed (and wrote).

    Attributes
    ----------
    materials, models : list of str
        In the order of the grid's columns and rows.
    exposure : float
        The display exposure every cell shares.
    results : dict
        ``(material, model) -> ShadeResult``.
    times : dict
        ``(material, model) -> solve time``, s.
    statistics : list of dict
        One row per (material, model, subset, channel), as in ``statistics.csv``.
    differences : list of dict
        One row per (material, model, subset) for models after the first: statistics of the relative
        difference of luminance against the first model.
    profiles : dict
        ``(material, model) -> (position (k,), radiance (k, 3))`` along the cut: signed arc length in mm
        from the point facing the light, and the interpolated radiance.
    profile_plane : dict
        The cut: ``center_mm``, unit ``normal``, ``light_direction``, ``length_mm`` and
        ``light_boundaries_mm`` (positions where the direct light ends).
    files : dict
        ``name -> Path`` of the written files (empty without an output folder).
    reference : ReferenceSetup or None
        With ``reference=``: the reference read back, its mesh, material and light
        (:class:`~translucency.app.reference_compare.ReferenceSetup`); None without.
    reference_rows : list of dict
        With ``reference=``: one row per (model, region, channel) of the models against the reference, as in
        ``reference.csv`` (:func:`~translucency.app.reference_compare.region_rows`); empty without.
    regions : ndarray or None
        With ``reference=``: the region of every vertex, (n,) int, an index into
        :data:`~translucency.app.reference_compare.REGIONS`; None without.
    reference_profile : tuple or None
        With ``reference=``: ``(position (k,), radiance (k, 3), stderr (k, 3))`` of the path-traced reference
        along the same cut as :attr:`profiles` (NaN where it was not traced); None without.
    """

    materials: list
    models: list
    exposure: float
    results: dict
    times: dict
    statistics: list
    differences: list
    profiles: dict
    profile_plane: dict
    files: dict = field(default_factory=dict)
    reference: object = None
    reference_rows: list = field(default_factory=list)
    regions: np.ndarray | None = None
    reference_profile: tuple | None = None

    def ratio(self, model: str, region: str = "lit") -> np.ndarray:
        """Mean model / mean reference per channel (R, G, B) over a region (``compare(..., reference=...)``);
        NaN where it cannot be formed."""
        rows = {
            row["channel"]: row["ratio"]
            for row in self.reference_rows
            if (row["model"], row["region"]) == (model, region)
        }
        if not rows:
            raise InvalidParameterError(f"no reference row for model {model!r} and region {region!r}.")
        return np.array([rows[c] if rows[c] is not None else np.nan for c in CHANNELS])

    def mean(self, material: str, model: str, subset: str = "lit") -> np.ndarray:
        """Mean radiance per channel (R, G, B) of one cell over ``subset`` (``"lit"`` or ``"all"``)."""
        rows = {
            row["channel"]: row["mean"]
            for row in self.statistics
            if (row["material"], row["model"], row["subset"]) == (material, model, subset)
        }
        return np.array([rows[c] if rows[c] is not None else np.nan for c in CHANNELS])


def compare_light_direction(up: str = "+y") -> np.ndarray:
    """:data:`COMPARE_LIGHT_DIRECTION` in the scan's coordinates for an up axis ``"+x"`` ... ``"-z"``."""
    from ..io.upright import to_scan_frame

    return to_scan_frame(COMPARE_LIGHT_DIRECTION, up)


def compare_view(mesh, up_axis: str, camera_direction=None, lights=None):
    """``(camera direction, lights)`` of compare's pictures: by default the scan's front
    (:func:`~translucency.app.framing.front_direction`) and compare's light (:func:`compare_light_direction`)
    turned about the up axis with the camera, so that the light keeps its place relative to the view."""
    from ..io.upright import up_vector
    from ..scatter.lights import DirectionalLight
    from .framing import front_direction, turned_to_front

    up = up_vector(up_axis)
    front = front_direction(mesh, up)
    if lights is None:
        lights = DirectionalLight(turned_to_front(compare_light_direction(up_axis), up, front), 1.0)
    return (front if camera_direction is None else camera_direction), lights


def visible_vertices(mesh, eye, normals=None) -> np.ndarray:
    """Which vertices a camera at ``eye`` (mm) sees: facing it (``n . (eye - p) > 0``) and not hidden by
    the mesh (an Embree ray toward the eye hits nothing), (n,) bool."""
    from ..scatter.visibility import Occluder

    points = mesh.points
    normals = mesh.vertex_normals() if normals is None else np.asarray(normals, dtype=np.float64)
    toward = np.asarray(eye, dtype=np.float64) - points
    distance = np.linalg.norm(toward, axis=1)
    facing = np.einsum("ij,ij->i", normals, toward) > 0
    seen = np.zeros(len(points), dtype=bool)
    index = np.flatnonzero(facing)
    seen[index] = Occluder(points, mesh.triangles).visible(
        points[index], normals[index], toward[index] / distance[index, None], distance[index]
    )
    return seen


def visible_shadow_fraction(mesh, lights=None, camera_direction=None, up="auto") -> float:
    """Share of the vertices the default camera sees that get no direct light (incident flux 0).

    ``lights`` and ``camera_direction`` default to compare's (:func:`compare_view`: the scan's front, and the light
    turned with it), placed by ``up`` (the camera at :func:`~translucency.app.framing.scan_camera`, as in
    ``grid.png``).
    """
    from ..io.upright import resolve_up, up_vector
    from .framing import scan_camera

    up_axis = resolve_up(up, mesh.points, mesh.triangles)
    scene = Scene(mesh, up=up_axis)
    camera_direction, lights = compare_view(mesh, up_axis, camera_direction, lights)
    eye = scan_camera(mesh, up_vector(up_axis), 1.0, camera_direction)[0]
    seen = visible_vertices(mesh, eye)
    lit = scene.light_cache.incident_on_mesh(resolve_medium(DEFAULT_MATERIAL), lights)[0].phi_rgb.max(axis=1) > 0
    return float(np.count_nonzero(seen & ~lit) / max(np.count_nonzero(seen), 1))


def radiance_statistics(radiance, mask=None) -> dict:
    """Per channel: vertex count, mean, median and :data:`PERCENTILES` of ``radiance`` (n, 3) where ``mask``.

    Values are None when the mask selects no vertex.
    """
    radiance = np.asarray(radiance, dtype=np.float64)
    values = radiance if mask is None else radiance[np.asarray(mask, dtype=bool)]
    out = {}
    for c, channel in enumerate(CHANNELS):
        v = values[:, c]
        empty = v.size == 0
        row = {
            "n_vertices": int(v.size),
            "mean": None if empty else float(v.mean()),
            "median": None if empty else float(np.median(v)),
        }
        for p in PERCENTILES:
            row[f"p{p}"] = None if empty else float(np.percentile(v, p))
        out[channel] = row
    return out


def relative_difference(radiance, reference) -> np.ndarray:
    """Per-vertex relative difference of luminance, ``(Y - Y_ref) / max(Y_ref, DIFFERENCE_FLOOR Y_ref,99)``."""
    y = np.asarray(radiance, dtype=np.float64) @ LUMINANCE
    y_ref = np.asarray(reference, dtype=np.float64) @ LUMINANCE
    floor = DIFFERENCE_FLOOR * float(np.percentile(y_ref, 99)) if y_ref.size else 0.0
    denominator = np.maximum(y_ref, floor)
    return np.divide(y - y_ref, denominator, out=np.zeros_like(y), where=denominator > 0)


def profile_cut(mesh, values, light_direction, up=DEFAULT_UP, camera_direction=DEFAULT_CAMERA_DIRECTION):
    """Per-vertex values along the cut across the light boundary (module docstring).

    The plane through the centre of the bounding box containing ``light_direction`` and ``up`` (or the
    camera direction, when the light is along ``up``) cuts the surface in closed lines; the longest is
    kept, and the values are interpolated linearly onto it.

    Parameters
    ----------
    mesh : TriangleMesh
        The mesh, mm.
    values : dict of str to (n, ...) array_like
        Per-vertex values to carry onto the cut.
    light_direction, up, camera_direction : sequence of 3 float
        Directions spanning the plane (see above).

    Returns
    -------
    position : (k,) ndarray
        Signed arc length along the cut, mm: 0 at the point that faces the light most, positive on the
        ``up`` side.
    samples : dict of str to (k, ...) ndarray
        The values at those points.
    plane : dict
        ``center_mm``, ``normal``, ``light_direction`` and ``length_mm`` of the cut.
    """
    d = np.asarray(light_direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    second = None
    for candidate in (up, camera_direction, (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)):
        u = np.asarray(candidate, dtype=np.float64)
        u = u - (u @ d) * d
        if np.linalg.norm(u) > 1e-3:
            second = u / np.linalg.norm(u)
            break
    center = 0.5 * (mesh.points.min(axis=0) + mesh.points.max(axis=0))
    normal = np.cross(d, second)
    poly = to_pyvista(mesh)
    for name, value in values.items():
        poly.point_data[name] = np.asarray(value, dtype=np.float64)
    cut = poly.slice(normal=normal, origin=center).strip(join=True)
    plane = {"center_mm": center.tolist(), "normal": normal.tolist(), "light_direction": d.tolist(), "length_mm": 0.0}
    lines, longest, i = np.asarray(cut.lines), np.zeros(0, dtype=np.int64), 0
    while i < len(lines):  # the VTK cell array: count, ids, count, ids, ...
        ids = lines[i + 1 : i + 1 + lines[i]]
        longest = ids if len(ids) > len(longest) else longest
        i += lines[i] + 1
    if len(longest) < 2:
        return np.zeros(0), {name: np.zeros((0,) + np.shape(v)[1:]) for name, v in values.items()}, plane
    closed = longest[0] == longest[-1]
    ids = longest[:-1] if closed else longest
    points = np.asarray(cut.points)[ids]
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)])
    length = arc[-1] + (np.linalg.norm(points[-1] - points[0]) if closed else 0.0)
    start = int(np.argmax((points - center) @ d))
    position = arc - arc[start]
    if closed:  # wrap onto (-length / 2, length / 2]
        position = (position + 0.5 * length) % length - 0.5 * length
    height = (points - center) @ second
    ahead, behind = height[position > 0], height[position < 0]
    if ahead.size and behind.size and ahead.mean() < behind.mean():
        position = -position  # positive toward up
    order = np.argsort(position, kind="stable")
    plane["length_mm"] = float(length)
    samples = {name: np.asarray(cut.point_data[name])[ids][order] for name in values}
    return position[order], samples, plane


def _names(values, what) -> list:
    if isinstance(values, str):
        values = [v.strip() for v in values.split(",")]
    values = [v for v in values if v]
    if not values:
        raise InvalidParameterError(f"give at least one {what}.")
    if len(set(values)) != len(values):
        raise InvalidParameterError(f"the {what}s {', '.join(values)} repeat a name; give each once.")
    return list(values)


def validate_choices(materials, models, sweep=None) -> tuple[list, list, dict]:
    """Materials and models as lists (a string ``"a,b"`` is split), checked; ``(materials, models, media)``.

    A material is a catalogue name, a material file, a definition mapping or a
    :class:`~translucency.scatter.medium.Medium` (:func:`~translucency.app.shading.settings.resolve_medium`).
    ``sweep`` (``{key: [values]}``, one key of :data:`~translucency.scatter.definition.SWEEP_KEYS`) turns the
    one material given into one per value (:func:`~translucency.scatter.definition.varied`). Raises a
    :class:`~translucency.errors.TranslucencyError` with one sentence for an empty or repeated list, an
    unknown model, an unknown or non-scattering material, or a sweep that is not one key over numbers.
    """
    from ..io.material_file import is_material_file
    from ..scatter.names import check_model

    entries = [v.strip() for v in materials.split(",")] if isinstance(materials, str) else list(materials)
    entries = [entry for entry in entries if not isinstance(entry, str) or entry]
    media = [resolve_medium(entry) for entry in entries]
    labels = [  # a name as given; a file or a medium by the material's own name
        entry if isinstance(entry, str) and not is_material_file(entry) else medium.name
        for entry, medium in zip(entries, media)
    ]
    if sweep is not None:
        media = _swept(media, sweep)
        labels = [medium.name for medium in media]
    labels = _names(labels, "material")
    models = [check_model(model) for model in _names(models, "model")]
    return labels, models, dict(zip(labels, media))


def _swept(media: list, sweep) -> list:
    """The one medium of ``media`` varied over the sweep's values (``{key: [values]}``), one per value."""
    from ..scatter.definition import SWEEP_KEYS, varied

    if not isinstance(sweep, dict) or len(sweep) != 1:
        raise InvalidParameterError(f"a sweep is one key of {', '.join(SWEEP_KEYS)} with its values, got {sweep!r}.")
    if len(media) != 1:
        raise InvalidParameterError(f"a sweep varies one material; give one, not {len(media)}.")
    ((key, values),) = sweep.items()
    values = list(values) if isinstance(values, (list, tuple, np.ndarray)) else [values]
    if not values:
        raise InvalidParameterError(f"the sweep over {key} needs at least one value.")
    return [varied(media[0], key, value) for value in values]


def compare(
    mesh=None,
    materials=None,
    models=(DEFAULT_MODEL,),
    lights=None,
    *,
    settings: ShadeSettings | None = None,
    output=None,
    camera_direction=None,
    cell_size=(480, 480),
    progress=None,
    unit=None,
    reference=None,
    sweep=None,
    **changes,
) -> Comparison:
    """Render and measure one scan in several materials and models (module docstring for every output).

    Parameters
    ----------
    mesh : TriangleMesh or pyvista.PolyData, optional
        A cleaned mesh in mm, or a PolyData in ``unit`` (converted and repaired,
        :func:`~translucency.app.shading.scan.mesh_for_shading`); default: the embedded default scan, cleaned.
    materials : sequence of str or Medium, or str "a,b,c", optional
        Catalogue names, material files (``.toml``, ``.json``), definition mappings or media (the grid's
        columns); default :data:`~translucency.app.shading.settings.DEFAULT_MATERIAL`, or the reference's material
        with ``reference``.
    models : sequence of str, or str
        Scattering models (the grid's rows; the first is the reference of the difference maps).
    lights : light or sequence of lights, optional
        Directions in the scan's own coordinates. Default: a white directional light of 1 W/m² from the
        right, above and a little behind (:func:`compare_light_direction`; why: the module docstring).
    output : path-like, optional
        Folder for the files (created; files in it are replaced atomically). None: numbers only.
    settings : ShadeSettings, optional
        Every setting of the solves (default: the defaults; :class:`~translucency.app.shading.settings.ShadeSettings`):
        each cell takes its material and model, and ``exposure`` is the common display exposure (default:
        automatic over all cells); ``up`` is the scan's up axis, ``"x"`` ... ``"-z"`` or ``"auto"`` (inferred
        from the mesh, :mod:`translucency.io.upright`): the view-up, the second axis of the profile's plane, and
        where the default camera and light are.
    **changes
        Any field of the settings by name (``method="exact"``, ``bounces=0``, ...), replacing the one of
        ``settings``, as in :func:`translucency.shade`.
    camera_direction : sequence of 3 float, optional
        From the mesh's centre toward the camera, in the scan's coordinates (default: the scan's front, a
        little above, :func:`compare_view`; the default light turns with it).
    cell_size : (int, int)
        Width and height of one grid cell, pixels; ``grid.png`` is ``(columns * width, rows * height)``.
    progress : callable, optional
        Called with a line of text after each solve.
    unit : {"mm", "cm", "m", "in"} or float, optional
        A PolyData's length unit (None: its ``field_data["length_unit"]``, else inferred from its size).
    reference : path-like or ReferenceFile, optional
        A path-traced reference (``translucency reference``) whose scan, material and light are then used (what
        is given too must agree); every model is measured against it per region
        (:mod:`translucency.app.reference_compare`, :attr:`Comparison.reference_rows`; files ``reference.*``).
    sweep : dict, optional
        One property of the one material over several values, one column each: ``{"mfp": [0.5, 1, 2, 4]}`` (mm),
        ``reflectance``, ``scale`` or ``eta`` (:func:`~translucency.scatter.definition.varied`).

    Returns
    -------
    Comparison
    """
    from ..io.upright import up_vector
    from ..scatter.lights import DirectionalLight, as_light_list

    setup, mesh, lights, unit, materials, models, media = _choices(
        reference, sweep, mesh, materials, models, lights, unit
    )
    if output is not None:
        from ..io.atomic import prepare_output_folder

        prepare_output_folder(output)
    # every solver setting checked once, before the scan is loaded; each cell changes material and model
    settings = settings_with(settings, **{**changes, "material": media[materials[0]], "model": models[0]})
    width, height = _cell_size(cell_size)
    mesh = _scan(mesh, unit)
    scene = scene_for(mesh, settings)
    up_axis = scene.up
    up = tuple(up_vector(up_axis))
    camera_direction, lights = compare_view(mesh, up_axis, camera_direction, lights)
    lights = as_light_list(lights)

    results, times = _solve_cells(scene, settings, media, materials, models, lights, progress)
    exposure = settings.exposure
    if exposure is None:
        _, exposure = display_colors(np.concatenate([r.radiance for r in results.values()]))
    lit = {
        material: scene.light_cache.incident_on_mesh(media[material], lights)[0].phi_rgb.max(axis=1) > 0
        for material in materials
    }
    statistics = _statistics(results, times, lit)
    relative, differences = _differences(results, materials, models, lit)
    key_light = next((light for light in lights if isinstance(light, DirectionalLight)), None)
    light_direction = key_light.direction if key_light is not None else np.asarray(up, dtype=np.float64)
    traced = None if setup is None else setup.reference
    profiles, plane, reference_profile = _profiles(
        mesh, results, lit[materials[0]], light_direction, up, camera_direction, traced
    )
    comparison = Comparison(
        materials, models, float(exposure), results, times, statistics, differences, profiles, plane
    )
    comparison.reference_profile = reference_profile
    if setup is not None:
        _measure_against_reference(comparison, setup, mesh, lit[materials[0]])
    if output is not None:
        comparison.files = _write_files(
            Path(output),
            mesh,
            comparison,
            relative,
            lights,
            camera_direction,
            up,
            (width, height),
            _recorded(settings, scene),
        )
    return comparison


def _cell_size(cell_size) -> tuple[int, int]:
    """The grid cell's width and height in pixels, at least 16 each (else a sentence)."""
    width, height = (int(v) for v in cell_size)
    if width < 16 or height < 16:
        raise InvalidParameterError(f"cell_size must be at least 16 x 16 pixels, got {cell_size!r}.")
    return width, height


def _scan(mesh, unit):
    """The mesh compared: the embedded default scan cleaned, or ``mesh`` as shading takes it."""
    if mesh is None:
        from .shading.scan import load_scan

        return load_scan(None)[0]
    return mesh_for_shading(mesh, unit, entry="compare")


def _recorded(settings, scene) -> dict:
    """The settings a comparison's files record (the material and model are the cells')."""
    recorded = {name: getattr(settings, name) for name in ("method", "tol", "resolution", "shadows", "per_direction")}
    return {
        **recorded,
        "bounces": settings.bounces,
        "albedo": settings.albedo,
        "up": scene.up,
        "up_inferred": scene.up_requested == "auto",
    }


def _choices(reference, sweep, mesh, materials, models, lights, unit):
    """``(setup or None, mesh, lights, unit, materials, models, media)``: the reference's scan, material and
    light when one is given (what else is given must agree with it), else the materials and models checked."""
    if reference is None:
        materials = materials if materials is not None else DEFAULT_MATERIAL
        materials, models, media = validate_choices(materials, models, sweep)
        return None, mesh, lights, unit, materials, models, media
    from .reference_compare import reference_setup

    if sweep is not None:
        raise InvalidParameterError(f"a reference fixes the material; compare against it without {option('sweep')}.")
    setup = reference_setup(reference, mesh, materials, lights, unit)
    _, models, _ = validate_choices([DEFAULT_MATERIAL], models)
    materials, media = [setup.medium.name], {setup.medium.name: setup.medium}
    return setup, setup.mesh, setup.light, None, materials, models, media  # the reference's points are in mm


def _solve_cells(scene, settings, media, materials, models, lights, progress):
    """Every (material, model) cell solved on one scene: ``(results, seconds)`` by cell."""
    results, times = {}, {}
    for material in materials:
        for model in models:
            start = time.perf_counter()
            cell = settings.replace(material=media[material], model=model, exposure=1.0)
            results[material, model] = scene.shade_with(cell, lights)
            times[material, model] = time.perf_counter() - start
            if progress is not None:
                progress(f"{material}, {model}: {times[material, model]:.2f} s")
    return results, times


def _statistics(results, times, lit) -> list:
    """The radiance statistics of every cell, over all vertices and the lit ones, per channel."""
    statistics = []
    for (material, model), result in results.items():
        for subset, mask in (("all", None), ("lit", lit[material])):
            for channel, row in radiance_statistics(result.radiance, mask).items():
                statistics.append(
                    {
                        "material": material,
                        "model": model,
                        "subset": subset,
                        "channel": channel,
                        **row,
                        "time_s": times[material, model],
                    }
                )
    return statistics


def _differences(results, materials, models, lit):
    """``(relative differences by cell, rows)``: each model's radiance against the first model's, per material."""
    relative, differences = {}, []
    for material in materials:
        for model in models[1:]:
            relative[material, model] = difference = relative_difference(
                results[material, model].radiance, results[material, models[0]].radiance
            )
            for subset, mask in (("all", slice(None)), ("lit", lit[material])):
                values = difference[mask]
                row = {
                    "material": material,
                    "model": model,
                    "reference": models[0],
                    "subset": subset,
                    "n_vertices": int(values.size),
                }
                if values.size:
                    row.update(
                        mean=float(values.mean()),
                        mean_abs=float(np.abs(values).mean()),
                        **{f"p{p}": float(np.percentile(values, p)) for p in (5, 50, 95)},
                    )
                differences.append(row)
    return relative, differences


def _profiles(mesh, results, lit, light_direction, up, camera_direction, reference=None):
    """``(profiles by cell, plane, reference profile)``: every cell's radiance along the cut through the light and
    the up axis, where the light's boundary crosses it (mm), and the path-traced ``reference``'s radiance and its
    standard error along the same cut (None without a reference)."""
    names = {key: f"{key[0]}/{key[1]}" for key in results}
    values = {names[key]: result.radiance for key, result in results.items()}
    values["lit"] = lit.astype(np.float64)
    if reference is not None:
        values["reference"], values["reference stderr"] = reference.radiance, reference.radiance_stderr
    position, samples, plane = profile_cut(mesh, values, light_direction, up, camera_direction)
    inside = samples["lit"] >= 0.5
    plane["light_boundaries_mm"] = (0.5 * (position[1:] + position[:-1]))[inside[1:] != inside[:-1]].tolist()
    traced = None if reference is None else (position, samples["reference"], samples["reference stderr"])
    return {key: (position, samples[names[key]]) for key in results}, plane, traced


def _measure_against_reference(comparison, setup, mesh, lit) -> None:
    """Every model's radiance against the path-traced reference per region (:attr:`Comparison.reference_rows`)."""
    from .reference_compare import assign_regions, region_rows

    material = comparison.materials[0]
    comparison.reference = setup
    comparison.regions = assign_regions(mesh.vertex_normals(), setup.light.direction, lit)
    for model in comparison.models:
        result = comparison.results[material, model]
        comparison.reference_rows += region_rows(
            model, result.radiance, setup.reference, comparison.regions, comparison.times[material, model]
        )


def _write_files(folder, mesh, comparison, relative, lights, camera_direction, up, cell_size, settings) -> dict:
    """Write every file into a staging folder, then move them into ``folder`` (module docstring)."""
    from ..io.atomic import staged_folder
    from .outputs import write_csv, write_png

    names = {"grid": "grid.png", "csv": "statistics.csv", "json": "statistics.json", "profile": "profile.png"}
    if relative:
        names["differences"] = "differences.png"
    setup = comparison.reference
    if setup is not None:
        names.update(
            reference_csv="reference.csv", reference_json="reference.json", reference_errors="reference_errors.png"
        )
    with staged_folder(folder) as staging:
        write_png(staging / names["grid"], grid_image(mesh, comparison, camera_direction, up, cell_size))
        if relative:
            write_png(
                staging / names["differences"],
                difference_image(mesh, comparison, relative, camera_direction, up, cell_size),
            )
        _profile_plot(comparison, staging / names["profile"])
        write_csv(staging / names["csv"], comparison.statistics, CSV_COLUMNS)
        document = {
            "format": "translucency-comparison",
            "version": __version__,
            "mesh": {
                "source": str(mesh.source) if mesh.source is not None else "embedded default scan",
                "vertices": mesh.n_points,
                "extent_mm": float(mesh.extent),
                **unit_metadata(mesh.mm_per_unit, mesh.unit_inferred),
            },
            "settings": {**settings, "lights": [light.to_dict() for light in lights]},
            "materials": comparison.materials,
            "models": comparison.models,
            "exposure": {"value": comparison.exposure, "rule": "common to every cell"},
            "radiance_unit": f"{RADIANCE_UNIT}, toward the normal",
            "times_s": [{"material": m, "model": k, "seconds": t} for (m, k), t in comparison.times.items()],
            "statistics": comparison.statistics,
            "differences": comparison.differences,
            "profile_plane": comparison.profile_plane,
            "files": names,
        }
        (staging / names["json"]).write_text(json.dumps(document, indent=1) + "\n", encoding="utf-8")
        if setup is not None:
            _write_reference_files(staging, names, comparison, document, camera_direction, up, cell_size)
    return {key: folder / name for key, name in names.items()}


def _write_reference_files(staging, names, comparison, document, camera_direction, up, cell_size) -> None:
    """``reference.csv``, ``reference.json`` and ``reference_errors.png`` (:mod:`.reference_compare`)."""
    from .outputs import write_csv, write_png
    from .reference_compare import CSV_COLUMNS as REFERENCE_CSV_COLUMNS
    from .reference_compare import reference_document, reference_errors_image

    setup, material = comparison.reference, comparison.materials[0]
    results = {model: comparison.results[material, model] for model in comparison.models}
    times = {model: comparison.times[material, model] for model in comparison.models}
    write_csv(staging / names["reference_csv"], comparison.reference_rows, REFERENCE_CSV_COLUMNS)
    reference = {
        "format": "translucency-reference-comparison",
        "version": __version__,
        "mesh": document["mesh"],
        "settings": document["settings"],
        "material": material,
        "models": comparison.models,
        **reference_document(setup, comparison.reference_rows, times),
    }
    (staging / names["reference_json"]).write_text(json.dumps(reference, indent=1) + "\n", encoding="utf-8")
    _, exposure = display_colors(np.nan_to_num(setup.reference.radiance))
    image = reference_errors_image(setup, results, comparison.models, exposure, camera_direction, up, cell_size)
    write_png(staging / names["reference_errors"], image)


#: Columns of ``statistics.csv``.
CSV_COLUMNS = (
    ["material", "model", "subset", "channel", "n_vertices", "mean", "median"]
    + [f"p{p}" for p in PERCENTILES]
    + ["time_s"]
)


def _profile_plot(comparison, path) -> None:
    """Write :func:`profile_figure` as a PNG."""
    profile_figure(comparison).savefig(path, format="png")
