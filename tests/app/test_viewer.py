"""The viewer: widgets driven from code re-solve (or only re-display), the CLI's screenshot equals the API's image."""

import os

import numpy as np
import pytest

from translucency.app import cli
from translucency.app.render import render_colors
from translucency.app.shading.scene import Scene
from translucency.app.viewer import Viewer, interactive_edge_length, light_angles, light_direction
from translucency.errors import InvalidParameterError
from translucency.geometry.mesh import TriangleMesh
from translucency.geometry.synthetic import icosphere
from translucency.io.baked import read_baked_ply
from translucency.io.polydata import to_pyvista
from translucency.scatter.lights import DirectionalLight, EnvironmentLight

needs_display = pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs an X display (run under xvfb-run)")

#: Mean absolute difference (8-bit levels) allowed between two renderings of the same colours: the
#: same renderer draws the same triangles, so only rasterisation order could differ.
PIXEL_TOLERANCE = 0.5


@pytest.fixture(scope="module")
def sphere():
    points, triangles = icosphere(3, 20.0)  # 642 vertices, 40 mm across
    return TriangleMesh(points, triangles)


@pytest.fixture
def viewer(sphere):
    view = Viewer(sphere, "marble", window_size=(400, 300), off_screen=False)
    yield view
    view.close()


def drag(widget, value):
    """Move a slider as a user would: set its value, then fire the events of a drag (the light sliders answer
    while they move, the others when they are let go)."""
    widget.GetRepresentation().SetValue(value)
    widget.InvokeEvent("InteractionEvent")
    widget.InvokeEvent("EndInteractionEvent")


def colors(view):
    return np.array(view.poly.point_data["colors"], dtype=float)


def test_light_angles_round_trip():
    for azimuth, elevation in [(0, 0), (90, 10), (-135, 45), (170, -60)]:
        direction = light_direction(azimuth, elevation)
        assert np.isclose(np.linalg.norm(direction), 1.0)
        np.testing.assert_allclose(light_angles(direction), (azimuth, elevation), atol=1e-9)
    np.testing.assert_allclose(light_direction(90, 0), (1, 0, 0), atol=1e-12)  # +x at azimuth 90 for up = +y
    np.testing.assert_allclose(light_direction(0, 90, up=(0, 0, 1)), (0, 0, 1), atol=1e-12)


def test_interactive_edge_gives_about_the_vertex_budget(sphere):
    from translucency.app.shading.resolution import proxy_edge_length
    from translucency.app.shading.settings import resolve_medium

    marble = resolve_medium("marble")
    big = sphere.replace(points=sphere.points * 10)  # 400 mm across: 64x the area of the sphere
    edge = interactive_edge_length(big, marble, vertices=500)
    result = Scene(big).shade(marble, method="exact", resolution=edge)
    assert 350 < result.stats["solver_vertices"] < 650
    # never finer than what the material needs
    assert interactive_edge_length(sphere, marble, vertices=10**9) == proxy_edge_length(marble)


@needs_display
def test_light_slider_solves_again_and_updates_colours_and_status(viewer, sphere):
    before, status = colors(viewer), viewer.status
    assert viewer.n_solves == 1 and "marble" in viewer.status and "relight, tolerance 0.01" in viewer.status
    assert "operators prepared in" in viewer.status
    # every vertex, relit: the operators are prepared once and every move of a slider reuses them
    assert viewer.result.stats["solver_vertices"] == viewer.result.stats["vertices"]
    drag(viewer.widgets["azimuth"], -140.0)
    assert "relight operators" in viewer.result.stats["reused"]
    drag(viewer.widgets["elevation"], -20.0)
    assert viewer.n_solves == 3 and "operators prepared" not in viewer.status
    assert (viewer.azimuth, viewer.elevation) == (-140.0, -20.0)
    assert viewer.status != status and "azimuth -140 deg, elevation -20 deg" in viewer.status
    assert f"solved in {viewer.solve_seconds:.2f} s" in viewer.status
    after = colors(viewer)
    assert np.abs(after - before).mean() > 10
    # the bright side is now the one facing the new light
    facing = sphere.vertex_normals() @ light_direction(-140.0, -20.0)
    assert after[facing > 0.5].mean() > after[facing < -0.5].mean() + 50


@needs_display
def test_material_and_model_sliders(viewer):
    marble = colors(viewer)
    names = viewer.controls.materials
    drag(viewer.widgets["material"], names.index("ketchup"))
    assert viewer.medium.name == "ketchup" and viewer.status.startswith("ketchup")
    ketchup = colors(viewer)
    red_over_blue = lambda c: c[:, 0].mean() / max(c[:, 2].mean(), 1.0)  # noqa: E731
    assert red_over_blue(ketchup) > 1.5 * red_over_blue(marble)
    drag(viewer.widgets["model"], 1)
    assert viewer.model == "standard" and "standard dipole" in viewer.status
    assert viewer.n_solves == 3
    assert np.abs(colors(viewer) - ketchup).mean() > 1


@needs_display
def test_exposure_changes_colours_without_a_solve(viewer):
    before, exposure, solves = colors(viewer), viewer.exposure, viewer.n_solves
    drag(viewer.widgets["exposure"], np.log2(exposure) + 1.0)
    assert viewer.n_solves == solves
    assert np.isclose(viewer.exposure, 2 * exposure)
    assert colors(viewer).mean() > before.mean() + 5
    assert f"exposure {2 * exposure:.3g}" in viewer.status


@needs_display
def test_scale_slider_makes_a_new_scene_of_the_scaled_mesh(viewer, sphere):
    scene = viewer.scene
    drag(viewer.widgets["scale"], 3.0)
    assert viewer.scene is not scene
    assert np.isclose(viewer.scene.mesh.extent, 3 * sphere.extent)
    assert viewer.scene.mesh.mm_per_unit == 3.0 and "120 mm (3 mm per unit)" in viewer.status
    # a larger object in the same material: light diffuses over a smaller fraction of it
    facing = sphere.vertex_normals() @ viewer.lights[0].direction
    dark = viewer.result.B[facing < -0.5].mean() / viewer.result.B[facing > 0.5].mean()
    small = Scene(sphere).shade("marble", viewer.lights, resolution="full")
    assert dark < small.B[facing < -0.5].mean() / small.B[facing > 0.5].mean()


@needs_display
def test_view_dependent_layer_follows_the_camera_without_a_solve(viewer, sphere):
    solves = viewer.n_solves
    checkbox = viewer.widgets["view_dependent"]
    checkbox.GetRepresentation().SetState(1)
    checkbox.InvokeEvent("StateChangedEvent")
    assert viewer.view_dependent and viewer.n_solves == solves
    facing = colors(viewer)
    normal_view = np.array(viewer.result.colors, dtype=float)
    # T21 toward the camera is below T21 along the normal at the silhouette, equal facing the camera
    eye = np.asarray(viewer.plotter.camera.position)
    w_o = eye - sphere.points
    cos_o = np.einsum("ij,ij->i", sphere.vertex_normals(), w_o / np.linalg.norm(w_o, axis=1, keepdims=True))
    grazing = (cos_o > 0) & (cos_o < 0.2) & (normal_view.max(axis=1) > 30)
    assert grazing.sum() > 5 and np.all(facing[grazing].max(axis=1) < normal_view[grazing].max(axis=1))
    viewer.plotter.camera.Azimuth(90)
    assert np.abs(colors(viewer) - facing).mean() > 1 and viewer.n_solves == solves


@needs_display
def test_specular_highlight_adds_light(viewer):
    before, solves = colors(viewer), viewer.n_solves
    viewer.set_specular(True)
    after = colors(viewer)
    assert viewer.n_solves == solves
    assert np.all(after >= before) and (after > before + 2).any(axis=1).sum() > 3
    assert viewer.widgets["specular"].GetRepresentation().GetState() == 1


@needs_display
def test_save_key_writes_a_screenshot_and_the_bake(viewer, tmp_path):
    viewer.output = tmp_path
    interactor = viewer.plotter.iren.interactor
    interactor.SetKeySym("s")
    interactor.InvokeEvent("KeyPressEvent")
    pngs, plys = sorted(tmp_path.glob("*.png")), sorted(tmp_path.glob("*.ply"))
    assert [p.name for p in pngs] == ["scan_marble_directional_000.png"] and len(plys) == 1
    import imageio.v3 as iio

    assert np.array_equal(iio.imread(pngs[0]), viewer.screenshot())  # the scan's part: no controls in it
    assert iio.imread(pngs[0]).shape[:2] == (300, 280)
    baked = read_baked_ply(plys[0])
    np.testing.assert_allclose(baked.radiance, viewer.result.radiance, rtol=1e-6, atol=1e-9)
    assert baked.metadata["material"] == "marble" and baked.metadata["exposure"] == viewer.exposure
    viewer.save(tmp_path)  # a second save does not overwrite the first
    assert len(list(tmp_path.glob("*.ply"))) == 2


@needs_display
def test_return_key_solves_on_every_vertex(sphere):
    view = Viewer(sphere.replace(points=sphere.points * 8), "marble", window_size=(200, 150), resolution=40.0)
    try:
        assert view.result.stats["solver_vertices"] < sphere.n_points
        interactor = view.plotter.iren.interactor
        interactor.SetKeySym("Return")
        interactor.InvokeEvent("KeyPressEvent")
        assert view.result.stats["solver_vertices"] == sphere.n_points
        assert f"{sphere.n_points} of {sphere.n_points} vertices" in view.status
    finally:
        view.close()


def test_without_a_directional_light_there_is_nothing_to_steer(sphere):
    view = Viewer(sphere, "marble", EnvironmentLight(1.0, n_directions=16), window_size=(160, 120), off_screen=True)
    try:
        assert "azimuth" not in view.widgets and view.azimuth is None
        with pytest.raises(InvalidParameterError, match="no directional light"):
            view.set_light(10, 20)
        with pytest.raises(InvalidParameterError):
            view.set_exposure(-1)
    finally:
        view.close()


def test_view_screenshot_equals_the_api_image(sphere, tmp_path):
    path = tmp_path / "sphere.ply"
    to_pyvista(sphere).save(path)
    out = tmp_path / "view.png"
    code = cli.main(
        [
            "view",
            str(path),
            "--material",
            "skim_milk",
            "--light-dir",
            "1,0.5,0.2",
            "--screenshot",
            str(out),
            "--window-size",
            "320x240",
        ]
    )
    assert code == 0 and out.exists()
    import imageio.v3 as iio

    image = iio.imread(out).astype(float)
    from translucency.app.shading.scan import load_scan
    from translucency.app.shading.settings import resolve_medium

    mesh, _, _ = load_scan(path)
    medium = resolve_medium("skim_milk")
    result = Scene(mesh).shade(medium, DirectionalLight((1, 0.5, 0.2), 1.0))  # one picture: every vertex
    expected = render_colors(mesh, result.colors, window_size=(320, 240)).astype(float)
    assert image.shape == expected.shape == (240, 320, 3)
    assert image.max() > 100  # the object is there
    assert np.abs(image - expected).mean() < PIXEL_TOLERANCE


@pytest.mark.parametrize(
    "args, fragment",
    [
        (["--screenshot", "view.jpg"], "not a .png"),
        (["--screenshot", "missing-folder/view.png"], "does not exist"),
        (["--screenshot", "v.png", "--window-size", "big"], "WIDTHxHEIGHT"),
        (["--screenshot", "v.png", "--roughness", "0"], "roughness"),
        (["--screenshot", "v.png", "--material", "no such thing"], "unknown material"),
    ],
)
def test_view_errors_are_one_sentence_with_exit_code_2(args, fragment, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["view", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("translucency: error:") and fragment in err[0]
    assert not list(tmp_path.iterdir())


def test_view_without_a_display_says_how_to_render_off_screen(monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert cli.main(["view"]) == 2
    assert "--screenshot" in capsys.readouterr().err


def test_interactive_proxy_of_a_tiny_object_is_one_the_mesh_allows():
    from translucency.app.shading.resolution import coarsest_proxy_edge
    from translucency.app.shading.settings import resolve_medium

    points, triangles = icosphere(4, 0.08)  # 0.16 mm across: the shared bunny read with --unit mm
    tiny = TriangleMesh(points, triangles)
    marble = resolve_medium("marble")
    edge = interactive_edge_length(tiny, marble)
    assert edge == pytest.approx(coarsest_proxy_edge(tiny.surface_area))
    result = Scene(tiny).shade(marble, method="exact", resolution=edge)  # used to fail: "pass a length below"
    assert 0 < result.stats["solver_vertices"] < tiny.n_points


@needs_display
def test_z_up_puts_the_camera_in_front_and_above_and_the_light_above():
    from tests.app.test_pipeline import _plinth

    view = Viewer(_plinth(2), "marble", window_size=(200, 150), off_screen=True, widgets=False, method="exact")
    try:
        assert view.up_axis == "+z" and view.up == (0.0, 0.0, 1.0)
        eye, focus, view_up = (np.asarray(v) for v in view.plotter.camera_position)
        np.testing.assert_allclose(view_up, (0, 0, 1), atol=1e-9)
        offset = eye - focus
        assert offset[2] > 0 and offset[1] < 0  # above, and in front (-y is the front of a Z-up scan)
        assert view.elevation == pytest.approx(60.3, abs=0.5) and "up +z" in view.status
    finally:
        view.close()


@needs_display
def test_shared_angel_is_shown_z_up_by_default(shared_meshes):
    from translucency.app.shading.scan import load_scan

    mesh, _, _ = load_scan(shared_meshes / "ggg_angel_sfm.ply")
    view = Viewer(mesh, "marble", window_size=(160, 120), off_screen=True, widgets=False, resolution=12.0)
    try:
        assert view.up_axis == "+z"
        np.testing.assert_allclose(view.plotter.camera_position[2], (0, 0, 1), atol=1e-9)
    finally:
        view.close()


def test_the_picture_is_the_scan_alone_and_no_control_covers_it(sphere, tmp_path):
    import imageio.v3 as iio

    from translucency.app.viewer import CONTROL_STRIP

    view = Viewer(sphere, "marble", window_size=(1024, 768), off_screen=True)
    try:
        picture = view.screenshot(tmp_path / "shot.png")
        window = view.screenshot(widgets=True)
        height, width = picture.shape[:2]
        assert window.shape == (768, 1024, 3) and height == 768 and abs(width - 1024 * (1 - CONTROL_STRIP)) <= 1
        assert np.array_equal(iio.imread(tmp_path / "shot.png"), picture)
        # a render of the same colours and camera with no widget at all: equal pixels, so neither the saved
        # picture nor the scan's part of the window holds a slider, a check box or text
        expected = render_colors(
            sphere, view.poly.point_data["colors"], window_size=(width, height), camera=view.renderer.camera_position
        )
        assert picture.max() > 100
        assert np.abs(picture.astype(float) - expected).mean() < PIXEL_TOLERANCE
        assert np.abs(window[:, :width].astype(float) - expected).mean() < PIXEL_TOLERANCE
        # and the controls are there, in the strip
        strip = window[:, width + 2 :]
        assert (strip != strip[0, 0]).any(axis=2).mean() > 0.05
    finally:
        view.close()


def test_false_colour_shows_the_luminance_with_a_colour_bar_and_no_solve(sphere):
    from matplotlib import colormaps

    from translucency.app.display import luminance
    from translucency.app.viewer.layers import LOWER_EDGE

    view = Viewer(sphere, "marble", window_size=(480, 360), off_screen=True)
    try:
        solves, srgb = view.n_solves, view.screenshot()
        view.set_false_colour(True)
        picture = view.screenshot()
        assert view.n_solves == solves and view.widgets["false_colour"].GetRepresentation().GetState() == 1
        low, high = view.state.false_colour_range()
        np.testing.assert_allclose(
            view.false_colour_poly.point_data["false colour"], np.maximum(luminance(view.result.radiance), low)
        )
        # the scan and the colour bar are drawn with matplotlib's inferno map (the sRGB view has no such pixels)
        lut = (colormaps["inferno"](np.linspace(0, 1, 256))[:, :3] * 255).astype(int)

        def on_map(image):
            pixels = image.reshape(-1, 3).astype(int)
            pixels = pixels[pixels.max(axis=1) > 40]
            return (np.abs(pixels[:, None, :] - lut[None]).sum(axis=2).min(axis=1) <= 6).mean()

        assert on_map(picture) > 0.9 and on_map(srgb) < 0.5
        assert view.layers.bar_title.GetText(LOWER_EDGE) == view.state.false_colour_title  # under the bar's labels
        view.set_false_colour_scale("linear")
        assert not (view.screenshot() == picture).all()
        view.set_false_colour(False)
        assert np.abs(view.screenshot().astype(float) - srgb).mean() < PIXEL_TOLERANCE
    finally:
        view.close()


def test_the_compass_arrow_follows_the_light_sliders(viewer):
    def arrow_direction():
        points = np.asarray(viewer.compass_arrow.points)
        centre = points.mean(axis=0)
        return centre / np.linalg.norm(centre)

    assert arrow_direction() @ viewer.lights[0].direction > 0.99
    drag(viewer.widgets["azimuth"], -120.0)
    drag(viewer.widgets["elevation"], 10.0)
    direction = light_direction(-120.0, 10.0)
    np.testing.assert_allclose(viewer.lights[0].direction, direction, atol=1e-12)
    assert arrow_direction() @ direction > 0.99


def test_draws_into_a_plotter_the_user_passes(sphere):
    import pyvista

    plotter = pyvista.Plotter(off_screen=True, window_size=(300, 200), shape=(1, 2), border=False)
    plotter.set_background("black")  # as the viewer's own, so that the pictures compare
    plotter.subplot(0, 1)
    view = Viewer(sphere, "marble", plotter=plotter)
    try:
        assert view.plotter is plotter and view.renderer is plotter.renderers[1] and view.widgets == {}
        picture = view.screenshot()
        assert picture.shape == (200, 150, 3) and picture.max() > 100
        expected = render_colors(
            sphere, view.poly.point_data["colors"], window_size=(150, 200), camera=view.renderer.camera_position
        )
        # a sub-viewport of the host's window rasterises the same triangles a little differently at the edges
        assert np.abs(picture.astype(float) - expected).mean() < 2 * PIXEL_TOLERANCE
        left = plotter.screenshot(return_img=True)[:, :150]
        assert np.all(left == left[0, 0])  # the other subplot is the host's, untouched
        view.set_exposure(2 * view.exposure)
        assert view.screenshot().astype(float).mean() > picture.astype(float).mean()
        view.close()
        plotter.render()  # still the host's, still open
    finally:
        plotter.close()


@needs_display
def test_keys_y_and_l_toggle_the_false_colour_and_its_scale(viewer):
    interactor = viewer.plotter.iren.interactor
    for key, expected in (("y", (True, "log")), ("l", (True, "linear")), ("y", (False, "linear"))):
        interactor.SetKeySym(key)
        interactor.InvokeEvent("KeyPressEvent")
        assert (viewer.state.false_colour, viewer.state.false_colour_scale) == expected
    assert viewer.widgets["log_scale"].GetRepresentation().GetState() == 0
