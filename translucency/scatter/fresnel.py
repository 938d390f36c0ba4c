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

import math

import numba
import numpy as np

__all__ = [
    "ETA_MAX",
    "fresnel_reflectance",
    "fresnel_reflectance_scalar",
    "fresnel_transmittance",
    "refract",
    "refracted",
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
        (``sin^2 theta_t >= 1``) and at grazing incidence (:func:`fresnel_reflectance_scalar` at each element).
    """
    c, e = _flat_broadcast(np.asarray(cos_i, dtype=np.float64), np.asarray(eta, dtype=np.float64))
    out = np.empty(c.shape)
    _reflectances(c.reshape(-1), e.reshape(-1), out.reshape(-1))
    return out


def _flat_broadcast(*arrays):
    """``arrays`` broadcast to one shape, each C-contiguous (copied only where it is broadcast or strided)."""
    shape = np.broadcast_shapes(*(a.shape for a in arrays))
    return tuple(_contiguous(a, shape) for a in arrays)


def _contiguous(a: np.ndarray, shape: tuple) -> np.ndarray:
    """``a`` broadcast to ``shape``, C-contiguous (copied only where it is broadcast or strided)."""
    return np.asarray(a if a.shape == tuple(shape) else np.broadcast_to(a, shape), order="C")


@numba.njit(cache=True)
def fresnel_reflectance_scalar(cos_i, eta):
    """:func:`fresnel_reflectance` of one cosine and one ``eta`` (floats), for compiled loops."""
    c = min(max(cos_i, 0.0), 1.0)
    sin2_t = (1.0 - c * c) / (eta * eta)  # Snell: sin^2 theta_t = sin^2 theta_i / eta^2
    if sin2_t >= 1.0:
        return 1.0  # total internal reflection
    c_t = math.sqrt(1.0 - sin2_t)
    denom_s = c + eta * c_t
    denom_p = eta * c + c_t
    if denom_s <= 0.0 or denom_p <= 0.0:
        return 1.0  # grazing
    r_s = (c - eta * c_t) / denom_s
    r_p = (eta * c - c_t) / denom_p
    return 0.5 * (r_s * r_s + r_p * r_p)


@numba.njit(cache=True, nogil=True)
def _reflectances(c, eta, out):
    """:func:`fresnel_reflectance_scalar` of each pair of ``c`` and ``eta`` (flat, same length) into ``out``."""
    for k in range(c.shape[0]):
        out[k] = fresnel_reflectance_scalar(c[k], eta[k])


def fresnel_transmittance(cos_i, eta):
    """Fresnel transmittance ``T = 1 - F_r(cos_i, eta)`` (docs/physics.md §3.1, §5.1).

    ``T12 = fresnel_transmittance(n_i . w_i, eta)`` at entry and
    ``T21 = fresnel_transmittance(n_o . w_o, eta)`` at exit (both with the outside cosine).
    """
    return 1.0 - fresnel_reflectance(cos_i, eta)


def refract(w_i, n, eta):
    """Refracted direction ``w12`` of light arriving from outside (docs/physics.md §3.2).

    ``w12 = -e w_i + (e c - sqrt(1 - e^2 (1 - c^2))) n`` with ``c = n . w_i`` and ``e = 1 / eta``
    (:func:`refracted` at each row).

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
    eta = np.asarray(eta, dtype=np.float64)
    rows = np.broadcast_shapes(w_i.shape[:-1], n.shape[:-1], eta.shape)  # eta one number a row, not three
    w_i, n, eta = _contiguous(w_i, (*rows, 3)), _contiguous(n, (*rows, 3)), _contiguous(eta, rows)
    out = np.empty(w_i.shape)
    _refracted_rows(w_i.reshape(-1, 3), n.reshape(-1, 3), eta.reshape(-1), out.reshape(-1, 3))
    return out


@numba.njit(cache=True, inline="always")
def refracted(w0, w1, w2, n0, n1, n2, eta):
    """:func:`refract` of one direction ``w`` toward the light and one outward unit normal ``n``: ``w12``'s three
    components."""
    e = 1.0 / eta
    c = min(max(n0 * w0 + n1 * w1 + n2 * w2, 0.0), 1.0)
    k = e * c - math.sqrt(max(1.0 - e * e * (1.0 - c * c), 0.0))
    return -e * w0 + k * n0, -e * w1 + k * n1, -e * w2 + k * n2


@numba.njit(cache=True, nogil=True)
def _refracted_rows(w, n, eta, out):
    """:func:`refracted` of each row of ``w`` and ``n`` (and element of ``eta``) into the rows of ``out``."""
    for k in range(w.shape[0]):
        out[k, 0], out[k, 1], out[k, 2] = refracted(w[k, 0], w[k, 1], w[k, 2], n[k, 0], n[k, 1], n[k, 2], eta[k])


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


#: The compiled kernels of the Fresnel terms over arrays: numba compiles each on first use; the set-up compiles them
#: ahead (:mod:`translucency.app.warmup`).
FRESNEL_KERNELS = (fresnel_reflectance_scalar, _reflectances, _refracted_rows)
