"""The two-media random walk (Woodcock tracking): the homogeneous walk unchanged, null collisions unbiased."""

import numpy as np
import pytest

from translucency.errors import InvalidParameterError
from translucency.scatter.montecarlo import simulate_half_space, simulate_two_media


def test_one_medium_on_both_sides_is_the_homogeneous_walk():
    """The same coefficients on both sides draw no extra random number: the pencil beam's totals and
    grid are bit for bit those of simulate_half_space."""
    kwargs = dict(n_photons=4000, seed=3, grid_extent_mm=4.0, grid_cells=21)
    half = simulate_half_space(0.02, 1.5, 0.0, 1.3, **kwargs)
    two = simulate_two_media((0.02, 1.5), (0.02, 1.5), 0.0, 1.3, **kwargs)
    assert two.total_reflectance == half.total_reflectance
    assert np.array_equal(two.exitance, half.exitance)
    # every escape of the pencil beam lands in a strip of the (wide) strip tally
    assert two.strip_exitance.sum() * np.diff(two.strip_edges_mm)[0] == pytest.approx(two.total_reflectance, rel=0.02)


def test_null_collisions_leave_the_reflectance_of_either_side_unchanged():
    """The same albedo with sigma_t twice as large on the right: a half-space's total reflectance does not
    depend on sigma_t, so under a uniform beam the exitance far from the boundary is the homogeneous total
    on both sides (the right side's flights go through null collisions, the left's do not)."""
    albedo, n = 0.95, 200_000
    left, right = (1.0 - albedo, albedo), (2.0 * (1.0 - albedo), 2.0 * albedo)
    total = simulate_half_space(*left, 0.0, 1.3, n_photons=n, seed=1).total_reflectance
    two = simulate_two_media(
        left, right, 0.0, 1.3, launch_x_mm=(-30.0, 30.0), n_photons=n, seed=2, strip_extent_mm=20.0, strip_cells=8
    )
    exitance, se = two.uniform_exitance
    far = np.abs(two.strip_centres_mm) > 10.0  # several diffusion lengths (4.5 mm on the left) away
    assert np.all(np.abs(exitance[far] - total) < 4 * se[far] + 0.01 * total)


def test_albedo_changes_across_the_boundary():
    """Two albedos under a uniform beam: the exitance is the brighter side's total far on its side, the
    darker's on the other, and in between at the boundary."""
    bright, dark = (0.01, 0.99), (0.2, 0.8)
    n = 200_000
    totals = [simulate_half_space(*m, 0.0, 1.3, n_photons=n, seed=1).total_reflectance for m in (bright, dark)]
    two = simulate_two_media(
        bright, dark, 0.0, 1.3, launch_x_mm=(-40.0, 40.0), n_photons=4 * n, seed=5, strip_extent_mm=30.0, strip_cells=12
    )
    exitance, se = two.uniform_exitance
    x = two.strip_centres_mm
    assert abs(exitance[0] - totals[0]) < 4 * se[0] + 0.02 * totals[0]  # 27.5 mm: 5 diffusion lengths
    assert abs(exitance[-1] - totals[1]) < 4 * se[-1] + 0.02 * totals[1]
    near = np.abs(x) < 3.0
    assert np.all((exitance[near] < totals[0]) & (exitance[near] > totals[1]))


def test_bad_sides_are_one_sentence():
    with pytest.raises(InvalidParameterError, match="pair"):
        simulate_two_media(0.1, (0.1, 1.0), 0.0, 1.3)
    with pytest.raises(InvalidParameterError, match="low <= high"):
        simulate_two_media((0.1, 1.0), (0.1, 1.0), 0.0, 1.3, launch_x_mm=(1.0, -1.0))


def test_its_sentences_name_it():
    """A mistake in the shared walk's settings is said in the name of the function the user called."""
    with pytest.raises(InvalidParameterError, match="^simulate_two_media: n_photons"):
        simulate_two_media((0.1, 1.0), (0.1, 1.0), 0.0, 1.3, n_photons=0)
    with pytest.raises(InvalidParameterError, match="^simulate_half_space: n_photons"):
        simulate_half_space(0.1, 1.0, 0.0, 1.3, n_photons=0)
