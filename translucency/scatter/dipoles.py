"""Reference (float64, vectorised numpy) formulas of the three diffusion models.

* :func:`directional_dipole` -- the directional dipole BSSRDF ``S_d`` of Frisvad, Hachisuka &
  Kjeldsen 2014 (FHK14), exactly as in docs/physics.md §4;
* :func:`standard_dipole_profile` -- the radial profile ``R_d(r)`` of Jensen et al. 2001 (docs/physics.md §6.1);
* :func:`better_dipole_profile` -- the radial profile ``R(r)`` of d'Eon 2012 (docs/physics.md §6.2);
* closed-form (standard, better) and quadrature (directional) total diffuse reflectances.

These functions are the truth every fast kernel is tested against; they favour clarity and float64
robustness over speed. Every array argument broadcasts over leading axes: vectors are ``(..., 3)``,
coefficients are scalars or ``(...)`` arrays.

========= ================================================================== ============
symbol    meaning                                                            unit
========= ================================================================== ============
x_i, n_i  point of incidence and its outward unit normal                     mm, 1
x_o, n_o  point of emergence and its outward unit normal                     mm, 1
w12       refracted incident direction (into the medium)                     1
x, r      x_o - x_i and its length                                           mm
n_i*      modified tangent-plane normal (n_i without its component along x)  1
x_v, w_v  virtual source position and direction                              mm, 1
mu0       -n_o . w12, cosine of the refracted ray at the exit point          1
d_r, d_v  corrected real-source distance, virtual-source distance            mm
S_d       diffusive BSSRDF (norm included, no Fresnel T12/T21)               1/(mm^2 sr)
R_d, R    radial exitance profiles per unit flux                             1/mm^2
========= ================================================================== ============

Numerical conventions (docs/physics.md §4.6): when ``r`` is ~0 or ``n_i`` is parallel to ``x``
the modified tangent plane is undefined and ``n_i* = n_i`` is used; ``mu0 > 0`` is frontlit and
``mu0 <= 0`` backlit; the result is clamped at 0 after subtracting the virtual source; exponentials
that underflow give 0, never NaN; ``d_r`` and ``d_v`` are floored at ``D_R_FLOOR * D`` (the only other
clamp).
"""

from __future__ import annotations

import numpy as np

from . import fresnel
from .medium import (
    alpha_reduced,
    diffusion_coefficient,
    extrapolation_distance,
    sigma_t,
    sigma_t_reduced,
    sigma_tr,
    validate_coefficients,
)

__all__ = [
    "directional_dipole",
    "directional_dipole_profile",
    "standard_dipole_profile",
    "better_dipole_profile",
    "standard_dipole_total_reflectance",
    "better_dipole_total_reflectance",
    "directional_dipole_total_reflectance",
]

#: ``r = 0`` or ``|n_i - (n_i . x_hat) x_hat|`` below this counts as degenerate: the modified tangent
#: plane falls back to ``n_i* = n_i`` (docs/physics.md §4.6).
PARALLEL_TOLERANCE = 1e-12

#: Lower bound of the corrected real-source distance, as a fraction of D. ``d_r`` reaches 0 only when
#: the exit point coincides with the entry point *and* the refracted ray grazes the exit surface
#: (``mu0 -> 0+``, possible at eta = 1 or on curved geometry), where the model is singular; the floor
#: keeps the value finite and never changes it elsewhere (``d_r >= D mu0`` at r = 0).
#: The virtual-source distance ``d_v`` has the same floor: with the fallback ``n_i* = n_i`` (exit point
#: on the outward normal of the entry point) the virtual source lies on the line of ``x`` and ``d_v``
#: is 0 at ``x = 2 A d_e n_i``, where the model is singular too; elsewhere ``d_v >= 2 A d_e > 4 D``.
D_R_FLOOR = 1e-9


def _dot(a, b):
    return np.sum(a * b, axis=-1)


def _ray_source_term(x, w, d, n_o, D, sigma_tr_, C_phi, C_E, norm):
    """One ray source of the directional dipole, ``S'_d(x, w, d)`` (docs/physics.md §4.4), 1/(mm^2 sr).

    ``norm exp(-s) / (4 pi^2 d^3) [C_phi (d^2/D + 3 (1+s) x.w)
    - C_E (3 D (1+s) w.n_o - ((1+s) + 3 D (3 (1+s) + s^2) x.w / d^2) x.n_o)]`` with ``s = sigma_tr d``.
    """
    s = sigma_tr_ * d
    x_dot_w = _dot(x, w)
    x_dot_n = _dot(x, n_o)
    w_dot_n = _dot(w, n_o)
    one_plus_s = 1.0 + s
    fluence = C_phi * (d * d / D + 3.0 * one_plus_s * x_dot_w)
    flux = C_E * (
        3.0 * D * one_plus_s * w_dot_n
        - (one_plus_s + 3.0 * D * (3.0 * one_plus_s + s * s) * x_dot_w / (d * d)) * x_dot_n
    )
    return norm * np.exp(-s) / (4.0 * np.pi**2 * d**3) * (fluence - flux)


def directional_dipole(x_i, n_i, w12, x_o, n_o, sigma_a, sigma_s, g, eta):
    """Directional dipole diffusive BSSRDF ``S_d(x_i, w12; x_o)`` of FHK14 (docs/physics.md §4.1-§4.5).

    Parameters
    ----------
    x_i, n_i : array_like, shape (..., 3)
        Point of incidence (mm) and its outward unit normal.
    w12 : array_like, shape (..., 3)
        Refracted direction of the incident light (unit, into the medium); see
        :func:`translucency.scatter.fresnel.refract`.
    x_o, n_o : array_like, shape (..., 3)
        Point of emergence (mm) and its outward unit normal.
    sigma_a, sigma_s : array_like
        Absorption and (unreduced) scattering coefficients, 1/mm.
    g : array_like
        Henyey-Greenstein mean cosine; ``sigma_s' = sigma_s (1 - g)``.
    eta : array_like
        Relative index ``n_inside / n_outside`` (>= 1).

    Returns
    -------
    ndarray
        ``S_d = max(0, S'_d(x_o - x_i, w12, d_r) - S'_d(x_o - x_v, w_v, d_v))`` in 1/(mm^2 sr),
        with the normalisation ``1 / (4 C_phi(1/eta))`` included and without the Fresnel
        transmittances T12, T21. The full BSSRDF is ``T12 * S_d * T21``.

    Raises
    ------
    InvalidParameterError
        For coefficients outside their valid range (see
        :func:`translucency.scatter.medium.validate_coefficients`).
    """
    sigma_a, sigma_s, g, eta = validate_coefficients(sigma_a, sigma_s, g, eta, what="directional_dipole")
    x_i, n_i, w12, x_o, n_o = (np.asarray(v, dtype=np.float64) for v in (x_i, n_i, w12, x_o, n_o))

    D = diffusion_coefficient(sigma_a, sigma_s, g)  # docs/physics.md §2.1: D = 1/(3 sigma_t')
    sigma_tr_ = sigma_tr(sigma_a, sigma_s, g)  # sqrt(sigma_a / D)
    d_e = extrapolation_distance(sigma_a, sigma_s, g)  # 2.131 D / sqrt(alpha')
    C_phi = fresnel.C_phi(eta)
    C_E = fresnel.C_E(eta)
    A = (1.0 - C_E) / (2.0 * C_phi)  # docs/physics.md §2.1
    norm = 1.0 / (4.0 * fresnel.C_phi(1.0 / eta))  # docs/physics.md §2.1, §5.2
    backlit_depth = 1.0 / (3.0 * sigma_t(sigma_a, sigma_s))  # docs/physics.md §4.3: unreduced sigma_t

    x = x_o - x_i
    r2 = _dot(x, x)
    r = np.sqrt(r2)

    # Modified tangent-plane normal n_i* = normalize(n_i - (n_i . x_hat) x_hat)   (docs/physics.md §4.1)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_hat = x / r[..., None]
        tangent = n_i - _dot(n_i, x_hat)[..., None] * x_hat
        tangent_norm = np.sqrt(_dot(tangent, tangent))
        n_star = tangent / tangent_norm[..., None]
    degenerate = ~(r > 0.0) | ~(tangent_norm > PARALLEL_TOLERANCE)
    n_star = np.where(degenerate[..., None], n_i, n_star)

    # Virtual source: mirrored direction and position above the surface   (docs/physics.md §4.2)
    w_v = w12 - 2.0 * _dot(w12, n_star)[..., None] * n_star
    x_v = x_i + (2.0 * A * d_e)[..., None] * n_star
    x_from_v = x_o - x_v
    d_v = np.maximum(np.sqrt(_dot(x_from_v, x_from_v)), D_R_FLOOR * D)  # explicit clamp, only on the n_i axis

    # Real source: corrected distance d_r   (docs/physics.md §4.3)
    mu0 = -_dot(n_o, w12)
    x_dot_w12 = _dot(x, w12)
    cos_beta = -np.sqrt(np.maximum(r2 - x_dot_w12 * x_dot_w12, 0.0) / (r2 + d_e * d_e))
    frontlit_d_r2 = r2 + D * mu0 * (D * mu0 - 2.0 * d_e * cos_beta)
    backlit_d_r2 = r2 + backlit_depth * backlit_depth
    d_r = np.sqrt(np.where(mu0 > 0.0, frontlit_d_r2, backlit_d_r2))
    d_r = np.maximum(d_r, D_R_FLOOR * D)  # explicit clamp of the singular grazing self-term (D_R_FLOOR)

    with np.errstate(over="ignore", under="ignore"):
        real = _ray_source_term(x, w12, d_r, n_o, D, sigma_tr_, C_phi, C_E, norm)
        virtual = _ray_source_term(x_from_v, w_v, d_v, n_o, D, sigma_tr_, C_phi, C_E, norm)
    return np.maximum(real - virtual, 0.0)  # docs/physics.md §4.5: clamp after subtracting the virtual source


def directional_dipole_profile(x_o, theta_i_deg, sigma_a, sigma_s, g, eta):
    """``S_d`` on the flat surface z = 0 for light arriving in the x-z plane (docs/physics.md §10.1 set-up).

    The point of incidence is the origin, ``n_i = n_o = +z``, and the light arrives from
    ``(-sin theta_i, 0, cos theta_i)``, so the refracted ray travels toward +x.

    Parameters
    ----------
    x_o : array_like, shape (..., 3) or (..., 2)
        Exit points on the plane, mm (a z component, if given, is ignored).
    theta_i_deg : float
        Polar angle of incidence in degrees, in [0, 90).

    Returns
    -------
    ndarray
        ``S_d`` in 1/(mm^2 sr) (norm included, no Fresnel transmittance).
    """
    x_o = np.asarray(x_o, dtype=np.float64)
    points = np.zeros(x_o.shape[:-1] + (3,))
    points[..., :2] = x_o[..., :2]
    theta = np.radians(theta_i_deg)
    normal = np.array([0.0, 0.0, 1.0])
    w_i = np.array([-np.sin(theta), 0.0, np.cos(theta)])
    w12 = fresnel.refract(w_i, normal, eta)
    return directional_dipole(np.zeros(3), normal, w12, points, normal, sigma_a, sigma_s, g, eta)


def standard_dipole_profile(r, sigma_a, sigma_s, g, eta):
    """Radial diffuse reflectance ``R_d(r)`` of the standard dipole (Jensen et al. 2001; docs/physics.md §6.1).

    ``R_d(r) = alpha'/(4 pi) [z_r (1 + sigma_tr d_r) e^{-sigma_tr d_r} / d_r^3
    + z_v (1 + sigma_tr d_v) e^{-sigma_tr d_v} / d_v^3]`` with ``z_r = 1/sigma_t'``,
    ``z_v = z_r (1 + 4A/3)``, ``A = (1 + F_dr)/(1 - F_dr)`` (Egan-Hilgeman ``F_dr``),
    ``d = sqrt(r^2 + z^2)``.

    Parameters
    ----------
    r : array_like
        Distance between entry and exit points, mm.
    sigma_a, sigma_s, g, eta
        As in :func:`directional_dipole` (``sigma_s' = sigma_s (1 - g)``).

    Returns
    -------
    ndarray
        ``R_d(r)`` in 1/mm^2: exitance per unit incident flux that entered the medium. The BSSRDF is
        ``S_d = F_t(eta, w_i) R_d(r) F_t(eta, w_o) / pi``.
    """
    sigma_a, sigma_s, g, eta = validate_coefficients(sigma_a, sigma_s, g, eta, what="standard_dipole_profile")
    r = np.asarray(r, dtype=np.float64)
    alpha = alpha_reduced(sigma_a, sigma_s, g)
    sigma_tr_ = sigma_tr(sigma_a, sigma_s, g)
    F_dr = fresnel.F_dr_egan_hilgeman(eta)
    A = (1.0 + F_dr) / (1.0 - F_dr)
    z_r = 1.0 / sigma_t_reduced(sigma_a, sigma_s, g)
    z_v = z_r * (1.0 + 4.0 * A / 3.0)  # z_r + 4 A D
    d_r = np.sqrt(r * r + z_r * z_r)
    d_v = np.sqrt(r * r + z_v * z_v)
    with np.errstate(under="ignore"):
        real = z_r * (1.0 + sigma_tr_ * d_r) * np.exp(-sigma_tr_ * d_r) / d_r**3
        virtual = z_v * (1.0 + sigma_tr_ * d_v) * np.exp(-sigma_tr_ * d_v) / d_v**3
    return alpha / (4.0 * np.pi) * (real + virtual)


def better_dipole_profile(r, sigma_a, sigma_s, g, eta):
    """Radial exitance ``R(r)`` of the better dipole (d'Eon 2012; docs/physics.md §6.2).

    Grosjean's ``D = (2 sigma_a + sigma_s') / (3 sigma_t'^2)``, ``sigma_tr = sqrt(sigma_a / D)``,
    ``A = (1 + 3 C2) / (1 - 2 C1)``, ``z_r = 1/sigma_t'``, ``z_v = -z_r - 4 A D`` and
    ``R(r) = alpha'^2/(4 pi) [(C_phi/D)(e^{-sigma_tr d_r}/d_r - e^{-sigma_tr d_v}/d_v)
    + C_E (z_r (1+sigma_tr d_r) e^{-sigma_tr d_r}/d_r^3 - z_v (1+sigma_tr d_v) e^{-sigma_tr d_v}/d_v^3)]``.

    Returns
    -------
    ndarray
        ``R(r)`` in 1/mm^2. The BSSRDF is ``S_d = F_t(w_i) R(r) F_t(w_o) / (4 C_phi(1/eta) pi)``.
    """
    sigma_a, sigma_s, g, eta = validate_coefficients(sigma_a, sigma_s, g, eta, what="better_dipole_profile")
    r = np.asarray(r, dtype=np.float64)
    sigma_t_red = sigma_t_reduced(sigma_a, sigma_s, g)
    alpha = alpha_reduced(sigma_a, sigma_s, g)
    sigma_s_red = sigma_t_red - sigma_a
    D = (2.0 * sigma_a + sigma_s_red) / (3.0 * sigma_t_red**2)  # Grosjean
    sigma_tr_ = np.sqrt(sigma_a / D)
    C_phi = fresnel.C_phi(eta)
    C_E = fresnel.C_E(eta)
    A = (1.0 - C_E) / (2.0 * C_phi)
    z_r = 1.0 / sigma_t_red
    z_v = -z_r - 4.0 * A * D
    d_r = np.sqrt(r * r + z_r * z_r)
    d_v = np.sqrt(r * r + z_v * z_v)
    with np.errstate(under="ignore"):
        e_r = np.exp(-sigma_tr_ * d_r)
        e_v = np.exp(-sigma_tr_ * d_v)
    fluence = C_phi / D * (e_r / d_r - e_v / d_v)
    flux = C_E * (z_r * (1.0 + sigma_tr_ * d_r) * e_r / d_r**3 - z_v * (1.0 + sigma_tr_ * d_v) * e_v / d_v**3)
    return alpha * alpha / (4.0 * np.pi) * (fluence + flux)


def standard_dipole_total_reflectance(alpha_reduced_, eta):
    """Total diffuse reflectance of the standard dipole (Jensen 2001; docs/physics.md §6.1), closed form.

    ``R_d = (alpha'/2) (1 + exp(-(4/3) A sqrt(3 (1 - alpha')))) exp(-sqrt(3 (1 - alpha')))`` with the
    Egan-Hilgeman ``A``; equals the integral of :func:`standard_dipole_profile` over the plane.
    """
    alpha = np.asarray(alpha_reduced_, dtype=np.float64)
    F_dr = fresnel.F_dr_egan_hilgeman(eta)
    A = (1.0 + F_dr) / (1.0 - F_dr)
    root = np.sqrt(3.0 * (1.0 - alpha))
    return 0.5 * alpha * (1.0 + np.exp(-4.0 / 3.0 * A * root)) * np.exp(-root)


def better_dipole_total_reflectance(alpha_reduced_, eta):
    """Total diffuse reflectance of the better dipole (Hery's closed form; docs/physics.md §6.2).

    ``R_d = (alpha'^2 / 2) exp(-sqrt(3 (1 - alpha') / (2 - alpha'))) [C_E (1 + e^{-4 A mu})
    + (C_phi / mu)(1 - e^{-4 A mu})]`` with ``mu = sqrt((1 - alpha')(2 - alpha') / 3)``; the limit
    ``mu -> 0`` (``alpha' -> 1``) is evaluated exactly (``(1 - e^{-4 A mu}) / mu -> 4 A``).
    """
    alpha = np.asarray(alpha_reduced_, dtype=np.float64)
    C_phi = fresnel.C_phi(eta)
    C_E = fresnel.C_E(eta)
    A = (1.0 - C_E) / (2.0 * C_phi)
    mu = np.sqrt((1.0 - alpha) * (2.0 - alpha) / 3.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(mu > 0.0, -np.expm1(-4.0 * A * mu) / mu, 4.0 * A)
    return (
        0.5
        * alpha**2
        * np.exp(-np.sqrt(3.0 * (1.0 - alpha) / (2.0 - alpha)))
        * (C_E * (1.0 + np.exp(-4.0 * A * mu)) + C_phi * ratio)
    )


def directional_dipole_total_reflectance(sigma_a, sigma_s, g, eta, theta_i_deg=0.0, n_radii=400, n_angles=64):
    """Total diffuse reflectance of the directional dipole per refracted photon, by quadrature.

    ``R = integral over the plane of pi S_d / norm dA`` (docs/physics.md §5.2, values §10.4: the model's
    exitance per unit flux that entered the medium; multiply by ``T12`` for per incident flux). Polar quadrature about
    the point of incidence: trapezoid rule in ``log r`` from ``1e-6 / sigma_t'`` to ``60`` diffusion
    lengths, trapezoid (spectral for a periodic integrand) in the azimuth. Relative accuracy is
    about 1e-6 with the default resolution. Scalar coefficients only.

    Returns
    -------
    float
        The dimensionless total reflectance.
    """
    sigma_a, sigma_s, g, eta = (float(v) for v in validate_coefficients(sigma_a, sigma_s, g, eta))
    sigma_t_red = float(sigma_t_reduced(sigma_a, sigma_s, g))
    reach = 60.0 / max(float(sigma_tr(sigma_a, sigma_s, g)), 1e-3 * sigma_t_red)
    radii = np.geomspace(1e-6 / sigma_t_red, reach, n_radii)
    phi = np.arange(n_angles) * (2.0 * np.pi / n_angles)
    rr, pp = np.meshgrid(radii, phi, indexing="ij")
    points = np.stack([rr * np.cos(pp), rr * np.sin(pp), np.zeros_like(rr)], axis=-1)
    S_d = directional_dipole_profile(points, theta_i_deg, sigma_a, sigma_s, g, eta)
    norm = 1.0 / (4.0 * float(fresnel.C_phi(1.0 / eta)))
    ring = S_d.mean(axis=1) * 2.0 * np.pi  # azimuthal integral (periodic trapezoid)
    integrand = ring * radii * radii  # r dr = r^2 d(log r)
    log_r = np.log(radii)
    inner = float(np.pi / norm * ring[0] * radii[0] ** 2 / 2.0)  # disc inside the first radius
    return float(np.pi / norm * np.trapezoid(integrand, log_r)) + inner
