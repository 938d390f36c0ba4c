"""The desktop viewer (translucency.app.desktop) under a real X display (xvfb-run), driven with pytest-qt.

Each test opens the window on a small sphere and waits for the solves, which run off the window's thread.
"""

import os

import numpy as np
import pytest

from translucency.errors import TranslucencyError
from translucency.geometry.synthetic import icosphere

pytestmark = pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs an X display (run under xvfb-run)")
pytest.importorskip("pyvistaqt", reason="the desktop viewer needs pyvistaqt")
pytest.importorskip("pytestqt", reason="the desktop viewer's tests need pytest-qt")

#: Longest wait for a solve of the small sphere (s): relighting's operators are prepared on the first one.
SOLVE_WAIT_S = 120


@pytest.fixture
def sphere_file(tmp_path):
    import pyvista

    points, triangles = icosphere(3, 20.0)  # 642 vertices, 40 mm across
    path = tmp_path / "sphere.ply"
    pyvista.PolyData.from_regular_faces(points, triangles).save(path)
    return path


def _settled(window):
    return window.state is not None and window.state.result is not None and not window.jobs.busy


@pytest.fixture
def window(qtbot, sphere_file, tmp_path):
    from translucency.app.desktop import MainWindow

    main = MainWindow(sphere_file, unit="mm", output=tmp_path / "saved", window_size=(1100, 700))
    qtbot.addWidget(main)
    main.show()
    qtbot.waitUntil(lambda: _settled(main), timeout=SOLVE_WAIT_S * 1000)
    qtbot.wait(50)  # the last job's signals
    yield main
    main.close()


def _wait_for_solves(qtbot, window, solves_before):
    qtbot.waitUntil(lambda: window.state.n_solves > solves_before and not window.jobs.busy, timeout=SOLVE_WAIT_S * 1000)
    qtbot.wait(50)


def test_the_window_shows_the_scan_solved_and_says_how(window):
    state = window.state
    assert state.method == "relight" and state.result.stats["solver_vertices"] == 642
    status = window.panel.status.text()
    assert "marble" in status and "relight" in status and "tolerance 0.01" in status and "last frame" in status
    assert "sphere.ply" in window.windowTitle() and "marble" in window.windowTitle()
    image = window.screenshot()
    height, width = image.shape[:2]
    middle = image[height // 3 : 2 * height // 3, width // 3 : 2 * width // 3]
    assert middle.mean() > 60  # the lit sphere fills the middle of the view


def test_the_window_appears_before_the_scan_is_solved(qtbot, sphere_file):
    from translucency.app.desktop import MainWindow
    from translucency.app.shading.settings import viewer_settings

    main = MainWindow(sphere_file, unit="mm")
    qtbot.addWidget(main)
    main.show()
    qtbot.waitExposed(main)
    try:
        assert main.state is None or main.state.result is None  # shown first, solved later
        free = main.screen().availableGeometry()  # the default size fits the screen, the side panel on it
        assert main.width() <= free.width() and main.height() <= free.height()
        settings = viewer_settings()  # the panel shows the starting settings from the first moment
        assert main.panel.tol.currentText() == f"{settings.tol:g}" and main.panel.bounces.value() == settings.bounces
        assert main.panel.unit.currentText() == "mm"
        qtbot.waitUntil(lambda: _settled(main), timeout=SOLVE_WAIT_S * 1000)
    finally:
        main.close()


def test_the_panel_changes_the_solve(qtbot, window):
    solves = window.state.n_solves
    window.panel.model.setCurrentText("standard")
    _wait_for_solves(qtbot, window, solves)
    assert window.state.model == "standard"
    assert "standard dipole" in window.panel.status.text()
    solves = window.state.n_solves
    bright = window.state.result.radiance.mean()
    window.panel.materials.material_chosen.emit("skim_milk")
    _wait_for_solves(qtbot, window, solves)
    assert window.state.medium.name == "skim_milk" and "skim_milk" in window.windowTitle()
    assert window.state.result.radiance.mean() != pytest.approx(bright)


def test_the_material_search_filters_the_list(window):
    chooser = window.panel.materials
    chooser.material_search.setText("milk")
    shown = [
        chooser.material_list.item(row).text()
        for row in range(chooser.material_list.count())
        if not chooser.material_list.item(row).isHidden()
    ]
    assert shown and all("milk" in name.lower() for name in shown)


def _display_point(renderer, world):
    """Display pixel (VTK's, origin at the bottom left) of a world point."""
    renderer.SetWorldPoint(*world, 1.0)
    renderer.WorldToDisplay()
    x, y, _ = renderer.GetDisplayPoint()
    return int(round(x)), int(round(y))


def test_dragging_the_ball_moves_the_light(qtbot, window):
    handle = window.handle
    before = window.state.lights[0].direction.copy()
    renderer = handle.overlay
    start = _display_point(renderer, handle.widget.GetHandlePosition())
    centre = _display_point(renderer, window._centre)
    interactor = window.view.iren.interactor
    solves = window.state.n_solves
    end = (start[0] + (centre[0] - start[0]) // 2 + 40, start[1] + (centre[1] - start[1]) // 2)
    interactor.SetEventInformation(*start, 0, 0)
    interactor.InvokeEvent("LeftButtonPressEvent")
    for k in range(1, 6):
        interactor.SetEventInformation(start[0] + k * (end[0] - start[0]) // 5, start[1] + k * (end[1] - start[1]) // 5)
        interactor.InvokeEvent("MouseMoveEvent")
    interactor.InvokeEvent("LeftButtonReleaseEvent")
    _wait_for_solves(qtbot, window, solves)
    after = window.state.lights[0].direction
    assert np.degrees(np.arccos(np.clip(before @ after, -1, 1))) > 5.0  # the light moved with the ball
    assert window.panel.azimuth.value() == pytest.approx(window.state.azimuth, abs=0.01)
    assert "ms" in window.panel.status.text()
    # the frames while it moved left the bounce out; the one when it was let go has it
    assert window.state.result.metadata["bounces"] == window.state.bounces == 1
    assert "no bounce" not in window.panel.status.text()


def test_point_and_environment_lights_from_the_panel(qtbot, window):
    from translucency.scatter.lights import EnvironmentLight, PointLight

    solves = window.state.n_solves
    window.panel.light_kind.setCurrentText("point")
    _wait_for_solves(qtbot, window, solves)
    assert isinstance(window.state.lights[0], PointLight)
    solves = window.state.n_solves
    window.panel.light_kind.setCurrentText("environment")
    _wait_for_solves(qtbot, window, solves)
    assert isinstance(window.state.lights[0], EnvironmentLight)
    assert not window.handle.widget.GetEnabled()  # nothing to drag for light from everywhere


def test_the_colour_bar_is_outside_the_scan(qtbot, window):
    window.panel.false_colour.setChecked(True)
    qtbot.waitUntil(lambda: window.colour_bar.isVisible(), timeout=5000)
    assert window.state.false_colour
    view = window.view.interactor
    view_rect = view.geometry().translated(view.mapTo(window, view.rect().topLeft()) - view.geometry().topLeft())
    bar = window.colour_bar
    bar_rect = bar.geometry().translated(bar.mapTo(window, bar.rect().topLeft()) - bar.geometry().topLeft())
    assert not view_rect.intersects(bar_rect)
    assert window.colour_bar.shown[1] == "log"
    window.panel.scale.setCurrentText("linear")
    assert window.state.false_colour_scale == "linear" and window.colour_bar.shown[1] == "linear"


def test_a_cancelled_material_change_keeps_the_last_picture(qtbot, window):
    medium = window.state.medium.name
    cancelled = []

    def cancel_once(kind, stage, fraction):
        if not cancelled:
            cancelled.append(kind)
            window.cancel()

    window.jobs.progress.connect(cancel_once)
    window.panel.materials.material_chosen.emit("ketchup")
    qtbot.waitUntil(lambda: bool(cancelled) and not window.jobs.busy, timeout=SOLVE_WAIT_S * 1000)
    qtbot.wait(50)
    assert window.state.medium.name == medium  # the change was taken back
    assert "cancelled" in window.status_line.message.text()


def test_a_bad_tolerance_is_one_sentence(window):
    window.panel.tol_chosen.emit(5.0)
    message = window.status_line.message.text()
    assert "relative error in (0, 1)" in message and "Traceback" not in message


def test_key_s_saves_the_picture_and_the_bake(qtbot, window, tmp_path):
    from translucency.io.baked import read_baked_ply

    window.menus.save_numbered()
    saved = sorted((tmp_path / "saved").iterdir())
    assert [path.suffix for path in saved] == [".ply", ".png"]
    assert len(read_baked_ply(saved[0]).points) == 642


def test_key_q_closes_the_window_not_only_the_view(qtbot, window):
    from PySide6 import QtCore

    window.activateWindow()
    window.view.interactor.setFocus()
    qtbot.waitUntil(lambda: window.view.interactor.hasFocus(), timeout=5000)
    qtbot.keyClick(window.view.interactor, QtCore.Qt.Key_Q)
    qtbot.waitUntil(lambda: not window.isVisible(), timeout=5000)
    assert not window.jobs._thread.is_alive()  # closed as a whole: the worker ended with it


def test_help_lists_the_keys_and_the_mouse():
    from translucency.app.desktop.menus import help_text

    text = help_text()
    for key in ("Return", "Esc", "h, ?, F1", "left drag", "yellow ball"):
        assert key in text


def test_a_missing_system_library_is_a_sentence(monkeypatch):
    import ctypes.util

    from translucency.app.desktop import check_can_start

    monkeypatch.setenv("DISPLAY", ":99")
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(ctypes.util, "find_library", lambda name: None if name == "xcb-cursor" else "found")
    with pytest.raises(TranslucencyError, match="apt-get install libxcb-cursor0"):
        check_can_start()


@pytest.mark.parametrize("name, fragment", [("missing.ply", "does not exist"), (".", "is a directory")])
def test_view_of_a_mesh_that_is_not_there_says_so_before_a_window_opens(name, fragment, tmp_path, monkeypatch, capsys):
    from translucency.app import cli

    monkeypatch.chdir(tmp_path)
    assert cli.main(["view", name]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("translucency: error:") and fragment in err[0]


def test_a_scan_that_cannot_be_read_is_one_sentence_in_the_window(qtbot, tmp_path):
    from translucency.app.desktop import MainWindow

    bad = tmp_path / "bad.ply"
    bad.write_bytes(b"ply\nformat nonsense\n")
    main = MainWindow(bad)
    qtbot.addWidget(main)
    main.show()
    try:
        qtbot.waitUntil(lambda: "PLY" in main.status_line.message.text(), timeout=60000)
        message = main.status_line.message.text()
        assert "bad.ply" in message and "PLY header" in message  # the loader's own sentence
        assert "Traceback" not in message and "\n" not in message and main.state is None
    finally:
        main.close()


def test_a_new_material_shows_a_quick_first_picture_then_relights_every_vertex(qtbot, window):
    methods = []
    window.jobs.finished.connect(lambda kind, value: methods.append(window.state.result.metadata["method"]))
    solves = window.state.n_solves
    window.panel.materials.material_chosen.emit("whole_milk")
    qtbot.waitUntil(lambda: window.state.n_solves >= solves + 2 and not window.jobs.busy, timeout=SOLVE_WAIT_S * 1000)
    qtbot.wait(50)
    assert methods[-2:] == ["tree", "relight"]  # the coarse preview first, then the prepared operators
    assert window.state.medium.name == "whole_milk" and "relight" in window.panel.status.text()
