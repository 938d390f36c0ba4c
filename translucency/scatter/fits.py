"""Fits of the diffusive BSSRDF in the refracted direction, for relighting (docs/physics.md §8.7).

``S_d(x_i, w12; x_o)`` depends on the direction ``w12`` the light takes into the medium through a few linear
terms and through the real source's corrected distance ``d_r(w12)`` (§4.3). Relighting stores, per pair,
the least-squares fit of ``S_d`` over the directions light from outside can take inside: affine, ``a + b .
w12`` (:data:`AFFINE_TERMS` per channel; the far field), or with the quadratic terms too
(:data:`QUADRATIC_TERMS`; the near field). :func:`fitted_run` fits a run of pairs that share one end (a row or a
column of the far field's matrix) and :func:`fitted_points` a batch of the near field's quadrature points, a step
at a time, so that each step vectorises (the tests check both against the fit of one pair at a time).

=========== ==================================================================== ==============
symbol      meaning                                                              unit
=========== ==================================================================== ==============
a           ``S_d`` at ``w12 = 0`` of the fit, per channel                        1/(mm^2 sr)
b           its gradient in ``w12``                                               1/(mm^2 sr)
Q           the quadratic form of the near field's fit                            1/(mm^2 sr)
=========== ==================================================================== ==============
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .dipoles import D_R_FLOOR
from .kernels import (
    FOUR_PI_SQUARED,
    MODEL_DIRECTIONAL,
    P_BACKLIT,
    P_C_E,
    P_C_PHI,
    P_D,
    P_D_E,
    P_NORM,
    P_SIGMA_TR,
    P_VIRTUAL,
    exp_nonpositive,
    modified_normal,
    orthonormal_frame,
    radial_dipole,
)

__all__ = [
    "AFFINE_TERMS",
    "QUADRATIC_TERMS",
    "fit_directions",
    "fitted_block",
    "fitted_run",
    "fitted_points",
    "run_scratch",
]


#: Coefficients per channel of a far-field relighting entry: ``a`` and ``b`` (3), ``S_d ~ a + b . w12``.
AFFINE_TERMS = 4
#: ... of a near-field entry: also the quadratic terms ``w_x^2, w_y^2, w_z^2, w_x w_y, w_x w_z, w_y w_z`` (6).
QUADRATIC_TERMS = 10


def fit_directions(eta: float, terms: int):
    """Sample directions and least-squares matrix of the fits: ``(dirs (K, 3), pinv)``.

    The directions are refracted directions ``w12`` in the frame of the source normal (``z`` = outward
    normal, so ``w_z < 0``): straight in, and six azimuths at the critical angle ``asin(1 / eta)`` (every
    refracted direction of light from outside lies in that cone), and for the quadratic fit six more at half
    of it (K = 7 or 13). ``pinv`` maps
    ``S_d`` at them to the coefficients of ``1, w_x, w_y, w_z`` (``terms`` = :data:`AFFINE_TERMS`), and of
    ``w_x^2, w_y^2, w_x w_y, w_x w_z, w_y w_z`` too (:data:`QUADRATIC_TERMS`; ``w_z^2 = 1 - w_x^2 - w_y^2``
    on the sphere), in that frame."""
    critical = math.asin(min(1.0, 1.0 / float(eta)))
    dirs = [(0.0, 0.0, -1.0)]
    rings = ((0.5 * critical, math.pi / 6.0), (critical, 0.0)) if terms == QUADRATIC_TERMS else ((critical, 0.0),)
    for polar, turn in rings:
        for k in range(6):
            azimuth = k * math.pi / 3.0 + turn
            dirs.append((math.sin(polar) * math.cos(azimuth), math.sin(polar) * math.sin(azimuth), -math.cos(polar)))
    dirs = np.array(dirs)
    x, y, z = dirs.T
    columns = [np.ones_like(x), x, y, z]
    if terms == QUADRATIC_TERMS:
        columns += [x * x, y * y, x * y, x * z, y * z]
    return dirs, np.ascontiguousarray(np.linalg.pinv(np.stack(columns, axis=1)))


@numba.njit(cache=True, fastmath=True)
def _affine_parts(x_dot_n, d, D, sigma_tr_, scale, C_phi, C_E):
    """``S'_d`` of one ray source of distance ``d`` (mm) as ``a + b . w`` with ``b = along_x x + along_n n``
    (docs/physics.md §4.4 rearranged, §8.7): ``(a, along_x, along_n)`` for the offset ``x`` to the exit point and the
    receiver normal ``n`` (``x_dot_n`` their dot product), with the channel's parameters as numbers (``scale = norm /
    (4 pi^2)``): a loop over pairs that reads them before it starts vectorises, one that reads them from an array in
    every pass did not."""
    s = sigma_tr_ * d
    one_plus_s = 1.0 + s
    inv_d = 1.0 / d
    k = scale * exp_nonpositive(-s) * inv_d * inv_d * inv_d
    a = k * (C_phi * d * d / D + C_E * one_plus_s * x_dot_n)
    along_x = k * (3.0 * C_phi * one_plus_s + 3.0 * C_E * D * (3.0 * one_plus_s + s * s) * x_dot_n * inv_d * inv_d)
    along_n = -k * 3.0 * C_E * D * one_plus_s
    return a, along_x, along_n


@numba.njit(cache=True, fastmath=True)
def _affine_terms(x0, x1, x2, x_dot_n, n0, n1, n2, d, D, sigma_tr_, scale, C_phi, C_E):
    """:func:`_affine_parts` as ``(a, b0, b1, b2)``: ``b = along_x x + along_n n``."""
    a, along_x, along_n = _affine_parts(x_dot_n, d, D, sigma_tr_, scale, C_phi, C_E)
    return a, along_x * x0 + along_n * n0, along_x * x1 + along_n * n1, along_x * x2 + along_n * n2


# rows of the run's scratch arrays (one array per step's output: a loop that writes one array and reads others
# vectorises, one that writes rows of an array it also reads may not)
_X0, _X1, _X2, _NI0, _NI1, _NI2, _NO0, _NO1, _NO2 = range(9)  # the pairs
_R2, _S0, _S1, _S2, _XN, _XS, _SN, _E0, _E1, _E2, _F0, _F1, _F2 = range(13)  # their geometry
_VA, _VB0, _VB1, _VB2, _INVERSE = range(5)  # the virtual source's a, b; 1 / (r^2 + d_e^2)
#: Coefficients of the quadratic fit in the source's frame: ``1, w_x, w_y, w_z, w_x^2, w_y^2, w_x w_y, w_x w_z,
#: w_y w_z`` (:func:`fit_directions`).
LOCAL_QUADRATIC_TERMS = 9


@numba.njit(cache=True)
def run_scratch(directions, length):
    """Scratch space of :func:`fitted_run` and :func:`fitted_points` for ``directions`` fit directions and up to
    ``length`` pairs: a tuple of arrays (the pairs' offsets and normals are the rows of the first, see
    :func:`fitted_points`), their rows a little longer than the run and an odd number of cache lines long (rows
    a power of two apart in memory compete for the same cache sets, which made runs of 512 three times
    slower)."""
    width = (length // 8 + 1) // 2 * 16 + 8
    return (
        np.empty((9, width)),
        np.empty((13, width)),
        np.empty((5, width)),
        np.empty((directions, width)),
        np.empty((LOCAL_QUADRATIC_TERMS, width)),
        np.empty((2 * directions, width)),
    )


@numba.njit(cache=True, fastmath=True, nogil=True, error_model="numpy")
def _gathered(P, N, fixed, lo, length, sources_vary, pair):
    """:func:`fitted_run`'s pairs into the rows of ``pair``: offsets ``x_o - x_i`` (mm) and both normals."""
    for q in range(length):
        o = fixed if sources_vary else lo + q
        i = lo + q if sources_vary else fixed
        for t in range(3):
            pair[_X0 + t, q] = P[o, t] - P[i, t]
            pair[_NI0 + t, q] = N[i, t]
            pair[_NO0 + t, q] = N[o, t]


@numba.njit(cache=True, fastmath=True, nogil=True, error_model="numpy")
def _run_geometry(length, pair, geo):
    """The channel-independent geometry of a run's pairs into the rows of ``geo``: ``r^2``, ``n_i*`` (§4.1), the
    dot products, and the frame ``(e, f, n_i)`` the fit's directions are given in.

    Three loops, each writing a few rows: one loop writing all thirteen did not vectorise (the compiler checks, at
    run time, every row it writes against every row it reads, and gives up past a few such checks; bench/README.md,
    "The preparation, 7 December 2026 (night)")."""
    for q in range(length):
        r2, s0, s1, s2 = modified_normal(
            pair[_X0, q], pair[_X1, q], pair[_X2, q], pair[_NI0, q], pair[_NI1, q], pair[_NI2, q]
        )
        geo[_R2, q] = r2
        geo[_S0, q] = s0
        geo[_S1, q] = s1
        geo[_S2, q] = s2
    for q in range(length):
        x0, x1, x2 = pair[_X0, q], pair[_X1, q], pair[_X2, q]
        n0, n1, n2 = pair[_NO0, q], pair[_NO1, q], pair[_NO2, q]
        s0, s1, s2 = geo[_S0, q], geo[_S1, q], geo[_S2, q]
        geo[_XN, q] = x0 * n0 + x1 * n1 + x2 * n2
        geo[_XS, q] = x0 * s0 + x1 * s1 + x2 * s2
        geo[_SN, q] = s0 * n0 + s1 * n1 + s2 * n2
    for q in range(length):
        e0, e1, e2, f0, f1, f2 = orthonormal_frame(pair[_NI0, q], pair[_NI1, q], pair[_NI2, q])
        geo[_E0, q] = e0
        geo[_E1, q] = e1
        geo[_E2, q] = e2
        geo[_F0, q] = f0
        geo[_F1, q] = f1
        geo[_F2, q] = f2


@numba.njit(cache=True, fastmath=True, nogil=True, error_model="numpy")
def _run_channel(p, dirs, pinv, length, scratch, out):
    """The fits of one channel (parameters ``p``) of a run's pairs into ``out (length, terms)``, each step one loop
    over the run: the virtual source, the corrected distances (with
    ``x . w`` and ``n_o . w`` at each direction, kept for the next step), ``S_d`` at each direction (the real source
    evaluated at each direction's distance), the least-squares fit, and its terms in global coordinates
    (:data:`AFFINE_TERMS`, or :data:`QUADRATIC_TERMS` when ``pinv`` has :data:`LOCAL_QUADRATIC_TERMS` rows)."""
    pair, geo, virtual, dist, coef, along = scratch
    n_dirs = dirs.shape[0]
    D = p[P_D]
    d_e = p[P_D_E]
    backlit2 = p[P_BACKLIT] * p[P_BACKLIT]
    floor = D_R_FLOOR * D
    height = p[P_VIRTUAL]
    sigma_tr_, scale, C_phi, C_E = p[P_SIGMA_TR], p[P_NORM] / FOUR_PI_SQUARED, p[P_C_PHI], p[P_C_E]
    for q in range(length):  # the virtual source, exactly affine in w (section 4.2)
        s0, s1, s2 = geo[_S0, q], geo[_S1, q], geo[_S2, q]
        d_v = max(math.sqrt(max(geo[_R2, q] - 2.0 * height * geo[_XS, q] + height * height, 0.0)), floor)
        a_v, bv0, bv1, bv2 = _affine_terms(
            pair[_X0, q] - height * s0, pair[_X1, q] - height * s1, pair[_X2, q] - height * s2,
            geo[_XN, q] - height * geo[_SN, q], pair[_NO0, q], pair[_NO1, q], pair[_NO2, q], d_v,
            D, sigma_tr_, scale, C_phi, C_E,
        )  # fmt: skip
        mirror = 2.0 * (bv0 * s0 + bv1 * s1 + bv2 * s2)
        virtual[_VA, q] = a_v
        virtual[_VB0, q] = bv0 - mirror * s0
        virtual[_VB1, q] = bv1 - mirror * s1
        virtual[_VB2, q] = bv2 - mirror * s2
        virtual[_INVERSE, q] = 1.0 / (geo[_R2, q] + d_e * d_e)
    for k in range(n_dirs):  # the real source's corrected distance at each direction (section 4.3)
        u0, u1, u2 = dirs[k, 0], dirs[k, 1], dirs[k, 2]
        for q in range(length):
            w0 = u0 * geo[_E0, q] + u1 * geo[_F0, q] + u2 * pair[_NI0, q]
            w1 = u0 * geo[_E1, q] + u1 * geo[_F1, q] + u2 * pair[_NI1, q]
            w2 = u0 * geo[_E2, q] + u1 * geo[_F2, q] + u2 * pair[_NI2, q]
            r2 = geo[_R2, q]
            mu0 = -(pair[_NO0, q] * w0 + pair[_NO1, q] * w1 + pair[_NO2, q] * w2)
            xw = pair[_X0, q] * w0 + pair[_X1, q] * w1 + pair[_X2, q] * w2
            cos_beta = -math.sqrt(max(r2 - xw * xw, 0.0) * virtual[_INVERSE, q])
            front = r2 + D * mu0 * (D * mu0 - 2.0 * d_e * cos_beta)
            dist[k, q] = max(math.sqrt(front if mu0 > 0.0 else r2 + backlit2), floor)
            along[k, q] = xw
            along[n_dirs + k, q] = mu0
    for k in range(n_dirs):  # S_d's real source at each direction, in place of its distance
        for q in range(length):
            a, along_x, along_n = _affine_parts(geo[_XN, q], dist[k, q], D, sigma_tr_, scale, C_phi, C_E)
            dist[k, q] = (
                a + along_x * along[k, q] - along_n * along[n_dirs + k, q]
            )  # b . w, b = along_x x + along_n n_o
    if pinv.shape[0] == AFFINE_TERMS and n_dirs == 7:
        _affine_fit(pinv, length, dist, coef)
    else:
        for j in range(pinv.shape[0]):  # the least-squares fit over the directions
            for q in range(length):
                coef[j, q] = 0.0
            for k in range(n_dirs):
                g = pinv[j, k]
                for q in range(length):
                    coef[j, q] += g * dist[k, q]
    for q in range(length):  # from the source's frame to global coordinates, less the virtual source
        c1, c2, c3 = coef[1, q], coef[2, q], coef[3, q]
        out[q, 0] = coef[0, q] - virtual[_VA, q]
        out[q, 1] = geo[_E0, q] * c1 + geo[_F0, q] * c2 + pair[_NI0, q] * c3 - virtual[_VB0, q]
        out[q, 2] = geo[_E1, q] * c1 + geo[_F1, q] * c2 + pair[_NI1, q] * c3 - virtual[_VB1, q]
        out[q, 3] = geo[_E2, q] * c1 + geo[_F2, q] * c2 + pair[_NI2, q] * c3 - virtual[_VB2, q]
    if pinv.shape[0] == LOCAL_QUADRATIC_TERMS:
        _global_quadratic(length, pair, geo, coef, out)


@numba.njit(cache=True, fastmath=True, nogil=True, error_model="numpy")
def _affine_fit(pinv, length, dist, coef):
    """The affine least-squares fit over seven directions in one loop over the run (its 28 weights read before it):
    thirty-two loops of a step each cost more to start than a run of 50 pairs takes in them."""
    g00, g01, g02, g03, g04, g05, g06 = (
        pinv[0, 0],
        pinv[0, 1],
        pinv[0, 2],
        pinv[0, 3],
        pinv[0, 4],
        pinv[0, 5],
        pinv[0, 6],
    )
    g10, g11, g12, g13, g14, g15, g16 = (
        pinv[1, 0],
        pinv[1, 1],
        pinv[1, 2],
        pinv[1, 3],
        pinv[1, 4],
        pinv[1, 5],
        pinv[1, 6],
    )
    g20, g21, g22, g23, g24, g25, g26 = (
        pinv[2, 0],
        pinv[2, 1],
        pinv[2, 2],
        pinv[2, 3],
        pinv[2, 4],
        pinv[2, 5],
        pinv[2, 6],
    )
    g30, g31, g32, g33, g34, g35, g36 = (
        pinv[3, 0],
        pinv[3, 1],
        pinv[3, 2],
        pinv[3, 3],
        pinv[3, 4],
        pinv[3, 5],
        pinv[3, 6],
    )
    for q in range(length):
        d0, d1, d2, d3 = dist[0, q], dist[1, q], dist[2, q], dist[3, q]
        d4, d5, d6 = dist[4, q], dist[5, q], dist[6, q]
        coef[0, q] = g00 * d0 + g01 * d1 + g02 * d2 + g03 * d3 + g04 * d4 + g05 * d5 + g06 * d6
        coef[1, q] = g10 * d0 + g11 * d1 + g12 * d2 + g13 * d3 + g14 * d4 + g15 * d5 + g16 * d6
        coef[2, q] = g20 * d0 + g21 * d1 + g22 * d2 + g23 * d3 + g24 * d4 + g25 * d5 + g26 * d6
        coef[3, q] = g30 * d0 + g31 * d1 + g32 * d2 + g33 * d3 + g34 * d4 + g35 * d5 + g36 * d6


@numba.njit(cache=True, fastmath=True, nogil=True, error_model="numpy")
def _global_quadratic(length, pair, geo, coef, out):
    """The quadratic terms of each pair's fit in global coordinates: ``Q = R Q_l R^T`` with ``R``'s columns the
    frame ``(e, f, n_i)`` and ``Q_l`` the local form (no ``w_z^2`` term, ``w_z^2 = 1 - w_x^2 - w_y^2``), written
    as ``Q00, Q11, Q22, 2 Q01, 2 Q02, 2 Q12`` (the order of :data:`QUADRATIC_TERMS`)."""
    for q in range(length):
        xx, yy, xy, xz, yz = coef[4, q], coef[5, q], 0.5 * coef[6, q], 0.5 * coef[7, q], 0.5 * coef[8, q]
        # rows of R (global axis i): (e_i, f_i, n_i); Q_ij = r_i . Q_l r_j
        e0, e1, e2 = geo[_E0, q], geo[_E1, q], geo[_E2, q]
        f0, f1, f2 = geo[_F0, q], geo[_F1, q], geo[_F2, q]
        n0, n1, n2 = pair[_NI0, q], pair[_NI1, q], pair[_NI2, q]
        m00, m01, m02 = xx * e0 + xy * f0 + xz * n0, xy * e0 + yy * f0 + yz * n0, xz * e0 + yz * f0  # Q_l r_0
        m10, m11, m12 = xx * e1 + xy * f1 + xz * n1, xy * e1 + yy * f1 + yz * n1, xz * e1 + yz * f1  # Q_l r_1
        m20, m21, m22 = xx * e2 + xy * f2 + xz * n2, xy * e2 + yy * f2 + yz * n2, xz * e2 + yz * f2  # Q_l r_2
        out[q, 4] = e0 * m00 + f0 * m01 + n0 * m02
        out[q, 5] = e1 * m10 + f1 * m11 + n1 * m12
        out[q, 6] = e2 * m20 + f2 * m21 + n2 * m22
        out[q, 7] = 2.0 * (e0 * m10 + f0 * m11 + n0 * m12)
        out[q, 8] = 2.0 * (e0 * m20 + f0 * m21 + n0 * m22)
        out[q, 9] = 2.0 * (e1 * m20 + f1 * m21 + n1 * m22)


@numba.njit(cache=True, fastmath=True, nogil=True, error_model="numpy")
def fitted_run(model, P, N, fixed, lo, hi, sources_vary, params, dirs, pinv, scratch, out):
    """The affine fits (:data:`AFFINE_TERMS`; docs/physics.md §8.7) of a run of pairs that share one end, written to
    ``out[q, c, :]`` for every channel ``c`` (rows of ``params``): receiver ``fixed`` and sources ``lo + q``
    (``sources_vary``; a row of the far field's matrix), or source ``fixed`` and receivers ``lo + q`` (a column);
    ``P``, ``N`` the points (mm) and unit normals; ``scratch`` is :func:`run_scratch`'s for at least ``hi - lo``
    pairs.

    The fits of each pair alone (to rounding; the tests check them one pair at a time), computed a step at a time
    over the whole run so that each step is one loop the compiler vectorises: the geometry, the virtual source, the
    corrected distance at every direction and the real source at it, the fit (:func:`fitted_points`' steps)."""
    length = hi - lo
    _gathered(P, N, fixed, lo, length, sources_vary, scratch[0])
    fitted_points(model, length, params, dirs, pinv, scratch, out)


@numba.njit(cache=True, fastmath=True, nogil=True, error_model="numpy")
def fitted_block(model, P, N, r0, r1, c0, c1, params, dirs, pinv, scratch, out):
    """The affine fits of every pair of a block, receivers ``r0 .. r1 - 1`` and sources ``c0 .. c1 - 1``, in one run
    (:func:`fitted_points`; a run a row was too short a loop to vectorise well): receiver ``r0 + a`` and source ``c0 +
    b`` written to ``out[a (c1 - c0) + b, c, :]`` for every channel ``c`` (rows of ``params``); ``scratch`` is
    :func:`run_scratch`'s for at least ``(r1 - r0) (c1 - c0)`` pairs."""
    sources = c1 - c0
    for a in range(r1 - r0):
        _gathered(P, N, r0 + a, c0, sources, True, scratch[0][:, a * sources :])
    fitted_points(model, (r1 - r0) * sources, params, dirs, pinv, scratch, out)


@numba.njit(cache=True, fastmath=True, nogil=True, error_model="numpy")
def fitted_points(model, length, params, dirs, pinv, scratch, out):
    """The fits (affine or quadratic, by ``pinv`` of :func:`fit_directions`) of ``length`` pairs already written
    into the first array of ``scratch`` (:func:`run_scratch`): row ``t`` of it the offsets ``x_o - x_i`` (mm, rows
    0-2), the source normals (3-5) and the receiver normals (6-8), column ``q`` the pair; written to ``out[q, c,
    :]`` for every channel (rows of ``params``), a step at a time over the pairs. The real source is evaluated at
    each direction's corrected distance."""
    if _directional_run(model, length, params, scratch, out):
        _run_geometry(length, scratch[0], scratch[1])
        for c in range(params.shape[0]):
            _run_channel(params[c], dirs, pinv, length, scratch, out[:, c, :])


@numba.njit(cache=True, fastmath=True, nogil=True, error_model="numpy")
def _directional_run(model, length, params, scratch, out) -> bool:
    """The start of a run's fits: for the directional dipole nothing (True: the geometry and the channels are to
    come), for the radial models the whole of them (False)."""
    if model != MODEL_DIRECTIONAL:
        _radial_run(model, length, params, scratch[0], out)
        return False
    return True


@numba.njit(cache=True, fastmath=True, nogil=True, error_model="numpy")
def _radial_run(model, length, params, pair, out):
    """The radial models' fits of a run's pairs: ``a = S_d(r)``, every other term 0."""
    for c in range(params.shape[0]):
        for q in range(length):
            r2 = pair[_X0, q] * pair[_X0, q] + pair[_X1, q] * pair[_X1, q] + pair[_X2, q] * pair[_X2, q]
            out[q, c, 0] = radial_dipole(model, r2, params[c])
            for t in range(1, out.shape[2]):
                out[q, c, t] = 0.0
