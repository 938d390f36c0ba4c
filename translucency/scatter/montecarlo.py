"""Monte Carlo reference: a photon random walk in a semi-infinite homogeneous medium (validation only).

The medium fills ``z < 0`` below a smooth boundary ``z = 0`` (outward normal ``+z``) with relative
index of refraction ``eta = n_inside / n_outside``. A collimated pencil beam hits the origin from
the direction ``w_i = (-sin theta_i, 0, cos theta_i)`` (toward the light), so the refracted ray
``w12`` travels toward ``+x``, the convention of the directional dipole tables (docs/physics.md
§10.1, §9.1). The walk follows docs/physics.md §9.1:

1. launch at the origin along ``w12`` with weight 1 (``launch="refracted"``: tallies per unit
   flux that entered the medium) or with weight ``T12 = 1 - F_r(cos theta_i, eta)``
   (``launch="incident"``: tallies per unit incident flux, the specular reflection discarded as
   MCML does);
2. free flights ``s = -ln(xi) / sigma_t`` with the unreduced ``sigma_t``;
3. at the boundary the weight is split: ``w (1 - F_r)`` escapes and is tallied, ``w F_r`` is
   reflected specularly (``F_r = 1`` under total internal reflection);
4. at an interaction implicit capture ``w <- w sigma_s / sigma_t``, then a new direction from the
   Henyey-Greenstein phase function with the true ``g``;
5. Russian roulette below ``w = 1e-4`` (survival 0.1, weight x 10).

Escapes are tallied on a square grid and in annuli, split into single scattering (one interaction
before escape) and multiple scattering (two or more). Standard errors come from batch means: the
photons are split into ``n_batches`` independent batches, each with its own random stream seeded
from ``(seed, batch index)`` (xoshiro256** seeded through splitmix64), so the result depends only on
the seed and the number of batches, never on the number of threads. Batches run in parallel.

================ ================================================================== ===========
symbol           meaning                                                            unit
================ ================================================================== ===========
sigma_a          absorption coefficient                                             1/mm
sigma_s          scattering coefficient (unreduced; the walk uses the true g)       1/mm
g                Henyey-Greenstein mean cosine                                      1
eta              relative index of refraction n_inside / n_outside                  1
theta_i          polar angle of the incident beam                                   degree
w12              refracted direction of the beam inside the medium                  1
T12              Fresnel transmittance at entry, 1 - F_r(cos theta_i, eta)          1
M(x, y)          radiant exitance per unit launched flux (grid cell average)        1/mm^2
M(r)             radiant exitance per unit launched flux (annulus average)          1/mm^2
R                total diffuse reflectance (escaped fraction of launched flux)      1
A                absorbed fraction of launched flux                                 1
================ ================================================================== ===========

Comparison with the diffusion models (docs/physics.md §6.3, §9.2), per refracted photon:
directional dipole ``M = pi S_d / norm = pi S_d 4 C_phi(1/eta)``; standard dipole
``M = R_d(r) (1 - 2 C1(1/eta))``; better dipole ``M = R(r)``. Per incident photon multiply each by
``T12``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numba
import numpy as np

from ..errors import InvalidParameterError
from .fresnel import fresnel_reflectance_scalar
from .medium import validate_coefficients

__all__ = [
    "HalfSpaceTally",
    "TwoMediaTally",
    "simulate_half_space",
    "simulate_two_media",
    "sample_hg_cosine",
    "LAUNCH_MODES",
]

#: Accepted values of ``launch``: per refracted photon or per incident photon.
LAUNCH_MODES = ("refracted", "incident")

#: Russian roulette threshold, survival probability (MCML's values; docs/physics.md §9.1 item 5).
ROULETTE_WEIGHT = 1e-4
ROULETTE_SURVIVAL = 0.1

# Indices of the order classes in the tallies.
_SINGLE = 0
_MULTIPLE = 1

_U64_MASK53 = np.uint64(11)
_TWO_POW_MINUS_53 = 1.0 / 9007199254740992.0


# --------------------------------------------------------------------------------------------------
# Random numbers: splitmix64 (seeding) and xoshiro256** (Blackman & Vigna), one stream per batch.
# --------------------------------------------------------------------------------------------------


@numba.njit(cache=True, inline="always")
def _rotl(x, k):
    return (x << np.uint64(k)) | (x >> np.uint64(64 - k))


@numba.njit(cache=True)
def _splitmix64(x):
    """One splitmix64 step: returns (next state, output), both uint64."""
    x = x + np.uint64(0x9E3779B97F4A7C15)
    z = x
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return x, z ^ (z >> np.uint64(31))


@numba.njit(cache=True)
def _seed_stream(state, seed, stream):
    """Fill the 4-word xoshiro256** ``state`` from (seed, stream) through splitmix64."""
    x = np.uint64(seed) * np.uint64(0x9E3779B97F4A7C15) ^ (np.uint64(stream) + np.uint64(0x632BE59BD9B4E019))
    for k in range(4):
        x, z = _splitmix64(x)
        state[k] = z
    if state[0] == 0 and state[1] == 0 and state[2] == 0 and state[3] == 0:  # the one forbidden state
        state[0] = np.uint64(1)


@numba.njit(cache=True, inline="always")
def _next_uint64(state):
    s0 = state[0]
    s1 = state[1]
    s2 = state[2]
    s3 = state[3]
    result = _rotl(s1 * np.uint64(5), 7) * np.uint64(9)
    t = s1 << np.uint64(17)
    s2 ^= s0
    s3 ^= s1
    s1 ^= s2
    s0 ^= s3
    s2 ^= t
    s3 = _rotl(s3, 45)
    state[0] = s0
    state[1] = s1
    state[2] = s2
    state[3] = s3
    return result


@numba.njit(cache=True, inline="always")
def _uniform(state):
    """A uniform double in (0, 1] (53 random bits; never 0, so -log is finite)."""
    return (float(_next_uint64(state) >> _U64_MASK53) + 1.0) * _TWO_POW_MINUS_53


# --------------------------------------------------------------------------------------------------
# Physics helpers (scalar, njit)
# --------------------------------------------------------------------------------------------------


@numba.njit(cache=True, inline="always")
def sample_hg_cosine(g, xi):
    """Cosine of the deflection angle sampled from Henyey-Greenstein (docs/physics.md §9.1 item 4)."""
    if abs(g) < 1e-6:
        return 1.0 - 2.0 * xi
    ratio = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi)
    cos_theta = (1.0 + g * g - ratio * ratio) / (2.0 * g)
    return min(max(cos_theta, -1.0), 1.0)


# --------------------------------------------------------------------------------------------------
# The kernel
# --------------------------------------------------------------------------------------------------


@numba.njit(cache=True, parallel=True)
def _random_walk_batches(
    sigma_a,
    sigma_s,
    g,
    eta,
    start_x,
    start_y,
    start_z,
    start_weight,
    photons_per_batch,
    n_batches,
    seed,
    grid_half_width,
    grid_cells,
    radial_edges,
    max_interactions,
    sigma_a_right,
    sigma_s_right,
    boundary_x,
    launch_x_low,
    launch_x_high,
    strip_half_width,
    strip_cells,
):
    """Run ``n_batches`` independent batches of photons; returns the per-batch tallies.

    Where ``x >= boundary_x`` the medium is ``(sigma_a_right, sigma_s_right)`` (the same ``g`` and
    ``eta``): free flights are drawn with the larger ``sigma_t`` and a collision in the thinner side is
    real with probability ``sigma_t(x) / sigma_t_max`` (Woodcock tracking, docs/physics.md §9.1 item 8);
    with one medium no number is drawn for it, so the walk is the homogeneous one. Photons start at
    ``x`` uniform in ``[launch_x_low, launch_x_high]`` (one point draws nothing).

    Returns
    -------
    totals : ndarray, shape (n_batches, 2)
        Escaped weight per batch and order class (single, multiple).
    absorbed : ndarray, shape (n_batches,)
        Weight removed by implicit capture.
    truncated : ndarray, shape (n_batches,)
        Weight still alive when a photon reached ``max_interactions`` (0 for any sigma_a > 0 in
        practice).
    interactions : ndarray, shape (n_batches,)
        Number of interactions (scattering events) simulated.
    grid : ndarray, shape (n_batches, 2, grid_cells, grid_cells)
        Escaped weight per cell, indexed [batch, order, iy, ix].
    radial : ndarray, shape (n_batches, 2, n_annuli)
        Escaped weight per annulus.
    strip : ndarray, shape (n_batches, strip_cells)
        Escaped weight per strip ``x`` in ``[-strip_half_width, strip_half_width]``, every ``y``.
    normal_radiance : ndarray, shape (n_batches,)
        Sum over interactions of weight x phase function toward +z x attenuation to the boundary, 1/sr.
    """
    sigma_t_left = sigma_a + sigma_s
    sigma_t_right = sigma_a_right + sigma_s_right
    albedo_left = sigma_s / sigma_t_left
    albedo_right = sigma_s_right / sigma_t_right
    sigma_t_max = max(sigma_t_left, sigma_t_right)
    strip_cell = 2.0 * strip_half_width / strip_cells
    inv_eta = 1.0 / eta
    n_annuli = radial_edges.shape[0] - 1
    r_max = radial_edges[n_annuli]
    cell = 2.0 * grid_half_width / grid_cells

    totals = np.zeros((n_batches, 2))
    absorbed = np.zeros(n_batches)
    truncated = np.zeros(n_batches)
    interactions = np.zeros(n_batches, dtype=np.int64)
    grid = np.zeros((n_batches, 2, grid_cells, grid_cells))
    radial = np.zeros((n_batches, 2, n_annuli))
    normal_radiance = np.zeros(n_batches)
    strip = np.zeros((n_batches, strip_cells))
    hg_norm = (1.0 - g * g) / (4.0 * math.pi)

    for batch in numba.prange(n_batches):
        state = np.empty(4, dtype=np.uint64)
        _seed_stream(state, seed, batch)
        batch_interactions = 0
        for _photon in range(photons_per_batch):
            x = launch_x_low
            if launch_x_high > launch_x_low:
                x += (launch_x_high - launch_x_low) * _uniform(state)
            y = 0.0
            z = 0.0
            ux = start_x
            uy = start_y
            uz = start_z
            w = start_weight
            events = 0
            while True:
                step = -math.log(_uniform(state)) / sigma_t_max  # free flight, docs/physics.md §9.1 item 2
                if uz > 0.0 and z + step * uz >= 0.0:
                    # Reaches the boundary: move there, split the weight by Fresnel.
                    to_boundary = -z / uz
                    x += to_boundary * ux
                    y += to_boundary * uy
                    z = 0.0
                    reflectance = fresnel_reflectance_scalar(uz, inv_eta)  # light inside: 1/eta
                    escaped = w * (1.0 - reflectance)
                    if escaped > 0.0:
                        order = _SINGLE if events == 1 else _MULTIPLE
                        totals[batch, order] += escaped
                        ix = int(math.floor((x + grid_half_width) / cell))
                        iy = int(math.floor((y + grid_half_width) / cell))
                        if 0 <= ix < grid_cells and 0 <= iy < grid_cells:
                            grid[batch, order, iy, ix] += escaped
                        r = math.sqrt(x * x + y * y)
                        if r < r_max:
                            ir = np.searchsorted(radial_edges, r, side="right") - 1
                            if 0 <= ir < n_annuli:
                                radial[batch, order, ir] += escaped
                        ix = int(math.floor((x + strip_half_width) / strip_cell))
                        if 0 <= ix < strip_cells:
                            strip[batch, ix] += escaped
                    w -= escaped
                    uz = -uz  # specular reflection of what remains; memoryless, so a new flight
                    if w <= 0.0:
                        break
                else:
                    x += step * ux
                    y += step * uy
                    z += step * uz
                    sigma_t = sigma_t_left if x < boundary_x else sigma_t_right
                    if sigma_t < sigma_t_max and _uniform(state) * sigma_t_max >= sigma_t:
                        continue  # a null collision: the flight goes on (docs/physics.md §9.1 item 8)
                    albedo = albedo_left if x < boundary_x else albedo_right
                    # Interaction: implicit capture, then a new direction (docs/physics.md §9.1 item 4).
                    absorbed[batch] += w * (1.0 - albedo)
                    w *= albedo
                    events += 1
                    batch_interactions += 1
                    # Next event toward a sensor above: what this interaction sends straight up (+z), the
                    # phase function at the travel direction's cosine uz, attenuated to the boundary
                    # (docs/physics.md §9.1 item 7).
                    normal_radiance[batch] += w * hg_norm / (1.0 + g * g - 2.0 * g * uz) ** 1.5 * math.exp(sigma_t * z)
                    cos_theta = sample_hg_cosine(g, _uniform(state))
                    sin_theta = math.sqrt(max(0.0, 1.0 - cos_theta * cos_theta))
                    phi = 2.0 * math.pi * _uniform(state)
                    cos_phi = math.cos(phi)
                    sin_phi = math.sin(phi)
                    if abs(uz) > 0.99999:
                        nx = sin_theta * cos_phi
                        ny = sin_theta * sin_phi
                        nz = cos_theta if uz > 0.0 else -cos_theta
                    else:
                        tmp = math.sqrt(1.0 - uz * uz)
                        nx = sin_theta * (ux * uz * cos_phi - uy * sin_phi) / tmp + ux * cos_theta
                        ny = sin_theta * (uy * uz * cos_phi + ux * sin_phi) / tmp + uy * cos_theta
                        nz = -sin_theta * cos_phi * tmp + uz * cos_theta
                    length = math.sqrt(nx * nx + ny * ny + nz * nz)
                    ux = nx / length
                    uy = ny / length
                    uz = nz / length
                    if events >= max_interactions:
                        truncated[batch] += w
                        break
                # Russian roulette (docs/physics.md §9.1 item 5).
                if w < ROULETTE_WEIGHT:
                    if _uniform(state) <= ROULETTE_SURVIVAL:
                        w /= ROULETTE_SURVIVAL
                    else:
                        break
        interactions[batch] = batch_interactions
    return totals, absorbed, truncated, interactions, grid, radial, normal_radiance, strip


# --------------------------------------------------------------------------------------------------
# Public API
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class HalfSpaceTally:
    """Result of :func:`simulate_half_space`: exitance tallies with batch-means standard errors.

    All exitances and reflectances are per unit *launched* flux: per refracted photon when
    ``launch == "refracted"``, per incident photon when ``launch == "incident"``. Every quantity
    ``q`` has its standard error ``q_se`` (standard deviation of the batch means over
    ``sqrt(n_batches)``). Orders: "single" = escaped after exactly one interaction, "multiple" =
    after two or more; the plain names are their sum.

    Attributes
    ----------
    sigma_a, sigma_s, g, eta, theta_i_deg, seed, launch, max_interactions
        The settings (1/mm, 1/mm, 1, 1, degrees, --, --, interactions per photon).
    n_photons, n_batches : int
        Photons simulated (a multiple of ``n_batches``) and number of batches.
    refracted_direction : ndarray, shape (3,)
        ``w12``, the launch direction inside the medium.
    entry_transmittance : float
        ``T12 = 1 - F_r(cos theta_i, eta)``; the specular reflectance is ``1 - T12``.
    total_reflectance, single_reflectance, multiple_reflectance : float
        Escaped fraction of the launched flux (dimensionless).
    absorbed : float
        Fraction removed by absorption (implicit capture). ``total_reflectance + absorbed +
        truncated`` is 1 up to the statistical error of the Russian roulette.
    truncated : float
        Fraction still travelling when a photon reached ``max_interactions`` (0 unless
        ``sigma_a`` is ~0).
    normal_radiance, normal_radiance_se : float
        Radiance inside the medium at the boundary travelling along the outward normal ``+z``, averaged
        over the boundary, under a *uniform* collimated beam of unit launched flux per unit area, 1/sr
        (docs/physics.md §9.1 item 7); outside it is ``T21(eta, 1) / eta^2`` times this. The pencil
        beam and the uniform beam give the same average by translation invariance.
    mean_interactions : float
        Interactions per photon.
    grid_edges_mm : ndarray, shape (grid_cells + 1,)
        Cell edges of the square grid, the same along x and y, mm.
    exitance, exitance_single, exitance_multiple : ndarray, shape (grid_cells, grid_cells)
        Cell-averaged exitance ``M(x, y)`` in 1/mm^2, indexed ``[iy, ix]`` (rows = y, as an image).
    radial_edges_mm : ndarray, shape (n_annuli + 1,)
        Annulus edges, mm.
    radial_exitance, radial_exitance_single, radial_exitance_multiple : ndarray, shape (n_annuli,)
        Annulus-averaged exitance ``M(r)`` in 1/mm^2.
    total_reflectance_se, single_reflectance_se, multiple_reflectance_se, absorbed_se : float
        Standard errors of the fractions above (dimensionless).
    exitance_se, exitance_single_se, exitance_multiple_se : ndarray, shape (grid_cells, grid_cells)
        Standard errors of the cell-averaged exitances, 1/mm^2.
    radial_exitance_se, radial_exitance_single_se, radial_exitance_multiple_se : ndarray, shape (n_annuli,)
        Standard errors of the annulus-averaged exitances, 1/mm^2.
    elapsed_s : float
        Wall time of the simulation, s (including compilation on the first call of a session without
        a numba cache).
    """

    sigma_a: float
    sigma_s: float
    g: float
    eta: float
    theta_i_deg: float
    n_photons: int
    n_batches: int
    seed: int
    launch: str
    max_interactions: int
    refracted_direction: np.ndarray
    entry_transmittance: float
    total_reflectance: float
    total_reflectance_se: float
    single_reflectance: float
    single_reflectance_se: float
    multiple_reflectance: float
    multiple_reflectance_se: float
    absorbed: float
    absorbed_se: float
    truncated: float
    normal_radiance: float
    normal_radiance_se: float
    mean_interactions: float
    grid_edges_mm: np.ndarray
    exitance: np.ndarray
    exitance_se: np.ndarray
    exitance_single: np.ndarray
    exitance_single_se: np.ndarray
    exitance_multiple: np.ndarray
    exitance_multiple_se: np.ndarray
    radial_edges_mm: np.ndarray
    radial_exitance: np.ndarray
    radial_exitance_se: np.ndarray
    radial_exitance_single: np.ndarray
    radial_exitance_single_se: np.ndarray
    radial_exitance_multiple: np.ndarray
    radial_exitance_multiple_se: np.ndarray
    elapsed_s: float = field(default=0.0, compare=False)

    @property
    def grid_centres_mm(self) -> np.ndarray:
        """Cell centres of the grid along x (and y), mm."""
        return 0.5 * (self.grid_edges_mm[1:] + self.grid_edges_mm[:-1])

    @property
    def cell_area_mm2(self) -> float:
        """Area of one grid cell, mm^2."""
        return float((self.grid_edges_mm[1] - self.grid_edges_mm[0]) ** 2)

    def summary(self) -> dict:
        """Settings and totals as plain numbers (for JSON and tables)."""
        return {
            "sigma_a_per_mm": self.sigma_a,
            "sigma_s_per_mm": self.sigma_s,
            "g": self.g,
            "eta": self.eta,
            "theta_i_deg": self.theta_i_deg,
            "launch": self.launch,
            "n_photons": self.n_photons,
            "n_batches": self.n_batches,
            "seed": self.seed,
            "entry_transmittance": self.entry_transmittance,
            "total_reflectance": self.total_reflectance,
            "total_reflectance_se": self.total_reflectance_se,
            "single_reflectance": self.single_reflectance,
            "single_reflectance_se": self.single_reflectance_se,
            "multiple_reflectance": self.multiple_reflectance,
            "multiple_reflectance_se": self.multiple_reflectance_se,
            "absorbed": self.absorbed,
            "absorbed_se": self.absorbed_se,
            "truncated": self.truncated,
            "mean_interactions": self.mean_interactions,
            "elapsed_s": self.elapsed_s,
        }


def _batch_mean_and_se(per_batch):
    """Mean over axis 0 and its batch-means standard error."""
    mean = per_batch.mean(axis=0)
    se = per_batch.std(axis=0, ddof=1) / np.sqrt(per_batch.shape[0])
    return mean, se


def _by_order(name, per_batch):
    """Batch means and standard errors of a per-batch tally ``[batch, order, ...]``, as tally fields.

    Returns ``{name, name_se, name_single, name_single_se, name_multiple, name_multiple_se}``.
    """
    fields = {}
    fields[name], fields[name + "_se"] = _batch_mean_and_se(per_batch.sum(axis=1))
    for suffix, order in (("_single", _SINGLE), ("_multiple", _MULTIPLE)):
        fields[name + suffix], fields[name + suffix + "_se"] = _batch_mean_and_se(per_batch[:, order])
    return fields


def _check_positive_int(name, value, minimum, what="simulate_half_space"):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise InvalidParameterError(f"{what}: {name} must be an integer >= {minimum}, got {value!r}.")
    return int(value)


def _check_positive_float(name, value, what="simulate_half_space"):
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{what}: {name} must be a positive number, got {value!r}.") from None
    if not (math.isfinite(value) and value > 0.0):
        raise InvalidParameterError(f"{what}: {name} must be a positive number, got {value!r}.")
    return value


def simulate_half_space(
    sigma_a,
    sigma_s,
    g,
    eta,
    theta_i_deg=0.0,
    n_photons=100_000,
    seed=0,
    grid_extent_mm=None,
    grid_cells=101,
    radial_bins=100,
    radial_edges_mm=None,
    n_batches=32,
    launch="refracted",
    max_interactions=10_000_000,
) -> HalfSpaceTally:
    """Monte Carlo exitance of a semi-infinite medium lit by a collimated pencil beam (docs/physics.md §9.1).

    Parameters
    ----------
    sigma_a, sigma_s : float
        Absorption and *unreduced* scattering coefficients, 1/mm (``sigma_s > 0``).
    g : float
        Henyey-Greenstein mean cosine in (-1, 1); the walk uses this phase function itself (give
        ``sigma_s'`` with ``g = 0`` only if that is the comparison intended).
    eta : float
        Relative index ``n_inside / n_outside`` (>= 1; 1 is an index-matched boundary).
    theta_i_deg : float, optional
        Polar angle of incidence, degrees, in [0, 90). The beam arrives in the x-z plane and its
        refracted ray travels toward +x.
    n_photons : int, optional
        Photons to simulate; rounded up to a multiple of ``n_batches``.
    seed : int, optional
        Seed (>= 0). The result is bitwise reproducible for a given ``(seed, n_batches, n_photons)``
        whatever the number of threads.
    grid_extent_mm : float, optional
        Half-width of the square tally grid ``[-extent, extent]^2`` and outer radius of the radial
        tally, mm. Default: 4 reduced mean free paths ``4 / (sigma_s (1 - g) + sigma_a)``.
    grid_cells : int, optional
        Cells per side of the grid (odd numbers put a cell centre on the point of incidence).
    radial_bins : int, optional
        Number of equal-width annuli over ``[0, grid_extent_mm]``; ignored if ``radial_edges_mm``.
    radial_edges_mm : array_like, optional
        Increasing annulus edges starting at 0, mm.
    n_batches : int, optional
        Independent batches for the batch-means standard errors (>= 2); they run in parallel.
    launch : {"refracted", "incident"}, optional
        Tally per refracted photon (weight 1 along ``w12``) or per incident photon (weight
        ``T12``; specular reflection discarded).
    max_interactions : int, optional
        Safety limit on interactions per photon; weight still alive there is reported as
        ``truncated``. Only a medium with ``sigma_a`` ~ 0 gets near it.

    Returns
    -------
    HalfSpaceTally
        Totals, grid and radial exitance (1/mm^2) with standard errors, and the settings.

    Raises
    ------
    InvalidParameterError
        For coefficients out of range, an angle outside [0, 90), a non-positive photon count or
        grid, fewer than two batches, or an unknown launch mode.
    """
    a, s, gg, e = validate_coefficients(sigma_a, sigma_s, g, eta, what="simulate_half_space")
    if a.ndim != 0:
        raise InvalidParameterError(
            "simulate_half_space: sigma_a, sigma_s, g and eta must be single numbers (one channel at a time), "
            f"got arrays of shape {a.shape}."
        )
    sigma_a, sigma_s, g, eta = float(a), float(s), float(gg), float(e)
    if grid_extent_mm is None:
        grid_extent_mm = 4.0 / (sigma_s * (1.0 - g) + sigma_a)
    walk = _walk(
        (sigma_a, sigma_s),
        (sigma_a, sigma_s),
        math.inf,
        g,
        eta,
        theta_i_deg,
        n_photons,
        seed,
        grid_extent_mm,
        grid_cells,
        radial_bins,
        radial_edges_mm,
        n_batches,
        launch,
        max_interactions,
        (0.0, 0.0),
        (1.0, 1),
    )
    walk.pop("strip")
    return HalfSpaceTally(sigma_a=sigma_a, sigma_s=sigma_s, g=g, eta=eta, **walk)


def _walk(
    left,
    right,
    boundary_x,
    g,
    eta,
    theta_i_deg,
    n_photons,
    seed,
    grid_extent_mm,
    grid_cells,
    radial_bins,
    radial_edges_mm,
    n_batches,
    launch,
    max_interactions,
    launch_x,
    strip,
    what="simulate_half_space",
):
    """The checks and the walk shared by :func:`simulate_half_space` and :func:`simulate_two_media`: the
    tallies' fields as batch means with standard errors (``strip``: escaped weight per photon per mm of x)."""
    try:
        theta_i_deg = float(theta_i_deg)
    except (TypeError, ValueError):
        raise InvalidParameterError(
            f"{what}: theta_i_deg must be a number of degrees in [0, 90), got {theta_i_deg!r}."
        ) from None
    if not (0.0 <= theta_i_deg < 90.0):
        raise InvalidParameterError(
            f"{what}: theta_i_deg must lie in [0, 90) degrees, got {theta_i_deg!r}; "
            "grazing or back-facing light does not enter the medium."
        )
    if launch not in LAUNCH_MODES:
        raise InvalidParameterError(f"{what}: launch must be one of {LAUNCH_MODES}, got {launch!r}.")
    n_photons = _check_positive_int("n_photons", n_photons, 1, what)
    n_batches = _check_positive_int("n_batches", n_batches, 2, what)
    seed = _check_positive_int("seed", seed, 0, what)
    if seed >= 2**63:
        raise InvalidParameterError(f"{what}: seed must be below 2**63, got {seed}.")
    grid_cells = _check_positive_int("grid_cells", grid_cells, 1, what)
    max_interactions = _check_positive_int("max_interactions", max_interactions, 1, what)
    grid_extent_mm = _check_positive_float("grid_extent_mm", grid_extent_mm, what)
    if radial_edges_mm is None:
        radial_bins = _check_positive_int("radial_bins", radial_bins, 1, what)
        radial_edges = np.linspace(0.0, grid_extent_mm, radial_bins + 1)
    else:
        radial_edges = np.asarray(radial_edges_mm, dtype=np.float64)
        if (
            radial_edges.ndim != 1
            or radial_edges.size < 2
            or not np.all(np.isfinite(radial_edges))
            or radial_edges[0] != 0.0
            or np.any(np.diff(radial_edges) <= 0.0)
        ):
            raise InvalidParameterError(
                f"{what}: radial_edges_mm must be a 1-D increasing array of at least two finite "
                "radii starting at 0 (mm)."
            )

    # Entry: Snell refraction of w_i = (-sin, 0, cos) into the medium (docs/physics.md §3.2).
    theta = math.radians(theta_i_deg)
    cos_i = math.cos(theta)
    sin_t = math.sin(theta) / eta
    w12 = np.array([sin_t, 0.0, -math.sqrt(1.0 - sin_t * sin_t)])
    entry_transmittance = 1.0 - fresnel_reflectance_scalar(cos_i, eta)
    start_weight = 1.0 if launch == "refracted" else entry_transmittance

    photons_per_batch = -(-n_photons // n_batches)
    n_total = photons_per_batch * n_batches
    started = time.perf_counter()
    totals, absorbed, truncated, interactions, grid, radial, normal_radiance, strip_weight = _random_walk_batches(
        left[0],
        left[1],
        g,
        eta,
        float(w12[0]),
        float(w12[1]),
        float(w12[2]),
        start_weight,
        photons_per_batch,
        n_batches,
        seed,
        grid_extent_mm,
        grid_cells,
        radial_edges,
        max_interactions,
        right[0],
        right[1],
        float(boundary_x),
        float(launch_x[0]),
        float(launch_x[1]),
        float(strip[0]),
        int(strip[1]),
    )
    elapsed = time.perf_counter() - started

    # Per-batch estimates, then batch means and their standard errors.
    per_photon = 1.0 / photons_per_batch
    edges = np.linspace(-grid_extent_mm, grid_extent_mm, grid_cells + 1)
    cell_area = (edges[1] - edges[0]) ** 2
    annulus_area = np.pi * (radial_edges[1:] ** 2 - radial_edges[:-1] ** 2)

    totals = totals * per_photon
    grid = grid * (per_photon / cell_area)
    radial = radial * (per_photon / annulus_area)
    total, total_se = _batch_mean_and_se(totals.sum(axis=1))
    by_order, by_order_se = _batch_mean_and_se(totals)
    absorbed_mean, absorbed_se = _batch_mean_and_se(absorbed * per_photon)
    normal_radiance_mean, normal_radiance_se = _batch_mean_and_se(normal_radiance * per_photon)
    strip_mean, strip_se = _batch_mean_and_se(strip_weight * (per_photon * strip[1] / (2.0 * strip[0])))

    return dict(
        theta_i_deg=theta_i_deg,
        n_photons=n_total,
        n_batches=n_batches,
        seed=seed,
        launch=launch,
        max_interactions=max_interactions,
        refracted_direction=w12,
        entry_transmittance=entry_transmittance,
        total_reflectance=float(total),
        total_reflectance_se=float(total_se),
        single_reflectance=float(by_order[_SINGLE]),
        single_reflectance_se=float(by_order_se[_SINGLE]),
        multiple_reflectance=float(by_order[_MULTIPLE]),
        multiple_reflectance_se=float(by_order_se[_MULTIPLE]),
        absorbed=float(absorbed_mean),
        absorbed_se=float(absorbed_se),
        truncated=float(truncated.sum() / n_total),
        normal_radiance=float(normal_radiance_mean),
        normal_radiance_se=float(normal_radiance_se),
        mean_interactions=float(interactions.sum() / n_total),
        grid_edges_mm=edges,
        radial_edges_mm=radial_edges,
        **_by_order("exitance", grid),
        **_by_order("radial_exitance", radial),
        elapsed_s=elapsed,
        strip=(strip_mean, strip_se),
    )


@dataclass(frozen=True, eq=False)
class TwoMediaTally:
    """Result of :func:`simulate_two_media`: the exitance across the boundary ``x = 0`` between two media.

    Attributes
    ----------
    left, right : tuple of float
        ``(sigma_a, sigma_s)`` in 1/mm of the medium at ``x < 0`` and at ``x >= 0``.
    g, eta, theta_i_deg, launch_x_mm, n_photons, n_batches, seed
        The settings (``launch_x_mm``: photons start at ``x`` uniform in this range, ``y = 0``).
    total_reflectance, total_reflectance_se : float
        Escaped fraction of the launched flux.
    strip_edges_mm : ndarray, shape (cells + 1,)
        Edges of the strips along x, mm.
    strip_exitance, strip_exitance_se : ndarray, shape (cells,)
        Escaped flux per launched photon per mm of x, every y counted, 1/mm. Under a beam spread
        uniformly over the launch range (:attr:`uniform_exitance`) this times the range's width is the
        exitance per unit incident flux density.
    exitance, exitance_se : ndarray, shape (grid_cells, grid_cells)
        Cell-averaged exitance ``M(x, y)`` per launched photon, 1/mm^2, indexed ``[iy, ix]`` (a pencil beam).
    grid_edges_mm : ndarray, shape (grid_cells + 1,)
        Cell edges of that grid along x and y, mm.
    """

    left: tuple
    right: tuple
    g: float
    eta: float
    theta_i_deg: float
    launch_x_mm: tuple
    n_photons: int
    n_batches: int
    seed: int
    total_reflectance: float
    total_reflectance_se: float
    strip_edges_mm: np.ndarray
    strip_exitance: np.ndarray
    strip_exitance_se: np.ndarray
    exitance: np.ndarray
    exitance_se: np.ndarray
    grid_edges_mm: np.ndarray

    @property
    def strip_centres_mm(self) -> np.ndarray:
        """Centres of the strips along x, mm."""
        return 0.5 * (self.strip_edges_mm[1:] + self.strip_edges_mm[:-1])

    @property
    def uniform_exitance(self) -> tuple:
        """``(M, standard error)`` per strip under a beam of unit flux density spread over the launch range
        (dimensionless: exitance over incident flux density; meaningful well inside the range)."""
        width = self.launch_x_mm[1] - self.launch_x_mm[0]
        return self.strip_exitance * width, self.strip_exitance_se * width


def simulate_two_media(
    left,
    right,
    g,
    eta,
    *,
    launch_x_mm=(0.0, 0.0),
    theta_i_deg=0.0,
    n_photons=100_000,
    seed=0,
    strip_extent_mm=10.0,
    strip_cells=100,
    grid_extent_mm=10.0,
    grid_cells=101,
    n_batches=32,
    max_interactions=10_000_000,
) -> TwoMediaTally:
    """Monte Carlo exitance of a half-space made of two media side by side (``x < 0`` and ``x >= 0``),
    the reference for spatially varying coefficients (docs/physics.md §9.1 item 8).

    The walk is :func:`simulate_half_space`'s (per refracted photon) with Woodcock tracking through the
    two media; photons enter at ``x`` uniform in ``launch_x_mm`` (mm; equal ends: a pencil beam).

    Parameters
    ----------
    left, right : (sigma_a, sigma_s)
        Absorption and unreduced scattering coefficients of each side, 1/mm.
    g, eta : float
        Henyey-Greenstein mean cosine and relative index, shared by both sides.
    launch_x_mm : (float, float), optional
        Range of entry points along x, mm.
    theta_i_deg, n_photons, seed, grid_extent_mm, grid_cells, n_batches, max_interactions
        As in :func:`simulate_half_space`.
    strip_extent_mm : float, optional
        Half-width of the strip tally along x, mm.
    strip_cells : int, optional
        Strips over ``[-strip_extent_mm, strip_extent_mm]``.

    Returns
    -------
    TwoMediaTally
    """
    sides = []
    for side, coefficients in (("left", left), ("right", right)):
        try:
            sigma_a, sigma_s = coefficients
        except (TypeError, ValueError):
            raise InvalidParameterError(
                f"simulate_two_media: {side} must be a pair (sigma_a, sigma_s) in 1/mm, got {coefficients!r}."
            ) from None
        a, s, gg, e = validate_coefficients(sigma_a, sigma_s, g, eta, what="simulate_two_media")
        sides.append((float(a), float(s)))
    g, eta = float(gg), float(e)
    try:
        low, high = (float(v) for v in launch_x_mm)
    except (TypeError, ValueError):
        raise InvalidParameterError(
            f"simulate_two_media: launch_x_mm must be a pair (low, high) of mm, got {launch_x_mm!r}."
        ) from None
    if not (math.isfinite(low) and math.isfinite(high) and low <= high):
        raise InvalidParameterError(
            f"simulate_two_media: launch_x_mm must be finite with low <= high, got {launch_x_mm!r}."
        )
    strip_extent_mm = _check_positive_float("strip_extent_mm", strip_extent_mm, "simulate_two_media")
    strip_cells = _check_positive_int("strip_cells", strip_cells, 1, "simulate_two_media")
    walk = _walk(
        sides[0],
        sides[1],
        0.0,
        g,
        eta,
        theta_i_deg,
        n_photons,
        seed,
        grid_extent_mm,
        grid_cells,
        1,
        None,
        n_batches,
        "refracted",
        max_interactions,
        (low, high),
        (strip_extent_mm, strip_cells),
        "simulate_two_media",
    )
    strip, strip_se = walk["strip"]
    return TwoMediaTally(
        left=sides[0],
        right=sides[1],
        g=g,
        eta=eta,
        theta_i_deg=walk["theta_i_deg"],
        launch_x_mm=(low, high),
        n_photons=walk["n_photons"],
        n_batches=walk["n_batches"],
        seed=walk["seed"],
        total_reflectance=walk["total_reflectance"],
        total_reflectance_se=walk["total_reflectance_se"],
        strip_edges_mm=np.linspace(-strip_extent_mm, strip_extent_mm, strip_cells + 1),
        strip_exitance=strip,
        strip_exitance_se=strip_se,
        exitance=walk["exitance"],
        exitance_se=walk["exitance_se"],
        grid_edges_mm=walk["grid_edges_mm"],
    )
