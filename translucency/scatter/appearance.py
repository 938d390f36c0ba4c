"""Materials as they look: a diffuse reflectance and a mean free path, turned into coefficients.

Renderers let people give a translucent material by its appearance rather than by its coefficients:
pbrt-v4 and appleseed take a diffuse reflectance and a mean free path and invert the reflectance to an
albedo; Blender's old renderer did the same by the secant method. Here a material is given per channel
by

* ``reflectance`` -- the total diffuse reflectance ``R_d`` of a thick flat slab, per unit flux that entered
  the medium: the colour it has under even light, away from edges and thin parts; in (0, 1);
* ``mean_free_path`` -- ``l = 1 / sigma_t'`` in mm: how far light goes between scattering events, i.e.
  how much the light blurs;
* ``eta`` and, optionally, ``g`` (the Henyey-Greenstein mean cosine, 0 by default).

The reflectance inverted is the better dipole's closed-form total ``R_d(alpha'; eta)`` (Hery's form,
docs/physics.md §6.2 and §6.4), whichever model then renders. It rises monotonically from 0 at
``alpha' = 0`` to 1 at ``alpha' = 1``, so every reflectance in (0, 1) has exactly one reduced albedo;
it is below the Monte Carlo totals of docs/physics.md §10.4 (all orders), the more the lower the albedo
(figures in docs/physics.md §6.4), so a given reflectance inverts to a slightly higher albedo than a
random walk would need where the material is dark. (The directional dipole's own total exceeds 1 at high
albedo, marble's for one, so it cannot serve as the thing to invert.) The root is found by Brent's method on ``[0, 1]``
(:func:`scipy.optimize.brentq`, to ``1e-15`` in ``alpha'``), then

    sigma_t' = 1 / l,   sigma_s' = alpha' sigma_t',   sigma_a = sigma_t' - sigma_s',   sigma_s = sigma_s' / (1 - g).

=============== ========================================================= =====
symbol          meaning                                                   unit
=============== ========================================================= =====
reflectance     total diffuse reflectance per unit flux that entered      1
mean_free_path  reduced mean free path ``1 / sigma_t'``                   mm
alpha'          reduced albedo ``sigma_s' / sigma_t'``                    1
=============== ========================================================= =====
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError
from .dipoles import better_dipole_total_reflectance
from .medium import CHANNELS, DEFAULT_ETA, Medium, check_eta

__all__ = ["ALBEDO_TOLERANCE", "reduced_albedo", "medium_from_appearance", "appearance_of"]

#: Absolute tolerance of the root finder on the reduced albedo (the round trip coefficients ->
#: appearance -> coefficients is then exact to about 1e-12 relative).
ALBEDO_TOLERANCE = 1e-15


def _per_channel(values, what: str) -> np.ndarray:
    """``values`` as a float64 vector per channel (a scalar for all three), or a sentence saying what is wrong."""
    try:
        array = np.atleast_1d(np.asarray(values, dtype=np.float64))
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{what} must be numbers, got {values!r}.") from None
    if array.ndim != 1 or array.size == 0:
        raise InvalidParameterError(f"{what} must be one number or one number per channel, got {values!r}.")
    return np.full(len(CHANNELS), array[0]) if array.size == 1 else array


def _channel_name(c: int, n: int) -> str:
    return CHANNELS[c] if n == len(CHANNELS) else f"channel {c}"


def reduced_albedo(reflectance, eta: float = DEFAULT_ETA) -> np.ndarray:
    """The reduced albedo ``alpha'`` per channel whose better-dipole total diffuse reflectance (docs/physics.md
    §6.4) is ``reflectance`` (in (0, 1), per unit flux that entered) at relative index ``eta``.

    Raises :class:`~translucency.errors.InvalidParameterError` with one sentence where no albedo gives
    that reflectance (0 or less, 1 or more, not finite).
    """
    from scipy.optimize import brentq

    reflectance = _per_channel(reflectance, "reflectance")
    for c, value in enumerate(reflectance):
        if not (np.isfinite(value) and 0.0 < value < 1.0):
            raise InvalidParameterError(
                f"reflectance {value:g} ({_channel_name(c, reflectance.size)}) is not between 0 and 1: a thick "
                "slab of any albedo reflects less than all and more than none of the light that enters; give a "
                "value strictly between 0 and 1."
            )
    check_eta(eta)
    eta = float(eta)
    return np.array(
        [
            brentq(
                lambda alpha, target=value: float(better_dipole_total_reflectance(alpha, eta)) - target,
                0.0,
                1.0,
                xtol=ALBEDO_TOLERANCE,
                rtol=4 * np.finfo(float).eps,
            )
            for value in reflectance
        ]
    )


def medium_from_appearance(
    reflectance, mean_free_path, eta: float = DEFAULT_ETA, g=0.0, name: str = "custom"
) -> Medium:
    """A :class:`~translucency.scatter.medium.Medium` from its look (module docstring): total diffuse
    reflectance per channel in (0, 1), reduced mean free path ``1 / sigma_t'`` per channel in mm, relative
    index ``eta`` and mean cosine ``g`` (default 0: ``sigma_s`` is then the reduced one)."""
    albedo = reduced_albedo(reflectance, eta)
    path = _per_channel(mean_free_path, "mean free path")
    if path.size != albedo.size:
        raise InvalidParameterError(
            f"reflectance and mean free path must have as many channels, got {albedo.size} and {path.size}."
        )
    for c, value in enumerate(path):
        if not (np.isfinite(value) and value > 0.0):
            raise InvalidParameterError(
                f"mean free path {value:g} mm ({_channel_name(c, path.size)}) must be a positive number of mm."
            )
    g = _per_channel(g, "g")
    sigma_t_reduced = 1.0 / path
    sigma_s_reduced = albedo * sigma_t_reduced
    sigma_a = sigma_t_reduced - sigma_s_reduced
    # g is validated by Medium; the division only needs it below 1 to be meaningful
    with np.errstate(divide="ignore", invalid="ignore"):
        sigma_s = sigma_s_reduced / (1.0 - g)
    return Medium(sigma_a, sigma_s, g, eta, name)


def appearance_of(medium: Medium) -> tuple[np.ndarray, np.ndarray]:
    """``(reflectance, mean free path in mm)`` per channel of a medium: the better dipole's total diffuse
    reflectance at its reduced albedo (docs/physics.md §6.4) and ``1 / sigma_t'``."""
    return np.asarray(better_dipole_total_reflectance(medium.alpha_reduced, medium.eta)), medium.mean_free_path
