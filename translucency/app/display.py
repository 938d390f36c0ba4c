"""The display transform: linear radiance to what a screen shows, and the luminance of linear RGB.

Everything in the library is linear radiance; only pictures and the display colours of a bake go
through :func:`display_colors` (exposure, then the sRGB transfer function, then 8 bits).

========== ================================================================ ======================
symbol     meaning                                                          unit
========== ================================================================ ======================
L          linear radiance per channel                                      W/(m^2 sr) per W/m^2
exposure   linear factor applied before the transfer function               1 / (unit of L)
Y          luminance of linear RGB, Rec. 709 / sRGB primaries               unit of L
========== ================================================================ ======================

False colour (:func:`false_colour_values`, :func:`false_colour_range`): one number per vertex in the
unit of ``L`` -- the luminance ``Y`` or one channel -- mapped through a colour map on a linear or a
log scale, next to the sRGB view, so that a picture can be read in physical units. The top of the
range is the radiance the sRGB view shows as white (``1 / exposure``), so both views share one
brightness scale; a log scale spans :data:`LOG_DECADES` decades below it.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "REC709_LUMINANCE",
    "RADIANCE_UNIT",
    "FALSE_COLOUR_QUANTITIES",
    "FALSE_COLOUR_SCALES",
    "FALSE_COLOUR_MAP",
    "LOG_DECADES",
    "srgb_encode",
    "srgb_decode",
    "display_colors",
    "luminance",
    "false_colour_values",
    "false_colour_range",
    "false_colour_label",
]

#: Weights of linear R, G, B in the luminance Y (ITU-R BT.709, the primaries sRGB shares).
REC709_LUMINANCE = (0.2126, 0.7152, 0.0722)
#: Unit of the radiance the library computes (per W/m² of irradiance on a surface facing the light), as
#: pictures print it: the typeset form of :data:`translucency.io.units.RADIANCE_UNIT`, which files record.
RADIANCE_UNIT = "W/(m² sr) per W/m²"
#: What a false-colour view shows: the luminance Y, or one linear channel.
FALSE_COLOUR_QUANTITIES = ("luminance", "red", "green", "blue")
#: How values map to colours: ``log`` (decades; a shadow next to a bright edge stays readable) or ``linear``.
FALSE_COLOUR_SCALES = ("log", "linear")
#: Colour map of the false-colour views (matplotlib's name; perceptually uniform, dark to bright).
FALSE_COLOUR_MAP = "inferno"
#: Decades a log-scale false-colour view spans below the top of its range.
LOG_DECADES = 3.0


def srgb_encode(linear):
    """sRGB transfer function (IEC 61966-2-1) of linear values clipped to [0, 1]."""
    c = np.clip(np.asarray(linear, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


def srgb_decode(encoded):
    """Inverse of :func:`srgb_encode` (IEC 61966-2-1): sRGB-encoded values in [0, 1] to linear ones.

    ``srgb_decode(colors / 255)`` is the linear light a display shows for 8-bit sRGB colours (what
    glTF's linear vertex colours need).
    """
    c = np.clip(np.asarray(encoded, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, np.power((c + 0.055) / 1.055, 2.4))


def display_colors(radiance, exposure: float | None = None):
    """Linear RGB radiance to 8-bit sRGB colours: ``srgb(exposure * L)``.

    With ``exposure=None`` the exposure maps the 99.5th percentile of the brightest channel to 0.9.

    Returns
    -------
    colors : (n, 3) uint8
    exposure : float
    """
    radiance = np.asarray(radiance, dtype=np.float64)
    if exposure is None:
        level = float(np.percentile(radiance.max(axis=1), 99.5)) if radiance.size else 0.0
        exposure = 0.9 / level if level > 0 else 1.0
    colors = np.round(srgb_encode(radiance * exposure) * 255.0).astype(np.uint8)
    return colors, float(exposure)


def luminance(radiance) -> np.ndarray:
    """Luminance ``Y = 0.2126 R + 0.7152 G + 0.0722 B`` of linear RGB ``(..., 3)`` (Rec. 709), in the
    unit of the radiance; the last axis is summed away."""
    radiance = np.asarray(radiance, dtype=np.float64)
    return radiance @ np.asarray(REC709_LUMINANCE)


def _check_choice(value, choices, what: str) -> str:
    from ..errors import InvalidParameterError

    if value not in choices:
        raise InvalidParameterError(f"the false colour's {what} must be one of {', '.join(choices)}, got {value!r}.")
    return value


def false_colour_values(radiance, quantity: str = "luminance") -> np.ndarray:
    """The number per vertex a false-colour view shows, in the unit of the radiance, (n,) float64.

    Parameters
    ----------
    radiance : (n, 3) array_like
        Linear RGB radiance, W/(m² sr) per W/m² of irradiance.
    quantity : {"luminance", "red", "green", "blue"}
        The luminance ``Y`` (:func:`luminance`) or one channel.
    """
    _check_choice(quantity, FALSE_COLOUR_QUANTITIES, "quantity")
    radiance = np.asarray(radiance, dtype=np.float64)
    if quantity == "luminance":
        return luminance(radiance)
    return radiance[:, FALSE_COLOUR_QUANTITIES.index(quantity) - 1].copy()


def false_colour_range(values, scale: str = "log", exposure: float | None = None) -> tuple[float, float]:
    """Limits ``(low, high)`` of a false-colour view, in the unit of the values.

    ``high`` is ``1 / exposure`` (what the sRGB view at that exposure shows as white) or, with no exposure,
    the 99.5th percentile of the values over 0.9 (the automatic exposure's rule, :func:`display_colors`);
    ``low`` is 0 on a linear scale and ``high`` over ``10 ** LOG_DECADES`` on a log scale (darker values
    take the lowest colour).
    """
    _check_choice(scale, FALSE_COLOUR_SCALES, "scale")
    values = np.asarray(values, dtype=np.float64)
    if exposure is not None:
        high = 1.0 / float(exposure)
    else:
        level = float(np.percentile(values, 99.5)) if values.size else 0.0
        high = level / 0.9 if level > 0 else 1.0
    return (high * 10.0**-LOG_DECADES if scale == "log" else 0.0), high


def false_colour_label(quantity: str = "luminance", scale: str = "log") -> str:
    """Title of a false-colour view's colour bar: the quantity, its unit and the scale."""
    _check_choice(quantity, FALSE_COLOUR_QUANTITIES, "quantity")
    _check_choice(scale, FALSE_COLOUR_SCALES, "scale")
    what = "luminance Y" if quantity == "luminance" else f"{quantity} radiance"
    return f"{what}, {RADIANCE_UNIT} ({scale} scale)"
