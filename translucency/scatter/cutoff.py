"""The ``cutoff`` method: skip source/receiver pairs beyond a radius where the kernel is negligible.

The radius comes from a bound of ``S_d`` that holds for every geometry. Each ray source of the
directional dipole (spec 1.3) has ``|x . w|, |x . n_o| <= d`` and ``d >= r`` (``d_r^2 >= r^2``,
``d_v^2 = r^2 + (2 A d_e)^2``), and every term of ``S'_d`` decreases with ``d``, so::

    S_d(r) <= 2 b(r),  b(r) = norm e^{-s} / (4 pi^2) [C_phi (1/(D r) + 3 (1+s)/r^2)
                                  + C_E ((1+s)/r^2 + 3 D (4 (1+s) + s^2)/r^3)],   s = sigma_tr r.

The cutoff radius ``R(tol)`` is the smallest radius whose tail ``int_R^inf 2 b(r) 2 pi r dr`` is at
most ``tol`` times the total ``int S_d dA`` of a flat surface at normal incidence (so ``tol`` is the
fraction of the reflected energy that may be dropped per receiver on a flat surface), the largest
over the channels. The radial models use their own profile, which is its own bound.

========= ============================================ =====
symbol    meaning                                      unit
========= ============================================ =====
R         cutoff radius                                mm
tol       relative tail energy allowed                 1
========= ============================================ =====
"""

from __future__ import annotations

import math

import numba
import numpy as np
from scipy import integrate, optimize

from . import dipoles, fresnel
from .kernels import directional_three, padded_three_rows, source_to_receiver
from .medium import Medium


def _directional_bound(r, D, sigma_tr_, C_phi, C_E, norm):
    s = sigma_tr_ * r
    return 2.0 * norm * math.exp(-s) / (4.0 * math.pi**2) * (
        C_phi * (1.0 / (D * r) + 3.0 * (1.0 + s) / r**2) + C_E * ((1.0 + s) / r**2 + 3.0 * D * (4.0 * (1.0 + s) + s * s) / r**3)
    )


def cutoff_radius(medium: Medium, tol: float, model: str = "directional") -> float:
    """Radius (mm) beyond which pairs may be skipped with at most ``tol`` of the energy dropped.

    Memoised on the coefficients (a few quadratures and a root search: ~50 ms per call otherwise)."""
    key = (tuple(np.asarray(medium.sigma_a, float).tolist()), tuple(np.asarray(medium.sigma_s, float).tolist()),
           tuple(np.asarray(medium.g, float).tolist()), float(medium.eta), float(tol), str(model))
    if key not in _RADII:
        if len(_RADII) >= 256:
            _RADII.clear()
        _RADII[key] = _cutoff_radius(medium, tol, model)
    return _RADII[key]


_RADII: dict = {}


def _cutoff_radius(medium: Medium, tol: float, model: str) -> float:
    radii = []
    norm = 1.0 / (4.0 * float(fresnel.C_phi(1.0 / medium.eta)))
    for c in range(medium.n_channels):
        a, s, g, eta = medium.sigma_a[c], medium.sigma_s[c], medium.g[c], medium.eta
        if model == "directional":
            D = float(medium.D[c])
            st = float(medium.sigma_tr[c])
            C_phi, C_E = float(fresnel.C_phi(eta)), float(fresnel.C_E(eta))
            total = dipoles.directional_dipole_total_reflectance(a, s, g, eta) * norm / math.pi  # int S_d dA
            density = lambda r: 2.0 * math.pi * r * _directional_bound(r, D, st, C_phi, C_E, norm)  # noqa: E731
        else:
            profile = dipoles.standard_dipole_profile if model == "standard" else dipoles.better_dipole_profile
            scale = 1.0 / math.pi if model == "standard" else norm / math.pi
            reflectance = (dipoles.standard_dipole_total_reflectance if model == "standard"
                           else dipoles.better_dipole_total_reflectance)(float(medium.alpha_reduced[c]), eta)
            total = float(reflectance) * scale
            density = lambda r, a=a, s=s, g=g: 2.0 * math.pi * r * scale * float(profile(r, a, s, g, eta))  # noqa: E731
        if total <= 0.0:
            radii.append(0.0)
            continue
        if model == "directional" and st == 0.0:
            return math.inf  # no absorption: S_d decays as a power law and every pair matters
        tail = lambda R: integrate.quad(density, R, np.inf, limit=200)[0] - tol * total  # noqa: E731
        lo = 1e-3 / float(medium.sigma_t_reduced[c])
        if tail(lo) <= 0.0:
            radii.append(lo)
            continue
        hi = 2.0 * lo
        while tail(hi) > 0.0:
            lo, hi = hi, 2.0 * hi
        radii.append(float(optimize.brentq(tail, lo, hi, xtol=1e-6 * hi)))
    return max(radii)


class SourceGrid:
    """Sources binned in a uniform grid of cubic cells (mm); cell ``i`` holds ``order[start[i]:start[i+1]]``."""

    def __init__(self, points: np.ndarray, cell: float, max_cells_per_axis: int = 256):
        lo = points.min(axis=0)
        extent = points.max(axis=0) - lo
        cell = max(cell, float(extent.max()) / max_cells_per_axis, 1e-12)
        dims = np.maximum(np.ceil(extent / cell).astype(np.int64), 1) + 1
        ijk = np.minimum(((points - lo) / cell).astype(np.int64), dims - 1)
        flat = (ijk[:, 0] * dims[1] + ijk[:, 1]) * dims[2] + ijk[:, 2]
        self.order = np.argsort(flat, kind="stable").astype(np.int64)
        self.start = np.zeros(int(np.prod(dims)) + 1, dtype=np.int64)
        np.cumsum(np.bincount(flat, minlength=int(np.prod(dims))), out=self.start[1:])
        self.origin = lo.astype(np.float64)
        self.cell = float(cell)
        self.dims = dims


@numba.njit(cache=True, parallel=True, fastmath=True)
def cutoff_sum(model, grid_order, grid_start, origin, cell, dims, radius, src_points, src_normals, src_w12, src_flux,
               rcv_points, rcv_normals, params, channel_of):
    """Sum over the sources within ``radius`` of each receiver; returns ``B`` and pairs evaluated per receiver."""
    n_rcv = rcv_points.shape[0]
    n_out = src_flux.shape[1]
    B = np.zeros((n_rcv, n_out))
    evaluated = np.zeros(n_rcv, dtype=np.int64)
    reach = int(math.ceil(radius / cell))
    r2max = radius * radius
    for o in numba.prange(n_rcv):
        sd = np.empty(params.shape[0])
        px = rcv_points[o, 0]
        py = rcv_points[o, 1]
        pz = rcv_points[o, 2]
        ci = int((px - origin[0]) / cell)
        cj = int((py - origin[1]) / cell)
        ck = int((pz - origin[2]) / cell)
        for i in range(max(ci - reach, 0), min(ci + reach + 1, dims[0])):
            for j in range(max(cj - reach, 0), min(cj + reach + 1, dims[1])):
                base = (i * dims[1] + j) * dims[2]
                for q in range(grid_start[base + max(ck - reach, 0)], grid_start[base + min(ck + reach + 1, dims[2])]):
                    s = grid_order[q]
                    dx = src_points[s, 0] - px
                    dy = src_points[s, 1] - py
                    dz = src_points[s, 2] - pz
                    if dx * dx + dy * dy + dz * dz > r2max:
                        continue
                    source_to_receiver(model, src_points, src_normals, src_w12, s, px, py, pz, rcv_normals[o, 0],
                                       rcv_normals[o, 1], rcv_normals[o, 2], params, sd)
                    for c in range(n_out):
                        B[o, c] += sd[channel_of[c]] * src_flux[s, c]
                    evaluated[o] += 1
    return B, evaluated


@numba.njit(cache=True, parallel=True, fastmath=True)
def cutoff_sum_directional(sx, sy, sz, snx, sny, snz, swx, swy, swz, flux_t, grid_start, origin, cell, dims, radius,
                           rcv_points, rcv_normals, params, channel_of):
    """:func:`cutoff_sum` for the directional dipole with <= 3 channels, vectorised over each grid row.

    The source columns (``sx`` ... ``swz``, ``flux_t[c, j]``) must be in grid order (sorted by cell), so
    the sources of consecutive cells along z are contiguous; pairs beyond ``radius`` are masked out.
    Returns ``B`` and the number of pairs within the radius per receiver.
    """
    n_rcv = rcv_points.shape[0]
    n_out = flux_t.shape[0]
    rows = padded_three_rows(params)
    B = np.zeros((n_rcv, n_out))
    evaluated = np.zeros(n_rcv, dtype=np.int64)
    reach = int(math.ceil(radius / cell))
    r2max = radius * radius
    m0 = channel_of[0]
    m1 = channel_of[min(1, n_out - 1)]
    m2 = channel_of[min(2, n_out - 1)]
    f0 = flux_t[0]
    f1 = flux_t[min(1, n_out - 1)]
    f2 = flux_t[min(2, n_out - 1)]
    for o in numba.prange(n_rcv):
        px = rcv_points[o, 0]
        py = rcv_points[o, 1]
        pz = rcv_points[o, 2]
        nx = rcv_normals[o, 0]
        ny = rcv_normals[o, 1]
        nz = rcv_normals[o, 2]
        ci = int((px - origin[0]) / cell)
        cj = int((py - origin[1]) / cell)
        ck = int((pz - origin[2]) / cell)
        a0 = 0.0
        a1 = 0.0
        a2 = 0.0
        count = 0
        for i in range(max(ci - reach, 0), min(ci + reach + 1, dims[0])):
            for j in range(max(cj - reach, 0), min(cj + reach + 1, dims[1])):
                base = (i * dims[1] + j) * dims[2]
                for q in range(grid_start[base + max(ck - reach, 0)], grid_start[base + min(ck + reach + 1, dims[2])]):
                    x0 = px - sx[q]
                    x1 = py - sy[q]
                    x2 = pz - sz[q]
                    inside = x0 * x0 + x1 * x1 + x2 * x2 <= r2max
                    e0, e1, e2 = directional_three(x0, x1, x2, snx[q], sny[q], snz[q], swx[q], swy[q], swz[q], nx, ny, nz,
                                                   rows)
                    e0 = max(e0, 0.0) if inside else 0.0
                    e1 = max(e1, 0.0) if inside else 0.0
                    e2 = max(e2, 0.0) if inside else 0.0
                    count += inside
                    a0 += (e0 if m0 == 0 else (e1 if m0 == 1 else e2)) * f0[q]
                    a1 += (e0 if m1 == 0 else (e1 if m1 == 1 else e2)) * f1[q]
                    a2 += (e0 if m2 == 0 else (e1 if m2 == 1 else e2)) * f2[q]
        B[o, 0] = a0
        if n_out > 1:
            B[o, 1] = a1
        if n_out > 2:
            B[o, 2] = a2
        evaluated[o] = count
    return B, evaluated
