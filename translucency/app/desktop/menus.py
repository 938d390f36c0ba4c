"""The desktop viewer's menus, keys and help: File (open, recent scans, save the bake or a screenshot, quit),
View (front view, accurate solve, cancel), Help (keys and mouse), and the keys of the render view.

:class:`Menus` builds them on a :class:`~translucency.app.desktop.window.MainWindow` and calls its methods; the
recent scans are kept in Qt's settings (:data:`SETTINGS_NAME`).
"""

from __future__ import annotations

from pathlib import Path

from PySide6 import QtCore, QtGui, QtWidgets

from ..viewer.saving import numbered_paths

#: The keys and the mouse, as the Help menu and the ``h`` / ``?`` keys show them.
KEYS = (
    ("left drag", "turn the camera (on the yellow ball: move the light)"),
    ("right drag or wheel", "zoom"),
    ("middle drag or shift + left drag", "pan"),
    ("r", "frame the scan from its front again"),
    ("Return", "solve every vertex accurately (the method's default tolerance)"),
    ("y", "false colour on or off"),
    ("l", "log or linear false colour"),
    ("s", "save a screenshot and the bake into the output folder"),
    ("Esc", "cancel the running solve"),
    ("q", "quit (as in PyVista's windows)"),
    ("h, ?, F1", "this help"),
    ("Ctrl+O / Ctrl+S / Ctrl+Q", "open a scan / save the bake / quit"),
)
#: Scans kept in File > Open Recent.
RECENT_FILES = 8
#: Qt settings' organisation and application names (where the recent files are kept).
SETTINGS_NAME = ("translucency", "viewer")


def scan_file_filter() -> str:
    """The open dialog's filter: every mesh format :func:`translucency.io.load.load_mesh` reads."""
    from ...io.load import SUPPORTED_FORMATS

    patterns = " ".join(f"*{suffix}" for suffix in SUPPORTED_FORMATS)
    return f"Scans ({patterns});;All files (*)"


def help_text() -> str:
    """The keys and the mouse as an HTML table (the Help menu's dialog)."""
    rows = "".join(f"<tr><td><b>{key}</b></td><td>{what}</td></tr>" for key, what in KEYS)
    return (
        f"<table cellspacing=6>{rows}</table><p>The status under the panel says what was solved, how, and how "
        "long a frame took.</p>"
    )


class Menus:
    """The menu bar, the keys and the dialogs of ``window``."""

    def __init__(self, window):
        self.window = window
        menu = window.menuBar()
        file = menu.addMenu("&File")
        self._action(file, "&Open scan...", self.open_dialog, QtGui.QKeySequence.Open)
        self.recent_menu = file.addMenu("Open &recent")
        self.fill_recent()
        self._action(file, "Open the &default scan", lambda: window.open_scan(None))
        file.addSeparator()
        self._action(file, "&Save bake...", self.save_bake_dialog, QtGui.QKeySequence.Save)
        self._action(file, "Save scree&nshot...", self.save_screenshot_dialog, "Ctrl+Shift+S")
        file.addSeparator()
        self._action(file, "&Quit", window.close, QtGui.QKeySequence.Quit)
        view = menu.addMenu("&View")
        self._action(view, "&Front view", window.reset_camera)
        self._action(view, "Solve every vertex &accurately", window.solve_full)
        self._action(view, "&Cancel the solve", window.cancel)
        help_menu = menu.addMenu("&Help")
        self._action(help_menu, "&Keys and mouse", self.show_help, QtGui.QKeySequence.HelpContents)
        self._make_keys()

    def open_dialog(self) -> None:
        """File > Open: choose a scan."""
        path, _ = QtWidgets.QFileDialog.getOpenFileName(self.window, "Open a scan", "", scan_file_filter())
        if path:
            self.window.open_scan(path)

    def save_bake_dialog(self) -> None:
        """File > Save bake: the current result as PLY, VTP or glTF (the suffix names the format)."""
        window = self.window
        if window.state is None or window.state.result is None:
            return window.say("nothing is solved yet to save.")
        suggested = str(window.output / f"{window.state.file_stem}.ply")
        path, _ = QtWidgets.QFileDialog.getSaveFileName(
            window, "Save the bake", suggested, "PLY (*.ply);;VTK PolyData (*.vtp);;glTF binary (*.glb)"
        )
        if path:
            window.guarded(lambda: window.say(f"saved {window.state.write_bake(path)}"))

    def save_screenshot_dialog(self) -> None:
        """File > Save screenshot: the view as a PNG (the scan, no panel)."""
        window = self.window
        if window.state is None:
            return
        suggested = str(window.output / f"{window.state.file_stem}.png")
        path, _ = QtWidgets.QFileDialog.getSaveFileName(window, "Save a screenshot", suggested, "PNG (*.png)")
        if path:
            window.guarded(lambda: window.say(f"saved {window.screenshot(path)}"))

    def save_numbered(self) -> None:
        """Key ``s``: a screenshot and the bake (PLY) into the window's output folder, named
        ``<scan>_<material>_<model>_<n>`` with the first free ``n``."""
        window = self.window
        if window.state is None or window.state.result is None:
            return window.say("nothing is solved yet to save.")

        def write():
            folder = window.output
            folder.mkdir(parents=True, exist_ok=True)
            png_path, ply_path = numbered_paths(folder, window.state.file_stem, (".png", ".ply"))
            png = window.screenshot(png_path)
            ply = window.state.write_bake(ply_path)
            window.say(f"saved {png} and {ply.name}")

        window.guarded(write)

    def show_help(self) -> None:
        """The keys and the mouse (Help menu, ``h``, ``?``, F1)."""
        QtWidgets.QMessageBox.information(self.window, "Keys and mouse", help_text())

    def remember(self, path) -> None:
        """Put ``path`` first in File > Open recent."""
        store = QtCore.QSettings(*SETTINGS_NAME)
        path = str(Path(path).resolve())
        recent = [path] + [p for p in (store.value("recent") or []) if p != path]
        store.setValue("recent", recent[:RECENT_FILES])
        self.fill_recent()

    def fill_recent(self) -> None:
        """File > Open recent: the scans opened last that still exist."""
        self.recent_menu.clear()
        recent = [p for p in (QtCore.QSettings(*SETTINGS_NAME).value("recent") or []) if Path(p).exists()]
        for path in recent:
            self._action(self.recent_menu, path, lambda p=path: self.window.open_scan(p))
        self.recent_menu.setEnabled(bool(recent))

    def _make_keys(self) -> None:
        window = self.window
        panel = window.panel
        keys = {
            "h": self.show_help,
            "?": self.show_help,
            "Return": window.solve_full,
            "Enter": window.solve_full,
            "s": self.save_numbered,
            "r": window.reset_camera,
            "q": window.close,  # PyVista's own q would end the view and leave the window
            "y": lambda: panel.false_colour.toggle(),
            "l": lambda: panel.scale.setCurrentText("linear" if panel.scale.currentText() == "log" else "log"),
        }
        for key, slot in keys.items():  # in the view, where a letter is not typed into a field
            shortcut = QtGui.QShortcut(QtGui.QKeySequence(key), window.view.interactor)
            shortcut.setContext(QtCore.Qt.WidgetWithChildrenShortcut)
            shortcut.activated.connect(slot)
        for key, slot in (("Escape", window.cancel), ("F1", self.show_help)):  # anywhere in the window
            QtGui.QShortcut(QtGui.QKeySequence(key), window).activated.connect(slot)

    def _action(self, menu, text, slot, shortcut=None):
        action = QtGui.QAction(text, self.window)
        if shortcut is not None:
            action.setShortcut(QtGui.QKeySequence(shortcut))
        action.triggered.connect(lambda *_: slot())
        menu.addAction(action)
        return action
