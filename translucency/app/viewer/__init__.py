"""The interactive viewer: :mod:`.state` (what is shown, no PyVista) and :mod:`.widgets` (the PyVista window).

``from translucency.app.viewer import Viewer`` is the window; :class:`ViewerState` is the same viewer
without one. The state holds its parts, one module each: the scan at its scale (:mod:`.scaled_scan`), the solve's
settings (:mod:`.solve_settings`), the lights (:mod:`.light_rig`) and the display settings (:mod:`.appearance`);
it draws on :mod:`.view_layers`, :mod:`.status` and :mod:`.saving`. The window's control strip is
:mod:`.controls`, with its light compass in :mod:`.compass`; :mod:`.layers` draws the scan for both windows.
"""

from .controls import CONTROL_STRIP, EXPOSURE_STOPS, SCALE_RANGE
from .light_rig import light_angles, light_direction
from .solve_settings import INTERACTIVE_VERTICES, interactive_edge_length
from .state import ViewerState, diffusive_materials
from .widgets import Viewer

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
