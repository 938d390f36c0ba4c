"""Per-vertex geometry: property tests on generated meshes (areas partition the surface, normals)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from translucency.errors import InvalidParameterError
from translucency.geometry.measure import (
    area_centroids,
    barycentric_vertex_areas,
    hull_candidates,
    longest_edges,
    mean_edge_length,
    signed_volume,
    triangle_areas,
    triangle_centroids,
    triangle_normals,
    vertex_areas,
    vertex_normals,
)

from ..io.conftest import grid, icosphere

coordinates = arrays(np.float64, (12, 3), elements=st.floats(-100, 100, allow_nan=False, width=64))
triangle_lists = arrays(np.int64, (15, 3), elements=st.integers(0, 11))


@settings(max_examples=60, deadline=None)
@given(points=coordinates, triangles=triangle_lists, method=st.sampled_from(["barycentric", "mixed_voronoi"]))
def test_vertex_areas_sum_to_surface_area(points, triangles, method):
    # any triangle soup, degenerate triangles included: the shares partition the area (tolerance 1e-9 relative)
    areas = vertex_areas(points, triangles, method=method)
    total = triangle_areas(points, triangles).sum()
    assert np.all(areas >= -1e-9 * max(total, 1))
    assert areas.sum() == pytest.approx(total, rel=1e-9, abs=1e-9)
    assert np.all(np.isfinite(areas))


@settings(max_examples=40, deadline=None)
@given(points=coordinates, triangles=triangle_lists)
def test_barycentric_areas_are_the_bincount_of_thirds_to_the_bit(points, triangles):
    # an independent sum: numpy's bincount over the flattened corners, each weighted by a third of its triangle
    areas = triangle_areas(points, triangles)
    expected = np.bincount(triangles.ravel(), weights=np.repeat(areas / 3.0, 3), minlength=len(points))
    assert np.array_equal(barycentric_vertex_areas(triangles, areas, len(points)), expected)


@settings(max_examples=40, deadline=None)
@given(points=coordinates, triangles=triangle_lists)
def test_vertex_normals_are_unit_or_zero_and_finite(points, triangles):
    normals = vertex_normals(points, triangles)
    length = np.linalg.norm(normals, axis=1)
    assert np.all(np.isfinite(normals))
    assert np.all((np.abs(length - 1) < 1e-12) | (length == 0))


@settings(max_examples=30, deadline=None)
@given(
    scale=st.floats(1e-3, 1e3),
    shift=arrays(np.float64, 3, elements=st.floats(-1e3, 1e3)),
    method=st.sampled_from(["barycentric", "mixed_voronoi"]),
)
def test_areas_scale_quadratically_and_ignore_translation(scale, shift, method):
    points, triangles = icosphere(1, 3.0)
    base = vertex_areas(points, triangles, method=method)
    moved = vertex_areas(points * scale + shift, triangles, method=method)
    np.testing.assert_allclose(moved, base * scale**2, rtol=1e-9, atol=1e-9 * scale**2 * base.max())
    np.testing.assert_allclose(
        vertex_normals(points * scale + shift, triangles), vertex_normals(points, triangles), atol=1e-12
    )


def test_sphere_normals_point_outward_radially():
    points, triangles = icosphere(3, 10.0)
    normals = vertex_normals(points, triangles)
    radial = points / np.linalg.norm(points, axis=1, keepdims=True)
    assert np.min(np.einsum("ij,ij->i", normals, radial)) > 0.999


def test_sphere_area_volume_and_edge_length():
    points, triangles = icosphere(4, 10.0)
    assert triangle_areas(points, triangles).sum() == pytest.approx(4 * np.pi * 100, rel=2e-3)
    assert signed_volume(points, triangles) == pytest.approx(4 / 3 * np.pi * 1000, rel=5e-3)
    assert signed_volume(points, triangles[:, ::-1]) < 0
    # 2562 vertices on a 10 mm sphere: edges are about 0.7 mm
    assert 0.5 < mean_edge_length(points, triangles) < 0.9


def test_flat_grid_values():
    points, triangles = grid(4, 4.0)  # unit right triangles
    np.testing.assert_allclose(triangle_areas(points, triangles), 0.5)
    np.testing.assert_allclose(triangle_normals(points, triangles), np.tile([0, 0, 1.0], (len(triangles), 1)))
    np.testing.assert_allclose(vertex_normals(points, triangles), np.tile([0, 0, 1.0], (len(points), 1)))
    areas = vertex_areas(points, triangles)
    # an interior vertex touches 6 triangles of this grid: 6 * 0.5 / 3 = 1 mm²
    assert areas[2 * 5 + 2] == pytest.approx(1.0)
    # mixed Voronoi on right triangles: the right-angle corner's Voronoi cell
    voronoi = vertex_areas(points, triangles, method="mixed_voronoi")
    assert voronoi.sum() == pytest.approx(16.0)
    assert voronoi[2 * 5 + 2] == pytest.approx(1.0)


def test_mixed_voronoi_of_equilateral_triangle_is_a_third_each():
    points = np.array([[0, 0, 0], [1, 0, 0], [0.5, 3**0.5 / 2, 0]])
    np.testing.assert_allclose(vertex_areas(points, [[0, 1, 2]], method="mixed_voronoi"), 3**0.5 / 4 / 3)


def test_obtuse_triangle_gives_half_to_the_obtuse_corner():
    points = np.array([[0, 0, 0], [4, 0, 0], [2, 0.5, 0]])  # obtuse at vertex 2
    areas = vertex_areas(points, [[0, 1, 2]], method="mixed_voronoi")
    np.testing.assert_allclose(areas, [0.25, 0.25, 0.5])


def test_degenerate_and_unreferenced_vertices_get_zero():
    points = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [9, 9, 9]], dtype=float)
    assert np.all(vertex_normals(points, [[0, 1, 2]]) == 0)
    assert np.all(vertex_areas(points, [[0, 1, 2]], method="mixed_voronoi") == 0)


def test_unknown_area_method():
    with pytest.raises(InvalidParameterError, match="barycentric"):
        vertex_areas(*grid(1), method="voronoi")


def test_vertex_normals_of_subnormal_triangles_are_unit():
    # found by the property test above: a triangle whose cross product has subnormal components, whose
    # norm came out 0.73 instead of 1 after the division
    a = 8.14864815e-163
    points = np.array([[2.0, a, a], [a, a, a], [a, 0.0, a]])
    triangles = np.array([[2, 0, 1]])
    length = np.linalg.norm(vertex_normals(points, triangles), axis=1)
    assert np.all((np.abs(length - 1) < 1e-12) | (length == 0))
    assert np.count_nonzero(length) == 3


def test_area_centroids_match_a_sum_over_the_triangles():
    """Per label, the area and the area-weighted mean of the triangles' centroids, summed here with numpy."""
    rng = np.random.default_rng(3)
    points = rng.normal(size=(60, 3)) * 10.0
    triangles = rng.integers(0, 60, size=(200, 3))
    labels = rng.integers(0, 4, size=200)
    areas, centroids = area_centroids(points, triangles, labels, 5)
    corners = points[triangles]
    a = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    for k in range(4):
        mine = labels == k
        assert areas[k] == pytest.approx(a[mine].sum(), rel=1e-12)
        expected = (a[mine, None] * corners[mine].mean(axis=1)).sum(axis=0) / a[mine].sum()
        np.testing.assert_allclose(centroids[k], expected, rtol=1e-12)
    assert areas[4] == 0.0 and np.all(centroids[4] == 0.0)  # a label without triangles


@pytest.mark.parametrize("cloud", ["ball", "sphere", "box"])
def test_hull_candidates_keep_every_vertex_of_the_hull(cloud):
    """The culled points have the same convex hull as all of them (scipy's hull of every point)."""
    from scipy.spatial import ConvexHull

    rng = np.random.default_rng(5)
    points = rng.normal(size=(20000, 3))
    if cloud == "sphere":  # every point on the hull
        points /= np.linalg.norm(points, axis=1, keepdims=True)
    elif cloud == "box":  # flat faces: many points on the hull's facets, few vertices
        points = rng.uniform(-1.0, 1.0, size=(20000, 3))
        points[:2000, 0] = 1.0
    kept = hull_candidates(points * 30.0 + 5.0)
    full = ConvexHull(points * 30.0 + 5.0)
    culled = ConvexHull(kept)
    assert culled.volume == pytest.approx(full.volume, rel=1e-12)
    assert culled.area == pytest.approx(full.area, rel=1e-12)
    vertices = {tuple(p) for p in (points * 30.0 + 5.0)[full.vertices]}
    assert vertices <= {tuple(p) for p in kept}
    if cloud == "ball":
        assert len(kept) < 0.2 * len(points)  # it culls


def test_longest_edges_and_centroids_match_numpy():
    """One pass each in numba, against the (m, 3, 3) arrays numpy makes."""
    rng = np.random.default_rng(8)
    points = rng.normal(size=(50, 3)) * 7.0
    triangles = rng.integers(0, 50, size=(300, 3))
    corners = points[triangles]
    edges = np.linalg.norm(np.roll(corners, -1, axis=1) - corners, axis=2)
    np.testing.assert_allclose(longest_edges(points, triangles), edges.max(axis=1), rtol=1e-14)
    np.testing.assert_allclose(triangle_centroids(points, triangles), corners.mean(axis=1), rtol=1e-14, atol=1e-14)


def test_mean_edge_length_counts_each_shared_edge_once():
    """Two triangles of a 2 x 3 mm rectangle: edges 2, 3, 2, 3 and the shared diagonal sqrt(13), each once."""
    points = np.array([[0.0, 0, 0], [2, 0, 0], [2, 3, 0], [0, 3, 0]])
    triangles = np.array([[0, 1, 2], [0, 2, 3]])
    assert mean_edge_length(points, triangles) == pytest.approx((10 + np.sqrt(13)) / 5, rel=1e-14)
    assert np.isnan(mean_edge_length(points, np.zeros((0, 3), dtype=np.int64)))


def test_mean_edge_length_is_that_of_the_unique_edges_on_any_triangle_list():
    """Repeated indices (an edge from a vertex to itself counts, of length 0), duplicate and non-manifold triangles:
    the mean of unique_edges' lengths."""
    from translucency.geometry.topology import unique_edges

    rng = np.random.default_rng(3)
    for _ in range(20):
        points = rng.normal(size=(30, 3))
        triangles = rng.integers(0, 30, size=(60, 3))
        edges, _ = unique_edges(triangles)
        expected = np.linalg.norm(points[edges[:, 0]] - points[edges[:, 1]], axis=1).mean()
        assert mean_edge_length(points, triangles) == pytest.approx(expected, rel=1e-14)


def test_row_lengths_are_numpys_norm_bit_for_bit():
    """The compiled row lengths are np.linalg.norm(axis=1) to the last bit, from 1e-150 to 1e150 mm."""
    from translucency.geometry.measure import row_lengths

    rng = np.random.default_rng(7)
    vectors = rng.normal(size=(10_000, 3)) * 10.0 ** rng.uniform(-150, 150, size=(10_000, 1))
    vectors[:3] = 0.0
    assert np.array_equal(row_lengths(vectors), np.linalg.norm(vectors, axis=1))


def test_unit_rows_of_zero_and_nan_rows_are_zero():
    from translucency.geometry.measure import _normalise_rows

    vectors = np.array([[0.0, 0.0, 0.0], [np.nan, 1.0, 0.0], [1.0, np.nan, 0.0], [3.0, 0.0, 4.0], [-1e-300, 0, 0]])
    unit = _normalise_rows(vectors)
    assert np.array_equal(unit[:3], np.zeros((3, 3)))
    assert np.array_equal(unit[3:], [[0.6, 0.0, 0.8], [-1.0, 0.0, 0.0]])
