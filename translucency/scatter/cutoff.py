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


def cutoff_sum(model, grid, radius, points, normals, w12, flux, rcv_points, rcv_normals, params, channel_of,
               block=4096):
    """Sum over the sources within ``radius`` (mm) of each receiver: ``(B, pairs evaluated per receiver)``.

    ``grid`` is a :class:`SourceGrid` over the sources (rows of ``points``, ``normals``, ``w12``,
    ``flux``). For each block of receivers the sources within the radius are listed from the grid
    cells around the receiver (a count, then the list) and evaluated with
    :func:`~translucency.scatter.kernels.indexed_sum`, any model.
    """
    from .kernels import channel_lanes, indexed_sum

    order = grid.order
    table = np.ascontiguousarray(np.hstack([points[order], normals[order], w12[order]]).T)  # sources cell by cell
    weights = np.ascontiguousarray(flux[order].T)
    lanes = channel_lanes(params, channel_of, flux.shape[1])
    n_rcv = rcv_points.shape[0]
    B = np.zeros((n_rcv, flux.shape[1]))
    evaluated = np.zeros(n_rcv, dtype=np.int64)
    for first in range(0, n_rcv, block):
        part = slice(first, min(n_rcv, first + block))
        p, nrm = rcv_points[part], rcv_normals[part]
        counts = evaluated[part]
        _within(table, grid.start, grid.origin, grid.cell, grid.dims, radius, p, np.empty(0, dtype=np.int64),
                np.zeros(1, dtype=np.int64), counts)
        starts = np.zeros(counts.size, dtype=np.int64)
        np.cumsum(counts[:-1], out=starts[1:])
        columns = np.empty(int(counts.sum()), dtype=np.int64)
        _within(table, grid.start, grid.origin, grid.cell, grid.dims, radius, p, columns, starts, counts)
        B[part] = indexed_sum(model, p, nrm, table, weights, starts, counts, columns, np.ones(columns.size), params,
                              lanes, channel_of)
    return B, evaluated


@numba.njit(cache=True, parallel=True)
def _within(table, grid_start, origin, cell, dims, radius, rcv_points, columns, starts, counts):
    """Count (``columns`` empty) or list from ``starts[o]`` on the sources (columns of ``table``, in grid
    order) within ``radius`` of each receiver."""
    write = columns.shape[0] > 0
    reach = int(math.ceil(radius / cell))
    r2max = radius * radius
    for o in numba.prange(rcv_points.shape[0]):
        px = rcv_points[o, 0]
        py = rcv_points[o, 1]
        pz = rcv_points[o, 2]
        ci = int((px - origin[0]) / cell)
        cj = int((py - origin[1]) / cell)
        ck = int((pz - origin[2]) / cell)
        at = starts[o] if write else 0
        count = 0
        for i in range(max(ci - reach, 0), min(ci + reach + 1, dims[0])):
            for j in range(max(cj - reach, 0), min(cj + reach + 1, dims[1])):
                base = (i * dims[1] + j) * dims[2]
                for q in range(grid_start[base + max(ck - reach, 0)], grid_start[base + min(ck + reach + 1, dims[2])]):
                    dx = table[0, q] - px
                    dy = table[1, q] - py
                    dz = table[2, q] - pz
                    if dx * dx + dy * dy + dz * dz <= r2max:
                        if write:
                            columns[at] = q
                            at += 1
                        count += 1
        counts[o] = count
