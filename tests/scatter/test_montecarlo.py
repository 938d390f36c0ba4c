"""The Monte Carlo half-space reference (translucency.scatter.montecarlo) against exact results.

Exact references: the Chandrasekhar H-function totals of docs/physics.md §9.3 (eta = 1, isotropic
scattering), the closed-form single-scattering reflectance of an index-matched half-space, energy
conservation, and the numpy Fresnel reflectance. Statistical tolerances are stated at each test; the
seeds are fixed, so every test is deterministic.
"""

import math

import numba
import numpy as np
import pytest
from scipy import integrate

from translucency.errors import InvalidParameterError
from translucency.scatter import fresnel
from translucency.scatter.montecarlo import (
    HalfSpaceTally,
    fresnel_reflectance_scalar,
    sample_hg_cosine,
    simulate_half_space,
)

# docs/physics.md §9.3: exact total diffuse reflectance R(mu0) = 1 - H(mu0) sqrt(1 - alpha), eta = 1, g = 0.
SPEC_3_3 = {
    0.3: {0: 0.057214, 30: 0.062152, 45: 0.069298, 60: 0.081716},
    0.5: {0: 0.115226, 30: 0.124479, 45: 0.137688, 60: 0.160144},
    0.9: {0: 0.414947, 30: 0.436124, 45: 0.464423, 60: 0.507939},
    0.99: {0: 0.752721, 30: 0.768333, 45: 0.787838, 60: 0.815140},
}


def _index_matched(albedo, theta, **kwargs):
    """An index-matched (eta = 1), isotropically scattering medium with sigma_t = 1/mm."""
    options = {"n_photons": 1_000_000, "seed": 7, "grid_cells": 11, "radial_bins": 10}
    options.update(kwargs)
    return simulate_half_space(1.0 - albedo, albedo, 0.0, 1.0, theta, **options)


# --------------------------------------------------------------------------------------------------
# Fresnel (njit scalar) against the numpy reference
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("eta", [1.0, 1.1, 1.3, 1.33, 1.5, 2.4, 1 / 1.3, 1 / 1.5, 1 / 2.4])
def test_fresnel_scalar_matches_numpy_reference(eta):
    cosines = np.concatenate([np.linspace(0.0, 1.0, 1001), [1e-12, 1 - 1e-12, math.sqrt(max(0.0, 1 - eta * eta))]])
    expected = fresnel.fresnel_reflectance(cosines, eta)
    got = np.array([fresnel_reflectance_scalar(float(c), eta) for c in cosines])
    assert np.allclose(got, expected, rtol=0.0, atol=1e-14)


def test_fresnel_scalar_total_internal_reflection():
    critical = math.sqrt(1.0 - (1.0 / 1.4) ** 2)  # inside cosine at the critical angle, eta = 1.4
    assert fresnel_reflectance_scalar(0.99 * critical, 1.0 / 1.4) == 1.0
    assert fresnel_reflectance_scalar(1.01 * critical, 1.0 / 1.4) < 1.0
    assert fresnel_reflectance_scalar(1.0, 1.0) == 0.0  # index-matched: no reflection at all


# --------------------------------------------------------------------------------------------------
# Exact references
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("albedo", [0.5, 0.9])
# normal and 60 deg incidence bracket the angles; 30 and 45 deg run with the slow tests
@pytest.mark.parametrize(
    "theta", [0, pytest.param(30, marks=pytest.mark.slow), pytest.param(45, marks=pytest.mark.slow), 60]
)
def test_total_reflectance_matches_chandrasekhar_exact_values(albedo, theta):
    # docs/physics.md §9.3; tolerance: within 3 standard errors and within 0.5 %.
    tally = _index_matched(albedo, theta)
    exact = SPEC_3_3[albedo][theta]
    difference = tally.total_reflectance - exact
    assert abs(difference) <= 3.0 * tally.total_reflectance_se
    assert abs(difference) <= 0.005 * exact
    assert tally.total_reflectance_se < 0.002 * exact  # the check above is a real one


@pytest.mark.parametrize("albedo", [0.5, 0.9])
def test_radiance_along_the_normal_matches_chandrasekhar(albedo):
    # docs/physics.md §9.3: at eta = 1, g = 0, normal incidence and exit, a uniform beam of unit flux per
    # unit area gives the intensity alpha H(1)^2 / (8 pi), with H(1) = (1 - R(1)) / sqrt(1 - alpha) from
    # the exact totals above. Tolerance: 3 standard errors and 1 %.
    tally = _index_matched(albedo, 0, n_photons=400_000)
    h1 = (1.0 - SPEC_3_3[albedo][0]) / math.sqrt(1.0 - albedo)
    exact = albedo * h1**2 / (8.0 * math.pi)
    assert abs(tally.normal_radiance - exact) <= 3.0 * tally.normal_radiance_se
    assert abs(tally.normal_radiance - exact) <= 0.01 * exact
    assert tally.normal_radiance_se < 0.004 * exact


@pytest.mark.parametrize("theta", [0, 60])
def test_single_scattering_matches_closed_form(theta):
    # Index-matched half-space, isotropic scattering: R1(mu0) = (alpha/2) (1 - mu0 ln(1 + 1/mu0)).
    albedo = 0.8
    tally = _index_matched(albedo, theta)
    mu0 = math.cos(math.radians(theta))
    exact = 0.5 * albedo * (1.0 - mu0 * math.log(1.0 + 1.0 / mu0))
    assert abs(tally.single_reflectance - exact) <= 3.0 * tally.single_reflectance_se
    assert abs(tally.single_reflectance - exact) <= 0.005 * exact


@pytest.mark.parametrize("g", [-0.3, 0.6])
def test_single_scattering_uses_the_henyey_greenstein_phase_function(g):
    # Normal incidence, eta = 1: R1 = alpha * int_0^1 2 pi p_HG(cos = -mu) mu / (mu + 1) dmu. A phase
    # function with the wrong sign of g or the wrong frame would miss by tens of per cent.
    albedo = 0.9

    def integrand(mu):
        phase = (1 - g * g) / (4 * math.pi * (1 + g * g + 2 * g * mu) ** 1.5)
        return 2 * math.pi * phase * mu / (mu + 1)

    exact = albedo * integrate.quad(integrand, 0.0, 1.0, epsabs=1e-13)[0]
    tally = simulate_half_space(
        1 - albedo, albedo, g, 1.0, 0.0, n_photons=1_000_000, seed=3, grid_cells=5, radial_bins=5
    )
    assert abs(tally.single_reflectance - exact) <= 3.0 * tally.single_reflectance_se
    assert abs(tally.single_reflectance - exact) <= 0.02 * exact


@pytest.mark.parametrize("g", [-0.5, 0.0, 0.3, 0.9])
def test_henyey_greenstein_sampler_has_mean_cosine_g(g):
    # Midpoint rule over xi: the mean of cos(theta) is g to quadrature accuracy.
    xi = (np.arange(200_000) + 0.5) / 200_000
    mean = np.mean([sample_hg_cosine(g, x) for x in xi[::10]])
    assert mean == pytest.approx(g, abs=2e-3)


# --------------------------------------------------------------------------------------------------
# Properties: energy, consistency of the tallies, launch modes
# --------------------------------------------------------------------------------------------------


def test_energy_is_conserved_with_a_refractive_boundary():
    # Reflected + absorbed = 1: exact in expectation, only the Russian roulette adds noise.
    tally = simulate_half_space(0.01, 0.99, 0.5, 1.4, 45.0, n_photons=100_000, seed=11)
    balance = tally.total_reflectance + tally.absorbed + tally.truncated
    spread = math.hypot(tally.total_reflectance_se, tally.absorbed_se)
    assert tally.truncated == 0.0
    assert abs(balance - 1.0) <= max(4.0 * spread, 1e-3)
    assert 0.0 < tally.total_reflectance < 1.0
    assert tally.single_reflectance + tally.multiple_reflectance == pytest.approx(tally.total_reflectance, rel=1e-12)


def test_non_absorbing_medium_reflects_everything_it_does_not_truncate():
    tally = simulate_half_space(0.0, 1.0, 0.0, 1.3, 0.0, n_photons=20_000, seed=5, max_interactions=2_000)
    assert tally.absorbed == 0.0
    assert tally.truncated > 0.0  # the walk into a non-absorbing half-space can be arbitrarily long
    assert tally.total_reflectance + tally.truncated == pytest.approx(1.0, abs=5e-3)


def test_tallies_are_consistent_and_non_negative():
    tally = simulate_half_space(0.05, 0.95, 0.0, 1.3, 30.0, n_photons=100_000, seed=2, grid_cells=41, radial_bins=20)
    for array in (
        tally.exitance,
        tally.exitance_single,
        tally.exitance_multiple,
        tally.radial_exitance,
        tally.exitance_se,
    ):
        assert np.all(np.isfinite(array)) and np.all(array >= 0.0)
    assert np.allclose(tally.exitance, tally.exitance_single + tally.exitance_multiple, rtol=1e-12, atol=0)
    on_grid = tally.exitance.sum() * tally.cell_area_mm2
    annuli = np.pi * np.diff(tally.radial_edges_mm**2)
    in_disc = np.sum(tally.radial_exitance * annuli)
    assert in_disc <= on_grid <= tally.total_reflectance  # disc inside the square inside the plane
    assert on_grid > 0.8 * tally.total_reflectance  # 4 reduced mean free paths hold most of it
    # The refracted ray travels toward +x: at 30 degrees more light comes out forward than backward.
    mid = tally.exitance.shape[0] // 2
    assert tally.exitance[:, mid + 1 :].sum() > tally.exitance[:, :mid].sum()


def test_incident_launch_is_the_refracted_one_times_the_entry_transmittance():
    settings = dict(n_photons=200_000, seed=4, grid_cells=5, radial_bins=5)
    refracted = simulate_half_space(0.1, 0.9, 0.0, 1.5, 60.0, launch="refracted", **settings)
    incident = simulate_half_space(0.1, 0.9, 0.0, 1.5, 60.0, launch="incident", **settings)
    T12 = 1.0 - fresnel.fresnel_reflectance(math.cos(math.radians(60.0)), 1.5)
    assert incident.entry_transmittance == pytest.approx(T12, rel=1e-14)
    expected = T12 * refracted.total_reflectance
    spread = math.hypot(incident.total_reflectance_se, T12 * refracted.total_reflectance_se)
    assert abs(incident.total_reflectance - expected) <= 4.0 * spread
    expected_w12 = fresnel.refract(np.array([-math.sin(math.pi / 3), 0.0, 0.5]), np.array([0.0, 0.0, 1.0]), 1.5)
    assert np.allclose(refracted.refracted_direction, expected_w12, atol=1e-14)


# --------------------------------------------------------------------------------------------------
# Reproducibility
# --------------------------------------------------------------------------------------------------


def _fields(tally: HalfSpaceTally):
    return [
        tally.total_reflectance,
        tally.total_reflectance_se,
        tally.single_reflectance,
        tally.absorbed,
        tally.exitance,
        tally.exitance_se,
        tally.radial_exitance,
        tally.radial_exitance_multiple_se,
    ]


def test_same_seed_gives_bitwise_identical_results_whatever_the_thread_count():
    settings = dict(n_photons=20_000, seed=123, n_batches=8, grid_cells=21, radial_bins=10)
    first = simulate_half_space(0.02, 1.5, 0.7, 1.33, 45.0, **settings)
    second = simulate_half_space(0.02, 1.5, 0.7, 1.33, 45.0, **settings)
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        serial = simulate_half_space(0.02, 1.5, 0.7, 1.33, 45.0, **settings)
    finally:
        numba.set_num_threads(threads)
    for a, b, c in zip(_fields(first), _fields(second), _fields(serial)):
        assert np.array_equal(a, b)
        assert np.array_equal(a, c)
    other = simulate_half_space(0.02, 1.5, 0.7, 1.33, 45.0, **{**settings, "seed": 124})
    assert other.total_reflectance != first.total_reflectance
    assert not np.array_equal(other.exitance, first.exitance)


# --------------------------------------------------------------------------------------------------
# Validation at the boundary
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"theta_i_deg": 90.0}, "theta_i_deg"),
        ({"theta_i_deg": -5.0}, "theta_i_deg"),
        ({"eta": 0.8}, "eta"),
        ({"sigma_a": -0.1}, "sigma_a"),
        ({"sigma_s": 0.0}, "scatter"),
        ({"g": 1.0}, "g must"),
        ({"n_batches": 1}, "n_batches"),
        ({"n_photons": 0}, "n_photons"),
        ({"launch": "outside"}, "launch"),
        ({"grid_extent_mm": -1.0}, "grid_extent_mm"),
        ({"radial_edges_mm": [0.5, 1.0]}, "radial_edges_mm"),
        ({"sigma_a": [0.1, 0.2]}, "single numbers"),
    ],
)
def test_invalid_parameters_are_rejected_with_a_sentence(kwargs, words):
    arguments = {"sigma_a": 0.1, "sigma_s": 1.0, "g": 0.0, "eta": 1.3, "n_photons": 100}
    arguments.update(kwargs)
    with pytest.raises(InvalidParameterError, match=words):
        simulate_half_space(**arguments)
