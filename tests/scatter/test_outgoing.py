"""Outgoing radiance toward a viewer: T21 of the subsurface part, the GGX highlight's energy and reciprocity."""

import numpy as np
import pytest

from translucency.errors import InvalidParameterError
from translucency.scatter.fresnel import fresnel_reflectance, fresnel_transmittance
from translucency.scatter.outgoing import (
    ggx_distribution,
    specular_radiance,
    subsurface_radiance,
    view_directions,
)


def hemisphere(n, seed=0):
    """Directions uniform in solid angle over z > 0 (pdf 1 / (2 pi))."""
    rng = np.random.default_rng(seed)
    cos = rng.random(n)
    phi = 2 * np.pi * rng.random(n)
    sin = np.sqrt(1 - cos**2)
    return np.stack([sin * np.cos(phi), sin * np.sin(phi), cos], axis=1)


def test_subsurface_radiance_is_T21_B_and_zero_facing_away():
    B = np.array([[1.0, 2.0, 3.0]] * 3)
    normals = np.array([[0, 0, 1.0]] * 3)
    w_o = np.array([[0, 0, 1.0], [0.6, 0, 0.8], [0, 0, -1.0]])
    L = subsurface_radiance(B, normals, w_o, 1.5)
    np.testing.assert_allclose(L[0], fresnel_transmittance(1.0, 1.5) * B[0])
    np.testing.assert_allclose(L[1], fresnel_transmittance(0.8, 1.5) * B[1])
    np.testing.assert_array_equal(L[2], 0.0)


def test_ggx_distribution_is_normalised():
    # integral of D(h) cos(theta_h) over the hemisphere of h is 1
    h = hemisphere(400_000)
    for alpha in (0.2, 0.5, 1.0):
        assert (ggx_distribution(h[:, 2], alpha) * h[:, 2]).mean() * 2 * np.pi == pytest.approx(1.0, rel=0.02)


def test_highlight_reflects_about_F0_at_normal_incidence_and_is_reciprocal():
    n = 400_000
    w_o = hemisphere(n, seed=1)
    normals = np.tile([0.0, 0.0, 1.0], (n, 1))
    # E cos = 1 W/m^2 from the normal: the reflected flux fraction is F_r(1, eta) for a smooth-ish surface
    L = specular_radiance(normals, w_o, [0.0, 0.0, 1.0], np.ones((n, 1)), 1.5, 0.1)
    albedo = (L[:, 0] * w_o[:, 2]).mean() * 2 * np.pi
    assert albedo == pytest.approx(fresnel_reflectance(1.0, 1.5), rel=0.05)
    rough = specular_radiance(normals, w_o, [0.0, 0.0, 1.0], np.ones((n, 1)), 1.5, 1.0)
    assert 0 < (rough[:, 0] * w_o[:, 2]).mean() * 2 * np.pi < albedo  # shadowing-masking loses some
    # reciprocity: with E cos(theta_i) = 1 the radiance is the BRDF, symmetric in w_i, w_o
    a, b = hemisphere(50, seed=2), hemisphere(50, seed=3)
    f_ab = specular_radiance(normals[:50], b, a, np.ones((50, 1)), 1.5, 0.3)[:, 0]
    f_ba = specular_radiance(normals[:50], a, b, np.ones((50, 1)), 1.5, 0.3)[:, 0]
    assert f_ab.max() > 0
    np.testing.assert_allclose(f_ab, f_ba, rtol=1e-10)


def test_highlight_is_zero_where_the_surface_faces_away_and_never_negative():
    normals = np.tile([0.0, 0.0, 1.0], (4, 1))
    w_o = np.array([[0, 0, 1.0], [0, 0, -1.0], [1.0, 0, 0], [0.6, 0, 0.8]])
    L = specular_radiance(normals, w_o, [0.0, 0.0, -1.0], np.ones((4, 3)), 1.3, 0.3)  # light from below
    np.testing.assert_array_equal(L, 0.0)
    L = specular_radiance(normals, w_o, [0.0, 0.0, 1.0], np.ones((4, 3)), 1.3, 0.3)
    assert np.all(np.isfinite(L)) and np.all(L >= 0) and L[0, 0] > 0 and L[1, 0] == 0 and L[2, 0] == 0
    with pytest.raises(InvalidParameterError, match="roughness"):
        specular_radiance(normals, w_o, [0.0, 0.0, 1.0], np.ones((4, 3)), 1.3, 0.0)


def test_view_directions_point_at_the_eye():
    w = view_directions([[0, 0, 0], [10, 0, 0]], [0, 0, 10])
    np.testing.assert_allclose(w, [[0, 0, 1], [-1 / np.sqrt(2), 0, 1 / np.sqrt(2)]])
