"""The reference diffusion models against the independent values of docs/physics.md §10 and physical properties."""

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy import integrate

from translucency.errors import InvalidParameterError
from translucency.scatter import dipoles, fresnel

# ---------------------------------------------------------------- golden values (tests/data, computed independently)


def _evaluate(case):
    w12 = fresnel.refract(case["w_i"], case["n_i"], case["eta"])
    S_d = dipoles.directional_dipole(
        case["x_i"],
        case["n_i"],
        w12,
        case["x_o"],
        case["n_o"],
        case["sigma_a"],
        case["sigma_s"],
        case["g"],
        case["eta"],
    )
    return w12, S_d


def test_every_reference_vector(dirpole_vectors):
    """All 252 configurations of dirpole_vectors.json: relative 1e-9 (absolute 1e-15 where S_d = 0)."""
    cases = dirpole_vectors["edge_cases"] + dirpole_vectors["random"]
    assert len(cases) == 252
    for case in cases:
        w12, S_d = _evaluate(case)
        assert np.allclose(w12, case["w12"], rtol=1e-12, atol=1e-15)
        if case["S_d"] == 0.0:
            assert S_d == pytest.approx(0.0, abs=1e-15), case.get("note")
        else:
            assert S_d == pytest.approx(case["S_d"], rel=1e-9), case.get("note")
        T12 = fresnel.fresnel_transmittance(np.dot(case["n_i"], case["w_i"]), case["eta"])
        T21 = fresnel.fresnel_transmittance(np.dot(case["n_o"], case["w_o"]), case["eta"])
        assert T12 == pytest.approx(case["T12"], rel=1e-12)
        assert T21 == pytest.approx(case["T21"], rel=1e-12)
        assert T12 * S_d * T21 == pytest.approx(case["S"], rel=1e-9, abs=1e-15)


def test_reference_vectors_vectorised(dirpole_vectors):
    """The same vectors evaluated in one broadcast call give the same answers."""
    cases = dirpole_vectors["random"]
    stack = {
        k: np.array([c[k] for c in cases])
        for k in ("x_i", "n_i", "w_i", "x_o", "n_o", "sigma_a", "sigma_s", "g", "eta", "S_d")
    }
    w12 = fresnel.refract(stack["w_i"], stack["n_i"], stack["eta"])
    S_d = dipoles.directional_dipole(
        stack["x_i"],
        stack["n_i"],
        w12,
        stack["x_o"],
        stack["n_o"],
        stack["sigma_a"],
        stack["sigma_s"],
        stack["g"],
        stack["eta"],
    )
    assert S_d.shape == (len(cases),)
    nonzero = stack["S_d"] > 0
    assert np.allclose(S_d[nonzero], stack["S_d"][nonzero], rtol=1e-9, atol=0)
    assert np.all(np.abs(S_d[~nonzero]) <= 1e-15)


# docs/physics.md §10.1: flat surface, sigma_s = 0.99, sigma_a = 0.01, g = 0, eta = 1.3;
# S_d at x_o for theta_i 0 and 45 deg.
SPEC_FLAT = [
    ((0, 0, 0), 2.865155e-01, 4.004100e-01),
    ((0.5, 0, 0), 3.015027e-02, 4.201651e-02),
    ((-0.5, 0, 0), 3.015027e-02, 2.590373e-02),
    ((0, 0.5, 0), 3.015027e-02, 3.138076e-02),
    ((1, 0, 0), 1.176877e-02, 1.588037e-02),
    ((-1, 0, 0), 1.176877e-02, 8.306006e-03),
    ((2, 0, 0), 3.890385e-03, 5.012283e-03),
    ((5, 0, 0), 5.488104e-04, 6.396252e-04),
]


@pytest.mark.parametrize("x_o, normal, oblique", SPEC_FLAT)
def test_flat_surface_table(x_o, normal, oblique):
    args = (0.01, 0.99, 0.0, 1.3)
    assert dipoles.directional_dipole_profile(np.array(x_o, float), 0.0, *args) == pytest.approx(normal, rel=1e-6)
    assert dipoles.directional_dipole_profile(np.array(x_o, float), 45.0, *args) == pytest.approx(oblique, rel=1e-6)


def test_full_bssrdf_example_of_spec_1_9():
    S_d = dipoles.directional_dipole_profile(np.array([1.0, 0, 0]), 45.0, 0.01, 0.99, 0.0, 1.3)
    T12 = fresnel.fresnel_transmittance(np.cos(np.radians(45)), 1.3)
    T21 = fresnel.fresnel_transmittance(1.0, 1.3)
    assert T12 * S_d * T21 == pytest.approx(1.523841e-02, rel=1e-6)


# docs/physics.md §10.4 (eta = 1.3, sigma_t' = 1, normal incidence): totals per refracted photon, 4 decimals.
SPEC_TOTALS_13 = [  # alpha', directional, standard, better
    (0.3, 0.1825, 0.0355, 0.0085),
    (0.5, 0.2244, 0.0745, 0.0289),
    (0.7, 0.2943, 0.1406, 0.0783),
    (0.8, 0.3565, 0.1969, 0.1312),
    (0.9, 0.4752, 0.2991, 0.2434),
    (0.95, 0.6021, 0.4066, 0.3703),
    (0.99, 0.8717, 0.6445, 0.6421),
    (0.999, 1.1032, 0.8639, 0.8693),
]


@pytest.mark.parametrize("alpha, directional, standard, better", SPEC_TOTALS_13)
def test_total_reflectance_table_eta_1_3(alpha, directional, standard, better):
    tol = 1e-4  # the table prints 4 decimals (its standard dipole at alpha' = 0.3 differs by 5.3e-5)
    assert dipoles.directional_dipole_total_reflectance(1 - alpha, alpha, 0.0, 1.3) == pytest.approx(
        directional, abs=tol
    )
    assert dipoles.standard_dipole_total_reflectance(alpha, 1.3) == pytest.approx(standard, abs=tol)
    assert dipoles.better_dipole_total_reflectance(alpha, 1.3) == pytest.approx(better, abs=tol)


def test_total_reflectance_index_matched_spec_3_3():
    # docs/physics.md §9.3, eta = 1, normal incidence: standard 0.7465 / 0.3853, better 0.7381 / 0.3441,
    # directional 1.0874 / 0.7103 for alpha = 0.99 / 0.9.
    for alpha, std, bet, direc in [(0.99, 0.7465, 0.7381, 1.0874), (0.9, 0.3853, 0.3441, 0.7103)]:
        assert dipoles.standard_dipole_total_reflectance(alpha, 1.0) == pytest.approx(std, abs=6e-5)
        assert dipoles.better_dipole_total_reflectance(alpha, 1.0) == pytest.approx(bet, abs=6e-5)
        assert dipoles.directional_dipole_total_reflectance(1 - alpha, alpha, 0.0, 1.0) == pytest.approx(
            direc, abs=6e-5
        )


# ------------------------------------------------------ closed forms against the integral of the profile


def _plane_integral(profile, *args):
    """Integral of a radial profile over the plane, 2 pi int_0^inf R(r) r dr, by adaptive quadrature."""
    value, _ = integrate.quad(
        lambda r: 2 * np.pi * r * float(profile(r, *args)), 0, np.inf, limit=500, epsabs=0, epsrel=1e-10
    )
    return value


@pytest.mark.parametrize("alpha", [0.1, 0.5, 0.9, 0.99, 0.9999])
@pytest.mark.parametrize("eta", [1.0, 1.3, 1.5])
def test_closed_form_totals_equal_integrals(alpha, eta):
    sigma_t = 2.5  # any scale: the totals depend on alpha' only
    sigma_s, sigma_a = alpha * sigma_t, (1 - alpha) * sigma_t
    assert dipoles.standard_dipole_total_reflectance(alpha, eta) == pytest.approx(
        _plane_integral(dipoles.standard_dipole_profile, sigma_a, sigma_s, 0.0, eta), rel=1e-7
    )
    assert dipoles.better_dipole_total_reflectance(alpha, eta) == pytest.approx(
        _plane_integral(dipoles.better_dipole_profile, sigma_a, sigma_s, 0.0, eta), rel=1e-7
    )


def test_directional_total_at_normal_incidence_equals_radial_integral():
    # At normal incidence on a plane the directional dipole is radially symmetric: a 1D integral of
    # pi S_d / norm checks the polar quadrature of directional_dipole_total_reflectance.
    sigma_a, sigma_s, eta = 0.02, 1.1, 1.4
    norm = 1 / (4 * fresnel.C_phi(1 / eta))

    def radial(r):
        return (
            np.pi / norm * dipoles.directional_dipole_profile(np.array([r, 0.0, 0.0]), 0.0, sigma_a, sigma_s, 0.0, eta)
        )

    expected = _plane_integral(radial)
    assert dipoles.directional_dipole_total_reflectance(sigma_a, sigma_s, 0.0, eta) == pytest.approx(expected, rel=1e-5)


def test_better_dipole_total_tends_to_one_without_absorption():
    # docs/physics.md §6.2: as alpha' -> 1 the better dipole conserves energy, 2 A C_phi + C_E = 1.
    for eta in (1.0, 1.3, 1.5):
        assert dipoles.better_dipole_total_reflectance(1.0, eta) == pytest.approx(1.0, abs=1e-12)


# ----------------------------------------------------------------------------- property tests


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


vectors = (
    st.tuples(*[st.floats(-1, 1, allow_subnormal=False)] * 3).filter(lambda v: np.linalg.norm(v) > 1e-3).map(_unit)
)
axis_vectors = st.sampled_from([np.array(v, float) for v in [(0, 0, 1), (0, 0, -1), (1, 0, 0), (0, 1, 0), (0, -1, 0)]])
directions = st.one_of(vectors, axis_vectors)
log_floats = lambda lo, hi: st.floats(np.log10(lo), np.log10(hi)).map(lambda e: 10.0**e)  # noqa: E731


@settings(max_examples=400, deadline=None)
@given(
    n_i=directions,
    light=directions,
    n_o=directions,
    offset=st.one_of(st.just(np.zeros(3)), vectors.map(lambda v: v * 0.0), vectors),
    distance=st.one_of(st.just(0.0), log_floats(1e-12, 1e4)),
    sigma_s=log_floats(1e-4, 1e4),
    albedo=st.floats(1e-6, 1 - 1e-9),
    g=st.floats(-0.95, 0.95),
    eta=st.floats(1.0, 2.5),
)
def test_finite_and_non_negative(n_i, light, n_o, offset, distance, sigma_s, albedo, g, eta):
    """No NaN, no inf and S_d >= 0 over wide ranges, degenerate geometry included (r = 0, n_i || x)."""
    w_i = light if np.dot(light, n_i) > 0 else light - 2 * np.dot(light, n_i) * n_i
    assume(np.dot(w_i, n_i) >= 0)
    sigma_s_reduced = sigma_s
    sigma_a = sigma_s_reduced * (1 - albedo) / albedo
    x_o = offset * distance
    w12 = fresnel.refract(w_i, n_i, eta)
    with np.errstate(over="raise", invalid="raise", divide="raise", under="ignore"):
        S_d = dipoles.directional_dipole(np.zeros(3), n_i, w12, x_o, n_o, sigma_a, sigma_s_reduced / (1 - g), g, eta)
    assert np.isfinite(S_d)
    assert S_d >= 0.0


def test_continuous_as_r_goes_to_zero():
    args = (0.01, 0.99, 0.0, 1.3)
    for theta in (0.0, 45.0, 80.0):
        at_zero = dipoles.directional_dipole_profile(np.zeros(3), theta, *args)
        for direction in ([1, 0, 0], [-1, 0, 0], [0, 1, 0], [0.6, 0.8, 0]):
            for r in (1e-5, 1e-7, 1e-9, 1e-12):
                value = dipoles.directional_dipole_profile(np.array(direction) * r, theta, *args)
                # Lipschitz near 0: |S_d(r) - S_d(0)| <= 20/mm * r * S_d(0) for this material
                assert abs(value - at_zero) <= 20.0 * r * at_zero


def test_exit_point_on_the_normal_axis_uses_n_i():
    """On the axis n_i || x the modified tangent plane is undefined and n_i* = n_i is used (docs/physics.md §4.6).

    The limit is not unique (approaching the axis from any side turns n_i* by 90 degrees), so the
    fallback is a choice, not a continuous extension; the value equals the edge case in tests/data
    (docs/physics.md §10.7).
    """
    n = np.array([0.0, 0.0, 1.0])
    w12 = fresnel.refract(_unit([-1, 0, 1]), n, 1.3)
    on_axis = dipoles.directional_dipole(np.zeros(3), n, w12, np.array([0.0, 0.0, -2.0]), -n, 0.01, 0.99, 0.0, 1.3)
    assert on_axis == pytest.approx(0.009291946683014009, rel=1e-9)
    off_axis = dipoles.directional_dipole(np.zeros(3), n, w12, np.array([1e-9, 0.0, -2.0]), -n, 0.01, 0.99, 0.0, 1.3)
    assert np.isfinite(off_axis) and off_axis > 0


@settings(max_examples=100, deadline=None)
@given(
    scale=log_floats(1e-3, 1e3), n_i=vectors, light=vectors, n_o=vectors, offset=vectors, distance=st.floats(0.0, 10.0)
)
def test_scale_invariance(scale, n_i, light, n_o, offset, distance):
    """x -> s x with sigma -> sigma / s multiplies S_d by 1 / s^2."""
    w_i = light if np.dot(light, n_i) > 0 else light - 2 * np.dot(light, n_i) * n_i
    assume(np.dot(w_i, n_i) > 1e-6)
    w12 = fresnel.refract(w_i, n_i, 1.4)
    x_i, x_o = np.array([0.3, -0.2, 0.1]), offset * distance
    base = dipoles.directional_dipole(x_i, n_i, w12, x_o, n_o, 0.05, 1.2, 0.3, 1.4)
    scaled = dipoles.directional_dipole(x_i * scale, n_i, w12, x_o * scale, n_o, 0.05 / scale, 1.2 / scale, 0.3, 1.4)
    assert scaled * scale**2 == pytest.approx(base, rel=1e-9, abs=1e-300)
    for profile in (dipoles.standard_dipole_profile, dipoles.better_dipole_profile):
        assert profile(distance * scale, 0.05 / scale, 1.2 / scale, 0.3, 1.4) * scale**2 == pytest.approx(
            profile(distance, 0.05, 1.2, 0.3, 1.4), rel=1e-9
        )


def test_broadcasting_matches_loops():
    rng = np.random.default_rng(7)
    x_i = rng.normal(size=(5, 1, 3))
    n_i = rng.normal(size=(5, 1, 3))
    n_i /= np.linalg.norm(n_i, axis=-1, keepdims=True)
    x_o = rng.normal(size=(1, 4, 3))
    n_o = rng.normal(size=(1, 4, 3))
    n_o /= np.linalg.norm(n_o, axis=-1, keepdims=True)
    w12 = -n_i
    sigma_a = np.array([0.01, 0.02, 0.03, 0.04])
    out = dipoles.directional_dipole(x_i, n_i, w12, x_o, n_o, sigma_a, 1.0, 0.0, 1.3)
    assert out.shape == (5, 4)
    for i in range(5):
        for j in range(4):
            single = dipoles.directional_dipole(
                x_i[i, 0], n_i[i, 0], w12[i, 0], x_o[0, j], n_o[0, j], sigma_a[j], 1.0, 0.0, 1.3
            )
            assert out[i, j] == pytest.approx(single, rel=1e-14)


def test_invalid_parameters_are_rejected_with_a_sentence():
    z = np.array([0.0, 0.0, 1.0])
    with pytest.raises(InvalidParameterError, match="eta"):
        dipoles.directional_dipole(np.zeros(3), z, -z, np.ones(3), z, 0.01, 1.0, 0.0, 0.9)
    with pytest.raises(InvalidParameterError, match="scatter"):
        dipoles.directional_dipole(np.zeros(3), z, -z, np.ones(3), z, 0.01, 0.0, 0.0, 1.3)
    with pytest.raises(InvalidParameterError, match="sigma_a"):
        dipoles.standard_dipole_profile(1.0, -0.01, 1.0, 0.0, 1.3)
    with pytest.raises(InvalidParameterError, match="finite"):
        dipoles.better_dipole_profile(1.0, np.nan, 1.0, 0.0, 1.3)
