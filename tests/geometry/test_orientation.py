"""Coherent and outward orientation."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from translucency.geometry.orientation import coherent_orientation, flip_triangles, outward_flips
from translucency.io import find_defects, signed_volume

from ..io.conftest import grid, icosphere


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), fraction=st.floats(0, 1))
def test_random_flips_are_undone(seed, fraction):
    points, triangles = icosphere(2)
    rng = np.random.default_rng(seed)
    scrambled = flip_triangles(triangles, rng.random(len(triangles)) < fraction)
    flip, non_orientable = coherent_orientation(scrambled)
    coherent = flip_triangles(scrambled, flip)
    assert non_orientable == 0
    assert find_defects(points, coherent).inconsistent_edges == 0
    # never more than half the triangles are flipped (the smaller side is chosen)
    assert np.count_nonzero(flip) <= len(triangles) / 2
    flip, count = outward_flips(points, coherent)
    outward = flip_triangles(coherent, flip)
    np.testing.assert_array_equal(outward, triangles)


def test_inward_sphere_and_two_components():
    a_points, a_triangles = icosphere(1, 5.0)
    b_points = a_points + [100, 0, 0]
    points = np.concatenate([a_points, b_points])
    triangles = np.concatenate([a_triangles[:, ::-1], a_triangles + len(a_points)])  # first inward
    flip, count = outward_flips(points, triangles)
    assert count == 1 and flip[: len(a_triangles)].all() and not flip[len(a_triangles) :].any()
    assert signed_volume(points, flip_triangles(triangles, flip)) > 0


def test_open_cap_faces_away_from_its_centroid():
    points, triangles = icosphere(2, 10.0)
    cap = triangles[points[triangles].mean(axis=1)[:, 2] > 3.0]  # a dome, normals outward (+z side)
    flip, count = outward_flips(points, cap[:, ::-1])
    assert count == 1 and flip.all()
    flip, count = outward_flips(points, cap)
    assert count == 0


def test_mobius_strip_is_non_orientable():
    n = 12
    angle = np.linspace(0, 2 * np.pi, n, endpoint=False)
    points = []
    for t in angle:
        for s in (-1, 1):
            radius = 10 + s * np.cos(t / 2)
            points.append([radius * np.cos(t), radius * np.sin(t), s * np.sin(t / 2)])
    points = np.array(points)
    triangles = []
    for i in range(n):
        a, b = 2 * i, 2 * i + 1
        c, d = (2 * (i + 1), 2 * (i + 1) + 1) if i < n - 1 else (1, 0)  # the half twist
        triangles += [[a, c, b], [b, c, d]]
    flip, non_orientable = coherent_orientation(np.array(triangles))
    assert non_orientable == 1


def test_flat_grid_is_left_alone():
    points, triangles = grid(3)
    flip, _ = coherent_orientation(triangles)
    assert not flip.any()


def test_outward_flips_take_components_already_found():
    """Given the components (as the cleaning does after finding defects) the flips are the same."""
    from translucency.geometry.topology import face_components

    points, triangles = icosphere(2)
    inside_out = flip_triangles(triangles, np.ones(len(triangles), dtype=bool))
    flips, flipped = outward_flips(points, inside_out)
    again, flipped_again = outward_flips(points, inside_out, face_components(inside_out))
    assert flipped == flipped_again == 1 and np.array_equal(flips, again) and flips.all()
