"""What the format readers share: colours as 8-bit RGB, and an exception's text inside a sentence."""

from __future__ import annotations

import numpy as np

__all__ = ["as_rgb8", "short_reason"]


def as_rgb8(colors: np.ndarray) -> np.ndarray:
    """Colours as uint8; float colours in [0, 1] are scaled by 255."""
    if colors.dtype == np.uint8:
        return colors
    colors = colors.astype(np.float64)
    if colors.size and np.nanmax(colors) <= 1.0:
        colors = colors * 255.0
    return np.clip(np.round(np.nan_to_num(colors)), 0, 255).astype(np.uint8)


def short_reason(exc: BaseException) -> str:
    """First line of an exception's message, shortened, for inclusion in a sentence."""
    text = " ".join(str(exc).split())
    return (text[:117] + "...") if len(text) > 120 else (text or type(exc).__name__)
