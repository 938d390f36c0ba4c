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
"""

from __future__ import annotations

import numpy as np

__all__ = ["REC709_LUMINANCE", "srgb_encode", "srgb_decode", "display_colors", "luminance"]

#: Weights of linear R, G, B in the luminance Y (ITU-R BT.709, the primaries sRGB shares).
REC709_LUMINANCE = (0.2126, 0.7152, 0.0722)


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
