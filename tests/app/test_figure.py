"""The labelled two-view picture: both views, a scale bar that measures the scan, the light's arrow, the colour bar."""

import numpy as np
import pytest

from translucency.app.figure import figure_image, nice_length, render_views, write_figure
from translucency.app.shading.scene import Scene
from translucency.geometry.mesh import TriangleMesh
from translucency.geometry.synthetic import icosphere
from translucency.scatter.lights import DirectionalLight


def distance_to_map(pixels, lut):
    """Per pixel (..., 3), the smallest sum of absolute RGB differences to a colour of ``lut`` (k, 3)."""
    from scipy.spatial import cKDTree

    distance, _ = cKDTree(lut).query(np.asarray(pixels, dtype=float).reshape(-1, 3), p=1)
    return distance.reshape(np.shape(pixels)[:-1])


def blue(image):
    """Pixels of the light's arrow (deepskyblue, shaded): blue well above red; neither the white scan nor
    the inferno map has such pixels."""
    image = image.astype(int)
    return (image[..., 2] > 120) & (image[..., 2] > image[..., 0] + 60)


@pytest.fixture(scope="module")
def sphere_result():
    points, triangles = icosphere(3, 20.0)  # 642 vertices, 40 mm across
    mesh = TriangleMesh(points, triangles)
    return mesh, Scene(mesh).shade("marble", DirectionalLight((1.0, 0.6, 0.3), 1.0), method="exact")


def test_nice_lengths():
    assert [nice_length(v) for v in (37.0, 10.0, 0.3, 7.9, 1999.0)] == [20.0, 10.0, 0.2, 5.0, 1000.0]


def test_the_views_measure_the_scan_in_mm(sphere_result):
    mesh, result = sphere_result
    from translucency.app.display import false_colour_range, false_colour_values

    values = false_colour_values(result.radiance)
    panel = 300
    image, mm_per_pixel = render_views(
        mesh, result, values, false_colour_range(values, "log", result.exposure), "log", None, "+y", panel
    )
    assert image.shape == (panel, 2 * panel, 3)
    for view in (image[:, :panel], image[:, panel:]):
        assert blue(view).sum() == 0  # nothing is drawn over the scan: the light is shown beside the views
        scan = view.max(axis=2) > 0
        rows = np.flatnonzero(scan.any(axis=1))
        # the sphere is 40 mm across (icosphere vertices on r = 20 mm; the facets come in by < 1 %)
        height_mm = (rows[-1] - rows[0] + 1) * mm_per_pixel
        assert 38.5 < height_mm < 41.0
    # the false colour uses matplotlib's inferno map: scan pixels lie on it
    from matplotlib import colormaps

    lut = (colormaps["inferno"](np.linspace(0, 1, 256))[:, :3] * 255).astype(int)
    right = image[:, panel:].reshape(-1, 3).astype(int)
    pixels = right[(right.max(axis=1) > 0) & ~blue(right)]
    assert np.median(distance_to_map(pixels, lut)) <= 6


def test_a_false_colour_below_its_range_keeps_its_outline_on_the_dark_background(sphere_result):
    # every value below the range takes the map's lowest colour, nearly black: without the grey outline the
    # scan would vanish into the background
    mesh, result = sphere_result
    from translucency.app.render import SILHOUETTE_COLOUR

    panel = 300
    values = np.full(mesh.n_points, 1e-9)
    image, mm_per_pixel = render_views(mesh, result, values, (1e-3, 1.0), "log", None, "+y", panel)
    right = image[:, panel:].astype(int)
    grey = int(SILHOUETTE_COLOUR[1:3], 16)
    outline = (np.abs(right - grey) <= 40).all(axis=2)
    rows, cols = np.nonzero(outline)
    assert outline.sum() > 100
    # the outline goes round the 40 mm sphere
    assert 36.0 < (rows.max() - rows.min() + 1) * mm_per_pixel < 42.0
    assert 36.0 < (cols.max() - cols.min() + 1) * mm_per_pixel < 42.0


def test_the_figure_has_both_views_a_colour_bar_and_is_written_atomically(sphere_result, tmp_path):
    import imageio.v3 as iio
    from matplotlib import colormaps

    mesh, result = sphere_result
    path = write_figure(tmp_path / "sphere_marble.png", mesh, result, name="sphere", panel=240)
    image = iio.imread(path)[..., :3].astype(int)
    assert path.name == "sphere_marble.png" and [p.name for p in tmp_path.iterdir()] == ["sphere_marble.png"]
    assert image.shape[1] > 2 * 240 and image.shape[0] > 240
    # the colour bar: a row running through inferno from black-purple to pale yellow
    lut = (colormaps["inferno"](np.linspace(0, 1, 256))[:, :3] * 255).astype(int)
    on_map = distance_to_map(image, lut) < 8
    bar_rows = np.flatnonzero((on_map & (image.sum(axis=2) > 60)).sum(axis=1) > 0.3 * image.shape[1])
    bar_rows = bar_rows[bar_rows > 0.7 * image.shape[0]]  # under the views
    assert bar_rows.size >= 5
    row = image[bar_rows[len(bar_rows) // 2]]
    yellow = np.flatnonzero(np.all(np.abs(row - lut[-1]) < 12, axis=1))
    purple = np.flatnonzero(np.all(np.abs(row - lut[64]) < 12, axis=1))
    assert yellow.size and purple.size and purple.mean() < yellow.mean()  # dark on the left, bright on the right
    assert figure_image(mesh, result, scale="linear", quantity="red", panel=120).ndim == 3


def test_the_title_says_when_the_colours_were_solved_on_a_proxy(sphere_result):
    from translucency.app.figure import figure_title

    mesh, result = sphere_result
    full = figure_title(mesh, result.metadata, "sphere")
    assert full.startswith("sphere: 642 vertices, ") and "proxy" not in full and "marble" in full
    assert "exact method (every pair" in full
    chosen = figure_title(mesh, {**result.metadata, "method": "auto", "method_used": "relight"}, "sphere")
    assert "auto method: relight (tol " in chosen  # the default says what it chose for the light
    proxy = figure_title(mesh, {**result.metadata, "resolution": "proxy, 1096375 vertices, edge 0.157 mm"}, "igea")
    assert proxy.startswith("igea: 642 vertices, ") and len(proxy.splitlines()) == 3
    assert proxy.splitlines()[1].startswith("solved on a proxy of 1,096,375 vertices (0.157 mm edges)")
    points, triangles = icosphere(5, 20.0)  # over a tight time limit the pipeline solves on a proxy
    scene = Scene(TriangleMesh(points, triangles), shadows=False)
    estimate = scene.shade("marble", bounces=0, time_limit=None).stats["solver"]["budget"]["seconds"]
    coarse = scene.shade("marble", bounces=0, time_limit=0.3 * estimate, warn=lambda line: None)
    assert "solved on a proxy of" in figure_title(scene.mesh, coarse.metadata)


def test_the_light_compass_draws_each_light_as_the_camera_sees_it():
    from matplotlib.figure import Figure
    from matplotlib.patches import FancyArrowPatch

    from translucency.app.figure import light_compass

    ax = Figure().add_subplot()
    lights = [
        {"type": "directional", "direction": [1.0, 0.0, 0.0]},  # from the picture's right, beside the object
        {"type": "directional", "direction": [0.0, 0.6, -0.8]},  # from above and behind
        {"type": "point", "position_mm": [0.0, 0.0, 50.0]},  # not drawn
    ]
    light_compass(ax, lights, camera_direction=(0.0, 0.0, 1.0), up=(0.0, 1.0, 0.0))
    arrows = [patch for patch in ax.patches if isinstance(patch, FancyArrowPatch)]
    assert len(arrows) == 2
    starts = [arrow._posA_posB[0] for arrow in arrows]
    assert starts[0] == pytest.approx((1.0, 0.0)) and starts[1] == pytest.approx((0.0, 0.6))
    assert arrows[0].get_linestyle() == "-" and arrows[1].get_linestyle() == "--"
