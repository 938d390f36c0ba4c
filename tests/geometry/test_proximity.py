"""Exact closest points on triangle meshes, against brute force."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from translucency.geometry.proximity import (
    closest_point_barycentric,
    closest_points_on_triangles,
    vertex_hausdorff_distance,
)

from ..io.conftest import grid, icosphere


def brute_force(query, points, triangles):
    weights = closest_point_barycentric(query[:, None, :], *(points[triangles][None, :, i] for i in range(3)))
    closest = np.einsum("qti,tij->qtj", weights, points[triangles])
    distance = np.linalg.norm(query[:, None, :] - closest, axis=2)
    return distance.min(axis=1)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), spread=st.floats(0.1, 10), k=st.integers(1, 8))
def test_matches_brute_force_on_random_soups(seed, spread, k):
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(40, 3))
    points[:5] *= 20  # a few huge triangles next to small ones
    triangles = rng.integers(0, 40, size=(60, 3))
    query = rng.normal(size=(200, 3)) * spread
    index, weights, distance = closest_points_on_triangles(query, points, triangles, k=k)
    np.testing.assert_allclose(distance, brute_force(query, points, triangles), rtol=1e-9, atol=1e-12)
    closest = np.einsum("qi,qij->qj", weights, points[triangles[index]])
    np.testing.assert_allclose(np.linalg.norm(query - closest, axis=1), distance, rtol=1e-9, atol=1e-12)
    assert np.all(weights >= 0) and np.allclose(weights.sum(axis=1), 1)


def test_numba_kernel_agrees_with_numpy_reference():
    rng = np.random.default_rng(3)
    points, triangles = icosphere(2, 5.0)
    query = rng.normal(size=(300, 3)) * 6
    index, weights, _ = closest_points_on_triangles(query, points, triangles)
    reference = closest_point_barycentric(query, *(points[triangles[index]][:, i] for i in range(3)))
    np.testing.assert_allclose(weights, reference, atol=1e-12)


def test_vertices_get_exact_one_hot_weights():
    points, triangles = icosphere(2, 7.3)
    index, weights, distance = closest_points_on_triangles(points, points, triangles)
    assert np.all(distance == 0)
    assert np.all(np.sort(weights, axis=1) == [0.0, 0.0, 1.0])
    corner = points[triangles[index]][np.arange(len(points)), np.argmax(weights, axis=1)]
    np.testing.assert_array_equal(corner, points)


def test_points_above_a_plane():
    points, triangles = grid(5, 10.0)
    query = np.array([[3.3, 4.4, 2.0], [-1.0, 5.0, 0.0], [12.0, 12.0, -1.0]])
    _, _, distance = closest_points_on_triangles(query, points, triangles)
    np.testing.assert_allclose(distance, [2.0, 1.0, np.sqrt(2 * 4 + 1)])


def test_hausdorff_of_identical_and_shifted_meshes():
    points, triangles = icosphere(2)
    assert vertex_hausdorff_distance(points, triangles, points, triangles) == 0
    assert np.isclose(vertex_hausdorff_distance(points, triangles, points + [0, 0, 0.5], triangles), 0.5, rtol=0.05)


def test_queries_in_chunks_give_the_same_answer(monkeypatch):
    """Looking the candidates up a few queries at a time (as a 10M-vertex mapping does, to bound memory)
    changes nothing: every query is answered on its own."""
    from translucency.geometry import proximity
    from translucency.geometry.synthetic import icosphere

    points, triangles = icosphere(3)
    query = np.random.default_rng(5).normal(size=(500, 3)) * 1.5
    whole = proximity.closest_points_on_triangles(query, points, triangles)
    monkeypatch.setattr(proximity, "QUERY_CHUNK", 7)
    chunked = proximity.closest_points_on_triangles(query, points, triangles)
    for a, b in zip(whole, chunked):
        assert np.array_equal(a, b)


def test_queries_near_the_surface_are_certified_by_the_grid(monkeypatch):
    """A fine mesh's vertices against a coarser mesh of the same sphere (the proxy mapping's case): every query is
    within the grid's margin, answered by it alone, and the answer is brute force's; queries far off go on."""
    from translucency.geometry import proximity

    points, triangles = icosphere(2, 5.0)
    fine, _ = icosphere(4, 5.0)
    query = fine * (1.0 + np.random.default_rng(1).normal(scale=1e-3, size=(len(fine), 1)))  # noisy, both sides
    searched = []
    search = proximity._nearest_search
    monkeypatch.setattr(proximity, "_nearest_search", lambda q, *args: searched.append(len(q)) or search(q, *args))
    index, weights, distance = closest_points_on_triangles(query, points, triangles)
    assert searched == []
    np.testing.assert_allclose(distance, brute_force(query, points, triangles), rtol=1e-9, atol=1e-12)
    closest = np.einsum("qi,qij->qj", weights, points[triangles[index]])
    np.testing.assert_allclose(np.linalg.norm(query - closest, axis=1), distance, rtol=1e-9, atol=1e-12)
    far = np.vstack([query[:50], query[:50] * 3.0])  # 10 mm off the surface: beyond the margin
    _, _, distance = closest_points_on_triangles(far, points, triangles)
    assert searched == [50]
    np.testing.assert_allclose(distance, brute_force(far, points, triangles), rtol=1e-9, atol=1e-12)
    stray = np.vstack([query, [[1e9, 0.0, 0.0]]])  # one query far outside does not send the others on
    _, _, distance = closest_points_on_triangles(stray, points, triangles)
    assert searched == [50, 1]
    np.testing.assert_allclose(distance[:-1], brute_force(query, points, triangles), rtol=1e-9, atol=1e-12)


def test_the_grid_lists_large_triangles_at_coarser_levels(monkeypatch):
    """Triangles far larger than the median sit at coarser levels of the grid; queries near them are answered
    there, exactly."""
    from translucency.geometry import proximity

    small, small_triangles = icosphere(3, 5.0)  # 1280 triangles of about 1 mm
    big = np.array([[-40.0, -40.0, 8.0], [40.0, -40.0, 8.0], [0.0, 40.0, 8.0]])  # one of 80 mm, above them (it holds
    # the square -10 .. 10 mm where the queries are)
    points = np.vstack([small, big])
    triangles = np.vstack([small_triangles, [[len(small), len(small) + 1, len(small) + 2]]])
    rng = np.random.default_rng(2)
    on_big = np.column_stack([rng.uniform(-10, 10, size=(200, 2)), 8.0 + rng.normal(scale=0.01, size=200)])
    query = np.vstack([small * 1.01, on_big])
    searched = []
    search = proximity._nearest_search
    monkeypatch.setattr(proximity, "_nearest_search", lambda q, *args: searched.append(len(q)) or search(q, *args))
    index, _, distance = closest_points_on_triangles(query, points, triangles)
    assert searched == [] and np.all(index[len(small) :] == len(small_triangles))
    np.testing.assert_allclose(distance, brute_force(query, points, triangles), rtol=1e-9, atol=1e-12)
