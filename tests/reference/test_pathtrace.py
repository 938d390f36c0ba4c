"""The path-traced reference on a mesh (translucency.reference.pathtrace) against independent answers.

- On a large flat slab, the radiance along the normal equals the half-space walk's (a photon walk from
  the light with a different estimator, docs/physics.md §9.1 item 7), itself checked against
  Chandrasekhar's H-function in tests/scatter/test_montecarlo.py: within 2 standard errors.
- On a sphere, it equals Mitsuba 3's volpath (tests/data/mitsuba_sphere.json) face by face.
- A convex object re-enters nothing; a torus re-enters light on its inner side.
- Scaling the object by k and the coefficients by 1/k changes nothing.
- The radiance is linear in the irradiance; identical channels are walked once.
Seeds are fixed, so every test is deterministic.
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from translucency.errors import InvalidParameterError, MeshError
from translucency.geometry.measure import triangle_normals
from translucency.geometry.synthetic import box, icosphere, torus
from translucency.reference.pathtrace import trace_radiance
from translucency.scatter.fresnel import fresnel_reflectance
from translucency.scatter.medium import Medium
from translucency.scatter.montecarlo import simulate_half_space

DATA = Path(__file__).resolve().parents[1] / "data"


def _medium(sigma_a, sigma_s, g, eta, channels=1):
    return Medium(sigma_a=[sigma_a] * channels, sigma_s=[sigma_s] * channels, g=[g] * channels, eta=eta)


@pytest.mark.slow
@pytest.mark.parametrize(("g", "eta", "theta"), [(0.3, 1.4, 30.0), (0.0, 1.0, 0.0)])
def test_flat_slab_matches_the_half_space_walk(g, eta, theta):
    # A 120 x 120 x 80 mm box: with sigma_tr = 0.34/mm its sides and bottom are 20-40 diffusion lengths
    # from the sensors, so the top face is a half-space to far below the standard error.
    sigma_a, sigma_s = 0.05, 1.0
    points, triangles = box((60.0, 60.0, 40.0), centre=(0.0, 0.0, -40.0))
    w_light = np.array([-math.sin(math.radians(theta)), 0.0, math.cos(math.radians(theta))])
    sensors = np.array([[0.0, 0.0, 0.0], [1.3, -0.7, 0.0]])
    normals = np.tile([0.0, 0.0, 1.0], (2, 1))
    traced = trace_radiance(points, triangles, sensors, normals, _medium(sigma_a, sigma_s, g, eta), w_light, spp=25_000)
    walk = simulate_half_space(sigma_a, sigma_s, g, eta, theta, n_photons=400_000, seed=11, grid_cells=3, radial_bins=3)
    cos_i = math.cos(math.radians(theta))
    factor = (1 - fresnel_reflectance(cos_i, eta)) * cos_i * (1 - fresnel_reflectance(1.0, 1 / eta)) / eta**2
    expected, expected_se = walk.normal_radiance * factor, walk.normal_radiance_se * factor
    got = traced.radiance.mean()
    got_se = math.sqrt(np.sum(traced.radiance_stderr**2)) / 2
    assert got_se < 0.005 * got  # a real check
    assert abs(got - expected) <= 2.0 * math.hypot(got_se, expected_se)
    assert traced.stats["leaked_paths"] == 0


def test_a_convex_object_re_enters_nothing_and_a_torus_does():
    medium = _medium(0.02, 1.0, 0.0, 1.3)
    light = np.array([0.3, 0.2, 1.0])
    points, triangles = icosphere(2, radius=4.0)
    normals = points / np.linalg.norm(points, axis=1, keepdims=True)
    sphere = trace_radiance(points, triangles, points[:40], normals[:40], medium, light, spp=16)
    assert np.all(sphere.radiance_reentered == 0.0)
    assert np.any(sphere.radiance > 0)

    points, triangles = torus(8.0, 3.0, 36, 18)
    # sensors on the inner equator, facing the hole, where light leaving the far side of the hole comes in
    angle = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    sensors = np.stack([5.0 * np.cos(angle), 5.0 * np.sin(angle), np.zeros_like(angle)], axis=1)
    inward = -sensors / 5.0
    ring = trace_radiance(points, triangles, sensors, inward, medium, np.array([0.2, 0.1, 1.0]), spp=64)
    assert np.all(ring.radiance_reentered > 0)
    assert np.all(ring.radiance_reentered < ring.radiance)
    assert ring.stats["leaked_paths"] < 0.01 * ring.stats["paths"]


def test_scaling_the_object_and_the_coefficients_together_changes_nothing():
    points, triangles = icosphere(2, radius=3.0)
    normals = points / np.linalg.norm(points, axis=1, keepdims=True)
    light = np.array([0.0, 0.6, 1.0])
    small = trace_radiance(points, triangles, points[:30], normals[:30], _medium(0.05, 2.0, 0.2, 1.4), light, spp=64)
    k = 1000.0
    large = trace_radiance(
        points * k, triangles, points[:30] * k, normals[:30], _medium(0.05 / k, 2.0 / k, 0.2, 1.4), light, spp=64
    )
    # The same random numbers drive both walks; only float32 ray casting can tell them apart.
    relative = np.abs(large.radiance - small.radiance) / np.maximum(small.radiance, 1e-12)
    assert np.median(relative) < 1e-6
    assert abs(large.radiance.mean() - small.radiance.mean()) <= 3 * np.sqrt(np.mean(small.radiance_stderr**2))


def test_radiance_is_linear_in_the_irradiance_and_identical_channels_walk_once():
    points, triangles = icosphere(1, radius=3.0)
    normals = points / np.linalg.norm(points, axis=1, keepdims=True)
    medium = _medium(0.1, 1.0, 0.0, 1.3, channels=3)
    one = trace_radiance(points, triangles, points, normals, _medium(0.1, 1.0, 0.0, 1.3), [0, 0, 1], spp=8)
    three = trace_radiance(points, triangles, points, normals, medium, [0, 0, 1], irradiance=[1.0, 2.0, 0.5], spp=8)
    assert three.stats["paths"] == one.stats["paths"]
    assert np.allclose(three.radiance, one.radiance * [1.0, 2.0, 0.5], rtol=1e-12, atol=0)
    assert np.allclose(three.radiance_stderr, one.radiance_stderr * [1.0, 2.0, 0.5], rtol=1e-12, atol=0)


def test_bad_input_is_refused_with_a_sentence():
    points, triangles = icosphere(1, radius=3.0)
    normals = points / np.linalg.norm(points, axis=1, keepdims=True)
    medium = _medium(0.1, 1.0, 0.0, 1.3)
    with pytest.raises(MeshError, match="closed surface"):
        trace_radiance(points, triangles[1:], points, normals, medium, [0, 0, 1], spp=4)
    with pytest.raises(MeshError, match="face inward"):
        trace_radiance(points, triangles[:, ::-1], points, normals, medium, [0, 0, 1], spp=4)
    with pytest.raises(InvalidParameterError, match="spp"):
        trace_radiance(points, triangles, points, normals, medium, [0, 0, 1], spp=1)
    with pytest.raises(InvalidParameterError, match="light_direction"):
        trace_radiance(points, triangles, points, normals, medium, [0, 0, 0], spp=4)
    with pytest.raises(InvalidParameterError, match="unit vector"):
        trace_radiance(points, triangles, points, normals * 0, medium, [0, 0, 1], spp=4)


@pytest.mark.slow
def test_a_sphere_matches_mitsubas_volpath():
    # tests/data/mitsuba_sphere.json: Mitsuba 3's volpath (a different program and estimator: it finds a
    # small sphere light by chance after refraction out, docs/physics.md §9.6) on the same polyhedron, at
    # face centroids along the face normals. Its 5-degree light changes the answer by about 0.1 % (exact
    # on a half-space), below both standard errors. Tolerance: 3 combined standard errors per face, 2 on
    # the sum over the lit faces.
    data = json.loads((DATA / "mitsuba_sphere.json").read_text())
    points, triangles = icosphere(3, radius=5.0)
    faces = np.array(data["faces"])
    normals = triangle_normals(points, triangles)[faces]
    centroids = points[triangles[faces]].mean(axis=1)
    m = data["medium"]
    medium = Medium(m["sigma_a_per_mm"], m["sigma_s_per_mm"], m["g"], m["eta"])
    traced = trace_radiance(points, triangles, centroids, normals, medium, data["light_direction"], spp=8192, seed=5)
    ours, ours_se = traced.radiance[:, 0], traced.radiance_stderr[:, 0]
    theirs, theirs_se = np.array(data["radiance"]), np.array(data["stderr"])
    assert np.all(np.abs(ours - theirs) <= 3 * np.hypot(ours_se, theirs_se))
    lit = np.array(data["lit"])
    difference = ours[lit].sum() - theirs[lit].sum()
    assert abs(difference) <= 2 * math.hypot(np.sqrt(np.sum(ours_se[lit] ** 2)), np.sqrt(np.sum(theirs_se[lit] ** 2)))
    assert np.sqrt(np.sum(theirs_se[lit] ** 2)) < 0.02 * theirs[lit].sum()  # a real check
