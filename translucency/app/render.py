"""Off-screen rendering set-up for PyVista/VTK on machines without a display.

Without an X display VTK must render through EGL (``libegl1``); this module selects the EGL render
window before PyVista is first imported and checks that rendering really produces pixels.
"""

from __future__ import annotations

import os


def configure_offscreen() -> None:
    """Select VTK's EGL render window when there is no X display (call before importing pyvista)."""
    if not os.environ.get("DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")


def offscreen_check() -> tuple[bool, str]:
    """Render a small sphere off-screen; return (works, a sentence saying how or why not)."""
    configure_offscreen()
    try:
        import pyvista

        plotter = pyvista.Plotter(off_screen=True, window_size=(64, 48))
        plotter.add_mesh(pyvista.Sphere(), color="white")
        image = plotter.screenshot(return_img=True)
        window = type(plotter.render_window).__name__
        plotter.close()
    except Exception as exc:  # any VTK/OpenGL failure is reported, not raised
        return False, f"{type(exc).__name__}: {exc}; install libegl1 (apt-get install libegl1) or run under Xvfb"
    if image is None or image.size == 0 or image.max() == image.min():
        return False, "the rendered image is blank; install libegl1 (apt-get install libegl1) or run under Xvfb"
    return True, f"{window}, {image.shape[1]}x{image.shape[0]} image"
