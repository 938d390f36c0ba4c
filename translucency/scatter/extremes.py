"""Extreme configurations of the three diffusion models and their evaluation by every implementation.

Shared by ``tests/scatter/test_stability.py`` (a bounded part) and ``bench/stability.py`` (millions of
configurations). A configuration is one source/receiver pair of one colour channel of one material:

* a **block** is one material -- ``eta`` and three channels of ``sigma_a``, ``sigma_s``, ``g`` (1/mm),
  drawn so that the reduced albedo spans 1e-6 to 1 - 1e-9 and the reduced mean free path
  ``1/sigma_t'`` spans 1e-4 to 1e4 times the block's size ``L`` (mm) -- with ``S`` sources and ``R``
  receivers placed at the scale ``L``;
* every receiver is placed relative to one source (``R / S`` per source): at it (``r = 0``), in its
  tangent plane, along or against its normal (``n_i || x``), exactly at the virtual source
  ``x_i + 2 A d_e n_i``, or anywhere, at distances from 1e-10 to 1e3 times ``L``, ``1/sigma_t'``,
  ``1/sigma_tr`` or ``D`` (far field: the value underflows to 0); its normal is the source's, the
  opposite one (a thin sheet, backlit), perpendicular to the refracted ray (``mu0 = 0``) or random;
* light arrives at normal incidence, exactly grazing, nearly grazing or from anywhere in the
  hemisphere; normals include exact coordinate axes;
* the **pairs** are every (receiver, source) combination of a block: the designed ones above and
  the cross pairs at distances of the order of ``L``.

Values are ``S_d`` in 1/(mm^2 sr) (norm included, Fresnel transmittances excluded): the directional
dipole (FHK14), and ``R_d(r) / pi`` (standard dipole) and ``R(r) / (pi 4 C_phi(1/eta))`` (better dipole),
exactly what :mod:`translucency.scatter.kernels` computes.

"Float32 input" means the geometry and the coefficients are given as float32 arrays (the values a
float32 mesh file or array holds): the reference functions convert them to float64, the kernels
are compiled for them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from translucency.scatter import dipoles, fresnel, kernels
from translucency.scatter.medium import diffusion_coefficient, extrapolation_distance, sigma_tr

MODELS = ("directional", "standard", "better")

#: Ranges of the draws (docs/physics.md §2.2: eta >= 1, a scattering medium, g in (-1, 1)).
ETA_RANGE = (1.0, 2.5)
ALBEDO_RANGE = (1e-6, 1.0 - 1e-9)  # reduced albedo alpha'
MFP_OVER_SIZE_RANGE = (1e-4, 1e4)  # reduced mean free path 1/sigma_t' over the block size L
G_RANGE = (-0.95, 0.99)
SIZE_RANGE_MM = (0.1, 3000.0)  # block (mesh) size L
DISTANCE_EXPONENTS = (-10.0, 3.0)  # r = scale * 10**e

OFFSETS = ("zero", "tangent", "along_normal", "against_normal", "virtual_source", "random")
OFFSET_WEIGHTS = (0.10, 0.25, 0.10, 0.10, 0.05, 0.40)
DISTANCE_SCALES = ("size", "mean_free_path", "diffusion_length", "D")
INCIDENCES = ("normal", "grazing", "near_grazing", "hemisphere")
INCIDENCE_WEIGHTS = (0.15, 0.15, 0.15, 0.55)
EXIT_NORMALS = ("same", "opposite", "perpendicular", "random")
EXIT_WEIGHTS = (0.25, 0.15, 0.10, 0.50)
AXES = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=np.float64)


@dataclass
class Blocks:
    """``G`` blocks of ``S`` sources and ``R`` receivers (arrays in mm, 1/mm, unit vectors).

    Attributes
    ----------
    eta : (G,)
        Relative index of refraction of each block (dimensionless).
    sigma_a, sigma_s, g : (G, 3)
        Per channel, 1/mm (``g`` dimensionless).
    size : (G,)
        Block size L, mm.
    x_i, n_i, w12 : (G, S, 3)
        Sources: position (mm), outward normal, refracted direction.
    x_o, n_o : (G, R, 3)
        Receivers: position (mm), outward normal.
    source_of : (R,) int
        The source each receiver was placed against.
    """

    eta: np.ndarray
    sigma_a: np.ndarray
    sigma_s: np.ndarray
    g: np.ndarray
    size: np.ndarray
    x_i: np.ndarray
    n_i: np.ndarray
    w12: np.ndarray
    x_o: np.ndarray
    n_o: np.ndarray
    source_of: np.ndarray

    @property
    def n_pairs(self) -> int:
        """Number of (receiver, source) pairs, each evaluated for three channels."""
        return self.x_i.shape[0] * self.x_i.shape[1] * self.x_o.shape[1]

    def subset(self, n_blocks: int) -> Blocks:
        """The first ``n_blocks`` blocks."""
        arrays = {
            name: getattr(self, name)[:n_blocks]
            for name in ("eta", "sigma_a", "sigma_s", "g", "size", "x_i", "n_i", "w12", "x_o", "n_o")
        }
        return Blocks(**arrays, source_of=self.source_of)

    def as_dtype(self, dtype) -> Blocks:
        """The same blocks with geometry and coefficients stored in ``dtype`` (rounded once)."""
        cast = {
            name: np.ascontiguousarray(getattr(self, name), dtype=dtype)
            for name in ("eta", "sigma_a", "sigma_s", "g", "size", "x_i", "n_i", "w12", "x_o", "n_o")
        }
        return Blocks(**cast, source_of=self.source_of)


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def perpendicular(v, helper):
    """Unit vectors perpendicular to the unit vectors ``v``: ``v x helper`` normalised (another axis if parallel)."""
    t = np.cross(v, helper)
    for axis in (AXES[0], AXES[2]):
        small = np.linalg.norm(t, axis=-1, keepdims=True) < 1e-6
        t = np.where(small, np.cross(v, np.broadcast_to(axis, np.shape(v))), t)
    return _unit(t)


def _log_uniform(rng, low, high, shape):
    return 10.0 ** rng.uniform(np.log10(low), np.log10(high), shape)


def coefficients(albedo, mfp_over_size, g, size):
    """``(sigma_a, sigma_s)`` in 1/mm from the reduced albedo, ``1/sigma_t'`` over the size ``L`` (mm) and g.

    ``sigma_t' = 1 / (ratio L)``, ``sigma_a = (1 - alpha') sigma_t'``, ``sigma_s = alpha' sigma_t' / (1 - g)``
    (docs/physics.md §2.1, §2.3: ``sigma_s' = sigma_s (1 - g)``).
    """
    sigma_t_reduced = 1.0 / (mfp_over_size * size)
    return (1.0 - albedo) * sigma_t_reduced, albedo * sigma_t_reduced / (1.0 - g)


def light_directions(n_i, incidence, cos_i, helper):
    """Unit vectors toward the light: ``INCIDENCES[incidence]``, with ``cos_i`` used for the last two kinds."""
    tangent = perpendicular(n_i, helper)
    cos_i = np.select([incidence == 0, incidence == 1], [1.0, 0.0], np.clip(cos_i, 0.0, 1.0))[..., None]
    w_i = cos_i * n_i + np.sqrt(1.0 - cos_i * cos_i) * tangent
    return np.where((incidence == 0)[..., None], n_i, np.where((incidence == 1)[..., None], tangent, w_i))


def receivers(src_x, src_n, src_w, offset, r, direction, virtual_height, exit_kind, n_o, helper):
    """Receivers ``(x_o, n_o)`` placed against their sources (mm, unit vectors).

    ``offset`` indexes :data:`OFFSETS`: ``r`` (mm) along ``direction`` (random kind), along a tangent
    (``direction x n_i``), along ``+-n_i``, at ``virtual_height`` along ``n_i`` (the virtual source
    ``x_i + 2 A d_e n_i``) or at the source. ``exit_kind`` indexes :data:`EXIT_NORMALS`: the source's
    normal, its opposite, perpendicular to ``src_w`` (``mu0 = 0``: ``src_w x helper``) or ``n_o``.
    """
    direction = np.where((offset == 1)[..., None], perpendicular(src_n, direction), direction)
    direction = np.where(((offset == 2) | (offset == 4))[..., None], src_n, direction)
    direction = np.where((offset == 3)[..., None], -src_n, direction)
    r = np.where(offset == 0, 0.0, np.where(offset == 4, virtual_height, r))
    n_o = np.where((exit_kind == 0)[..., None], src_n, n_o)
    n_o = np.where((exit_kind == 1)[..., None], -src_n, n_o)
    n_o = np.where((exit_kind == 2)[..., None], perpendicular(src_w, helper), n_o)
    return src_x + r[..., None] * direction, n_o


def random_blocks(n_blocks: int, n_sources: int = 8, receivers_per_source: int = 4, seed: int = 0) -> Blocks:
    """Draw ``n_blocks`` blocks of extreme configurations (see the module docstring); deterministic per seed."""
    rng = np.random.default_rng(seed)
    G, S, R = n_blocks, n_sources, n_sources * receivers_per_source

    eta = rng.uniform(*ETA_RANGE, G)
    pick = rng.random(G)
    eta[pick < 0.10] = ETA_RANGE[0]
    eta[pick > 0.95] = ETA_RANGE[1]
    lo, hi = ALBEDO_RANGE
    kind = rng.integers(0, 3, (G, 3))
    albedo = np.select(
        [kind == 0, kind == 1],
        [_log_uniform(rng, lo, 1.0, (G, 3)), 1.0 - _log_uniform(rng, 1.0 - hi, 1.0, (G, 3))],
        rng.uniform(lo, hi, (G, 3)),
    )
    pick = rng.random((G, 3))
    albedo = np.clip(np.where(pick < 0.05, lo, np.where(pick > 0.95, hi, albedo)), lo, hi)
    mfp = _log_uniform(rng, *MFP_OVER_SIZE_RANGE, (G, 3))
    g = np.where(rng.random((G, 3)) < 0.3, 0.0, rng.uniform(*G_RANGE, (G, 3)))
    size = _log_uniform(rng, *SIZE_RANGE_MM, G)
    sigma_a, sigma_s = coefficients(albedo, mfp, g, size[:, None])

    # sources: scan coordinates (not centred), normals with exact axes, four kinds of incidence
    x_i = size[:, None, None] * (rng.uniform(-2, 2, (G, 1, 3)) + rng.random((G, S, 3)))
    n_i = _unit(rng.normal(size=(G, S, 3)))
    axis = rng.random((G, S)) < 0.15
    n_i[axis] = AXES[rng.integers(0, 6, int(axis.sum()))]
    incidence = rng.choice(len(INCIDENCES), (G, S), p=INCIDENCE_WEIGHTS)
    cos_i = np.where(incidence == 2, _log_uniform(rng, 1e-9, 1e-2, (G, S)), rng.random((G, S)))
    w12 = fresnel.refract(light_directions(n_i, incidence, cos_i, rng.normal(size=(G, S, 3))), n_i, eta[:, None])

    # receivers, each against one source, at distances on one of the model's length scales
    source_of = np.repeat(np.arange(S), receivers_per_source)
    channel = rng.integers(0, 3, (G, R))
    a, s, gg = (np.take_along_axis(v, channel, 1) for v in (sigma_a, sigma_s, g))
    D = diffusion_coefficient(a, s, gg)
    s_tr = sigma_tr(a, s, gg)
    scales = np.stack(
        [
            np.broadcast_to(size[:, None], (G, R)),
            3.0 * D,
            np.where(s_tr > 0, 1.0 / np.where(s_tr > 0, s_tr, 1.0), size[:, None]),
            D,
        ],
        axis=-1,
    )
    r = np.take_along_axis(scales, rng.integers(0, len(DISTANCE_SCALES), (G, R, 1)), -1)[..., 0]
    r = r * 10.0 ** rng.uniform(*DISTANCE_EXPONENTS, (G, R))
    # virtual-source height 2 A d_e (docs/physics.md §4.2)
    virtual_height = 2.0 * fresnel.reflection_parameter_A(eta)[:, None] * extrapolation_distance(a, s, gg)
    x_o, n_o = receivers(
        x_i[:, source_of],
        n_i[:, source_of],
        w12[:, source_of],
        rng.choice(len(OFFSETS), (G, R), p=OFFSET_WEIGHTS),
        r,
        _unit(rng.normal(size=(G, R, 3))),
        virtual_height,
        rng.choice(len(EXIT_NORMALS), (G, R), p=EXIT_WEIGHTS),
        _unit(rng.normal(size=(G, R, 3))),
        rng.normal(size=(G, R, 3)),
    )
    return Blocks(eta, sigma_a, sigma_s, g, size, x_i, n_i, w12, x_o, n_o, source_of)


# --------------------------------------------------------------------------------------------------
# evaluation
# --------------------------------------------------------------------------------------------------
def _radial_scale(model, eta):
    """Factor from the radial profile (1/mm^2) to ``S_d`` (1/(mm^2 sr)) (docs/physics.md §6.1, §6.2)."""
    if model == "standard":
        return 1.0 / np.pi
    return 1.0 / (np.pi * 4.0 * fresnel.C_phi(1.0 / np.asarray(eta, dtype=np.float64)))


def reference(blocks: Blocks, model: str, chunk: int = 256) -> np.ndarray:
    """``S_d[g, o, j, c]`` of every (receiver o, source j) pair by the float64 reference formulas.

    The arrays of ``blocks`` are passed as they are (float32 blocks are float32 input); for the radial
    models the distance ``r`` is computed in the blocks' dtype and passed in it.
    """
    G, S, R = blocks.x_i.shape[0], blocks.x_i.shape[1], blocks.x_o.shape[1]
    out = np.empty((G, R, S, 3))
    for lo in range(0, G, chunk):
        b = slice(lo, min(lo + chunk, G))
        x_i, n_i, w12 = (a[b, None, :, :] for a in (blocks.x_i, blocks.n_i, blocks.w12))
        x_o, n_o = (a[b, :, None, :] for a in (blocks.x_o, blocks.n_o))
        eta = blocks.eta[b, None, None]
        if model != "directional":
            offset = x_o - x_i
            r = np.sqrt(np.sum(offset * offset, axis=-1))
        for c in range(3):
            coeff = tuple(v[b, c, None, None] for v in (blocks.sigma_a, blocks.sigma_s, blocks.g))
            with np.errstate(divide="ignore", over="ignore", under="ignore", invalid="ignore"):
                if model == "directional":
                    out[b, :, :, c] = dipoles.directional_dipole(x_i, n_i, w12, x_o, n_o, *coeff, eta)
                elif model == "standard":
                    out[b, :, :, c] = dipoles.standard_dipole_profile(r, *coeff, eta) * _radial_scale(model, eta)
                else:
                    out[b, :, :, c] = dipoles.better_dipole_profile(r, *coeff, eta) * _radial_scale(model, eta)
    return out


def peak(blocks: Blocks, model: str) -> np.ndarray:
    """``S_d`` at ``r = 0`` under normal incidence on a flat surface, per block and channel, (G, 3) 1/(mm^2 sr).

    The scale of the material's profile (its maximum for the radial models); values are compared
    relative to it.
    """
    z = np.array([0.0, 0.0, 1.0])
    a, s, g = (np.asarray(v, dtype=np.float64) for v in (blocks.sigma_a, blocks.sigma_s, blocks.g))
    eta = np.asarray(blocks.eta, dtype=np.float64)[:, None]
    if model == "directional":
        return dipoles.directional_dipole(np.zeros(3), z, -z, np.zeros(3), z, a, s, g, eta)
    profile = dipoles.standard_dipole_profile if model == "standard" else dipoles.better_dipole_profile
    return profile(0.0, a, s, g, eta) * _radial_scale(model, eta)


def kernel_parameters(blocks: Blocks, model: str) -> np.ndarray:
    """Channel parameters of every block, (G, 3, N_PARAMS) float64, from the blocks' coefficients."""
    return np.stack(
        [
            kernels.channel_parameters(blocks.sigma_a[k], blocks.sigma_s[k], blocks.g[k], blocks.eta[k], model)
            for k in range(len(blocks.eta))
        ]
    )


@numba.njit(cache=True)
def _kernel_pairs(model, x_i, n_i, w12, x_o, n_o, params):
    G, S, R = x_i.shape[0], x_i.shape[1], x_o.shape[1]
    out = np.empty((G, R, S, params.shape[1]))
    for g in range(G):  # serial: many small calls must not each start the thread pool
        for o in range(R):
            for j in range(S):
                kernels.model_pair(
                    model,
                    x_i[g, j, 0],
                    x_i[g, j, 1],
                    x_i[g, j, 2],
                    n_i[g, j, 0],
                    n_i[g, j, 1],
                    n_i[g, j, 2],
                    w12[g, j, 0],
                    w12[g, j, 1],
                    w12[g, j, 2],
                    x_o[g, o, 0],
                    x_o[g, o, 1],
                    x_o[g, o, 2],
                    n_o[g, o, 0],
                    n_o[g, o, 1],
                    n_o[g, o, 2],
                    params[g],
                    out[g, o, j],
                )
    return out


def kernel_pairs(blocks: Blocks, model: str, params: np.ndarray | None = None) -> np.ndarray:
    """``S_d[g, o, j, c]`` of every pair by :func:`translucency.scatter.kernels.model_pair` (blocks' dtype)."""
    params = kernel_parameters(blocks, model) if params is None else params
    return _kernel_pairs(kernels.MODELS[model], blocks.x_i, blocks.n_i, blocks.w12, blocks.x_o, blocks.n_o, params)


def kernel_sums(
    blocks: Blocks, model: str, flux: np.ndarray, params: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """``B[g, o, c] = sum_j S_d(j -> o)[c] flux[g, j, c]`` per block, by the solver's ``exact`` kernels.

    :func:`~translucency.scatter.kernels.vertex_sum` for every model. Returns ``B`` and the clamp
    counts per receiver.
    """
    params = kernel_parameters(blocks, model) if params is None else params
    G, R = blocks.x_o.shape[:2]
    B = np.empty((G, R, 3))
    clamped = np.empty((G, R), dtype=np.int64)
    channel_of = np.arange(3, dtype=np.int64)
    flux = np.ascontiguousarray(flux, dtype=blocks.x_i.dtype)
    for k in range(G):
        B[k], clamped[k] = kernels.vertex_sum(
            kernels.MODELS[model],
            blocks.x_i[k],
            blocks.n_i[k],
            blocks.w12[k],
            flux[k],
            blocks.x_o[k],
            blocks.n_o[k],
            params[k],
            channel_of,
        )
    return B, clamped


def bad_counts(values) -> dict:
    """Numbers of NaN, infinite and negative entries (and the total) of an array of ``S_d`` or ``B``."""
    values = np.asarray(values)
    return {
        "values": int(values.size),
        "nan": int(np.isnan(values).sum()),
        "inf": int(np.isinf(values).sum()),
        "negative": int((values < 0).sum()),
    }


def pair_geometry(blocks: Blocks) -> dict:
    """Per pair (G, R, S), float64: ``r`` (mm), ``mu0 = -n_o . w12``, the tangent norm ``|n_i - (n_i . x^) x^|``
    (0 on the ``n_i`` axis) and the largest coordinate magnitude of the two points (mm)."""
    x = blocks.x_o[:, :, None, :].astype(np.float64) - blocks.x_i[:, None, :, :]
    r = np.sqrt(np.sum(x * x, axis=-1))
    n_i = np.broadcast_to(blocks.n_i[:, None, :, :], x.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_hat = x / r[..., None]
        tangent = n_i - np.sum(n_i * x_hat, axis=-1, keepdims=True) * x_hat
    tangent_norm = np.where(r > 0, np.sqrt(np.sum(tangent * tangent, axis=-1)), 0.0)
    mu0 = -np.sum(blocks.n_o[:, :, None, :] * blocks.w12[:, None, :, :], axis=-1)
    magnitude = np.maximum(np.abs(blocks.x_o).max(axis=-1)[:, :, None], np.abs(blocks.x_i).max(axis=-1)[:, None, :])
    return {"r": r, "mu0": mu0, "tangent_norm": tangent_norm, "magnitude": magnitude}


#: A pair is *regular* when float32 rounding of its inputs cannot switch a branch of the model:
#: ``|mu0|`` at least this (frontlit/backlit switch at ``mu0 = 0``), ...
REGULAR_MU0 = 1e-3
#: ... the exit point at least this angle (rad) off the ``n_i`` axis (the ``n_i* = n_i`` fallback), ...
REGULAR_AXIS_ANGLE = 1e-3
#: ... and ``r = 0`` exactly or ``r`` at least this fraction of the coordinates' magnitude (float32
#: positions resolve ``r`` and the direction of ``x`` to better than 1e-4).
REGULAR_R_OVER_MAGNITUDE = 1e-3


def regular_pairs(geometry: dict) -> np.ndarray:
    """Boolean (G, R, S): pairs away from the model's discontinuities (see ``REGULAR_*``)."""
    r = geometry["r"]
    resolved = (r == 0) | (r >= REGULAR_R_OVER_MAGNITUDE * geometry["magnitude"])
    off_axis = (r == 0) | (geometry["tangent_norm"] >= np.sin(REGULAR_AXIS_ANGLE))
    return resolved & off_axis & (np.abs(geometry["mu0"]) >= REGULAR_MU0)


def relative_differences(values, reference_values, scale, threshold: float = 1e-6) -> np.ndarray:
    """``|values - reference| / reference`` where the reference is finite and at least ``threshold * scale``.

    ``scale`` broadcasts against the values (the material's :func:`peak`); entries below the threshold,
    or not finite in either array, are dropped (returned flattened).
    """
    values, reference_values = np.broadcast_arrays(
        np.asarray(values, np.float64), np.asarray(reference_values, np.float64)
    )
    scale = np.broadcast_to(scale, values.shape)
    keep = (
        np.isfinite(values)
        & np.isfinite(reference_values)
        & (reference_values >= threshold * scale)
        & (reference_values > 0)
    )
    return np.abs(values[keep] - reference_values[keep]) / reference_values[keep]
