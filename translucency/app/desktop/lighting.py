"""The desktop viewer's light: the panel's choice as lights, and the handle that drags it in the view.

The handle is a yellow ball on a sphere around the scan's centre (VTK's ``vtkSphereWidget``, its sphere hidden
and fixed: only the ball moves, over the sphere). Where the ball is, seen from the centre, is where the light
is: a directional light from that direction, or a point light that far along it. The ball is drawn in a
layer over the scan, with the scan's camera, so that it can be grabbed even when the light is behind the
scan; the sphere fits in the view (:func:`handle_radius`).
"""

from __future__ import annotations

import math

import numpy as np

from ...scatter.lights import DirectionalLight, EnvironmentLight, PointLight
from ..viewer.state import light_angles, light_direction

#: Irradiance of the panel's directional light, W/m² (the solver's default light).
IRRADIANCE = 1.0
#: Sample directions of the panel's environment light.
ENVIRONMENT_DIRECTIONS = 256
#: Radius of the handle's sphere, as a fraction of the half height (or half width) the view shows at the centre.
HANDLE_RADIUS = 0.85
#: Colour of the handle (the light).
HANDLE_COLOUR = (1.0, 0.85, 0.1)


def panel_lights(kind: str, azimuth: float, elevation: float, distance: float, up, centre, radius: float):
    """The light the panel describes, in the scan's coordinates.

    ``directional``: 1 W/m² (:data:`IRRADIANCE`) from ``azimuth``, ``elevation`` (degrees around ``up``,
    :func:`~translucency.app.viewer.state.light_direction`). ``point``: at ``distance`` radii (``radius``, mm)
    from ``centre`` in that direction, with the intensity that gives 1 W/m² at the centre,
    ``I = E d²`` (W/sr, ``d`` in m). ``environment``: a constant white sky of radiance ``1/pi`` W/(m² sr), so
    that an unoccluded surface facing any way receives 1 W/m², ``E = pi L``.
    """
    if kind == "environment":
        return EnvironmentLight(radiance_rgb=IRRADIANCE / math.pi, n_directions=ENVIRONMENT_DIRECTIONS)
    direction = light_direction(azimuth, elevation, up)
    if kind == "point":
        reach = float(distance) * float(radius)
        return PointLight(np.asarray(centre, dtype=np.float64) + reach * direction, IRRADIANCE * (reach / 1000.0) ** 2)
    return DirectionalLight(direction, IRRADIANCE)


def handle_radius(camera, centre, aspect: float) -> float:
    """Radius (mm) of the handle's sphere: :data:`HANDLE_RADIUS` of the half height (or, in a tall view, the
    half width) that ``camera`` (a vtkCamera, perspective) shows at the distance of ``centre``."""
    distance = float(np.linalg.norm(np.asarray(camera.GetPosition()) - np.asarray(centre, dtype=np.float64)))
    half_height = distance * math.tan(math.radians(0.5 * camera.GetViewAngle()))
    return HANDLE_RADIUS * half_height * min(1.0, float(aspect))


class LightHandle:
    """A ball the user drags over a sphere around the scan; ``on_move(azimuth, elevation)`` as it moves
    and ``on_release(azimuth, elevation)`` when it is let go (degrees around ``up``).

    Parameters
    ----------
    interactor : vtkRenderWindowInteractor
        The view's interactor.
    renderer : vtkRenderer
        The scan's renderer.
    centre : sequence of 3 float
        The scan's centre, mm.
    radius : float
        Radius of the sphere the ball moves on, mm (:func:`handle_radius`).
    up : sequence of 3 float
        The scan's up axis.
    """

    def __init__(self, interactor, renderer, centre, radius, up, on_move, on_release):
        import vtk

        self.up = np.asarray(up, dtype=np.float64)
        self.on_move, self.on_release = on_move, on_release
        window = renderer.GetRenderWindow()
        overlay = vtk.vtkRenderer()  # drawn over the scan's layer, with its camera
        overlay.SetLayer(1)
        overlay.SetActiveCamera(renderer.GetActiveCamera())
        overlay.SetViewport(renderer.GetViewport())
        window.SetNumberOfLayers(max(2, window.GetNumberOfLayers()))
        window.AddRenderer(overlay)
        self.overlay, self.window = overlay, window
        renderer = overlay
        widget = vtk.vtkSphereWidget()
        widget.SetInteractor(interactor)
        widget.SetCurrentRenderer(renderer)
        widget.SetRepresentationToOff()  # the sphere itself is neither drawn nor picked: only the ball
        widget.TranslationOff()
        widget.ScaleOff()
        widget.HandleVisibilityOn()
        widget.SetPlaceFactor(1.0)
        self._cube = [v for c in centre for v in (float(c) - float(radius), float(c) + float(radius))]
        widget.GetHandleProperty().SetColor(*HANDLE_COLOUR)
        widget.GetHandleProperty().SetAmbient(1.0)
        widget.GetSelectedHandleProperty().SetColor(1.0, 1.0, 0.6)
        widget.AddObserver("InteractionEvent", lambda *_: self.on_move(*self.angles()))
        widget.AddObserver("EndInteractionEvent", lambda *_: self.on_release(*self.angles()))
        self.widget = widget
        widget.PlaceWidget(self._cube)
        widget.On()

    @classmethod
    def in_view(cls, view, centre, up, on_move, on_release) -> LightHandle:
        """A handle in a PyVista plotter ``view`` (a pyvistaqt ``QtInteractor``), on the sphere of
        :func:`handle_radius` for its current camera."""
        size = view.interactor.size()
        radius = handle_radius(view.camera, centre, size.width() / max(size.height(), 1))
        return cls(view.iren.interactor, view.renderer, centre, radius, up, on_move, on_release)

    def angles(self) -> tuple[float, float]:
        """The ball's azimuth and elevation, degrees around ``up``."""
        return light_angles(np.asarray(self.widget.GetHandleDirection(), dtype=np.float64), self.up)

    def place(self, azimuth: float, elevation: float) -> None:
        """Put the ball at ``azimuth``, ``elevation`` (degrees), without calling back."""
        self.widget.SetHandleDirection(*(float(v) for v in light_direction(azimuth, elevation, self.up)))
        self.widget.PlaceWidget(self._cube)  # where the ball is drawn follows the direction only when placed

    def set_visible(self, on: bool) -> None:
        """Show the ball (a directional or point light) or hide it (an environment)."""
        self.widget.SetEnabled(int(bool(on)))

    def close(self) -> None:
        """Take the ball out of the view."""
        self.widget.Off()
        self.widget.SetInteractor(None)
        self.window.RemoveRenderer(self.overlay)
