"""How the viewer turns the solved radiance into a picture: display settings and camera, changed without a solve.

:class:`Appearance` holds the display exposure, the two view-dependent layers (transmission toward the
camera, specular highlight; :mod:`translucency.app.viewer.view_layers` computes them), the false colour and
the camera position those layers are seen from. It checks every change, and maps a radiance per vertex,
W/(m² sr), to what is drawn: ``sRGB(exposure L)``, or one number per vertex in W/(m² sr) per W/m² of
irradiance with its range and colour bar title (:func:`translucency.app.display.false_colour_range`). A
:class:`~translucency.app.viewer.state.ViewerState` holds one; its attributes are the state's too.
"""

from __future__ import annotations

import numpy as np

from ...errors import InvalidParameterError
from ..display import (
    FALSE_COLOUR_QUANTITIES,
    FALSE_COLOUR_SCALES,
    display_colors,
    false_colour_label,
    false_colour_range,
    false_colour_values,
)


class Appearance:
    """The display settings of a viewer: exposure, view-dependent layers, false colour; and the camera position.

    Every ``set_*`` method checks its value (a sentence on a bad one) and returns whether the picture changed;
    none needs a new solve.

    Parameters
    ----------
    exposure : float, optional
        Display exposure (linear factor on ``L`` before sRGB); None until the first solve fixes it.
    view_dependent, specular : bool
        Show ``T21(eta, n . w_o) B`` instead of ``T21(eta, 1) B``; add the specular highlight.
    roughness : float
        GGX ``alpha`` of the highlight.
    """

    def __init__(self, exposure=None, view_dependent=False, specular=False, roughness=0.25):
        self.exposure = exposure
        self.view_dependent, self.specular, self.roughness = bool(view_dependent), bool(specular), float(roughness)
        #: False colour instead of sRGB (:meth:`set_false_colour`), its quantity and scale.
        self.false_colour, self.false_colour_quantity, self.false_colour_scale = False, "luminance", "log"
        #: Camera position (mm, scan coordinates) the view-dependent layers use; None: not known yet.
        self.eye = None

    def set_exposure(self, exposure) -> bool:
        """Display exposure (linear factor on ``L`` before sRGB): new colours from the same solution, no solve."""
        exposure = float(exposure)
        if not (np.isfinite(exposure) and exposure > 0):
            raise InvalidParameterError(f"exposure must be a positive number, got {exposure!r}.")
        changed = exposure != self.exposure
        self.exposure = exposure
        return changed

    def set_view_dependent(self, on: bool) -> bool:
        """Show ``T21(eta, n . w_o) B`` (on) or ``T21(eta, 1) B`` (off; docs/physics.md §5.3); no solve."""
        changed = bool(on) != self.view_dependent
        self.view_dependent = bool(on)
        return changed

    def set_specular(self, on: bool) -> bool:
        """Add (on) or remove the specular highlight (docs/physics.md §5.5); no solve."""
        changed = bool(on) != self.specular
        self.specular = bool(on)
        return changed

    def set_false_colour(self, on: bool, quantity: str | None = None) -> bool:
        """Show false colour (on) or sRGB (off); ``quantity`` is ``luminance`` (kept when None) or a channel
        name (``red``, ``green``, ``blue``). No solve."""
        quantity = self.false_colour_quantity if quantity is None else quantity
        if quantity not in FALSE_COLOUR_QUANTITIES:
            raise InvalidParameterError(
                f"the false colour shows one of {', '.join(FALSE_COLOUR_QUANTITIES)}, got {quantity!r}."
            )
        changed = (bool(on), quantity) != (self.false_colour, self.false_colour_quantity)
        self.false_colour, self.false_colour_quantity = bool(on), quantity
        return changed

    def set_false_colour_scale(self, scale: str) -> bool:
        """Scale of the false colour: ``log`` (:data:`~translucency.app.display.LOG_DECADES` decades) or
        ``linear``; no solve. Returns whether the picture changed (only when false colour is on)."""
        if scale not in FALSE_COLOUR_SCALES:
            raise InvalidParameterError(f"the false colour's scale is one of log, linear; got {scale!r}.")
        changed = scale != self.false_colour_scale
        self.false_colour_scale = scale
        return changed and self.false_colour

    def set_eye(self, eye) -> bool:
        """Camera position (3 floats, mm, scan coordinates) for the view-dependent layers; no solve.

        Returns True when a view-dependent layer is on and the position moved (the colours change).
        """
        eye = tuple(float(v) for v in eye)
        moved = eye != self.eye
        self.eye = eye
        return moved and (self.view_dependent or self.specular)

    @property
    def sees_the_camera(self) -> bool:
        """Whether what is shown depends on the camera: a view-dependent layer is on and the camera is known."""
        return (self.view_dependent or self.specular) and self.eye is not None

    def colors(self, radiance) -> np.ndarray:
        """Display colours per vertex, (n, 3) uint8: ``sRGB(exposure L)`` of ``radiance`` (W/(m² sr), (n, 3))."""
        colors, _ = display_colors(radiance, self.exposure)
        return colors

    def false_colour_values(self, radiance) -> np.ndarray:
        """The false colour's number per vertex, (n,), in W/(m² sr) per W/m²: the luminance (or the channel) of
        ``radiance``."""
        return false_colour_values(radiance, self.false_colour_quantity)

    def false_colour_range(self) -> tuple[float, float]:
        """``(low, high)`` of the false colour, W/(m² sr) per W/m²: ``high = 1 / exposure`` (white in sRGB)."""
        return false_colour_range(np.zeros(0), self.false_colour_scale, self.exposure)

    @property
    def false_colour_title(self) -> str:
        """Title of the false colour's colour bar: quantity, unit and scale."""
        return false_colour_label(self.false_colour_quantity, self.false_colour_scale)
