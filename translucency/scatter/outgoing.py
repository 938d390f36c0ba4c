"""Radiance leaving the surface toward a viewer: the subsurface part and the boundary's reflection.

The solver's ``B(x_o)`` does not depend on the view. What leaves a vertex toward a viewer in
direction ``w_o`` is the light that crosses the boundary on its way out, ``L_sub = T21(eta, n . w_o) B``
(DESIGN.md; a bake stores ``T21(eta, 1) B``, toward the normal), plus the light the boundary itself
reflects. The reflection of a smooth dielectric is a mirror image of the lights; a scanned surface is
rough at the scale of its triangles, so it is modelled here with the GGX (Trowbridge-Reitz)
microfacet distribution and Smith's separable shadowing (Walter et al. 2007, "Microfacet models for
refraction through rough surfaces", eqs. 20, 33, 34), with the Fresnel reflectance of the same
``eta`` the subsurface part uses for ``T12`` and ``T21``:

    f_s = F_r(w_i . h, eta) D(h) G1(w_i) G1(w_o) / (4 (n . w_i)(n . w_o)),   L_spec = f_s E_surface

with ``E_surface = E (n . w_i) V`` the irradiance the light gives the surface itself.

========== ================================================================= ============
symbol     meaning                                                           unit
========== ================================================================= ============
B          diffuse radiance factor of the solver                             W/(m² sr)
n          unit outward vertex normal                                        1
w_o        unit vector from the surface toward the viewer                    1
w_i        unit vector from the surface toward the light                     1
h          half vector (w_i + w_o) / |w_i + w_o|                             1
eta        relative index of refraction n_inside / n_outside                 1
alpha      GGX roughness (0: mirror; 1: very rough)                          1
D          GGX distribution of microfacet normals                            1/sr
G1         Smith shadowing-masking of one direction                          1
F_r        Fresnel reflectance                                               1
E_surface  irradiance on the surface, E cos(theta_i) V                       W/m²
L          radiance                                                          W/(m² sr)
========== ================================================================= ============
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError
from .fresnel import fresnel_reflectance, fresnel_transmittance

__all__ = ["subsurface_radiance", "ggx_distribution", "smith_g1", "specular_radiance", "view_directions"]

#: Cosines below this count as grazing: the specular term is 0 there (avoids 0/0 at the silhouette).
MIN_COSINE = 1e-6


def _dot(a, b):
    return np.einsum("...k,...k->...", a, b)


def view_directions(points, eye):
    """Unit vectors from each point toward a perspective camera at ``eye`` (both in mm); (n, 3)."""
    w = np.asarray(eye, dtype=np.float64)[None, :] - np.asarray(points, dtype=np.float64)
    length = np.linalg.norm(w, axis=1, keepdims=True)
    return w / np.where(length > 0, length, 1.0)


def subsurface_radiance(B, normals, w_o, eta):
    """Subsurface radiance toward the viewer, ``L = T21(eta, n . w_o) B`` (0 where the surface faces away).

    Parameters
    ----------
    B : (n, C) array_like
        Diffuse radiance factor per vertex and channel, W/(m² sr).
    normals, w_o : (n, 3) array_like
        Unit outward normals and unit directions toward the viewer.
    eta : float
        Relative index of refraction of the medium.

    Returns
    -------
    (n, C) ndarray
        Radiance, W/(m² sr).
    """
    cos_o = _dot(np.asarray(normals, dtype=np.float64), np.asarray(w_o, dtype=np.float64))
    # T21(eta, n . w_o); fresnel_reflectance clips the cosine, so a vertex facing away gets F_r = 1, T21 = 0
    return fresnel_transmittance(cos_o, eta)[:, None] * np.asarray(B, dtype=np.float64)


def ggx_distribution(cos_h, alpha):
    """GGX distribution ``D = alpha² / (pi ((n.h)² (alpha² - 1) + 1)²)`` in 1/sr (Walter et al. 2007, eq. 33)."""
    c2 = np.clip(np.asarray(cos_h, dtype=np.float64), 0.0, 1.0) ** 2
    a2 = float(alpha) ** 2
    return np.where(c2 > 0, a2 / (np.pi * (c2 * (a2 - 1.0) + 1.0) ** 2), 0.0)


def smith_g1(cos_v, alpha):
    """Smith shadowing-masking of GGX, ``G1 = 2 c / (c + sqrt(alpha² + (1 - alpha²) c²))`` (eq. 34)."""
    c = np.clip(np.asarray(cos_v, dtype=np.float64), 0.0, 1.0)
    a2 = float(alpha) ** 2
    return 2.0 * c / (c + np.sqrt(a2 + (1.0 - a2) * c * c) + (c == 0))


def specular_radiance(normals, w_o, w_i, irradiance_surface, eta, roughness):
    """Radiance the boundary reflects toward the viewer from one light direction (module docstring).

    Parameters
    ----------
    normals, w_o : (n, 3) array_like
        Unit outward normals and unit directions toward the viewer.
    w_i : (3,) or (n, 3) array_like
        Unit direction toward the light.
    irradiance_surface : (n, C) array_like
        ``E (n . w_i) V``: the light's irradiance on the surface, shadows included, W/m².
    eta : float
        Relative index of refraction (>= 1).
    roughness : float
        GGX ``alpha`` in (0, 1].

    Returns
    -------
    (n, C) ndarray
        Reflected radiance, W/(m² sr); 0 where the surface faces away from the light or the viewer.
    """
    if not (np.isfinite(roughness) and 0 < roughness <= 1):
        raise InvalidParameterError(f"roughness must be a GGX alpha in (0, 1], got {roughness!r}.")
    normals = np.asarray(normals, dtype=np.float64)
    w_o = np.asarray(w_o, dtype=np.float64)
    w_i = np.broadcast_to(np.asarray(w_i, dtype=np.float64), normals.shape)
    cos_i, cos_o = _dot(normals, w_i), _dot(normals, w_o)
    h = w_i + w_o
    h_length = np.linalg.norm(h, axis=1, keepdims=True)
    h = h / np.where(h_length > 0, h_length, 1.0)
    valid = (cos_i > MIN_COSINE) & (cos_o > MIN_COSINE)
    F = fresnel_reflectance(_dot(w_i, h), eta)
    D = ggx_distribution(_dot(normals, h), roughness)
    G = smith_g1(cos_i, roughness) * smith_g1(cos_o, roughness)
    with np.errstate(divide="ignore", invalid="ignore"):
        f_s = np.where(valid, F * D * G / (4.0 * cos_i * cos_o), 0.0)  # Walter et al. 2007, eq. 20
    return f_s[:, None] * np.asarray(irradiance_surface, dtype=np.float64)
