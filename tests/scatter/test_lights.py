"""Lights: construction and validation, inverse-square law, environment sampling and its stated error."""

import numpy as np
import pytest

from translucency.errors import InvalidParameterError
from translucency.scatter.lights import (
    DirectionalLight,
    EnvironmentLight,
    PointLight,
    as_light_list,
    cosine_integral_error,
    point_light_irradiance,
)


def test_directional_light_is_normalised_and_read_only():
    light = DirectionalLight((0, 0, 5), 3.0)
    assert np.allclose(light.direction, (0, 0, 1))
    assert np.allclose(light.irradiance_rgb, (3, 3, 3))
    with pytest.raises(ValueError):
        light.direction[0] = 1.0
    samples = light.directional_samples()
    assert samples.directions.shape == (1, 3) and np.allclose(samples.irradiance_rgb, [[3, 3, 3]])


@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"direction": (0, 0, 0)}, "non-zero length"),
        ({"direction": (0, 0, np.nan)}, "finite"),
        ({"direction": (0, 1)}, "three numbers"),
        ({"direction": "up"}, "three numbers"),
        ({"direction": (0, 0, 1), "irradiance_rgb": -1.0}, ">= 0"),
        ({"direction": (0, 0, 1), "irradiance_rgb": (1, 2)}, "three RGB numbers"),
        ({"direction": (0, 0, 1), "irradiance_rgb": (1, np.inf, 1)}, "finite"),
    ],
)
def test_directional_light_rejects_bad_values_with_a_sentence(kwargs, words):
    with pytest.raises(InvalidParameterError, match=words) as info:
        DirectionalLight(**kwargs)
    assert str(info.value).startswith("DirectionalLight:") and str(info.value).endswith(".")


def test_point_light_inverse_square_in_watts_per_square_metre():
    # I = 2 W/sr at 1 m gives 2 W/m²; at 0.5 m four times that.
    E = point_light_irradiance(np.array([2.0, 1.0, 0.5]), np.array([1000.0, 500.0]))
    assert np.allclose(E, [[2.0, 1.0, 0.5], [8.0, 4.0, 2.0]])
    # A light on the surface: the distance is floored, the value stays finite.
    assert np.all(np.isfinite(point_light_irradiance(np.ones(3), np.array([0.0]))))
    with pytest.raises(InvalidParameterError, match="intensity_rgb must be >= 0"):
        PointLight((0, 0, 0), -1.0)
    with pytest.raises(InvalidParameterError, match="position_mm"):
        PointLight((0, 0), 1.0)


def test_constant_environment_samples_cover_the_sphere():
    light = EnvironmentLight((0.5, 1.0, 2.0), n_directions=256)
    samples = light.directional_samples()
    assert len(samples) == 256
    assert np.allclose(np.linalg.norm(samples.directions, axis=1), 1.0)
    assert samples.solid_angle.sum() == pytest.approx(4 * np.pi)
    assert np.allclose(samples.irradiance_rgb.sum(axis=0), 4 * np.pi * np.array([0.5, 1.0, 2.0]))
    # Deterministic for a seed, different for another.
    again = EnvironmentLight((0.5, 1.0, 2.0), n_directions=256).directional_samples()
    assert np.array_equal(again.directions, samples.directions)
    other = EnvironmentLight((0.5, 1.0, 2.0), n_directions=256, seed=1).directional_samples()
    assert not np.array_equal(other.directions, samples.directions)


def test_stratified_cosine_error_is_small_and_falls_with_n():
    errors = [
        cosine_integral_error(EnvironmentLight(1.0, n_directions=n).directional_samples()) for n in (16, 64, 256, 1024)
    ]
    assert errors[2] < 0.005  # 256 directions: irradiance of a plane within 0.5 %
    assert errors[3] < 0.001
    assert all(a > b for a, b in zip(errors, errors[1:]))


def _plane_irradiance(samples, normal):
    cos = np.maximum(samples.directions @ normal, 0.0)
    return cos @ samples.irradiance_rgb


def _exact_map_irradiance(image, normal, up=(0.0, 0.0, 1.0)):
    """int L cos+ dw over an equirectangular map with +z up, by fine quadrature inside every pixel."""
    h, w, _ = image.shape
    sub = 8
    theta = (np.arange(h * sub) + 0.5) * np.pi / (h * sub)
    phi = (np.arange(w * sub) + 0.5) * 2 * np.pi / (w * sub)
    T, P = np.meshgrid(theta, phi, indexing="ij")
    d = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1)
    dw = np.sin(T) * (np.pi / (h * sub)) * (2 * np.pi / (w * sub))
    L = np.repeat(np.repeat(image, sub, axis=0), sub, axis=1)
    return np.einsum("ij,ijc->c", np.maximum(d @ normal, 0.0) * dw, L)


def test_map_sampling_importance_finds_the_sun():
    image = np.full((32, 64, 3), 0.05)
    image[5, 10] = (2000.0, 1800.0, 1500.0)  # a small, very bright sun
    sun = EnvironmentLight(radiance_map=image, n_directions=1).directional_samples()  # any sample
    assert len(sun) == 1
    theta, phi = (5.5 / 32) * np.pi, (10.5 / 64) * 2 * np.pi
    normal = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    exact = _exact_map_irradiance(image, normal)
    importance = _plane_irradiance(
        EnvironmentLight(radiance_map=image, n_directions=256, sampling="importance").directional_samples(), normal
    )
    stratified = _plane_irradiance(EnvironmentLight(radiance_map=image, n_directions=256).directional_samples(), normal)
    assert np.allclose(importance, exact, rtol=0.03)
    assert np.abs(importance - exact).max() < np.abs(stratified - exact).max()


def test_constant_map_equals_constant_environment():
    image = np.ones((16, 32, 3))
    for sampling in ("stratified", "importance"):
        samples = EnvironmentLight(radiance_map=image, n_directions=512, sampling=sampling).directional_samples()
        assert samples.solid_angle.sum() == pytest.approx(4 * np.pi)
        assert cosine_integral_error(samples) < 0.03


def test_map_up_axis_turns_the_zenith():
    image = np.zeros((8, 16, 3))
    image[0] = 1.0  # only the top row (around the zenith) is bright
    samples = EnvironmentLight(
        radiance_map=image, n_directions=64, sampling="importance", up=(0, 1, 0)
    ).directional_samples()
    assert np.all(samples.directions[:, 1] > np.cos(np.pi / 8) - 1e-12)


def test_black_map_gives_no_samples():
    samples = EnvironmentLight(radiance_map=np.zeros((4, 8, 3)), sampling="importance").directional_samples()
    assert len(samples) == 0


@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"n_directions": 0}, "n_directions must lie in"),
        ({"n_directions": 2.5}, "n_directions must be an integer"),
        ({"sampling": "random"}, "sampling must be one of"),
        ({"radiance_map": np.ones((4, 8))}, r"shape \(H, W, 3\)"),
        ({"radiance_map": -np.ones((4, 8, 3))}, "negative"),
        ({"radiance_map": np.full((4, 8, 3), np.nan)}, "NaN"),
        ({"up": (0, 0, 0)}, "non-zero length"),
        ({"seed": -1}, "seed must be an integer"),
    ],
)
def test_environment_rejects_bad_values_with_a_sentence(kwargs, words):
    with pytest.raises(InvalidParameterError, match=words):
        EnvironmentLight(**kwargs)


def test_to_dict_describes_each_light():
    assert DirectionalLight((1, 0, 0), 2).to_dict()["type"] == "directional"
    assert PointLight((0, 0, 10), 1).to_dict()["position_mm"] == [0, 0, 10]
    d = EnvironmentLight(radiance_map=np.ones((2, 4, 3)), name="studio.hdr").to_dict()
    assert d["map_shape"] == [2, 4, 3] and d["name"] == "studio.hdr"


def test_as_light_list():
    light = DirectionalLight((0, 0, 1))
    assert as_light_list(light) == (light,)
    with pytest.raises(InvalidParameterError, match="DirectionalLight, PointLight or EnvironmentLight"):
        as_light_list([light, "sun"])
