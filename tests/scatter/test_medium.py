"""Medium: derived quantities (docs/physics.md §2.1, §10.1) and validation with readable sentences."""

import warnings

import numpy as np
import pytest

from translucency.errors import InvalidParameterError, TranslucencyError
from translucency.scatter.medium import Medium, validate_coefficients


def test_derived_quantities_match_spec_1_9():
    # sigma_s = 0.99, sigma_a = 0.01, g = 0, eta = 1.3: sigma_t' = 1, alpha' = 0.99, D = 1/3,
    # sigma_tr = 0.173205, d_e = 0.713912, A = 2.338986, 2 A d_e = 3.339659 mm.
    m = Medium(0.01, 0.99, 0.0, 1.3)
    assert m.n_channels == 3
    assert np.allclose(m.sigma_t_reduced, 1.0, rtol=1e-15)
    assert np.allclose(m.alpha_reduced, 0.99, rtol=1e-15)
    assert np.allclose(m.D, 1 / 3, rtol=1e-15)
    assert np.allclose(m.sigma_tr, 0.173205, atol=5e-7)
    assert np.allclose(m.d_e, 0.713912, atol=5e-7)
    assert m.A == pytest.approx(2.338986, abs=5e-7)
    assert np.allclose(2 * m.A * m.d_e, 3.339659, atol=5e-6)


def test_reduction_uses_g():
    m = Medium([0.01, 0.02, 0.03], [1.0, 2.0, 3.0], [0.5, 0.0, -0.5], 1.4)
    assert np.allclose(m.sigma_s_reduced, [0.5, 2.0, 4.5])
    assert np.allclose(m.sigma_t, [1.01, 2.02, 3.03])
    assert np.allclose(m.sigma_t_reduced, [0.51, 2.02, 4.53])
    assert np.allclose(m.mean_free_path, 1 / m.sigma_t_reduced)
    assert np.allclose(m.diffusion_length, 1 / np.sqrt(3 * m.sigma_a * m.sigma_t_reduced))


def test_from_reduced_and_scaled():
    m = Medium.from_reduced([0.0021, 0.0041, 0.0071], [2.19, 2.62, 3.00], eta=1.5, name="marble")
    assert np.all(m.g == 0) and m.eta == 1.5
    assert np.allclose(m.sigma_s_reduced, [2.19, 2.62, 3.00])
    cm = m.scaled(10.0)  # per mm -> per cm
    assert np.allclose(cm.sigma_a, np.array([0.0021, 0.0041, 0.0071]) * 10)
    assert np.allclose(cm.alpha_reduced, m.alpha_reduced)


def test_zero_absorption_is_valid_and_has_infinite_diffusion_length():
    m = Medium(0.0, 1.0, 0.0, 1.3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.all(np.isinf(m.diffusion_length))
    assert np.all(m.alpha_reduced == 1.0)


def test_arrays_are_read_only_copies():
    a = np.array([0.01, 0.02, 0.03])
    m = Medium(a, [1.0, 1.0, 1.0])
    a[0] = 99
    assert m.sigma_a[0] == 0.01
    with pytest.raises(ValueError):
        m.sigma_a[0] = 5


@pytest.mark.parametrize(
    "kwargs, fragment",
    [
        (dict(sigma_a=-0.1, sigma_s=1.0), "sigma_a must be >= 0"),
        (dict(sigma_a=0.1, sigma_s=-1.0), "sigma_s must be >= 0"),
        (dict(sigma_a=0.1, sigma_s=1.0, g=1.0), "g must lie in (-1, 1)"),
        (dict(sigma_a=0.1, sigma_s=1.0, g=-1.2), "g must lie in (-1, 1)"),
        (dict(sigma_a=0.1, sigma_s=1.0, eta=0.8), "eta = n_inside / n_outside must be >= 1"),
        (dict(sigma_a=0.1, sigma_s=0.0), "must scatter"),
        (dict(sigma_a=0.0, sigma_s=0.0), "must scatter"),
        (dict(sigma_a=np.nan, sigma_s=1.0), "sigma_a must be finite"),
        (dict(sigma_a=0.1, sigma_s=np.inf), "sigma_s must be finite"),
        (dict(sigma_a=0.1, sigma_s=1.0, eta=np.inf), "eta must be finite"),
        (dict(sigma_a=[0.1, 0.2], sigma_s=[1.0, 1.0, 1.0]), "matching shape"),
        (dict(sigma_a="abc", sigma_s=1.0), "must be numbers"),
    ],
)
def test_invalid_media_raise_one_sentence(kwargs, fragment):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no bare numpy warning on the way to the error
        with pytest.raises(InvalidParameterError) as info:
            Medium(**kwargs)
    message = str(info.value)
    assert fragment in message
    assert "\n" not in message
    assert isinstance(info.value, TranslucencyError) and isinstance(info.value, ValueError)


def test_eta_must_be_one_number():
    with pytest.raises(InvalidParameterError, match="single number"):
        Medium(0.1, 1.0, 0.0, [1.3, 1.4, 1.5])


def test_validate_coefficients_broadcasts():
    a, s, g, eta = validate_coefficients([0.1, 0.2], 1.0, 0.0, 1.3)
    assert a.shape == s.shape == g.shape == eta.shape == (2,)
    assert a.dtype == np.float64


def test_scaled_rejects_bad_factor():
    with pytest.raises(InvalidParameterError, match="positive"):
        Medium(0.1, 1.0).scaled(0.0)
