"""The spread of a cluster's sources about its aggregate, to second order (docs/physics.md §8.3).

A cluster of the ``tree`` walk is evaluated as one source at its flux-weighted centre ``x_c``. The first-order term of
the sum over its sources vanishes there; the second is ``(1/2) Phi tr(H Sigma)``, with ``Sigma`` the flux-weighted
covariance of its positions and ``H`` the Hessian of ``S_d`` in the source's position. ``S_d`` is a sum of radial
functions that decay and bend in the distance, so the term is nearly always positive: without it every cluster
undercounts, and a solve's error is a bias that grows with the scan (bench/README.md, "Every vertex at 10M, by
hand"). For a radial profile ``f(r)`` the Hessian is ``f'' u u^T + (f' / r) (I - u u^T)`` (``u`` the unit offset),
so the sum is the aggregate's ``S_d`` times::

    1 + (1 / (2 r^2)) [(r^2 f''/f) c_along + (r f'/f) c_across],

``c_along = u^T Sigma u`` and ``c_across = tr Sigma - c_along`` (mm^2). The two bends ``r^2 f''/f`` and ``r f'/f``
(dimensionless) are tabulated per channel from the model's profile on a flat surface (the directional dipole at
normal incidence) at the distances of the walk's table (:class:`~translucency.scatter.hierarchy.Opening`).

========= ============================================================== =====
symbol    meaning                                                        unit
========= ============================================================== =====
Sigma     flux-weighted covariance of a cluster's source positions       mm^2
bends     ``r^2 f''/f`` and ``r f'/f`` of the profile, per distance      1
========= ============================================================== =====
"""

from __future__ import annotations

import math

import numba
import numpy as np

from . import dipoles
from .cutoff import coefficients_key, memoised
from .kernels import in_precision_of
from .medium import Medium

#: The factor of a cluster is held within these: a cluster the walk accepts is small next to the profile's bend,
#: except in the first walk, whose sums are only estimates.
FACTOR_RANGE = (0.5, 2.0)


def profile_bends(medium: Medium, model: str, distances) -> np.ndarray:
    """``(C, 4, K)``: per channel, the profile's two bends ``r^2 f''/f`` and ``r f'/f`` (dimensionless) as lines in
    ``r`` (mm) between each of the log-spaced ``distances`` (mm) and the next, ``r^2 f''/f = t[0] + t[1] r`` and
    ``r f'/f = t[2] + t[3] r`` on ``[r_k, r_k+1]`` (the last held beyond), so that a group of receivers finds them at
    its own distance from a cluster with no logarithm (:func:`spread_factor`).

    ``f`` is the directional dipole on a flat surface at normal incidence
    (:func:`~translucency.scatter.dipoles.directional_dipole_profile`) or the radial models' own profile. The bends
    come from ``ln f`` by differences in ``ln r``, ``g1 = d ln f / d ln r`` and ``g2 = d g1 / d ln r``: ``r f'/f =
    g1`` and ``r^2 f''/f = g2 - g1 + g1^2``. Where ``f`` is 0 in double precision (far beyond any pair that adds to
    ``B``), the last distance's bends are held. Memoised on the medium's coefficients, the model and the distances
    (a solve's budget and its walk ask for the same table); the table is shared, not to be written to."""
    r = np.asarray(distances, dtype=np.float64)
    key = (*coefficients_key(medium), str(model), r.size, float(r[0]), float(r[-1]))
    return memoised(_BENDS, key, lambda: _profile_bends(medium, model, r))


_BENDS: dict = {}


def _profile_bends(medium: Medium, model: str, r: np.ndarray) -> np.ndarray:
    """:func:`profile_bends`, made."""
    log_r = np.log(r)
    bends = np.zeros((medium.n_channels, 2, r.size))
    points = np.column_stack([r, np.zeros_like(r)])
    for c in range(medium.n_channels):
        a, s, g, eta = medium.sigma_a[c], medium.sigma_s[c], medium.g[c], medium.eta
        with np.errstate(under="ignore"):
            if model == "directional":
                f = dipoles.directional_dipole_profile(points, 0.0, a, s, g, eta)
            elif model == "standard":
                f = dipoles.standard_dipole_profile(r, a, s, g, eta)
            else:
                f = dipoles.better_dipole_profile(r, a, s, g, eta)
        f = np.asarray(f, dtype=np.float64)
        gone = np.flatnonzero(~(np.isfinite(f) & (f > 0.0)))
        end = int(gone[0]) if gone.size else r.size  # f is a number from the first distance to here
        if end < 3:
            continue
        g1 = np.gradient(np.log(f[:end]), log_r[:end])
        g2 = np.gradient(g1, log_r[:end])
        bends[c, 0, :end] = g2 - g1 + g1 * g1
        bends[c, 1, :end] = g1
        bends[c, :, end:] = bends[c, :, end - 1 : end]
    lines = np.zeros((medium.n_channels, 4, r.size))
    slope = np.zeros_like(bends)
    slope[:, :, :-1] = np.diff(bends, axis=2) / np.diff(r)
    lines[:, 0::2] = bends - slope * r
    lines[:, 1::2] = slope
    return lines


@numba.njit(cache=True, inline="always", fastmath=True)
def spread_factor(x0, x1, x2, spread, trace, lines):
    """The sum over a cluster's sources over its aggregate's ``S_d``, to second order (the module's equation), at the
    offset ``x = x_o - x_c`` (mm) from its flux-weighted centre: ``spread`` its covariance ``xx, yy, zz, xy, xz, yz``
    and ``trace`` its trace (mm^2), ``lines`` the profile's bends near ``r = |x|`` (four numbers, a column of
    :func:`profile_bends`). Held within :data:`FACTOR_RANGE`; 1 at ``x = 0`` (no cluster is that near)."""
    one = in_precision_of(1.0, x0)
    r2 = x0 * x0 + x1 * x1 + x2 * x2
    inv_r2 = one / r2 if r2 > in_precision_of(0.0, x0) else in_precision_of(0.0, x0)  # at the centre: 1
    r = math.sqrt(r2)
    c_along = (
        spread[0] * x0 * x0
        + spread[1] * x1 * x1
        + spread[2] * x2 * x2
        + in_precision_of(2.0, x0) * (spread[3] * x0 * x1 + spread[4] * x0 * x2 + spread[5] * x1 * x2)
    ) * inv_r2
    along = lines[0] + lines[1] * r
    across = lines[2] + lines[3] * r
    factor = one + in_precision_of(0.5, x0) * inv_r2 * (along * c_along + across * (trace - c_along))
    return min(max(factor, in_precision_of(FACTOR_RANGE[0], x0)), in_precision_of(FACTOR_RANGE[1], x0))
