"""The ``cutoff`` method: skip source/receiver pairs beyond a radius where the kernel is negligible.

The radius comes from a bound of ``S_d`` that holds for every geometry (docs/physics.md §8.4). Each
ray source of the directional dipole (docs/physics.md §4.4) has ``|x . w|, |x . n_o| <= d`` and
``d >= r`` (``d_r^2 >= r^2``, ``d_v^2 = r^2 + (2 A d_e)^2``), and every term of ``S'_d`` decreases
with ``d``, so::

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
from scipy import optimize

from ..threads import for_ranges
from . import dipoles, fresnel, kernels
from .kernels import (
    MODEL_DIRECTIONAL,
    channel_lanes,
    group_inputs,
    model_pair,
    pair_three,
    rows_kernel,
    source_columns,
    store_three,
    table_rows,
)
from .medium import Medium
from .surface import PerSurface


def _directional_bound(r, D, sigma_tr_, C_phi, C_E, norm):
    r = np.asarray(r, dtype=np.float64)
    s = sigma_tr_ * r
    return (
        2.0
        * norm
        * np.exp(-s)
        / (4.0 * math.pi**2)
        * (
            C_phi * (1.0 / (D * r) + 3.0 * (1.0 + s) / r**2)
            + C_E * ((1.0 + s) / r**2 + 3.0 * D * (4.0 * (1.0 + s) + s * s) / r**3)
        )
    )


def cutoff_radius(medium: Medium, tol: float, model: str = "directional") -> float:
    """Radius (mm) beyond which pairs may be skipped with at most ``tol`` of the energy dropped.

    Memoised on the coefficients (otherwise a few quadratures and a root search per call)."""
    return memoised(
        _RADII, (*coefficients_key(medium), float(tol), str(model)), lambda: _cutoff_radius(medium, tol, model)
    )


_RADII: dict = {}


def coefficients_key(medium: Medium) -> tuple:
    """What the kernel of ``medium`` depends on, as a key: its coefficients per channel and ``eta``."""
    return (
        tuple(np.asarray(medium.sigma_a, float).tolist()),
        tuple(np.asarray(medium.sigma_s, float).tolist()),
        tuple(np.asarray(medium.g, float).tolist()),
        float(medium.eta),
    )


def memoised(store: dict, key, make):
    """``store[key]``, made by ``make()`` where missing; the store is emptied when it holds 256 (a value made here is
    returned even where another thread empties the store meanwhile)."""
    value = store.get(key)
    if value is None:
        value = make()
        if len(store) >= 256:
            store.clear()
        store[key] = value
    return value


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
            reflectance = (
                dipoles.standard_dipole_total_reflectance
                if model == "standard"
                else dipoles.better_dipole_total_reflectance
            )(float(medium.alpha_reduced[c]), eta)
            total = float(reflectance) * scale
            density = lambda r, a=a, s=s, g=g: 2.0 * math.pi * r * scale * profile(r, a, s, g, eta)  # noqa: E731
        if total <= 0.0:
            radii.append(0.0)
            continue
        sigma = float(medium.sigma_tr[c])
        if sigma == 0.0:
            return math.inf  # no absorption: S_d decays as a power law and every pair matters
        tail = lambda R, density=density, sigma=sigma: _tail(density, R, sigma) - tol * total  # noqa: E731
        lo = 1e-3 / float(medium.sigma_t_reduced[c])
        if tail(lo) <= 0.0:
            radii.append(lo)
            continue
        hi = 2.0 * lo
        while tail(hi) > 0.0:
            lo, hi = hi, 2.0 * hi
        radii.append(float(optimize.brentq(tail, lo, hi, xtol=1e-6 * hi)))
    return max(radii)


def pair_bound(medium: Medium, model: str, r) -> np.ndarray:
    """Upper bound of one pair's clamped ``S_d`` (1/(mm^2 sr)) at distance ``r`` (mm), per channel: ``2 b(r)``
    of the module docstring for the directional dipole, the profile itself for the radial models; decreasing
    in ``r``. Returns ``(C, len(r))``."""
    r = np.atleast_1d(np.asarray(r, dtype=np.float64))
    eta = medium.eta
    norm = 1.0 / (4.0 * float(fresnel.C_phi(1.0 / eta)))
    out = np.empty((medium.n_channels, r.size))
    for c in range(medium.n_channels):
        a, s, g = medium.sigma_a[c], medium.sigma_s[c], medium.g[c]
        if model == "directional":
            C_phi, C_E = float(fresnel.C_phi(eta)), float(fresnel.C_E(eta))
            D, st = float(medium.D[c]), float(medium.sigma_tr[c])
            out[c] = _directional_bound(r, D, st, C_phi, C_E, norm)
        else:
            profile = dipoles.standard_dipole_profile if model == "standard" else dipoles.better_dipole_profile
            scale = 1.0 / math.pi if model == "standard" else norm / math.pi
            out[c] = scale * np.asarray(profile(r, a, s, g, eta), dtype=np.float64)
    return out


#: Geometries :func:`largest_values` samples per distance, and the distances it samples: log-spaced from the first to
#: the last number of reduced mean free paths (of the densest and of the thinnest channel), this many a decade.
LARGEST_GEOMETRIES = 4096
LARGEST_MEAN_FREE_PATHS = (1e-3, 1e4)
LARGEST_PER_DECADE = 8


def largest_values(medium: Medium, model: str, r) -> np.ndarray:
    """The largest ``S_d`` (1/(mm^2 sr)) at distance ``r`` (mm) over :data:`LARGEST_GEOMETRIES` sampled geometries,
    per channel, ``(C, len(r))``, never above :func:`pair_bound`.

    A geometry is the receiver's direction from the source, its normal (both anywhere on the sphere) and a refracted
    direction light from outside can take (in the cone of ``asin(1 / eta)`` about the source's inward normal). The
    bound drops the cancellation of the real and the virtual source (docs/physics.md §4.5), which grows with the
    distance: in marble the largest value is a third of the bound at 1 mm and a two-hundredth at 64 mm, in ketchup a
    half to a fifth at every distance (bench/README.md, "Kernel throughput"). Sampled at
    :data:`LARGEST_MEAN_FREE_PATHS` (:data:`LARGEST_PER_DECADE` distances a decade) and interpolated as the share of
    the bound in ``log r``: the bound itself nearer than the first sampled distance, the last share beyond the last;
    memoised on the coefficients. The radial models: their profile (their bound)."""
    r = np.atleast_1d(np.asarray(r, dtype=np.float64))
    bound = pair_bound(medium, model, r)
    if model != "directional":
        return bound
    distances, share = memoised(_SHARES, coefficients_key(medium), lambda: _largest_shares(medium))
    out = np.empty_like(bound)
    for c in range(medium.n_channels):
        known = np.isfinite(share[c]) & (share[c] > 0.0)
        if not known.any():
            out[c] = bound[c]
            continue
        # log share 0 (the bound) below the first sampled distance, the last share beyond the last
        log_share = np.interp(np.log(r), np.log(distances[known]), np.log(share[c, known]), left=0.0)
        out[c] = bound[c] * np.minimum(1.0, np.exp(log_share))
    return out


_SHARES: dict = {}


def _largest_shares(medium: Medium) -> tuple[np.ndarray, np.ndarray]:
    """The sampled distances (mm) of :func:`largest_values` for the directional dipole and, per channel, the largest
    sampled ``S_d`` there as a share of :func:`pair_bound` (NaN where the bound is 0)."""
    sigma = np.asarray(medium.sigma_t_reduced, dtype=np.float64)
    first, last = LARGEST_MEAN_FREE_PATHS[0] / float(sigma.max()), LARGEST_MEAN_FREE_PATHS[1] / float(sigma.min())
    steps = max(2, int(math.ceil(LARGEST_PER_DECADE * math.log10(last / first))) + 1)
    distances = np.exp(np.linspace(math.log(first), math.log(last), steps))
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta, "directional")
    found = np.zeros((medium.n_channels, steps))
    _largest(MODEL_DIRECTIONAL, distances, _sampled_geometries(medium.eta), params, found)
    bound = pair_bound(medium, "directional", distances)
    with np.errstate(divide="ignore", invalid="ignore"):
        return distances, np.where(bound > 0.0, found / bound, np.nan)


def _sampled_geometries(eta: float) -> np.ndarray:
    """``(K, 9)`` rows of :func:`largest_values`' geometries, the source at the origin with its normal along ``z``: the
    receiver's unit direction, its unit normal (both spread over the sphere) and a unit refracted direction (spread
    over the solid angle of the cone of ``asin(1 / eta)`` about ``-z``). The points are an additive recurrence (the
    fractional parts of ``k`` times the square roots of six primes), the same on every machine and library version."""
    k = np.arange(1, LARGEST_GEOMETRIES + 1, dtype=np.float64)[:, None]
    u = np.mod(k * np.sqrt(np.array([2.0, 3.0, 5.0, 7.0, 11.0, 13.0])), 1.0)

    def on_sphere(a, b):
        z = 1.0 - 2.0 * a
        ring = np.sqrt(np.maximum(0.0, 1.0 - z * z))
        return np.column_stack([ring * np.cos(2.0 * math.pi * b), ring * np.sin(2.0 * math.pi * b), z])

    cos_edge = math.cos(math.asin(min(1.0, 1.0 / float(eta))))
    cos_t = 1.0 - u[:, 4] * (1.0 - cos_edge)
    sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t**2))
    turn = 2.0 * math.pi * u[:, 5]
    w12 = np.column_stack([sin_t * np.cos(turn), sin_t * np.sin(turn), -cos_t])
    return np.ascontiguousarray(np.column_stack([on_sphere(u[:, 0], u[:, 1]), on_sphere(u[:, 2], u[:, 3]), w12]))


@numba.njit(cache=True)
def _largest(model, distances, geometries, params, out):
    """Into ``out (C, distances)``: the largest of ``out`` and ``S_d`` over the ``geometries`` (rows of
    :func:`_sampled_geometries`) at each distance (mm)."""
    values = np.empty(params.shape[0])
    for a in range(distances.shape[0]):
        r = distances[a]
        for q in range(geometries.shape[0]):
            g = geometries[q]
            model_pair(model, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, g[6], g[7], g[8], r * g[0], r * g[1], r * g[2],
                       g[3], g[4], g[5], params, values)  # fmt: skip
            for c in range(values.shape[0]):
                out[c, a] = max(out[c, a], values[c])


#: The compiled kernel of :func:`largest_values`: numba compiles it on first use; the set-up compiles it ahead
#: (:mod:`translucency.app.warmup`).
LARGEST_KERNELS = (_largest,)


def receiver_radii(medium: Medium, model: str, tol: float, near_sum, total_flux, radius, largest, floor):
    """Radius (mm) each receiver needs so that what it skips is at most ``tol`` of its own ``B`` (docs/physics.md §8.4).

    A source beyond ``R`` adds at most ``pair_bound(R) Phi`` to a receiver, so the sources beyond ``R``
    add at most ``pair_bound(R) Phi_total``. A receiver keeps the first ``radius`` when that is at most
    ``tol`` times the sum it found within it (``near_sum``, ``(n, C)``) -- or ``tol`` times ``floor``
    times the largest such sum of the channel (``largest``: below that fraction of the brightest
    receiver, ``tol`` bounds the error relative to ``floor`` of the largest); otherwise the smallest of
    the radii ``radius 2^(k/4)`` for which it holds, and ``inf`` (every pair) when none below the
    object's ``diagonal`` does.

    Parameters
    ----------
    near_sum : (n, C) float64
        Each receiver's sum over the sources within ``radius``.
    total_flux : (C,) float64
        Total source flux per channel.
    radius : float
        The first radius, mm.
    largest : float
        The largest radius worth trying (the object's diagonal), mm.
    floor : float
        Fraction of the largest sum of a channel below which the error is measured against that fraction.

    Returns
    -------
    (n,) float64
    """
    steps = max(1, int(math.ceil(4.0 * math.log2(max(largest / radius, 1.0)))))
    radii = radius * 2.0 ** (np.arange(steps + 1) / 4.0)
    dropped = pair_bound(medium, model, radii).T * np.asarray(total_flux)[None, :]  # (radii, C)
    allowed = tol * np.maximum(near_sum, floor * near_sum.max(axis=0, initial=0.0)[None, :])  # (n, C)
    ok = np.all(dropped[None, :, :] <= allowed[:, None, :], axis=2)  # (n, radii)
    first = np.where(ok.any(axis=1), ok.argmax(axis=1), -1)
    return np.where(first >= 0, radii[np.maximum(first, 0)], math.inf)


#: The tail integral stops TAIL_DECAY_LENGTHS / sigma_tr beyond its start: the bound has fallen by
#: exp(-TAIL_DECAY_LENGTHS / sqrt(2)) there (the better dipole's sigma_tr is at least sigma_tr / sqrt(2)).
TAIL_DECAY_LENGTHS = 120.0
_TAIL_NODES, _TAIL_WEIGHTS = np.polynomial.legendre.leggauss(24)


def _tail(density, R, sigma_tr_):
    """``int_R^inf density(r) dr`` of a vectorised density that decays as ``exp(-sigma_tr r)`` or faster:
    24-point Gauss-Legendre on the pieces of ``[R, R + TAIL_DECAY_LENGTHS / sigma_tr]`` cut at
    ``R + 2^k / sigma_tr`` (and at ``2^k R``), where the integrand is smooth (an exponential times powers
    of ``r``). One vectorised call of the density; QUADPACK on ``[R, inf)`` lost the decay when
    ``sigma_tr R`` was far from 1 (``sigma_s`` = 1e-9/mm: "probably divergent", "roundoff error")."""
    scale = 1.0 / sigma_tr_
    end = R + TAIL_DECAY_LENGTHS * scale
    cuts = np.concatenate([R + scale * 2.0 ** np.arange(-8, 7), R * 2.0 ** np.arange(1, 40)])
    cuts = np.unique(np.concatenate([[R], cuts[(cuts > R) & (cuts < end)], [end]]))
    lo, hi = cuts[:-1, None], cuts[1:, None]
    r = 0.5 * (lo + hi) + 0.5 * (hi - lo) * _TAIL_NODES[None, :]
    return float(np.sum(0.5 * (hi - lo) * _TAIL_WEIGHTS[None, :] * density(r)))


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


_GRIDS = PerSurface("cutoff source grids")


def grid_of(surface, sources: np.ndarray, cell: float) -> SourceGrid:
    """The uniform grid over the given source vertices of ``surface`` with cells of ``cell`` mm, kept per (sources,
    cell) while the surface lives."""
    key = (sources.tobytes(), round(cell, 12))
    return _GRIDS.get(surface, key, lambda: SourceGrid(surface.points[sources], cell))


def cutoff_sum(
    model,
    grid_order,
    grid_start,
    origin,
    cell,
    dims,
    radius,
    src_points,
    src_normals,
    src_w12,
    src_flux,
    rcv_points,
    rcv_normals,
    params,
    channel_of,
):
    """Sum over the sources within ``radius`` (mm) of each receiver (method ``cutoff``).

    Arguments as :func:`~translucency.scatter.kernels.vertex_sum`, with the sources binned in a
    :class:`SourceGrid` (``grid_order``, ``grid_start``, ``origin``, ``cell``, ``dims``). The sources are
    copied into grid order, so that the sources of consecutive cells along z are contiguous and each
    grid row is one loop that vectorises (pairs beyond ``radius`` are masked out).

    Returns
    -------
    B : (n_rcv, C) float64
    evaluated : (n_rcv,) int64
        Pairs within the radius, per receiver.
    """
    order = np.asarray(grid_order)
    table, weights = source_columns(
        np.asarray(src_points)[order],
        np.asarray(src_normals)[order],
        np.asarray(src_w12)[order],
        np.asarray(src_flux)[order],
    )
    lanes = channel_lanes(params, channel_of, weights.shape[0])
    n_rcv = rcv_points.shape[0]
    B = np.zeros((n_rcv, weights.shape[0]))
    evaluated = np.zeros(n_rcv, dtype=np.int64)
    for_ranges(
        rows_kernel(model, _cutoff_rows_directional, _cutoff_rows_radial),
        n_rcv,
        model,
        table,
        weights,
        grid_start,
        origin,
        float(cell),
        dims,
        float(radius),
        rcv_points,
        rcv_normals,
        lanes,
        B,
        evaluated,
    )
    return B, evaluated


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _cutoff_rows_directional(
    worker,
    lo,
    hi,
    model,
    table,
    weights,
    grid_start,
    origin,
    cell,
    dims,
    radius,
    rcv_points,
    rcv_normals,
    lanes,
    B,
    evaluated,
):
    """:func:`_cutoff_rows` of the directional dipole (``model`` is ignored: a constant here)."""
    _cutoff_rows(
        worker,
        lo,
        hi,
        MODEL_DIRECTIONAL,
        table,
        weights,
        grid_start,
        origin,
        cell,
        dims,
        radius,
        rcv_points,
        rcv_normals,
        lanes,
        B,
        evaluated,
    )


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _cutoff_rows_radial(
    worker,
    lo,
    hi,
    model,
    table,
    weights,
    grid_start,
    origin,
    cell,
    dims,
    radius,
    rcv_points,
    rcv_normals,
    lanes,
    B,
    evaluated,
):
    """:func:`_cutoff_rows` of the standard and better dipoles."""
    _cutoff_rows(
        worker,
        lo,
        hi,
        model,
        table,
        weights,
        grid_start,
        origin,
        cell,
        dims,
        radius,
        rcv_points,
        rcv_normals,
        lanes,
        B,
        evaluated,
    )


@numba.njit(cache=True, inline="always", fastmath=True, error_model="numpy")
def _cutoff_rows(
    worker,
    lo,
    hi,
    model,
    table,
    weights,
    grid_start,
    origin,
    cell,
    dims,
    radius,
    rcv_points,
    rcv_normals,
    lanes,
    B,
    evaluated,
):
    """Receivers ``lo .. hi - 1`` of :func:`cutoff_sum`."""
    n_out = weights.shape[0]
    reach = int(math.ceil(radius / cell))
    r2max = radius * radius
    X0, X1, X2, N0, N1, N2, W0, W1, W2 = table_rows(table)
    for o in range(lo, hi):
        px, py, pz = rcv_points[o, 0], rcv_points[o, 1], rcv_points[o, 2]
        nx, ny, nz = rcv_normals[o, 0], rcv_normals[o, 1], rcv_normals[o, 2]
        ci = int((px - origin[0]) / cell)
        cj = int((py - origin[1]) / cell)
        ck = int((pz - origin[2]) / cell)
        count = 0
        for group in range(lanes.shape[0] // 3):
            c0 = 3 * group
            F0, F1, F2, p0, p1, p2 = group_inputs(weights, lanes, c0)
            a0 = a1 = a2 = 0.0
            count = 0  # pairs within the radius (the same for every group)
            for i in range(max(ci - reach, 0), min(ci + reach + 1, dims[0])):
                for j in range(max(cj - reach, 0), min(cj + reach + 1, dims[1])):
                    base = (i * dims[1] + j) * dims[2]
                    first = grid_start[base + max(ck - reach, 0)]
                    last = grid_start[base + min(ck + reach + 1, dims[2])]
                    b0, b1, b2, n = _cell_sources(
                        model,
                        first,
                        last,
                        r2max,
                        X0,
                        X1,
                        X2,
                        N0,
                        N1,
                        N2,
                        W0,
                        W1,
                        W2,
                        px,
                        py,
                        pz,
                        nx,
                        ny,
                        nz,
                        p0,
                        p1,
                        p2,
                        F0,
                        F1,
                        F2,
                    )
                    a0 += b0
                    a1 += b1
                    a2 += b2
                    count += n
            store_three(B, o, c0, n_out, a0, a1, a2)
        evaluated[o] = count


@numba.njit(cache=True, inline="always", fastmath=True)
def _cell_sources(
    model, first, last, r2max, X0, X1, X2, N0, N1, N2, W0, W1, W2, px, py, pz, nx, ny, nz, p0, p1, p2, F0, F1, F2
):
    """Sum over the sources ``first .. last - 1`` within ``sqrt(r2max)`` mm of three channels' clamped
    ``S_d`` times flux at one receiver, and how many were within."""
    a0 = a1 = a2 = 0.0
    count = 0
    for q in range(first, last):
        x0 = px - X0[q]
        x1 = py - X1[q]
        x2 = pz - X2[q]
        inside = x0 * x0 + x1 * x1 + x2 * x2 <= r2max
        e0, e1, e2 = pair_three(model, x0, x1, x2, N0[q], N1[q], N2[q], W0[q], W1[q], W2[q], nx, ny, nz, p0, p1, p2)
        count += inside
        a0 += (max(e0, 0.0) if inside else 0.0) * F0[q]
        a1 += (max(e1, 0.0) if inside else 0.0) * F1[q]
        a2 += (max(e2, 0.0) if inside else 0.0) * F2[q]
    return a0, a1, a2, count
