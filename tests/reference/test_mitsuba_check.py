"""The Mitsuba 3 check (translucency.reference.mitsuba_check) against results known exactly.

1. Index-matched half-space (eta = 1, isotropic scattering): Chandrasekhar's H-function gives the
   radiance diffusely reflected by a semi-infinite medium lit by a parallel beam of flux ``pi F`` per
   unit area normal to it, arriving at cosine ``mu0``, seen at cosine ``mu``:
   ``I(mu; mu0) = F alpha mu0 H(mu) H(mu0) / (4 (mu + mu0))`` (Chandrasekhar, *Radiative Transfer*; the
   same H-function gives the totals of docs/physics.md §9.3, and integrating this radiance over the
   hemisphere reproduces them, which the test checks too). A light of radiance ``L_e`` over a small
   cone contributes ``pi F = L_e dw`` per solid-angle element, so the reference is that formula
   integrated over the light's cone: the finite light adds no bias to the comparison. The slab is a
   60 x 60 x 30 mm box (the diffusion length is 1.7 mm, so its sides and bottom are out of reach);
   the sensor is the middle of the top face, seen along the normal with the light 30 deg off it.
2. Single scattering under a refracting boundary (eta = 1.5, Henyey-Greenstein g = 0.3): with
   ``max_depth = 4`` volpath keeps only the paths refracted in, scattered once and refracted out
   (three bounces, then the light), whose radiance along the normal is exact. A beam of irradiance
   ``E`` (on a surface facing it) at cosine ``mu`` enters with ``T12(mu)``, travels at inside cosine
   ``mu'``; the light scattered once toward the normal leaves with ``T21(1)`` and the radiance drops by
   ``eta^2`` on the way out:
   ``L1 = alpha T12 T21 E mu p(-mu') / (eta^2 (mu' + 1))`` (the depth integral of
   ``sigma_s E mu T12 / mu' exp(-sigma_t z (1/mu' + 1))``), again integrated over the light's cone.
   It checks the refraction of the light, both Fresnel factors, the phase function and the
   ``eta^2`` radiance law.
3. A slab that only absorbs (eta = 1.5), lit from behind and seen along the normal: the sensor ray
   crosses the two faces at normal incidence and sees the light straight through, so
   ``L = L_e T^2 e^-tau / (1 - R^2 e^-2 tau)`` exactly (``R = ((eta - 1)/(eta + 1))^2``, ``T = 1 - R``,
   the inter-reflections summed), which checks the light's radiance, the refractive boundary and the
   extinction in mm.

All are traced in Mitsuba's ``scalar_rgb`` variant; the test skips when Mitsuba is not installed. The
argument checks run without it.
"""

import math
import subprocess
import sys

import numpy as np
import pytest

from translucency.errors import InvalidParameterError, MeshError
from translucency.geometry.synthetic import icosphere
from translucency.reference.mitsuba_check import light_radiance, volpath_radiance
from translucency.scatter.fresnel import fresnel_reflectance
from translucency.scatter.medium import Medium


def _mitsuba():
    try:
        import mitsuba  # noqa: F401
    except ImportError:
        pytest.skip("Mitsuba 3 is not installed (the reference extra)")


def box(lo, hi):
    """A closed box with outward counter-clockwise triangles: (8, 3) points in mm and (12, 3) triangles."""
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])], float)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return corners, np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])


def h_function(albedo, n=64):
    """Chandrasekhar's H(mu) for isotropic scattering, as a function, solved by Gauss-Legendre iteration."""
    x, w = np.polynomial.legendre.leggauss(n)
    mu, w = 0.5 * (x + 1), 0.5 * w
    h = np.ones(n)
    for _ in range(1000):
        new = 1.0 / (1.0 - 0.5 * albedo * mu * np.sum(w * h / (mu[:, None] + mu), axis=1))
        if np.max(np.abs(new - h)) < 1e-14:
            break
        h = new

    def at(m):
        m = np.asarray(m, float)[..., None]
        return 1.0 / (1.0 - 0.5 * albedo * m[..., 0] * np.sum(w * h / (m + mu), axis=-1))

    return at


def reflected_radiance(albedo, theta_deg, half_angle_deg, irradiance):
    """Radiance reflected along the normal of an index-matched half-space lit by a uniform cone (W/(m^2 sr))."""
    h = h_function(albedo)

    def integrand(mu):
        return albedo * mu * h(1.0) * h(mu) / (4 * math.pi * (1 + mu))

    return light_radiance(irradiance, half_angle_deg) * cone_average(integrand, theta_deg, half_angle_deg)


def cone_average(integrand, theta_deg, half_angle_deg):
    """The integral of ``integrand(mu)`` over the light's cone (solid angle, sr), the cone ``theta_deg`` off the normal.

    ``mu`` is the cosine between each direction of the cone and the normal; Gauss-Legendre in the
    angle from the cone's axis, the midpoint rule in the azimuth.
    """
    x, w = np.polynomial.legendre.leggauss(24)
    psi = 0.5 * math.radians(half_angle_deg) * (x + 1)
    w_psi = 0.5 * math.radians(half_angle_deg) * w
    phi = (np.arange(64) + 0.5) * 2 * math.pi / 64
    theta = math.radians(theta_deg)
    mu = math.cos(theta) * np.cos(psi)[:, None] + math.sin(theta) * np.sin(psi)[:, None] * np.cos(phi)
    return np.sum(integrand(mu) * (np.sin(psi) * w_psi)[:, None]) * (2 * math.pi / 64)


def single_scattered_radiance(sigma_s, sigma_a, g, eta, theta_deg, half_angle_deg, irradiance):
    """Once-scattered radiance along the normal of a half-space under a smooth boundary, uniform cone light."""
    albedo = sigma_s / (sigma_s + sigma_a)
    exit_transmittance = 1 - fresnel_reflectance(1.0, eta)

    def integrand(mu):
        inside = np.sqrt(1 - (1 - mu**2) / eta**2)  # cosine of the refracted beam with the inward normal
        cos_scatter = -inside  # between the refracted beam (travelling down) and the normal (up)
        phase = (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * cos_scatter) ** 1.5)
        entry_transmittance = 1 - fresnel_reflectance(mu, eta)
        return albedo * entry_transmittance * exit_transmittance * mu * phase / (eta**2 * (inside + 1))

    return light_radiance(irradiance, half_angle_deg) * cone_average(integrand, theta_deg, half_angle_deg)


def test_the_h_function_reproduces_the_exact_totals():
    """Integrating I(mu; mu0) over the hemisphere gives R(mu0) = 1 - H(mu0) sqrt(1 - alpha) (docs/physics.md §9.3)."""
    for albedo, expected in ((0.5, 0.115226), (0.9, 0.414947)):
        h = h_function(albedo)
        x, w = np.polynomial.legendre.leggauss(64)
        mu, w = 0.5 * (x + 1), 0.5 * w
        total = 2 * np.sum(w * albedo * h(1.0) * h(mu) / (4 * (mu + 1)) * mu)
        assert total == pytest.approx(expected, abs=1e-6)


def half_space_radiance(medium, theta_deg, half_angle_deg, **options):
    """Mitsuba's radiance along the normal at the middle of the top face of a 60 x 60 x 30 mm box.

    The light is ``theta_deg`` off the normal; returns the :class:`VolpathRadiance`.
    """
    _mitsuba()
    points, triangles = box((-30.0, -30.0, -30.0), (30.0, 30.0, 0.0))
    theta = math.radians(theta_deg)
    light = (math.sin(theta), 0.0, math.cos(theta))
    sensor, normal = [[0.0, 0.0, 0.0]], [[0.0, 0.0, 1.0]]
    return volpath_radiance(
        points, triangles, sensor, normal, medium, light, light_half_angle_deg=half_angle_deg, **options
    )


def test_index_matched_half_space_matches_chandrasekhar():
    sigma_s, sigma_a, theta, half_angle = 1.0, 0.1, 30.0, 10.0
    medium = Medium([sigma_a], [sigma_s], [0.0], eta=1.0)
    result = half_space_radiance(medium, theta, half_angle, irradiance=2.0, spp=262_144, seed=3)
    expected = reflected_radiance(sigma_s / (sigma_s + sigma_a), theta, half_angle, 2.0)
    got, se = result.radiance[0, 0], result.stderr[0, 0]
    assert result.radiance.shape == (1, 1) and result.max_depth == (-1,) and result.rr_depth == (10,)
    assert 0 < se < 0.03 * expected
    assert abs(got - expected) < 4 * se, (got, se, expected)


def test_single_scattering_under_a_refracting_boundary():
    sigma_s, sigma_a, g, eta, theta, half_angle = 1.0, 0.1, 0.3, 1.5, 30.0, 10.0
    medium = Medium([sigma_a], [sigma_s], [g], eta=eta)
    result = half_space_radiance(medium, theta, half_angle, spp=1_048_576, seed=5, max_depth=4)
    expected = single_scattered_radiance(sigma_s, sigma_a, g, eta, theta, half_angle, 1.0)
    got, se = result.radiance[0, 0], result.stderr[0, 0]
    assert 0 < se < 0.05 * expected
    assert abs(got - expected) < 4 * se, (got, se, expected)


def test_absorbing_slab_seen_through():
    _mitsuba()
    eta, sigma_a, thickness, half_angle = 1.5, 0.2, 2.0, 3.0
    points, triangles = box((-10.0, -10.0, -thickness), (10.0, 10.0, 0.0))
    medium = Medium([sigma_a, 2 * sigma_a], [1e-9, 1e-9], [0.0, 0.0], eta=eta)
    result = volpath_radiance(
        points, triangles, [[0.0, 0.0, 0.0]], [[0.0, 0.0, 1.0]], medium, (0, 0, -1), light_half_angle_deg=half_angle
    )
    reflectance = ((eta - 1) / (eta + 1)) ** 2
    tau = np.array([sigma_a, 2 * sigma_a]) * thickness
    expected = (
        light_radiance(1.0, half_angle)
        * (1 - reflectance) ** 2
        * np.exp(-tau)
        / (1 - reflectance**2 * np.exp(-2 * tau))
    )
    got, se = result.radiance[0], result.stderr[0]
    assert np.all(se > 0) and np.all(se < 0.02 * expected)
    assert np.all(np.abs(got - expected) < 4 * se), (got, se, expected)


def test_a_sensor_that_sees_the_light_mirrored_is_refused():
    points, triangles = icosphere(1, 10.0)
    with pytest.raises(InvalidParameterError, match="mirrored"):
        volpath_radiance(points, triangles, [[0, 0, 10.0]], [[0, 0, 1.0]], Medium(0.1, 1.0, 0.0, 1.3), (0, 0.01, 1))


def test_an_open_or_inward_mesh_is_refused():
    points, triangles = icosphere(1, 10.0)
    args = ([[0, 0, 10.0]], [[1.0, 0, 0]], Medium(0.1, 1.0, 0.0, 1.3), (0, 0, 1))
    with pytest.raises(MeshError, match="closed"):
        volpath_radiance(points, triangles[1:], *args)
    with pytest.raises(MeshError, match="outward"):
        volpath_radiance(points, triangles[:, ::-1], *args)


def test_importing_the_package_loads_no_mitsuba():
    code = "import sys, translucency, translucency.reference; assert 'mitsuba' not in sys.modules"
    subprocess.run([sys.executable, "-c", code], check=True)
