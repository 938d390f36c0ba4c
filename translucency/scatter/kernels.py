"""numba kernels for the sums over source/receiver pairs (the hot loops of the solver).

The directional dipole of :mod:`translucency.scatter.dipoles` restated for one pair and several
colour channels at once: the geometry (``x``, ``r``, ``n_i*``, ``w_v``, the dot products) is computed
once per pair and shared by the channels; only the radial functions are per channel. One pair
function (:func:`_lane`, a model index argument) serves every model, and one kernel each traversal
(every pair, the cutoff grid, index lists), compiled without ``parallel=True`` and run on threads
(:mod:`translucency.threads`). Every kernel is tested against the float64 reference
(relative 1e-12). The pair functions compute in the precision they are handed
(:func:`in_precision_of`): the tree's sums of its lists
(:func:`translucency.scatter.listsums.grouped_sum`) may take float32 (tested to 5e-5), every
other kernel float64.

Inlining: numba's own (``inline="always"``) copies a function's IR into every call and types it again there, which
made most of the set-up's compilation (the pair functions nest four deep). It is kept where a loop would not
vectorise without it (the pair's geometry and channels, which return many values, and the loops over sources); the
leaves (:func:`exp_nonpositive`, :func:`_ray_source`, :func:`modified_normal`, :func:`radial_dipole`, the constants'
overloads) are plain compiled functions, which LLVM inlines as it optimises (bench/README.md, "First run").
numba also compiles a function once per constant it is handed (``True``, ``0``) and per array layout, so the kernels
hand each other values (``np.bool_(True)``, ``np.int64(0)``) and contiguous arrays. A function called from a
fast-math kernel is compiled with fast math, whatever its own flags, and cached so (a direct call then gets that
version too): a test for NaN there may be taken as false, so one that matters reads the bits (as the far field's
recompression does, :mod:`translucency.scatter.crosses`).

Channel parameters travel as a ``(K, N_PARAMS)`` float64 array built by :func:`channel_parameters`;
the columns are named by the ``P_*`` constants. Kernels never validate: the solver does, at its
boundary.

=============== =============================================================== =====
symbol          meaning                                                         unit
=============== =============================================================== =====
P_D             diffusion coefficient D = 1 / (3 sigma_t')                      mm
P_SIGMA_TR      effective transport coefficient                                 1/mm
P_D_E           extrapolation distance d_e                                      mm
P_VIRTUAL       virtual source height 2 A d_e                                   mm
P_C_PHI         C_phi(eta)                                                      1
P_C_E           C_E(eta)                                                        1
P_NORM          1 / (4 C_phi(1/eta))                                            1
P_BACKLIT       backlit depth 1 / (3 sigma_t), unreduced sigma_t                mm
=============== =============================================================== =====
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import types
from numba.extending import overload

from ..threads import for_ranges
from . import fresnel, names
from .dipoles import D_R_FLOOR, PARALLEL_TOLERANCE
from .medium import alpha_reduced, diffusion_coefficient, extrapolation_distance, sigma_t, sigma_t_reduced, sigma_tr

P_D, P_SIGMA_TR, P_D_E, P_VIRTUAL, P_C_PHI, P_C_E, P_NORM, P_BACKLIT = range(8)
N_PARAMS = 8
# radial models (standard, better dipole) reuse the columns: z_r, z_v, sigma_tr, scale, D, C_phi, C_E
R_Z_R, R_Z_V, R_SIGMA_TR, R_SCALE, R_D, R_C_PHI, R_C_E = range(7)

MODEL_DIRECTIONAL, MODEL_STANDARD, MODEL_BETTER = 0, 1, 2
MODELS = dict(zip(names.MODELS, (MODEL_DIRECTIONAL, MODEL_STANDARD, MODEL_BETTER)))  # name -> code
FOUR_PI_SQUARED = 4.0 * math.pi * math.pi
#: 1 / k! for k = 0 .. 10: the Taylor polynomial of :func:`exp_nonpositive`.
INVERSE_FACTORIALS = tuple(1.0 / math.factorial(k) for k in range(11))
#: :func:`exp_reduction` in float64 and in float32.
EXP_REDUCTION_64 = (-746.0, 1.0 / 4096.0, 12, INVERSE_FACTORIALS)
EXP_REDUCTION_32 = (np.float32(-104.0), np.float32(1.0 / 128.0), 7, tuple(np.float32(c) for c in INVERSE_FACTORIALS))


def in_precision_of(value, x):
    """``value`` (a constant) as a float of ``x``'s precision: float32 where ``x`` is one, else as it is.

    The pair functions write their constants through it, so that a kernel handed float32 inputs computes in float32
    (a float64 constant widens every step it enters) and one handed float64 computes as it always has."""
    return np.float32(value) if isinstance(x, np.float32) else value


@overload(in_precision_of)
def _in_precision_of_compiled(value, x):
    if isinstance(x, types.Float) and x.bitwidth == 32:
        return lambda value, x: np.float32(value)
    return lambda value, x: value


def exp_reduction(x):
    """``(lowest, 2^-m, m, 1/k! for k = 0 .. 10)`` of :func:`exp_nonpositive` in ``x``'s precision: ``x`` is taken
    at ``lowest`` below it, where ``e^x`` underflows to 0 (-746 in float64, -104 in float32), and ``e^x = (e^(x
    2^-m))^(2^m)`` with ``m`` = 12 squarings in float64 and 7 in float32 (each squaring doubles the relative error
    of what it squares). One call for all the constants: each call a kernel inlines costs compile time."""
    return EXP_REDUCTION_32 if isinstance(x, np.float32) else EXP_REDUCTION_64


@overload(exp_reduction)
def _exp_reduction_compiled(x):
    if isinstance(x, types.Float) and x.bitwidth == 32:
        return lambda x: EXP_REDUCTION_32
    return lambda x: EXP_REDUCTION_64


def channel_parameters(sigma_a, sigma_s, g, eta, model: str = "directional") -> np.ndarray:
    """Pack per-channel coefficients (already validated) into the ``(K, N_PARAMS)`` kernel array.

    ``model`` is ``"directional"`` (FHK14), ``"standard"`` (Jensen 2001) or ``"better"`` (d'Eon 2012);
    for the radial models ``S_d = R(r) / pi`` (standard) and ``R(r) / (pi 4 C_phi(1/eta))`` (better),
    the Fresnel transmittances excluded (docs/physics.md §6.1, §6.2).
    """
    sigma_a, sigma_s, g = (np.atleast_1d(np.asarray(v, dtype=np.float64)) for v in (sigma_a, sigma_s, g))
    eta = float(eta)
    if model != "directional":
        return _radial_parameters(sigma_a, sigma_s, g, eta, model)
    C_phi = float(fresnel.C_phi(eta))
    C_E = float(fresnel.C_E(eta))
    A = (1.0 - C_E) / (2.0 * C_phi)
    d_e = extrapolation_distance(sigma_a, sigma_s, g)
    params = np.empty((sigma_a.shape[0], N_PARAMS))
    params[:, P_D] = diffusion_coefficient(sigma_a, sigma_s, g)
    params[:, P_SIGMA_TR] = sigma_tr(sigma_a, sigma_s, g)
    params[:, P_D_E] = d_e
    params[:, P_VIRTUAL] = 2.0 * A * d_e
    params[:, P_C_PHI] = C_phi
    params[:, P_C_E] = C_E
    params[:, P_NORM] = 1.0 / (4.0 * float(fresnel.C_phi(1.0 / eta)))
    params[:, P_BACKLIT] = 1.0 / (3.0 * sigma_t(sigma_a, sigma_s))
    return params


def _radial_parameters(sigma_a, sigma_s, g, eta, model):
    sigma_t_red = sigma_t_reduced(sigma_a, sigma_s, g)
    alpha = alpha_reduced(sigma_a, sigma_s, g)
    params = np.zeros((sigma_a.shape[0], N_PARAMS))
    z_r = 1.0 / sigma_t_red
    if model == "standard":  # docs/physics.md §6.1
        F_dr = float(fresnel.F_dr_egan_hilgeman(eta))
        A = (1.0 + F_dr) / (1.0 - F_dr)
        params[:, R_Z_R] = z_r
        params[:, R_Z_V] = z_r * (1.0 + 4.0 * A / 3.0)
        params[:, R_SIGMA_TR] = sigma_tr(sigma_a, sigma_s, g)
        params[:, R_SCALE] = alpha / (4.0 * math.pi) / math.pi
    elif model == "better":  # docs/physics.md §6.2
        C_phi = float(fresnel.C_phi(eta))
        C_E = float(fresnel.C_E(eta))
        A = (1.0 - C_E) / (2.0 * C_phi)
        D = (2.0 * sigma_a + (sigma_t_red - sigma_a)) / (3.0 * sigma_t_red**2)  # Grosjean
        params[:, R_Z_R] = z_r
        params[:, R_Z_V] = -z_r - 4.0 * A * D
        params[:, R_SIGMA_TR] = np.sqrt(sigma_a / D)
        params[:, R_SCALE] = alpha * alpha / (4.0 * math.pi) / (math.pi * 4.0 * float(fresnel.C_phi(1.0 / eta)))
        params[:, R_D] = D
        params[:, R_C_PHI] = C_phi
        params[:, R_C_E] = C_E
    else:
        raise ValueError(f"unknown model {model!r}")
    return params


@numba.njit(cache=True, fastmath=True)
def exp_nonpositive(x):
    """``e^x`` for ``x <= 0`` without a library call, so that loops using it vectorise, in ``x``'s precision.

    ``e^x = (e^(x / 2^m))^(2^m)`` (:func:`exp_reduction`: ``m`` = 12 in float64, 7 in float32): the degree-10 Taylor
    polynomial on ``[-0.182, 0]`` (float64; ``[-0.82, 0]`` in float32; truncation error below 2e-16 and 3e-9)
    squared ``m`` times. Relative error below 5e-13 in float64 and 2e-5 in float32 (measured against ``math.exp``),
    0 below -746 in float64 and below -104 in float32 (where ``e^x`` underflows).
    """
    lowest, scale, squarings, c = exp_reduction(x)
    y = max(x, lowest) * scale
    p = c[10] * y + c[9]  # Horner's form of sum_k y^k / k!, k = 0 .. 10
    p = p * y + c[8]
    p = p * y + c[7]
    p = p * y + c[6]
    p = p * y + c[5]
    p = p * y + c[4]
    p = p * y + c[3]
    p = p * y + c[2]
    p = p * y + c[1]
    p = p * y + c[0]
    for _ in range(squarings):
        p = p * p
    return p


@numba.njit(cache=True, fastmath=True)
def _ray_source(x_dot_w, x_dot_n, w_dot_n, d, D, inv_D, sigma_tr_, C_phi, C_E, norm_over_4pi2):
    """``S'_d`` of one ray source from its dot products and distance (docs/physics.md §4.4), 1/(mm^2 sr).

    ``norm exp(-s) / (4 pi^2 d^3) [C_phi (d^2/D + 3 (1+s) x.w) - C_E (3 D (1+s) w.n_o
    - ((1+s) + 3 D (3 (1+s) + s^2) x.w / d^2) x.n_o)]`` with ``s = sigma_tr d``; written with
    reciprocals and :func:`exp_nonpositive` so that loops using it vectorise.
    """
    one, three = in_precision_of(1.0, d), in_precision_of(3.0, d)
    s = sigma_tr_ * d
    one_plus_s = one + s
    inv_d = one / d
    inv_d2 = inv_d * inv_d
    fluence = C_phi * (d * d * inv_D + three * one_plus_s * x_dot_w)
    flux = C_E * (
        three * D * one_plus_s * w_dot_n
        - (one_plus_s + three * D * (three * one_plus_s + s * s) * x_dot_w * inv_d2) * x_dot_n
    )
    return norm_over_4pi2 * exp_nonpositive(-s) * inv_d2 * inv_d * (fluence - flux)


@numba.njit(cache=True, inline="always", fastmath=True)
def _channel(p, r2, perp2, mu0, x_dot_w, x_dot_n, x_dot_v, s_dot_v, s_dot_n, v_dot_n, x_dot_s):
    """``S_d`` of one channel (``p``: its parameters, :func:`lane`) from the shared pair geometry, before the
    clamp (real minus virtual)."""
    D = p[P_D]
    d_e = p[P_D_E]
    c = p[P_VIRTUAL]
    zero, two = in_precision_of(0.0, r2), in_precision_of(2.0, r2)
    floor = in_precision_of(D_R_FLOOR, r2) * D
    cos_beta = -math.sqrt(perp2 / (r2 + d_e * d_e))
    b = p[P_BACKLIT]
    d_r2 = r2 + D * mu0 * (D * mu0 - two * d_e * cos_beta) if mu0 > zero else r2 + b * b
    d_r = max(math.sqrt(d_r2), floor)
    d_v = max(math.sqrt(max(r2 - two * c * x_dot_s + c * c, zero)), floor)  # |x - c n_i*|, floored as d_r
    inv_D = in_precision_of(1.0, r2) / D
    scale = p[P_NORM] / in_precision_of(FOUR_PI_SQUARED, r2)
    real = _ray_source(x_dot_w, x_dot_n, -mu0, d_r, D, inv_D, p[P_SIGMA_TR], p[P_C_PHI], p[P_C_E], scale)
    virtual = _ray_source(
        x_dot_v - c * s_dot_v, x_dot_n - c * s_dot_n, v_dot_n, d_v, D, inv_D, p[P_SIGMA_TR], p[P_C_PHI], p[P_C_E], scale
    )
    return real - virtual


@numba.njit(cache=True, inline="always")
def orthonormal_frame(u0, u1, u2):
    """``(a, b)`` as six floats: unit vectors that make the unit vector ``u`` a right-handed orthonormal frame
    ``(a, b, u)``; ``a`` is perpendicular to ``u`` and to the axis ``u`` is least along (z, else x), ``b = u x a``."""
    if abs(u2) < 0.9:
        a0, a1, a2 = -u1, u0, 0.0
    else:
        a0, a1, a2 = 0.0, -u2, u1
    length = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
    a0, a1, a2 = a0 / length, a1 / length, a2 / length
    return a0, a1, a2, u1 * a2 - u2 * a1, u2 * a0 - u0 * a2, u0 * a1 - u1 * a0


@numba.njit(cache=True, fastmath=True)
def modified_normal(x0, x1, x2, ni0, ni1, ni2):
    """``(r^2, n_i*)`` for the pair offset ``x = x_o - x_i`` (mm): the unit normal of the modified tangent
    plane, ``n_i`` less its part along ``x`` (``n_i`` when ``r = 0`` or ``n_i || x``; docs/physics.md §4.1)."""
    one = in_precision_of(1.0, x0)
    r2 = x0 * x0 + x1 * x1 + x2 * x2
    positive = r2 > in_precision_of(0.0, x0)
    inv_r = one / math.sqrt(r2 if positive else one)
    h0 = x0 * inv_r
    h1 = x1 * inv_r
    h2 = x2 * inv_r
    proj = ni0 * h0 + ni1 * h1 + ni2 * h2
    t0 = ni0 - proj * h0
    t1 = ni1 - proj * h1
    t2 = ni2 - proj * h2
    tn2 = t0 * t0 + t1 * t1 + t2 * t2
    regular = positive and tn2 > in_precision_of(PARALLEL_TOLERANCE * PARALLEL_TOLERANCE, x0)
    inv_t = one / math.sqrt(tn2 if regular else one)
    return r2, t0 * inv_t if regular else ni0, t1 * inv_t if regular else ni1, t2 * inv_t if regular else ni2


@numba.njit(cache=True, inline="always", fastmath=True)
def pair_geometry(x0, x1, x2, ni0, ni1, ni2, w0, w1, w2, nx, ny, nz):
    """The channel-independent part of the directional dipole for the pair offset ``x = x_o - x_i``.

    Modified tangent-plane normal ``n_i*`` (``n_i`` when ``r = 0`` or ``n_i || x``; docs/physics.md §4.1),
    virtual direction ``w_v`` (§4.2), and the dot products the channels need (branch-free, so that
    loops using it vectorise). Returns ``(r2, perp2, mu0, x.w12, x.n_o, x.w_v, n*.w_v, n*.n_o, w_v.n_o,
    x.n*)`` with ``perp2 = r^2 - (x.w12)^2`` (>= 0) and ``mu0 = -n_o.w12``.
    """
    r2, s0, s1, s2 = modified_normal(x0, x1, x2, ni0, ni1, ni2)
    w_dot_s = w0 * s0 + w1 * s1 + w2 * s2
    two = in_precision_of(2.0, x0)
    v0 = w0 - two * w_dot_s * s0
    v1 = w1 - two * w_dot_s * s1
    v2 = w2 - two * w_dot_s * s2
    mu0 = -(nx * w0 + ny * w1 + nz * w2)
    x_dot_w = x0 * w0 + x1 * w1 + x2 * w2
    x_dot_n = x0 * nx + x1 * ny + x2 * nz
    v_dot_n = v0 * nx + v1 * ny + v2 * nz
    s_dot_n = s0 * nx + s1 * ny + s2 * nz
    s_dot_v = s0 * v0 + s1 * v1 + s2 * v2
    x_dot_v = x0 * v0 + x1 * v1 + x2 * v2
    x_dot_s = x0 * s0 + x1 * s1 + x2 * s2
    perp2 = max(r2 - x_dot_w * x_dot_w, in_precision_of(0.0, x0))
    return r2, perp2, mu0, x_dot_w, x_dot_n, x_dot_v, s_dot_v, s_dot_n, v_dot_n, x_dot_s


@numba.njit(cache=True, fastmath=True)
def radial_dipole(model, r2, p):
    """``S_d`` of the standard (``model`` 1) or better (2) dipole at squared distance ``r2`` (mm^2) for one
    channel (``p``: its parameters, :func:`lane`)."""
    z_r = p[R_Z_R]
    z_v = p[R_Z_V]
    st = p[R_SIGMA_TR]
    one = in_precision_of(1.0, r2)
    d_r = math.sqrt(r2 + z_r * z_r)
    d_v = math.sqrt(r2 + z_v * z_v)
    e_r = math.exp(-st * d_r)
    e_v = math.exp(-st * d_v)
    if model == MODEL_STANDARD:
        value = z_r * (one + st * d_r) * e_r / (d_r * d_r * d_r) + z_v * (one + st * d_v) * e_v / (d_v * d_v * d_v)
    else:
        value = p[R_C_PHI] / p[R_D] * (e_r / d_r - e_v / d_v) + p[R_C_E] * (
            z_r * (one + st * d_r) * e_r / (d_r * d_r * d_r) - z_v * (one + st * d_v) * e_v / (d_v * d_v * d_v)
        )
    return p[R_SCALE] * value


@numba.njit(cache=True, inline="always", fastmath=True)
def _lane(model, p, r2, perp2, mu0, xw, xn, xv, sv, sn, vn, xs):
    """The pair function: unclamped ``S_d`` (1/(mm^2 sr)) of one channel (``p``: its parameters,
    :func:`lane`) for ``model`` (0 directional, 1 standard, 2 better) from the pair geometry of
    :func:`pair_geometry`. Every kernel evaluates every model through it."""
    if model == MODEL_DIRECTIONAL:
        return _channel(p, r2, perp2, mu0, xw, xn, xv, sv, sn, vn, xs)
    return radial_dipole(model, r2, p)


@numba.njit(cache=True, inline="always")
def lane(params, k):
    """Row ``k`` of ``params`` as a tuple of ``N_PARAMS`` floats. Kernels read a channel's parameters
    into one before their inner loop: values, not an array, so that the loop vectorises."""
    return (
        params[k, 0],
        params[k, 1],
        params[k, 2],
        params[k, 3],
        params[k, 4],
        params[k, 5],
        params[k, 6],
        params[k, 7],
    )


@numba.njit(cache=True, inline="always", fastmath=True)
def pair_three(model, x0, x1, x2, ni0, ni1, ni2, w0, w1, w2, nx, ny, nz, p0, p1, p2):
    """Unclamped ``S_d`` of three channels (parameters ``p0, p1, p2``, :func:`lane`) for the pair offset
    ``x = x_o - x_i``: the geometry once, the channels from it (branch-free, so loops vectorise)."""
    r2, perp2, mu0, xw, xn, xv, sv, sn, vn, xs = pair_geometry(x0, x1, x2, ni0, ni1, ni2, w0, w1, w2, nx, ny, nz)
    return (
        _lane(model, p0, r2, perp2, mu0, xw, xn, xv, sv, sn, vn, xs),
        _lane(model, p1, r2, perp2, mu0, xw, xn, xv, sv, sn, vn, xs),
        _lane(model, p2, r2, perp2, mu0, xw, xn, xv, sv, sn, vn, xs),
    )


@numba.njit(cache=True, fastmath=True)
def model_pair(model, xi0, xi1, xi2, ni0, ni1, ni2, w0, w1, w2, xo0, xo1, xo2, no0, no1, no2, params, out):
    """``S_d`` of one source/receiver pair for every channel of ``params`` and the chosen model
    (0 directional, 1 standard, 2 better), written into ``out`` (1/(mm^2 sr)).

    Same formulas and conventions as :mod:`translucency.scatter.dipoles` (docs/physics.md §4,
    §6.1, §6.2; the edge cases of §4.6):
    ``n_i* = n_i`` when ``r = 0`` or ``n_i || x``, ``d_r`` and ``d_v`` floored at ``D_R_FLOOR * D``,
    clamp at 0 after subtracting the virtual source.

    Returns
    -------
    int
        The number of channels whose value was clamped from below 0 to 0.
    """
    r2, perp2, mu0, xw, xn, xv, sv, sn, vn, xs = pair_geometry(
        xo0 - xi0, xo1 - xi1, xo2 - xi2, ni0, ni1, ni2, w0, w1, w2, no0, no1, no2
    )
    clamped = 0
    for k in range(params.shape[0]):
        value = _lane(model, lane(params, k), r2, perp2, mu0, xw, xn, xv, sv, sn, vn, xs)
        if value < 0.0:
            value = 0.0
            clamped += 1
        out[k] = value
    return clamped


def channel_lanes(params, channel_of, n_out):
    """Parameter rows in output-channel order, padded to a multiple of three with the last: lane ``c`` of
    :func:`pair_three` is output channel ``c``; ``(3 ceil(n_out / 3), N_PARAMS)`` float64."""
    lanes = -(-int(n_out) // 3) * 3
    channel_of = np.asarray(channel_of, dtype=np.int64)
    return np.ascontiguousarray(params[channel_of[np.minimum(np.arange(lanes), int(n_out) - 1)]], dtype=np.float64)


def clamp_counted(channel_of, n_lanes):
    """Per lane, 1 where its clamps are counted: at a row of ``params``' first output channel, so that output
    channels sharing a row count its clamps once (and never the padding lanes); ``(n_lanes,)`` int64."""
    channel_of = np.asarray(channel_of, dtype=np.int64)
    counted = np.zeros(int(n_lanes), dtype=np.int64)
    for c in range(channel_of.size):
        counted[c] = int(channel_of[c] not in channel_of[:c])
    return counted


def source_columns(points, normals, w12, flux):
    """Sources as the kernels read them: ``table (9, n)`` (position mm, unit normal, unit refracted
    direction) and ``weights (C, n)`` (flux per output channel); the input's dtype is kept."""
    table = np.ascontiguousarray(np.concatenate([np.asarray(points).T, np.asarray(normals).T, np.asarray(w12).T]))
    return table, np.ascontiguousarray(np.asarray(flux).T)


def vertex_sum(model, src_points, src_normals, src_w12, src_flux, rcv_points, rcv_normals, params, channel_of):
    """``B[o, c] = sum_j S_d(x_j, w12_j; x_o)[channel_of[c]] * flux[j, c]`` over every pair (method ``exact``).

    Parameters
    ----------
    model : int
        0 directional, 1 standard, 2 better (:data:`MODELS`).
    src_points, src_normals, src_w12 : (n_src, 3) float64
        Source positions (mm), outward unit normals and refracted directions.
    src_flux : (n_src, C) float64
        Flux per source and output channel (the solver drops sources with no flux first).
    rcv_points, rcv_normals : (n_rcv, 3) float64
        Receiver positions (mm) and outward unit normals.
    params : (K, N_PARAMS) float64
        Distinct channel parameters (identical channels share one row).
    channel_of : (C,) int64
        Row of ``params`` for each output channel.

    Returns
    -------
    B : (n_rcv, C) float64
        Diffuse radiance factor, flux units x 1/(mm^2 sr).
    clamped : (n_rcv,) int64
        Per receiver, the number of (pair, row of ``params``) values clamped from below 0 to 0.

    Receivers are done on :func:`~translucency.threads.for_ranges`' threads, sources in a loop
    that vectorises (three channels at a time).
    """
    table, weights = source_columns(src_points, src_normals, src_w12, src_flux)
    n_out = weights.shape[0]
    lanes = channel_lanes(params, channel_of, n_out)
    counted = clamp_counted(channel_of, lanes.shape[0])
    n_rcv = rcv_points.shape[0]
    B = np.zeros((n_rcv, n_out))
    clamped = np.zeros(n_rcv, dtype=np.int64)
    for_ranges(
        rows_kernel(model, _vertex_rows_directional, _vertex_rows_radial),
        n_rcv,
        model,
        table,
        weights,
        rcv_points,
        rcv_normals,
        lanes,
        counted,
        B,
        clamped,
    )
    return B, clamped


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _vertex_rows_directional(
    worker, lo, hi, model, table, weights, rcv_points, rcv_normals, lanes, counted, B, clamped
):
    """:func:`_vertex_rows` of the directional dipole (``model`` is ignored: a constant here)."""
    _vertex_rows(worker, lo, hi, MODEL_DIRECTIONAL, table, weights, rcv_points, rcv_normals, lanes, counted, B, clamped)


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _vertex_rows_radial(worker, lo, hi, model, table, weights, rcv_points, rcv_normals, lanes, counted, B, clamped):
    """:func:`_vertex_rows` of the standard and better dipoles."""
    _vertex_rows(worker, lo, hi, model, table, weights, rcv_points, rcv_normals, lanes, counted, B, clamped)


@numba.njit(cache=True, inline="always", fastmath=True, error_model="numpy")
def _vertex_rows(worker, lo, hi, model, table, weights, rcv_points, rcv_normals, lanes, counted, B, clamped):
    """Receivers ``lo .. hi - 1`` of :func:`vertex_sum`."""
    n_src = table.shape[1]
    n_out = weights.shape[0]
    rows = table_rows(table)
    for o in range(lo, hi):
        x_o = (rcv_points[o, 0], rcv_points[o, 1], rcv_points[o, 2])
        n_o = (rcv_normals[o, 0], rcv_normals[o, 1], rcv_normals[o, 2])
        count = 0
        for group in range(lanes.shape[0] // 3):
            c0 = 3 * group
            F0, F1, F2, p0, p1, p2 = group_inputs(weights, lanes, c0)
            k = (counted[c0], counted[c0 + 1], counted[c0 + 2])
            a0, a1, a2, n = vertex_sources(model, n_src, rows, x_o, n_o, (p0, p1, p2), (F0, F1, F2), k)
            count += n
            store_three(B, o, c0, n_out, a0, a1, a2)
        clamped[o] = count


@numba.njit(cache=True, inline="always", fastmath=True)
def vertex_sources(model, n_src, rows, x_o, n_o, p, flux, counted):
    """Sum over every source of three channels' clamped ``S_d`` times flux at one receiver, and the clamps. Tuples:
    the sources' nine rows (:func:`table_rows`), the receiver's position (mm) and normal, three lanes' parameters,
    their flux rows and whether their clamps count (:func:`weighted_pair`)."""
    X0, X1, X2, N0, N1, N2, W0, W1, W2 = rows
    F0, F1, F2 = flux
    px, py, pz = x_o
    a0 = in_precision_of(0.0, px)
    a1 = a0
    a2 = a0
    count = 0
    for j in range(n_src):
        e0, e1, e2, n = weighted_pair(
            model,
            (px - X0[j], py - X1[j], pz - X2[j]),
            (N0[j], N1[j], N2[j], W0[j], W1[j], W2[j]),
            n_o,
            p,
            (F0[j], F1[j], F2[j]),
            counted,
        )
        count += n
        a0 += e0
        a1 += e1
        a2 += e2
    return a0, a1, a2, count


@numba.njit(cache=True, inline="always", fastmath=True)
def weighted_pair(model, x, source, n_o, p, flux, counted):
    """One pair's three channels of ``S_d`` clamped at 0 (docs/physics.md §4.6) times the source's flux, and the
    clamps counted: the body of the loop over every source (:func:`vertex_sources`), on the CPU and on the GPU.
    Tuples: the offset ``x = x_o - x_i`` (mm), the source's ``(n_i, w12)`` (six floats), the receiver's normal, three
    lanes' parameters (:func:`lane`), their flux and whether their clamps count (1 or 0, :func:`clamp_counted`)."""
    ni0, ni1, ni2, w0, w1, w2 = source
    e0, e1, e2 = pair_three(
        model, x[0], x[1], x[2], ni0, ni1, ni2, w0, w1, w2, n_o[0], n_o[1], n_o[2], p[0], p[1], p[2]
    )
    zero = in_precision_of(0.0, e0)
    count = (e0 < zero) * counted[0] + (e1 < zero) * counted[1] + (e2 < zero) * counted[2]
    return max(e0, zero) * flux[0], max(e1, zero) * flux[1], max(e2, zero) * flux[2], count


def rows_kernel(model, directional, radial):
    """The compiled entry of a traversal for ``model``: each entry inlines the traversal's one body with
    the model a constant for the directional dipole, so that its loop over sources has no branch on the
    model and vectorises, and only the entry a run uses is compiled."""
    return directional if model == MODEL_DIRECTIONAL else radial


@numba.njit(cache=True, inline="always")
def table_rows(table):
    """The nine rows of a source table (position mm, unit normal, unit refracted direction)."""
    return table[0], table[1], table[2], table[3], table[4], table[5], table[6], table[7], table[8]


@numba.njit(cache=True, inline="always")
def group_inputs(weights, lanes, c0):
    """For the output channels ``c0 .. c0 + 2``: their weight rows (the last repeated past the end) and
    their parameters (:func:`lane`), read once before a kernel's inner loop."""
    n_out = weights.shape[0]
    return (
        weights[c0],
        weights[min(c0 + 1, n_out - 1)],
        weights[min(c0 + 2, n_out - 1)],
        lane(lanes, c0),
        lane(lanes, c0 + 1),
        lane(lanes, c0 + 2),
    )


@numba.njit(cache=True, inline="always")
def store_three(out, row, c0, n_out, a0, a1, a2):
    """``out[row, c0 .. c0 + 2] = a0, a1, a2`` for the channels that exist (the lanes past ``n_out`` pad)."""
    out[row, c0] = a0
    if c0 + 1 < n_out:
        out[row, c0 + 1] = a1
    if c0 + 2 < n_out:
        out[row, c0 + 2] = a2


def indexed_sum(model, rcv_points, rcv_normals, table, weights, starts, counts, columns, factors, lanes):
    """Per receiver ``r``: ``B[r, c] = sum_k S_d(point columns[k]; x_r)[c] * weights[c, columns[k]] * factors[k]``
    over ``k`` in ``starts[r] .. starts[r] + counts[r]``.

    The sources are columns of ``table`` (rows: position mm, unit normal, unit refracted direction) with
    ``weights (C, P)``; ``lanes`` is :func:`channel_lanes` of the parameters; ``model`` as in
    :func:`vertex_sum`. Returns ``(n_rcv, C)`` float64. Receivers run on
    :func:`~translucency.threads.for_ranges`' threads, each receiver's list in a loop that
    vectorises.
    """
    out = np.zeros((rcv_points.shape[0], weights.shape[0]))
    for_ranges(
        rows_kernel(model, _indexed_rows_directional, _indexed_rows_radial),
        rcv_points.shape[0],
        model,
        rcv_points,
        rcv_normals,
        table,
        weights,
        starts,
        counts,
        columns,
        factors,
        lanes,
        out,
    )
    return out


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _indexed_rows_directional(
    worker, lo, hi, model, rcv_points, rcv_normals, table, weights, starts, counts, columns, factors, lanes, out
):
    """:func:`_indexed_rows` of the directional dipole (``model`` is ignored: a constant here)."""
    _indexed_rows(
        worker,
        lo,
        hi,
        MODEL_DIRECTIONAL,
        rcv_points,
        rcv_normals,
        table,
        weights,
        starts,
        counts,
        columns,
        factors,
        lanes,
        out,
    )


@numba.njit(cache=True, nogil=True, fastmath=True, error_model="numpy")
def _indexed_rows_radial(
    worker, lo, hi, model, rcv_points, rcv_normals, table, weights, starts, counts, columns, factors, lanes, out
):
    """:func:`_indexed_rows` of the standard and better dipoles."""
    _indexed_rows(
        worker, lo, hi, model, rcv_points, rcv_normals, table, weights, starts, counts, columns, factors, lanes, out
    )


@numba.njit(cache=True, inline="always", fastmath=True, error_model="numpy")
def _indexed_rows(
    worker, lo, hi, model, rcv_points, rcv_normals, table, weights, starts, counts, columns, factors, lanes, out
):
    """Receivers ``lo .. hi - 1`` of :func:`indexed_sum`."""
    n_out = weights.shape[0]
    rows = table_rows(table)
    for r in range(lo, hi):
        x_o = (rcv_points[r, 0], rcv_points[r, 1], rcv_points[r, 2])
        n_o = (rcv_normals[r, 0], rcv_normals[r, 1], rcv_normals[r, 2])
        for group in range(lanes.shape[0] // 3):
            c0 = 3 * group
            F0, F1, F2, p0, p1, p2 = group_inputs(weights, lanes, c0)
            first, last = starts[r], starts[r] + counts[r]
            a0, a1, a2 = indexed_sources(
                model, first, last, columns, factors, rows, x_o, n_o, (p0, p1, p2), (F0, F1, F2)
            )
            store_three(out, r, c0, n_out, a0, a1, a2)


@numba.njit(cache=True, inline="always", fastmath=True)
def indexed_sources(model, first, last, columns, factors, rows, x_o, n_o, p, flux):
    """Sum over the listed sources ``columns[first:last]`` of three channels' clamped ``S_d`` times flux
    and factor at one receiver. Tuples as :func:`vertex_sources`' (the sources' nine rows, the receiver's position
    and normal, three lanes' parameters and flux rows)."""
    X0, X1, X2, N0, N1, N2, W0, W1, W2 = rows
    F0, F1, F2 = flux
    x0, x1, x2 = x_o
    n0, n1, n2 = n_o
    p0, p1, p2 = p
    a0 = 0.0
    a1 = 0.0
    a2 = 0.0
    for k in range(first, last):
        i = columns[k]
        e0, e1, e2 = pair_three(
            model, x0 - X0[i], x1 - X1[i], x2 - X2[i], N0[i], N1[i], N2[i], W0[i], W1[i], W2[i], n0, n1, n2, p0, p1, p2
        )
        f = factors[k]
        a0 += max(e0, 0.0) * F0[i] * f
        a1 += max(e1, 0.0) * F1[i] * f
        a2 += max(e2, 0.0) * F2[i] * f
    return a0, a1, a2


#: The compiled kernels of the directional dipole's indexed rows (a ``tree`` solve's near field): numba compiles each
#: on first use; the set-up compiles them ahead (:mod:`translucency.app.warmup`).
DIRECTIONAL_ROW_KERNELS = (_indexed_rows_directional,)
