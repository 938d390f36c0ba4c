"""Single pairs of the kernels' pair function, for the tests: ``S_d`` of one pair or of aligned rows of pairs, and
the relighting fits of one pair (:func:`fitted_pairs`, the reference the package's runs of fits are checked against)."""

import math

import numba
import numpy as np

from translucency.scatter import fits, kernels
from translucency.scatter.dipoles import D_R_FLOOR
from translucency.scatter.kernels import (
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
    modified_normal,
    orthonormal_frame,
    radial_dipole,
)


@numba.njit(cache=True)
def directional_dipole_pair(xi0, xi1, xi2, ni0, ni1, ni2, w0, w1, w2, xo0, xo1, xo2, no0, no1, no2, params, out):
    """:func:`translucency.scatter.kernels.model_pair` of the directional dipole (FHK14); returns the clamp count."""
    return kernels.model_pair(
        kernels.MODEL_DIRECTIONAL, xi0, xi1, xi2, ni0, ni1, ni2, w0, w1, w2, xo0, xo1, xo2, no0, no1, no2, params, out
    )


@numba.njit(cache=True)
def model_pairs(model, x_i, n_i, w12, x_o, n_o, params):
    """``S_d`` for aligned rows of pairs: ``out[p, k]`` for pair ``p`` and channel ``k``."""
    n = x_i.shape[0]
    out = np.empty((n, params.shape[0]))
    for p in range(n):
        kernels.model_pair(
            model,
            x_i[p, 0],
            x_i[p, 1],
            x_i[p, 2],
            n_i[p, 0],
            n_i[p, 1],
            n_i[p, 2],
            w12[p, 0],
            w12[p, 1],
            w12[p, 2],
            x_o[p, 0],
            x_o[p, 1],
            x_o[p, 2],
            n_o[p, 0],
            n_o[p, 1],
            n_o[p, 2],
            params,
            out[p],
        )
    return out


@numba.njit(cache=True, inline="always", fastmath=True)
def _affine_source(x0, x1, x2, x_dot_n, n0, n1, n2, d, p):
    """``S'_d`` of one ray source of distance ``d`` (mm) as ``a + b . w`` (docs/physics.md §4.4 rearranged,
    §8.7): returns ``(a, b0, b1, b2)`` for the offset ``x`` to the exit point and the receiver normal ``n``,
    the channel's parameters the row ``p``."""
    return fits._affine_terms(
        x0, x1, x2, x_dot_n, n0, n1, n2, d, p[P_D], p[P_SIGMA_TR], p[P_NORM] / FOUR_PI_SQUARED, p[P_C_PHI], p[P_C_E]
    )


#: Columns of :func:`fitted_pairs`' scratch space (per direction: w, mu0, x.w, distance, value, fit).
FIT_WORK_COLUMNS = 8


@numba.njit(cache=True, fastmath=True)
def fitted_pairs(model, x0, x1, x2, ni0, ni1, ni2, no0, no1, no2, params, dirs, pinv, work, out):
    """Coefficients of ``S_d(x_i, w; x_o)`` as a function of the refracted direction ``w`` (unclamped;
    docs/physics.md §8.7) for every channel (rows of ``params``) and the offset ``x = x_o - x_i`` (mm):
    ``a + b . w`` (``pinv`` of ``AFFINE_TERMS``) or ``a + b . w + w^T Q w`` (``QUADRATIC_TERMS``),
    the least-squares fit over the directions of :func:`~translucency.scatter.fits.fit_directions` turned into the
    frame of ``n_i``. The per-pair definition the package's runs (:func:`~translucency.scatter.fits.fitted_run`,
    :func:`~translucency.scatter.fits.fitted_points`) must equal, one pair at a time.

    The virtual source is affine in ``w`` and goes in exactly; the real source depends on ``w`` also through
    its corrected distance ``d_r(w)`` (§4.3), evaluated at each direction (one evaluation at a middle distance is
    not enough even far away, where the real and the virtual source nearly cancel and a small error in the real
    source is a large one in their difference). The geometry is
    shared by the channels. ``work`` is scratch space, ``(max(len(dirs), 9), FIT_WORK_COLUMNS)`` float64 (no
    allocation here: this runs once per operator entry). Written to ``out[c]``: ``a, b0, b1, b2`` then ``Q00,
    Q11, Q22, 2 Q01, 2 Q02, 2 Q12`` (the coefficients of ``1, w_x, w_y, w_z, w_x^2, w_y^2, w_z^2, w_x w_y, w_x
    w_z, w_y w_z``), 1/(mm^2 sr). The radial models: ``a = S_d(r)``, the rest 0."""
    n_terms = pinv.shape[0]
    n_c = params.shape[0]
    r2, s0, s1, s2 = modified_normal(x0, x1, x2, ni0, ni1, ni2)
    for c in range(n_c):
        for k in range(out.shape[1]):
            out[c, k] = 0.0
    if model != MODEL_DIRECTIONAL:
        for c in range(n_c):
            out[c, 0] = radial_dipole(model, r2, params[c])
        return
    x_dot_n = x0 * no0 + x1 * no1 + x2 * no2
    x_dot_s = x0 * s0 + x1 * s1 + x2 * s2
    s_dot_n = s0 * no0 + s1 * no1 + s2 * no2
    # a frame (e, f, n_i) about the source normal, and each direction's cosines
    e0, e1, e2, f0, f1, f2 = orthonormal_frame(ni0, ni1, ni2)
    n_dirs = dirs.shape[0]
    for k in range(n_dirs):
        w0 = dirs[k, 0] * e0 + dirs[k, 1] * f0 + dirs[k, 2] * ni0
        w1 = dirs[k, 0] * e1 + dirs[k, 1] * f1 + dirs[k, 2] * ni1
        w2 = dirs[k, 0] * e2 + dirs[k, 1] * f2 + dirs[k, 2] * ni2
        work[k, 0] = w0
        work[k, 1] = w1
        work[k, 2] = w2
        work[k, 3] = -(no0 * w0 + no1 * w1 + no2 * w2)  # mu0
        xw = x0 * w0 + x1 * w1 + x2 * w2
        work[k, 4] = max(r2 - xw * xw, 0.0)  # squared distance from the ray's line
    axes = ((e0, e1, e2), (f0, f1, f2), (ni0, ni1, ni2))
    for c in range(n_c):
        p = params[c]
        D = p[P_D]
        d_e = p[P_D_E]
        backlit = p[P_BACKLIT]
        floor = D_R_FLOOR * D
        # the virtual source: offset x - c n*, direction w mirrored in the plane of n* (section 4.2)
        height = p[P_VIRTUAL]
        d_v = max(math.sqrt(max(r2 - 2.0 * height * x_dot_s + height * height, 0.0)), floor)
        a_v, bv0, bv1, bv2 = _affine_source(
            x0 - height * s0, x1 - height * s1, x2 - height * s2, x_dot_n - height * s_dot_n, no0, no1, no2, d_v, p
        )
        mirror = 2.0 * (bv0 * s0 + bv1 * s1 + bv2 * s2)  # M b_v = b_v - 2 (n* . b_v) n*
        # the real source's distance at each direction (section 4.3)
        for k in range(n_dirs):
            mu0 = work[k, 3]
            if mu0 > 0.0:
                cos_beta = -math.sqrt(work[k, 4] / (r2 + d_e * d_e))
                d_r2 = r2 + D * mu0 * (D * mu0 - 2.0 * d_e * cos_beta)
            else:
                d_r2 = r2 + backlit * backlit
            a = _affine_source(x0, x1, x2, x_dot_n, no0, no1, no2, max(math.sqrt(d_r2), floor), p)
            work[k, 6] = a[0] + a[1] * work[k, 0] + a[2] * work[k, 1] + a[3] * work[k, 2]
        for j in range(n_terms):
            total = 0.0
            for k in range(n_dirs):
                total += pinv[j, k] * work[k, 6]
            work[j, 7] = total
        # from the frame's monomials to global ones, less the virtual source
        out[c, 0] = work[0, 7] - a_v
        out[c, 1] = e0 * work[1, 7] + f0 * work[2, 7] + ni0 * work[3, 7] - (bv0 - mirror * s0)
        out[c, 2] = e1 * work[1, 7] + f1 * work[2, 7] + ni1 * work[3, 7] - (bv1 - mirror * s1)
        out[c, 3] = e2 * work[1, 7] + f2 * work[2, 7] + ni2 * work[3, 7] - (bv2 - mirror * s2)
        if n_terms == fits.AFFINE_TERMS:
            continue
        # Q = R Ql R^T with R's columns (e, f, n_i), Ql the local quadratic form (no z^2 term)
        q_xx, q_yy, q_xy, q_xz, q_yz = work[4, 7], work[5, 7], 0.5 * work[6, 7], 0.5 * work[7, 7], 0.5 * work[8, 7]
        ql = ((q_xx, q_xy, q_xz), (q_xy, q_yy, q_yz), (q_xz, q_yz, 0.0))
        for at, i, j, factor in (
            (4, 0, 0, 1.0),
            (5, 1, 1, 1.0),
            (6, 2, 2, 1.0),
            (7, 0, 1, 2.0),
            (8, 0, 2, 2.0),
            (9, 1, 2, 2.0),
        ):
            total = 0.0
            for k in range(3):
                for m in range(3):
                    total += axes[k][i] * ql[k][m] * axes[m][j]
            out[c, at] = factor * total
