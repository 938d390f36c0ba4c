"""Fresnel reflectance, refraction and the Fresnel-moment fits against docs/physics.md (§3; values §10.2-§10.3)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import integrate

from translucency.scatter import fresnel

# docs/physics.md §10.2: F_r at eta = 1.3, printed to 6 decimals (absolute tolerance: half a unit in the last place).
SPEC_FR_ETA_13 = {0: 0.017013, 30: 0.017962, 45: 0.023817, 60: 0.053400, 80: 0.336118}


@pytest.mark.parametrize("theta_deg, expected", SPEC_FR_ETA_13.items())
def test_reflectance_matches_spec_table(theta_deg, expected):
    assert fresnel.fresnel_reflectance(np.cos(np.radians(theta_deg)), 1.3) == pytest.approx(expected, abs=5e-7)


def test_transmittance_matches_spec_1_9():
    # docs/physics.md §10.1: T12 at 45 degrees and T21 at normal exit, eta = 1.3 (6 significant digits).
    assert fresnel.fresnel_transmittance(np.cos(np.radians(45)), 1.3) == pytest.approx(0.976183, abs=5e-7)
    assert fresnel.fresnel_transmittance(1.0, 1.3) == pytest.approx(0.982987, abs=5e-7)


def test_normal_incidence_equals_closed_form():
    eta = np.array([1.0, 1.2, 1.5, 2.4])
    assert np.allclose(fresnel.fresnel_reflectance(1.0, eta), ((eta - 1) / (eta + 1)) ** 2, rtol=0, atol=1e-15)


def test_total_internal_reflection_and_grazing():
    # Leaving a denser medium (relative index 1/1.5) beyond the critical angle reflects everything.
    critical = np.sqrt(1 - (1 / 1.5) ** 2)  # cosine at the critical angle
    assert fresnel.fresnel_reflectance(critical * 0.99, 1 / 1.5) == 1.0
    assert fresnel.fresnel_reflectance(critical * 1.01, 1 / 1.5) < 1.0
    for eta in (1.0, 1.3):
        assert fresnel.fresnel_reflectance(0.0, eta) == 1.0
        assert fresnel.fresnel_reflectance(-0.3, eta) == 1.0  # back-facing is clipped to grazing


@given(st.floats(0.0, 1.0), st.floats(0.2, 3.0))
def test_reflectance_is_a_probability(cos_i, eta):
    value = fresnel.fresnel_reflectance(cos_i, eta)
    assert np.isfinite(value) and 0.0 <= value <= 1.0


def _exact_two_C1(eta):
    """2 C1 by quadrature of the Fresnel formula for light inside a medium of relative index eta."""
    return (
        2
        * integrate.quad(
            lambda mu: fresnel.fresnel_reflectance(mu, 1 / eta) * mu,
            0,
            1,
            limit=200,
            points=[np.sqrt(max(0, 1 - 1 / eta**2))],
        )[0]
    )


def _exact_three_C2(eta):
    return (
        3
        * integrate.quad(
            lambda mu: fresnel.fresnel_reflectance(mu, 1 / eta) * mu**2,
            0,
            1,
            limit=200,
            points=[np.sqrt(max(0, 1 - 1 / eta**2))],
        )[0]
    )


# docs/physics.md §10.3 table: eta, 2C1(eta) fit, 2C1(1/eta) fit, 3C2(eta) fit, 3C2(1/eta), C_phi(eta), C_phi(1/eta),
# C_E(eta), C_E(1/eta), A, 1/(4 C_phi(1/eta)).
SPEC_MOMENTS = [
    (1.30, 0.445295, 0.061116, 0.297448, 0.035378, 0.138676, 0.234721, 0.351276, 0.482311, 2.338986, 1.065094),
    (1.33, 0.472925, 0.065908, 0.325534, 0.039453, 0.131769, 0.233523, 0.337233, 0.480274, 2.514886, 1.070557),
    (1.40, 0.529885, 0.076788, 0.386347, 0.049084, 0.117529, 0.230803, 0.306826, 0.475458, 2.948953, 1.083172),
    (1.50, 0.596541, 0.091774, 0.462609, 0.063068, 0.100865, 0.227056, 0.268695, 0.468466, 3.625171, 1.101050),
]


@pytest.mark.parametrize("row", SPEC_MOMENTS, ids=lambda r: f"eta={r[0]}")
def test_moment_fits_match_spec_table(row):
    eta, c1, c1_inv, c2, c2_inv, cphi, cphi_inv, ce, ce_inv, A, norm = row
    tol = 1.5e-6  # the table prints 6 decimals
    assert fresnel.two_C1(eta) == pytest.approx(c1, abs=tol)
    assert fresnel.two_C1(1 / eta) == pytest.approx(c1_inv, abs=tol)
    assert fresnel.three_C2(eta) == pytest.approx(c2, abs=tol)
    assert fresnel.three_C2(1 / eta) == pytest.approx(c2_inv, abs=tol)
    assert fresnel.C_phi(eta) == pytest.approx(cphi, abs=tol)
    assert fresnel.C_phi(1 / eta) == pytest.approx(cphi_inv, abs=tol)
    assert fresnel.C_E(eta) == pytest.approx(ce, abs=tol)
    assert fresnel.C_E(1 / eta) == pytest.approx(ce_inv, abs=tol)
    assert fresnel.reflection_parameter_A(eta) == pytest.approx(A, abs=tol)
    # the last column of docs/physics.md §10.3 is rounded from unrounded intermediates: 5e-6 absolute
    assert 1 / (4 * fresnel.C_phi(1 / eta)) == pytest.approx(norm, abs=5e-6)
    # A = (1 + 3C2) / (1 - 2C1) is the same number (docs/physics.md §2.1)
    assert fresnel.reflection_parameter_A(eta) == pytest.approx((1 + c2) / (1 - c1), rel=1e-5)


@pytest.mark.parametrize("eta", [1.3, 1.33, 1.4, 1.5])
def test_moment_fits_agree_with_quadrature(eta):
    # docs/physics.md §3.3: fit error about 0.2 % for 2C1 and about 1 % for 3C2 (measured here for eta = 1.3-1.5).
    assert fresnel.two_C1(eta) == pytest.approx(_exact_two_C1(eta), rel=3e-3)
    assert fresnel.three_C2(eta) == pytest.approx(_exact_three_C2(eta), rel=1.5e-2)
    assert fresnel.two_C1(1 / eta) == pytest.approx(_exact_two_C1(1 / eta), rel=3e-3)


def test_quadrature_matches_spec_exact_column():
    assert _exact_two_C1(1.3) == pytest.approx(0.44446, abs=1e-5)
    assert _exact_two_C1(1 / 1.3) == pytest.approx(0.06113, abs=1e-5)
    assert _exact_three_C2(1.3) == pytest.approx(0.30027, abs=1e-5)
    assert _exact_two_C1(1.5) == pytest.approx(0.59635, abs=1e-5)


def test_egan_hilgeman_matches_spec_2_3():
    for eta, F_dr, A in [(1.3, 0.444763, 2.602064), (1.5, 0.596733, 3.959497)]:
        value = fresnel.F_dr_egan_hilgeman(eta)
        assert value == pytest.approx(F_dr, abs=1e-6)
        assert (1 + value) / (1 - value) == pytest.approx(A, abs=1e-5)


unit_vectors = (
    st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1))
    .filter(lambda v: 1e-3 < np.linalg.norm(v))
    .map(lambda v: np.array(v) / np.linalg.norm(v))
)


@settings(max_examples=200)
@given(unit_vectors, unit_vectors, st.floats(1.0, 2.5))
def test_refraction_obeys_snell(w_i, n, eta):
    if np.dot(w_i, n) < 0:
        w_i = w_i - 2 * np.dot(w_i, n) * n  # put the light on the outside
    w12 = fresnel.refract(w_i, n, eta)
    assert np.linalg.norm(w12) == pytest.approx(1.0, abs=1e-12)
    cos_t = -np.dot(w12, n)
    assert cos_t > -1e-12  # into the medium (grazing light at eta = 1 stays along the surface, to rounding)
    sin_i = np.linalg.norm(np.cross(w_i, n))
    sin_t = np.linalg.norm(np.cross(w12, n))
    assert sin_t == pytest.approx(sin_i / eta, abs=1e-9)
    # coplanar with w_i and n
    assert abs(np.dot(np.cross(w_i, n), w12)) < 1e-9


def test_refraction_broadcasts_and_is_identity_at_eta_one():
    rng = np.random.default_rng(3)
    w = rng.normal(size=(4, 5, 3))
    w /= np.linalg.norm(w, axis=-1, keepdims=True)
    n = np.array([0.0, 0.0, 1.0])
    w[..., 2] = np.abs(w[..., 2])
    assert fresnel.refract(w, n, 1.0).shape == (4, 5, 3)
    assert np.allclose(fresnel.refract(w, n, 1.0), -w, atol=1e-12)
    assert fresnel.refract(w, n, np.full((4, 5), 1.3)).shape == (4, 5, 3)
