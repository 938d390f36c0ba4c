"""Off-screen rendering set-up for PyVista/VTK on machines without a display.

Without an X display VTK must render through EGL (``libegl1``); this module selects the EGL render
window before PyVista is first imported and checks that rendering really produces pixels.
"""

from __future__ import annotations

import os

import numpy as np


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


def render_colors(mesh, colors_rgb8, path=None, *, window_size=(800, 800), camera_direction=(0.6, 0.35, 1.0)):
    """Render a mesh (mm) with per-vertex display colours off-screen; save a PNG when ``path`` is given.

    Returns
    -------
    ndarray
        The image, (height, width, 3) uint8.
    """
    configure_offscreen()
    import pyvista

    poly = mesh.to_pyvista()
    poly.point_data["colors"] = np.asarray(colors_rgb8, dtype=np.uint8)
    plotter = pyvista.Plotter(off_screen=True, window_size=list(window_size))
    plotter.set_background("black")
    plotter.add_mesh(poly, scalars="colors", rgb=True, lighting=False, smooth_shading=True)
    centre = np.asarray(poly.center)
    direction = np.asarray(camera_direction, dtype=float)
    direction /= np.linalg.norm(direction)
    plotter.camera_position = [tuple(centre + direction * 1.7 * poly.length), tuple(centre), (0.0, 1.0, 0.0)]
    image = plotter.screenshot(str(path) if path is not None else None, return_img=True)
    plotter.close()
    return image
