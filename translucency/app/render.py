"""Off-screen rendering set-up for PyVista/VTK on machines without a display.

Without an X display VTK must render through EGL (``libegl1``); this module selects the EGL render
window before PyVista is first imported and checks that rendering really produces pixels.
"""

from __future__ import annotations

import os

import numpy as np

from ..io.polydata import to_pyvista


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


def new_plotter(window_size, *, off_screen=True, **layout):
    """A PyVista plotter with the package's rendering set-up (black background, EGL without a display).

    ``layout`` goes to ``pyvista.Plotter`` (``shape``, ``row_weights``, ``groups``, ...).
    """
    configure_offscreen()
    import pyvista

    plotter = pyvista.Plotter(off_screen=off_screen, window_size=list(window_size), **layout)
    plotter.set_background("black")
    return plotter


def add_colored_mesh(plotter, mesh, colors_rgb8, *, name=None):
    """Add a mesh (mm) showing per-vertex display colours as they are (no lighting); returns the PolyData.

    The colours are the array ``"colors"`` of the returned PolyData: change it in place and call
    ``plotter.render()`` to show new colours. ``name`` names the actor (``plotter.renderer.actors[name]``).
    """
    poly = to_pyvista(mesh)
    poly.point_data["colors"] = np.asarray(colors_rgb8, dtype=np.uint8)
    plotter.add_mesh(poly, scalars="colors", rgb=True, lighting=False, name=name)
    return poly


def render_colors(
    mesh, colors_rgb8, path=None, *, window_size=(800, 800), camera_direction=None, camera=None, up="auto"
):
    """Render a mesh (mm) with per-vertex display colours off-screen; save a PNG when ``path`` is given.

    Parameters
    ----------
    mesh : TriangleMesh
        The mesh, mm.
    colors_rgb8 : (n, 3) uint8
        Display colours per vertex (display transform applied).
    path : path-like, optional
        PNG to write (atomically, see :func:`translucency.app.outputs.write_png`).
    window_size : (int, int)
        Image width and height, pixels.
    camera_direction : sequence of 3 float, optional
        From the mesh's centre toward the eye in the scan's coordinates (used when ``camera`` is None;
        default: the scan's front); the whole scan is framed (:func:`translucency.app.framing.scan_camera`).
    camera : list, optional
        An explicit PyVista camera position ``[eye, focal point, view up]`` (mm).
    up : str
        The scan's up axis, ``"x"`` ... ``"-z"`` or ``"auto"`` (inferred from the mesh,
        :mod:`translucency.io.upright`): the camera's view-up.

    Returns
    -------
    ndarray
        The image, (height, width, 3) uint8.
    """
    from ..io.upright import resolve_up, up_vector

    plotter = new_plotter(window_size)
    add_colored_mesh(plotter, mesh, colors_rgb8)
    if camera is None:
        from .framing import scan_camera

        up = resolve_up(up, mesh.points, mesh.triangles)
        camera = scan_camera(mesh, tuple(up_vector(up)), window_size[0] / window_size[1], camera_direction)
    plotter.camera_position = camera
    image = plotter.screenshot(return_img=True)
    plotter.close()
    if path is not None:
        from .outputs import write_png

        write_png(path, image)
    return image


#: Colour of the light glyph (an arrow from the light toward the object): in neither the scans' colours
#: nor the false colour map.
LIGHT_GLYPH_COLOR = "deepskyblue"


def light_glyph(center, radius, direction):
    """An arrow (PolyData) from the light toward the object: the light direction drawn as a glyph.

    Parameters
    ----------
    center : sequence of 3 float
        Where the arrow points to (the object's centre), mm.
    radius : float
        The object's radius (half its bounding-box diagonal), mm: the arrow's tip is that far from
        ``center`` toward the light, and the arrow is 0.6 of it long.
    direction : sequence of 3 float
        From the object toward the light (any non-zero length).
    """
    import pyvista

    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    length = 0.6 * float(radius)
    tail = np.asarray(center, dtype=float) + d * (float(radius) + length)
    return pyvista.Arrow(start=tail, direction=-d, tip_length=0.3, tip_radius=0.12, shaft_radius=0.045, scale=length)


#: The outline drawn around a false-colour mesh (a mid grey, seen on the dark background and against the map).
SILHOUETTE_COLOUR = "#8c8c8c"


def add_false_colour_mesh(plotter, mesh, values, clim, scale="log", *, title=None, scalar_bar=None, outline=False):
    """Add a mesh (mm) showing per-vertex ``values`` through the false colour map.

    ``values`` are in physical units (:func:`translucency.app.display.false_colour_values`), ``clim`` their
    range (:func:`~translucency.app.display.false_colour_range`); on a log scale values below the range
    take its lowest colour. With a ``title`` a colour bar is drawn (``scalar_bar``: more keywords of
    PyVista's ``add_scalar_bar``). The values are the array ``"false colour"`` of the PolyData: change it
    in place to show new ones. ``outline``: the silhouette in :data:`SILHOUETTE_COLOUR` (the map's lowest colour
    is nearly black, and a dark region's edge would vanish on a dark background), made with the plotter's
    camera as it is when the mesh is added.

    Returns
    -------
    poly : pyvista.PolyData
    actor : pyvista.Actor
    bar : vtkScalarBarActor or None
    """
    from .display import FALSE_COLOUR_MAP

    poly = to_pyvista(mesh)
    poly.point_data["false colour"] = np.maximum(np.asarray(values, dtype=np.float64), clim[0])
    actor = plotter.add_mesh(
        poly,
        scalars="false colour",
        cmap=FALSE_COLOUR_MAP,
        clim=list(clim),
        log_scale=scale == "log",
        lighting=False,
        show_scalar_bar=False,
        silhouette={"color": SILHOUETTE_COLOUR, "line_width": 2.0} if outline else False,
    )
    bar = None
    if title is not None:
        bar = plotter.add_scalar_bar(title=title, mapper=actor.mapper, **(scalar_bar or {}))
    return poly, actor, bar
