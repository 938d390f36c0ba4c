"""Fresnel terms of a smooth dielectric boundary and the diffuse Fresnel moments.

All functions are float64, vectorised and broadcast over their arguments. ``eta`` is always the
relative index of refraction ``n_inside / n_outside`` of the medium the light enters
(docs/physics.md §1.2); an argument ``1 / eta`` describes light leaving the medium.

========== ======================================================================= ======
symbol     meaning                                                                 unit
========== ======================================================================= ======
eta        relative index of refraction n_inside / n_outside                       1
cos_i      cosine between the incident direction and the normal, incident side     1
F_r        unpolarised Fresnel reflectance                                         1
T          Fresnel transmittance 1 - F_r                                           1
w_i        unit vector toward the light (outside the medium)                       1
w12        refracted direction, pointing into the medium                           1
2C1, 3C2   first and second Fresnel moments (d'Eon & Irving 2011 fits), times 2, 3 1
C_phi      (1 - 2C1) / 4, fluence boundary coefficient                             1
C_E        (1 - 3C2) / 2, flux boundary coefficient                                1
A          (1 - C_E) / (2 C_phi), boundary reflection parameter                    1
F_dr       Egan-Hilgeman fit of the internal diffuse reflectance (Jensen 2001)     1
========== ======================================================================= ======
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "ETA_MAX",
    "fresnel_reflectance",
    "fresnel_transmittance",
    "refract",
    "two_C1",
    "three_C2",
    "C_phi",
    "C_E",
    "reflection_parameter_A",
    "F_dr_egan_hilgeman",
]

#: Largest relative index the diffusion models accept: the dEI11 moment fits (docs/physics.md §3.3) are
#: polynomials in ``eta`` fitted for the indices of real translucent materials, and the solver's
#: per-vertex tolerance is tested from ``eta = 1`` up to this value; beyond it the fits are extrapolated
#: (at ``eta = 10``, ``2C1`` is about 8400, not a reflectance).
ETA_MAX = 2.5


def fresnel_reflectance(cos_i, eta):
    """Unpolarised Fresnel reflectance of a smooth dielectric boundary (docs/physics.md §3.1).

    Parameters
    ----------
    cos_i : array_like
        Cosine between the incident direction and the normal on the incident side; clipped to
        [0, 1] (a grazing or back-facing direction reflects fully).
    eta : array_like
        Relative index ``n_transmitted / n_incident`` (use ``eta`` for light entering the
        medium, ``1 / eta`` for light leaving it).

    Returns
    -------
    ndarray
        ``F_r = (r_s^2 + r_p^2) / 2`` with ``r_s = (c - eta c_t) / (c + eta c_t)`` and
        ``r_p = (eta c - c_t) / (eta c + c_t)``; 1 under total internal reflection
        (``sin^2 theta_t >= 1``) and at grazing incidence.
    """
    c = np.clip(np.asarray(cos_i, dtype=np.float64), 0.0, 1.0)
    eta = np.asarray(eta, dtype=np.float64)
    sin2_t = (1.0 - c * c) / (eta * eta)  # Snell: sin^2 theta_t = sin^2 theta_i / eta^2
    total_internal = sin2_t >= 1.0
    c_t = np.sqrt(np.maximum(1.0 - sin2_t, 0.0))
    denom_s = c + eta * c_t
    denom_p = eta * c + c_t
    grazing = (denom_s <= 0.0) | (denom_p <= 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        r_s = (c - eta * c_t) / denom_s
        r_p = (eta * c - c_t) / denom_p
        reflectance = 0.5 * (r_s * r_s + r_p * r_p)
    return np.where(total_internal | grazing, 1.0, reflectance)


def fresnel_transmittance(cos_i, eta):
    """Fresnel transmittance ``T = 1 - F_r(cos_i, eta)`` (docs/physics.md §3.1, §5.1).

    ``T12 = fresnel_transmittance(n_i . w_i, eta)`` at entry and
    ``T21 = fresnel_transmittance(n_o . w_o, eta)`` at exit (both with the outside cosine).
    """
    return 1.0 - fresnel_reflectance(cos_i, eta)


def refract(w_i, n, eta):
    """Refracted direction ``w12`` of light arriving from outside (docs/physics.md §3.2).

    ``w12 = -e w_i + (e c - sqrt(1 - e^2 (1 - c^2))) n`` with ``c = n . w_i`` and ``e = 1 / eta``.

    Parameters
    ----------
    w_i : array_like, shape (..., 3)
        Unit vectors toward the light, on the outside (``n . w_i > 0``; a cosine below 0 is treated
        as 0, i.e. grazing).
    n : array_like, shape (..., 3)
        Outward unit normals.
    eta : array_like
        Relative index ``n_inside / n_outside`` (>= 1, so no total internal reflection at entry).

    Returns
    -------
    ndarray, shape (..., 3)
        Unit refracted directions, pointing into the medium.
    """
    w_i = np.asarray(w_i, dtype=np.float64)
    n = np.asarray(n, dtype=np.float64)
    e = 1.0 / np.asarray(eta, dtype=np.float64)[..., None]
    c = np.clip(np.sum(n * w_i, axis=-1, keepdims=True), 0.0, 1.0)
    root = np.sqrt(np.maximum(1.0 - e * e * (1.0 - c * c), 0.0))
    return -e * w_i + (e * c - root) * n


def two_C1(eta):
    """Twice the first Fresnel moment, ``2 C1(eta)`` (d'Eon & Irving 2011 fit; docs/physics.md §3.3).

    ``2 C1(eta)`` is the cosine-weighted diffuse reflectance, total internal reflection included, of
    light inside a medium of relative index ``eta`` hitting its boundary; ``2 C1(1 / eta)`` is the
    diffuse reflectance for light arriving from outside. Both branches (eta < 1 and eta >= 1).
    """
    eta = np.asarray(eta, dtype=np.float64)
    low = 0.919317 + eta * (-3.4793 + eta * (6.75335 + eta * (-7.80989 + eta * (4.98554 - 1.36881 * eta))))
    high = -9.23372 + eta * (22.2272 + eta * (-20.9292 + eta * (10.2291 + eta * (-2.54396 + 0.254913 * eta))))
    return np.where(eta < 1.0, low, high)


def three_C2(eta):
    """Three times the second Fresnel moment, ``3 C2(eta)`` (d'Eon & Irving 2011 fit; docs/physics.md §3.3)."""
    eta = np.asarray(eta, dtype=np.float64)
    low = 0.828421 + eta * (-2.62051 + eta * (3.36231 + eta * (-1.95284 + eta * (0.236494 + 0.145787 * eta))))
    inv = 1.0 / eta
    high = (
        -1641.1
        + inv * (1376.53 + inv * (-656.175 + inv * 135.926))
        + eta * (1213.67 + eta * (-568.556 + eta * (164.798 + eta * (-27.0181 + 1.91826 * eta))))
    )
    return np.where(eta < 1.0, low, high)


def C_phi(eta):
    """Fluence boundary coefficient ``C_phi(eta) = (1 - 2 C1(eta)) / 4`` (docs/physics.md §2.1, §3.3)."""
    return 0.25 * (1.0 - two_C1(eta))


def C_E(eta):
    """Flux boundary coefficient ``C_E(eta) = (1 - 3 C2(eta)) / 2`` (docs/physics.md §2.1, §3.3)."""
    return 0.5 * (1.0 - three_C2(eta))


def reflection_parameter_A(eta):
    """Boundary reflection parameter ``A = (1 - C_E(eta)) / (2 C_phi(eta))`` (docs/physics.md §2.1).

    Equal to ``(1 + 3 C2) / (1 - 2 C1)``; used by the directional and the better dipole.
    """
    return (1.0 - C_E(eta)) / (2.0 * C_phi(eta))


def F_dr_egan_hilgeman(eta):
    """Internal diffuse Fresnel reflectance, Egan-Hilgeman fit used by Jensen 2001 (docs/physics.md §3.4).

    ``F_dr = -1.440 / eta^2 + 0.710 / eta + 0.668 + 0.0636 eta``.
    """
    eta = np.asarray(eta, dtype=np.float64)
    return -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta
