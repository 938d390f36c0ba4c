"""The interactive viewer: :mod:`.state` (what is shown, no PyVista) and :mod:`.widgets` (the PyVista window).

``from translucency.app.viewer import Viewer`` is the window; :class:`ViewerState` is the same viewer
without one.
"""

from .state import (
    INTERACTIVE_VERTICES,
    ViewerState,
    diffusive_materials,
    interactive_edge_length,
    light_angles,
    light_direction,
)
from .widgets import CONTROL_STRIP, EXPOSURE_STOPS, SCALE_RANGE, Viewer

__all__ = [
    "Viewer",
    "ViewerState",
    "light_direction",
    "light_angles",
    "interactive_edge_length",
    "diffusive_materials",
    "INTERACTIVE_VERTICES",
    "SCALE_RANGE",
    "EXPOSURE_STOPS",
    "CONTROL_STRIP",
]
