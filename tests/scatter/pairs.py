"""Single pairs of the kernels' pair function, for the tests: ``S_d`` of one pair or of aligned rows of pairs."""

import numba
import numpy as np

from translucency.scatter import kernels


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
