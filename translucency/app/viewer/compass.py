"""The light compass of the viewer's control strip: a small copy of the scan and the key light's arrow, seen from
where the scan's camera looks, so that the light's direction reads at a glance whatever the view."""

from __future__ import annotations

import numpy as np

from ..render import LIGHT_GLYPH_COLOR, light_glyph


class LightCompass:
    """The scan, scaled to a unit radius about its centre, and an arrow from the key light toward it, drawn in
    ``plotter``'s current renderer.

    Parameters
    ----------
    plotter : pyvista.Plotter
        Its current renderer becomes the compass's.
    mesh : TriangleMesh
        The scan (mm; only its shape matters).
    direction : sequence of 3 float
        Toward the key light, in the scan's coordinates.

    Attributes
    ----------
    arrow : pyvista.PolyData
        The arrow, from the key light toward the object; :meth:`point` changes it in place.
    """

    #: Radius the scan is scaled to, and the arrow's length scale.
    RADIUS = 1.0

    def __init__(self, plotter, mesh, direction):
        from ...io.polydata import to_pyvista

        self.renderer = plotter.renderer
        points = mesh.points - 0.5 * (mesh.points.min(axis=0) + mesh.points.max(axis=0))
        small = mesh.replace(points=points / (0.5 * float(mesh.extent)))
        plotter.add_mesh(to_pyvista(small), color="lightgrey", name="compass_scan")
        self.arrow = light_glyph((0.0, 0.0, 0.0), self.RADIUS, direction)
        plotter.add_mesh(self.arrow, color=LIGHT_GLYPH_COLOR, name="compass_arrow")
        plotter.add_text("light", position="upper_left", font_size=8, color="white", name="compass_label")

    def point(self, direction) -> None:
        """The arrow toward the key light's new ``direction`` (scan coordinates; no render)."""
        self.arrow.copy_from(light_glyph((0.0, 0.0, 0.0), self.RADIUS, direction))

    def turn(self, camera) -> None:
        """The compass's camera looks from where ``camera`` (the scan's) looks: same direction and view-up."""
        compass = self.renderer.camera
        offset = np.asarray(camera.GetPosition()) - np.asarray(camera.GetFocalPoint())
        offset = offset / np.linalg.norm(offset)
        compass.SetFocalPoint(0.0, 0.0, 0.0)
        compass.SetPosition(*(offset * 6.0 * self.RADIUS))
        compass.SetViewUp(*camera.GetViewUp())
        compass.SetParallelProjection(True)
        compass.SetParallelScale(1.7 * self.RADIUS)
        self.renderer.ResetCameraClippingRange()
        self.renderer.camera_set = True  # PyVista must not reset it on the first render
