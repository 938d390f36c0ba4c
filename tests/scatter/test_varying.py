"""Albedo per vertex (the scan's colour read as reflectance): levels, interpolation and the receiver's coefficients."""

import numpy as np
import pytest

from translucency.errors import InvalidParameterError
from translucency.geometry.measure import vertex_normals
from translucency.geometry.synthetic import icosphere
from translucency.scatter import fresnel, solve, varying
from translucency.scatter.appearance import medium_from_appearance
from translucency.scatter.materials import material

MFP = np.array([0.8, 1.2, 2.0])  # mm, per channel


@pytest.fixture(scope="module")
def sphere():
    points, triangles = icosphere(3)
    points = points * 10.0
    normals = vertex_normals(points, triangles)
    light = np.array([0.3, 0.4, 0.866])
    light /= np.linalg.norm(light)
    cos = normals @ light
    phi = np.where(cos > 0, fresnel.fresnel_transmittance(cos, 1.3) * cos, 0.0)
    w12 = fresnel.refract(np.broadcast_to(light, normals.shape), normals, 1.3)
    return solve.SurfaceGeometry(points, triangles, normals), np.repeat(phi[:, None], 3, axis=1), w12


def test_levels_cover_the_range_at_most_a_step_apart():
    values = np.array([[0.12, 0.5, 0.9], [0.3, 0.31, 0.77]])
    levels = varying.reflectance_levels(values, 0.05)
    assert levels[0] == 0.12 and levels[-1] == 0.9
    assert np.all(np.diff(levels) <= 0.05 + 1e-12)
    assert varying.reflectance_levels(np.full((4, 3), 0.4)).tolist() == [0.4]
    weights = sum(varying.level_weights(values, levels, k) for k in range(levels.size))
    assert np.allclose(weights, 1.0, atol=1e-12)


def test_one_reflectance_everywhere_is_the_homogeneous_material(sphere):
    """The same reflectance at every vertex gives the solve of the medium with that look (exact method)."""
    geometry, phi, w12 = sphere
    look = np.array([0.35, 0.6, 0.8])
    homogeneous = medium_from_appearance(look, MFP, eta=1.3)
    reference = solve.solve(geometry, phi, w12, homogeneous, method="exact")
    base = medium_from_appearance([0.5, 0.5, 0.5], MFP, eta=1.3)  # only its mean free path is used
    got = varying.solve_varying(
        geometry, phi, w12, base, reflectance=np.tile(look, (geometry.n_vertices, 1)), method="exact"
    )
    # each channel on its own level: interpolation weights are 1 and 0
    assert np.allclose(got.B, reference.B, rtol=1e-10, atol=1e-14 * reference.B.max())


def test_two_materials_use_each_receivers_own_coefficients(sphere):
    """Two halves of a sphere with two looks: each vertex gets the solve of its own material at that vertex
    (every source lit as it is), computed here by two independent homogeneous solves."""
    geometry, phi, w12 = sphere
    left = geometry.points[:, 0] < 0.0
    looks = (0.3, 0.7)  # on levels of step 0.05 (both ends of the range)
    reflectance = np.where(left[:, None], looks[0], looks[1]) * np.ones((1, 3))
    base = medium_from_appearance(0.5, MFP, eta=1.3)
    got = varying.solve_varying(geometry, phi, w12, base, reflectance=reflectance, method="exact")
    expected = np.empty_like(got.B)
    for look, where in zip(looks, (left, ~left)):
        medium = medium_from_appearance(look, MFP, eta=1.3)
        expected[where] = solve.solve(geometry, phi, w12, medium, method="exact", receivers=np.flatnonzero(where)).B
    assert np.allclose(got.B, expected, rtol=1e-10, atol=1e-14 * expected.max())
    assert got.stats["solves"] == 2  # the levels between have no receiver


def test_interpolation_between_levels_is_close_to_the_finer_solve(sphere):
    """A smooth colour ramp: the default levels agree with levels four times finer to within 1 % (p99)."""
    geometry, phi, w12 = sphere
    ramp = (geometry.points[:, 2] - geometry.points[:, 2].min()) / np.ptp(geometry.points[:, 2])
    reflectance = np.stack([0.2 + 0.6 * ramp, 0.5 + 0.3 * ramp, 0.8 - 0.5 * ramp], axis=1)
    base = material("marble").medium()
    coarse = varying.solve_varying(geometry, phi, w12, base, reflectance=reflectance, method="exact")
    step = varying.REFLECTANCE_STEP
    try:
        varying.REFLECTANCE_STEP = step / 4
        fine = varying.solve_varying(geometry, phi, w12, base, reflectance=reflectance, method="exact")
    finally:
        varying.REFLECTANCE_STEP = step
    lit = fine.B > 1e-4 * fine.B.max(axis=0)
    error = np.abs(coarse.B - fine.B)[lit] / fine.B[lit]
    assert np.percentile(error, 99) < 0.01
    assert len(fine.stats["levels"]) > 3 * len(coarse.stats["levels"])


def test_bad_reflectance_is_one_sentence(sphere):
    geometry, phi, w12 = sphere
    base = material("marble").medium()
    with pytest.raises(InvalidParameterError, match="one row per vertex"):
        varying.solve_varying(geometry, phi, w12, base, reflectance=np.full((3, 3), 0.5))
    with pytest.raises(InvalidParameterError, match="not finite"):
        varying.solve_varying(geometry, phi, w12, base, reflectance=np.full((geometry.n_vertices, 3), np.nan))
    values, clamped = varying.checked_reflectance(np.array([[0.0, 0.5, 1.0]]), 1, 3)
    assert (
        clamped == 2 and values.min() == varying.REFLECTANCE_RANGE[0] and values.max() == varying.REFLECTANCE_RANGE[1]
    )


def test_relighting_with_an_albedo_per_vertex_is_tree_on_the_device_asked_for(sphere, monkeypatch):
    """Relighting with an albedo per vertex solves each level by tree, on the device asked for: on the CPU the same B
    as tree, the device said; ``device="gpu"`` where no GPU works is the probe's sentence (the setting reached the
    levels' solves)."""
    from translucency.scatter.gpu import probe

    geometry, phi, w12 = sphere
    base = medium_from_appearance([0.5, 0.5, 0.5], MFP, eta=1.3)
    look = np.tile([0.35, 0.6, 0.8], (geometry.n_vertices, 1))
    asked = varying.solve_varying(geometry, phi, w12, base, reflectance=look, method="relight", tol=0.1, device="cpu")
    tree = varying.solve_varying(geometry, phi, w12, base, reflectance=look, method="tree", tol=0.1, device="cpu")
    assert asked.stats["device"] == "cpu"
    assert np.array_equal(asked.B, tree.B)
    # tree's counts added up over the levels: its evaluations are its sources one by one and its clusters
    assert tree.stats["solves"] > 1 and tree.stats["cluster_evaluations"] > 0
    assert tree.stats["pairs_direct"] + tree.stats["cluster_evaluations"] == tree.stats["pairs_evaluated"]
    monkeypatch.setattr(probe, "gpu_status", lambda: probe.GpuStatus(False, reason="no GPU in this test"))
    with pytest.raises(InvalidParameterError, match=r"device='gpu' needs an NVIDIA GPU, and no GPU in this test"):
        varying.solve_varying(geometry, phi, w12, base, reflectance=look, method="relight", tol=0.1, device="gpu")
