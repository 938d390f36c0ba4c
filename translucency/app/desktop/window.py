"""The desktop viewer: a Qt main window around the PyVista view, with a side panel, menus and solves off its thread.

Layout (Qt's desktop conventions, as in pyvistaqt's ``MainWindow``): the render view in the middle, the false
colour's colour bar under it (never over the scan), the side panel on the right
(:mod:`translucency.app.desktop.panel`), a File, View and Help menu, and a status bar with the progress of the
running solve and its Cancel button. Scans open from the File menu, the recent files, or by dropping a file on
the window.

The window is shown before anything is solved: the scan is loaded and drawn in grey, then solved off the
window's thread (:mod:`translucency.app.desktop.jobs`), and recoloured when the solve ends. Dragging the
yellow ball in the view (:class:`~translucency.app.desktop.lighting.LightHandle`) moves the light and relights
as it moves; only the newest waiting light is solved. Everything shown comes from one
:class:`~translucency.app.viewer.state.ViewerState`, drawn by :class:`~translucency.app.viewer.layers.ScanLayers`.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from ...errors import TranslucencyError
from ..shading.settings import viewer_settings
from ..viewer.layers import ScanLayers
from .changes import connect_panel
from .colour_bar import ColourBar
from .jobs import Jobs
from .lighting import LightHandle, panel_lights
from .menus import Menus
from .panel import SidePanel
from .status_line import StatusLine

#: Lines of notes (the unit inferred, warnings) shown under the status: the latest.
NOTES_SHOWN = 3
#: Time between showing the window and starting to load its scan, ms (the window paints first).
OPEN_DELAY_MS = 150


#: The share of the screen's free area a window takes at most.
SCREEN_SHARE = 0.95


def fitted_size(size) -> tuple[int, int]:
    """``size`` (pixels) shrunk to :data:`SCREEN_SHARE` of the primary screen's free area where it is larger: the
    side panel and the status bar stay on the screen."""
    screen = QtGui.QGuiApplication.primaryScreen()
    if screen is None:
        return int(size[0]), int(size[1])
    free = screen.availableGeometry()
    return min(int(size[0]), int(SCREEN_SHARE * free.width())), min(int(size[1]), int(SCREEN_SHARE * free.height()))


class MainWindow(QtWidgets.QMainWindow):
    """The desktop viewer's window (see the module docstring).

    Parameters
    ----------
    path : path-like, optional
        The scan to open once the window is shown (None: the embedded default scan; ``False``: none).
    settings : ShadeSettings, optional
        The starting solver settings (default :func:`~translucency.app.shading.settings.viewer_settings`).
    lights : light or sequence of lights, optional
        The starting lights (default: one directional light above and in front of the scan).
    unit : {"mm", "cm", "m", "in"} or float, optional
        The scan file's unit (None: inferred from its size, and said in the status).
    output : path-like
        Where the ``s`` key saves (default: the current folder).
    view_dependent, specular : bool
        Start with those display layers on.
    roughness : float
        GGX ``alpha`` of the specular highlight.
    window_size : (int, int)
        The window's size, pixels.
    """

    def __init__(
        self,
        path=None,
        *,
        settings=None,
        lights=None,
        unit=None,
        output=".",
        view_dependent=False,
        specular=False,
        roughness=0.25,
        window_size=(1400, 900),
    ):
        from pyvistaqt import QtInteractor

        super().__init__()
        self.settings, self.start_lights, self.unit = settings, lights, unit
        self.start_layers = {"view_dependent": bool(view_dependent), "specular": bool(specular), "roughness": roughness}
        self.output = Path(output)
        #: The viewer's state (None until a scan is loaded).
        self.state = None
        self.layers = self.handle = None
        self.scan_path = None
        self.light_kind, self.light_distance = "directional", 3.0
        self.unit_name = "mm"
        self._centre, self._radius = np.zeros(3), 1.0
        self._frame_time = None
        self.notes = []
        self.setWindowTitle("translucency")
        self.resize(*fitted_size(window_size))
        self.setAcceptDrops(True)

        central = QtWidgets.QWidget()
        column = QtWidgets.QVBoxLayout(central)
        column.setContentsMargins(0, 0, 0, 0)
        column.setSpacing(0)
        #: The render view (a pyvistaqt ``QtInteractor``, a PyVista plotter).
        # drawn when something changes, not on pyvistaqt's timer (a render costs CPU that a solve needs where the
        # OpenGL is software)
        self.view = QtInteractor(central, auto_update=False)
        self.view.set_background("black")
        self.view.enable_anti_aliasing("fxaa")
        column.addWidget(self.view.interactor, 1)
        #: The false colour's colour bar, under the view (shown with the false colour).
        self.colour_bar = ColourBar(central)
        self.colour_bar.hide()
        column.addWidget(self.colour_bar)
        self.setCentralWidget(central)

        self.panel = SidePanel()
        self.panel.show_settings(settings or viewer_settings(), unit)  # before the scan loads, not the widgets' own
        dock = QtWidgets.QDockWidget("Controls", self)
        dock.setObjectName("controls")
        dock.setWidget(self.panel)
        dock.setFeatures(QtWidgets.QDockWidget.DockWidgetMovable | QtWidgets.QDockWidget.DockWidgetFloatable)
        self.addDockWidget(QtCore.Qt.RightDockWidgetArea, dock)

        #: The status bar: one line, and the running solve's progress with its Cancel button.
        self.status_line = StatusLine(self.cancel)
        self.setStatusBar(self.status_line)

        self.jobs = Jobs(self)
        self.jobs.started.connect(self._job_started)
        self.jobs.progress.connect(self._job_progress)
        self.jobs.finished.connect(self._job_finished)
        self.jobs.failed.connect(self._job_failed)
        self.jobs.cancelled.connect(
            lambda kind: self._job_failed(kind, "cancelled; the picture is the last one solved")
        )
        self.jobs.idle.connect(lambda: self.status_line.show_busy(False))
        connect_panel(self)
        #: The menu bar, keys and dialogs.
        self.menus = Menus(self)
        if path is not False:
            # after the window's first paint: loading competes with it for the interpreter
            QtCore.QTimer.singleShot(OPEN_DELAY_MS, lambda: self.open_scan(path))

    # ------------------------------------------------------------------------------------------------
    # opening and saving

    def open_scan(self, path=None, unit=None) -> None:
        """Load ``path`` (None: the embedded default scan) off the window's thread, draw it, then solve it.

        The file is read and cleaned in a child process (:func:`~translucency.app.shading.scan.load_scan_quietly`):
        the mesh library's own Qt must not share this process with the window's.
        """
        from ...processes import run_in_child
        from ..shading.scan import load_scan_quietly
        from ..viewer.state import ViewerState

        unit = self.unit if unit is None else unit
        label = f"loading {Path(path).name if path is not None else 'the default scan'}"

        def load():
            mesh, name, notes = run_in_child(load_scan_quietly, path, unit)
            state = ViewerState(
                mesh,
                lights=self.start_lights,
                settings=self.settings,
                name=Path(name).stem,
                solve=False,
                **self.start_layers,
            )
            return state, notes, path

        self.jobs.cancel()
        self.jobs.submit("open", label, load)

    def screenshot(self, path=None) -> np.ndarray:
        """The view's picture, (h, w, 3) uint8; written as a PNG when ``path`` is given."""
        from ..outputs import write_png

        self.view.render()
        image = np.asarray(self.view.screenshot(return_img=True))[..., :3]
        if path is not None:
            return write_png(path, np.ascontiguousarray(image))
        return image

    # ------------------------------------------------------------------------------------------------
    # changes from the panel, the handle and the keys

    def request(self, kind: str, label: str, change) -> None:
        """Run ``change(state)`` off the window's thread (it solves when it must); the picture follows."""
        if self.state is None:
            return
        state = self.state
        self.jobs.submit(kind, label, lambda: (time.perf_counter(), change(state)))

    def set_light(self, kind: str, azimuth: float, elevation: float, distance: float, moving: bool = False) -> None:
        """The light the panel or the handle chose (:func:`~translucency.app.desktop.lighting.panel_lights`);
        ``moving``: a frame while the ball is dragged (``ViewerState.set_lights``: no bounce)."""
        if self.state is None:
            return
        self.light_kind, self.light_distance = kind, distance
        if self.handle is not None:
            self.handle.set_visible(kind != "environment")
            if kind != "environment" and not moving:  # while it is dragged the ball is where the user holds it
                self.handle.place(azimuth, elevation)
        lights = panel_lights(kind, azimuth, elevation, distance, self.state.up, self._centre, self._radius)
        self.request("light", f"relighting ({kind})", lambda state: state.set_lights(lights, moving=moving))

    def cancel(self) -> None:
        """Stop the running solve (Cancel, Esc); what is shown stays."""
        if self.jobs.busy:
            self.jobs.cancel()
            self.say("cancelling ...")

    def reset_camera(self) -> None:
        """Frame the whole scan from its front (:mod:`translucency.app.framing`)."""
        from ..framing import scan_camera

        if self.state is None:
            return
        size = self.view.interactor.size()
        aspect = size.width() / max(size.height(), 1)
        self.view.camera_position = scan_camera(self.state.base_mesh, self.state.up, aspect, self.state.front)
        self.view.reset_camera_clipping_range()
        self.view.render()

    def solve_full(self) -> None:
        """Key Return: the current state solved on every vertex at the default tolerance."""
        self.request("full", "solving every vertex", lambda state: state.solve_full())

    # ------------------------------------------------------------------------------------------------
    # the jobs' ends, on the window's thread

    def _job_started(self, kind: str, label: str) -> None:
        self.status_line.show_busy(True)
        self.say(label + " ...")

    def _job_progress(self, kind: str, stage: str, fraction: float) -> None:
        self.status_line.show_progress(stage, fraction)

    def _job_finished(self, kind: str, value) -> None:
        if kind == "open":
            self._install(*value)
            return
        started, _ = value
        self._frame_time = time.perf_counter() - started
        self.redraw()

    def _job_failed(self, kind: str, message: str) -> None:
        self.say(message)  # the state is as before the change (ViewerState._solve_with): show it so
        if self.state is not None:
            self.redraw(keep_message=True)

    def _install(self, state, notes, path) -> None:
        """A loaded scan: draw it in grey, frame it, put the handle on, then solve it."""
        if self.handle is not None:
            self.handle.close()
        self.view.clear()
        self.state = state
        state.on_progress = self.jobs.report
        self.scan_path = path
        self.layers = ScanLayers(self.view, state.base_mesh)
        self._centre = np.asarray(self.layers.poly.center, dtype=np.float64)
        self._radius = 0.5 * float(self.layers.poly.length)
        self.unit_name = _unit_name(state.mm_per_unit)
        self.light_kind = "directional" if state.key_light is not None else "point"
        self.reset_camera()
        moved, let_go = (lambda a, e: self._handle_moved(a, e, True)), self._handle_moved
        self.handle = LightHandle.in_view(self.view, self._centre, state.up, moved, let_go)
        if state.azimuth is not None:
            self.handle.place(state.azimuth, state.elevation)
        self.handle.set_visible(state.key_light is not None)
        self.panel.reset_exposure()
        self.panel.show_state(state, self.light_kind, self.light_distance, self.unit_name)
        self._show_title()
        if path is not None:
            self.menus.remember(path)
        self.view.render()
        #: Lines said while loading and solving (the unit inferred, warnings), shown under the status.
        self.notes = [_in_panel_words(note) for note in notes]
        self.request("preview", "a first picture on a coarser copy of the scan", lambda s: s.solve_preview())
        label = f"solving {state.medium.name} on {state.base_mesh.n_points:,} vertices"
        self.request("solve", label, lambda s: s.solve())

    def _handle_moved(self, azimuth: float, elevation: float, moving: bool = False) -> None:
        self.panel.set_angles(azimuth, elevation)
        self.set_light(self.light_kind, azimuth, elevation, self.light_distance, moving)

    def _show_title(self) -> None:
        scan = Path(self.scan_path).name if self.scan_path is not None else "default scan"
        self.setWindowTitle(f"{scan} - {self.state.medium.name} - translucency")

    def redraw(self, keep_message: bool = False) -> None:
        """Draw what the state holds: colours, colour bar, panel, status, title."""
        state = self.state
        if state.result is None:
            return
        state.set_eye(self.view.camera.position)
        self.layers.recolour(state)
        if state.false_colour:
            self.colour_bar.show_range(state.false_colour_range(), state.false_colour_scale, state.false_colour_title)
        self.colour_bar.setVisible(state.false_colour)
        self.panel.show_state(state, self.light_kind, self.light_distance, self.unit_name)
        frame = "" if self._frame_time is None else f"\nlast frame {1000 * self._frame_time:.0f} ms"
        notes = "".join(f"\n{note}" for note in self.notes[-NOTES_SHOWN:])
        self.panel.status.setText(state.status + frame + notes)
        self._show_title()
        if not keep_message:
            self.say(state.status.split("\n")[-1])
        self.view.render()

    # ------------------------------------------------------------------------------------------------
    # wiring

    def say(self, text: str) -> None:
        """Show one line in the status bar."""
        self.status_line.say(text)

    def guarded(self, work) -> None:
        """Run ``work()`` here; a translucency error becomes the status line's sentence."""
        try:
            work()
        except TranslucencyError as exc:
            self.say(str(exc))

    # ------------------------------------------------------------------------------------------------
    # Qt events

    def dragEnterEvent(self, event) -> None:  # noqa: N802 (Qt's name)
        if event.mimeData().hasUrls():
            event.acceptProposedAction()

    def dropEvent(self, event) -> None:  # noqa: N802 (Qt's name)
        urls = [url.toLocalFile() for url in event.mimeData().urls() if url.isLocalFile()]
        if urls:
            self.open_scan(urls[0])

    def closeEvent(self, event) -> None:  # noqa: N802 (Qt's name)
        self.jobs.shutdown()
        if self.handle is not None:
            self.handle.close()
        self.view.close()
        super().closeEvent(event)


def _in_panel_words(note: str) -> str:
    """A loading note as the window says it: the unit is changed in the panel, not by ``unit=``."""
    return note.replace("no unit= given", "no unit given").replace(
        "pass unit= to override", "the panel's file unit changes it"
    )


def _unit_name(mm_per_unit: float) -> str:
    """The panel's unit for ``mm_per_unit`` (:func:`~translucency.io.units.unit_label`), or ``mm`` for a scale of
    its own."""
    from ...io.units import UNITS, unit_label

    label = unit_label(mm_per_unit)
    return label if label in UNITS else "mm"


def run(path=None, **options) -> int:
    """Open the desktop viewer on ``path`` (None: the default scan) and return when its window is closed.

    ``options`` are :class:`MainWindow`'s. Python warnings (a material outside the models' range, ...) are
    shown under the panel's status as well as on standard error, in one line each.
    """
    import warnings

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(["translucency"])
    app.setApplicationName("translucency")
    window = MainWindow(path, **options)

    def show_warning(message, category, filename, lineno, file=None, line=None):
        window.notes.append(f"warning: {message}")
        print(f"translucency: warning: {message}", file=sys.stderr)

    warnings.showwarning = show_warning
    window.show()
    return app.exec()
