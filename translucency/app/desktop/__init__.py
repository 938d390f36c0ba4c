"""The desktop viewer: a Qt application around the PyVista view (``translucency view``).

:mod:`.window` is the main window (menus, view, colour bar, status bar), :mod:`.panel` its side panel,
:mod:`.lighting` the light the panel builds and the handle that drags it, :mod:`.jobs` the solves off the
window's thread, :mod:`.colour_bar` the false colour's bar. They need Qt (PySide6) and pyvistaqt, imported
only when the window is made; :func:`check_can_start` says in one sentence what is missing. The viewer
without Qt, for scripts and off-screen pictures, is :mod:`translucency.app.viewer`.
"""

from __future__ import annotations

import sys

from ...errors import TranslucencyError

__all__ = ["MainWindow", "run", "check_can_start"]


#: Shared libraries Qt's X11 platform plugin needs beyond Qt's own wheel, with the Debian package of each.
QT_X11_LIBRARIES = {
    "xcb-cursor": "libxcb-cursor0",
    "xcb-icccm": "libxcb-icccm4",
    "xcb-keysyms": "libxcb-keysyms1",
    "xkbcommon-x11": "libxkbcommon-x11-0",
}


def check_can_start() -> None:
    """A sentence, not Qt's abort, when the desktop viewer cannot start: Qt's Python packages or the X11
    libraries its platform plugin loads are missing."""
    import ctypes.util
    import importlib.util
    import os

    missing = [name for name in ("PySide6", "pyvistaqt") if importlib.util.find_spec(name) is None]
    if missing:
        raise TranslucencyError(
            f"the desktop viewer needs {' and '.join(missing)}; run ./run.sh once (it installs them), or "
            "pass --screenshot FILE.png for a picture without a window."
        )
    if sys.platform.startswith("linux") and os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        absent = [package for name, package in QT_X11_LIBRARIES.items() if ctypes.util.find_library(name) is None]
        if absent:
            raise TranslucencyError(
                f"Qt cannot open a window on this X display without the system libraries of {', '.join(absent)}; "
                f"install them (apt-get install {' '.join(absent)}) or run ./run.sh once, which does."
            )


def run(path=None, **options) -> int:
    """Open the desktop viewer on ``path`` (None: the default scan); returns when its window is closed
    (:func:`translucency.app.desktop.window.run`)."""
    from .window import run as run_window

    return run_window(path, **options)


def __getattr__(name):
    if name == "MainWindow":  # Qt is imported only when the window is asked for
        from .window import MainWindow

        return MainWindow
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
