"""What the format readers share: colours as 8-bit RGB, and an exception's text inside a sentence."""

from __future__ import annotations

import numpy as np

from ...errors import warn_user

__all__ = ["as_rgb8", "set_colors", "short_reason"]

#: Float colours are read on the 0-255 scale when more than this fraction of their values exceeds 1, else on
#: the 0-1 scale (values above 1 then clip to white): a few outliers do not turn a 0-1 scan black.
SCALE_255_FRACTION = 0.01


def as_rgb8(colors: np.ndarray) -> np.ndarray:
    """Finite colours as uint8: integers clipped to 0-255, floats on the 0-1 or the 0-255 scale by
    :data:`SCALE_255_FRACTION`."""
    if colors.dtype == np.uint8:
        return colors
    values = colors.astype(np.float64)
    if colors.dtype.kind == "f" and values.size and np.mean(values > 1.0) <= SCALE_255_FRACTION:
        values = values * 255.0
    return np.clip(np.round(values), 0, 255).astype(np.uint8)


def set_colors(point_data: dict, colors, name: str) -> None:
    """Put a scan's vertex colours into ``point_data["colors"]`` as 8-bit RGB(A) (:func:`as_rgb8`), or leave them
    out with a warning naming ``name`` when any is NaN or infinite: a colour that is not a number says nothing of
    the surface, and reading it as black would darken an albedo taken from the colours in silence."""
    colors = np.asarray(colors)
    if colors.dtype.kind == "f":
        bad = int(np.count_nonzero(~np.all(np.isfinite(colors), axis=1)))
        if bad:
            warn_user(
                f"{name}: {bad} of {len(colors)} vertex colours are NaN or infinite; the scan's colours are left "
                "out (an albedo from the colours has none to take); export the colours again."
            )
            return
    point_data["colors"] = as_rgb8(colors)


def short_reason(exc: BaseException) -> str:
    """First line of an exception's message, shortened, for inclusion in a sentence."""
    text = " ".join(str(exc).split())
    return (text[:117] + "...") if len(text) > 120 else (text or type(exc).__name__)
