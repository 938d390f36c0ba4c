"""Edges, components and fans of triangle lists, against computations written here independently
(sorting, scipy's graph components, a walk around each vertex) on triangle soups full of defects."""

import numpy as np
import pytest
from scipy import sparse
from scipy.sparse import csgraph

from translucency.geometry.synthetic import icosphere, torus
from translucency.geometry.topology import (
    count_non_manifold_vertices,
    duplicate_triangles,
    face_components,
    first_at_same_position,
    index_dtype,
    unique_edges,
)


def _soups():
    """Closed meshes, a fan around one vertex of degree 100, and random soups (non-manifold edges and
    vertices, duplicate and inconsistently oriented triangles, several components)."""
    rng = np.random.default_rng(1)
    yield icosphere(3, 1.0)[1]
    yield torus(3.0, 1.0, 12, 8)[1]
    m = 100
    fan = np.stack([np.zeros(m, dtype=np.int64), np.arange(1, m + 1), np.r_[np.arange(2, m + 1), 1]], axis=1)
    yield fan
    yield np.vstack([icosphere(2, 1.0)[1], icosphere(2, 1.0)[1] + 200, fan + 400])
    for _ in range(30):
        n, m = rng.integers(4, 40), rng.integers(1, 120)
        t = rng.integers(0, n, size=(m, 3))
        t = t[(t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])]
        if len(t):
            yield t


def _sorted_edges(triangles):
    directed = np.stack([triangles, np.roll(triangles, -1, axis=1)], axis=2).reshape(-1, 2)
    keys, inverse = np.unique(np.sort(directed, axis=1), axis=0, return_inverse=True)
    return keys, inverse.reshape(-1, 3)


def _fans_per_vertex(triangles, n):
    """Per vertex, the groups of its triangles linked through edges (at that vertex) of exactly two triangles."""
    edges, edge_of_corner = _sorted_edges(triangles)
    faces = np.bincount(edge_of_corner.ravel(), minlength=len(edges))
    fans = np.zeros(n, dtype=int)
    for v in range(n):
        around = np.flatnonzero((triangles == v).any(axis=1))
        if len(around) == 0:
            continue
        links = []
        for a in range(len(around)):
            for b in range(a + 1, len(around)):
                ta, tb = around[a], around[b]
                shared = set(edge_of_corner[ta]) & set(edge_of_corner[tb])
                if any(faces[e] == 2 and v in edges[e] for e in shared):
                    links.append((a, b))
        graph = sparse.coo_matrix(
            (np.ones(len(links)), ([a for a, _ in links], [b for _, b in links])), shape=(len(around),) * 2
        )
        fans[v] = csgraph.connected_components(graph, directed=False)[0]
    return fans


@pytest.mark.parametrize("index", range(34))
def test_edges_components_and_fans_match_independent_computations(index):
    triangles = list(_soups())[index]
    n = int(triangles.max()) + 1
    edges, edge_of_corner = unique_edges(triangles)
    expected_edges, expected_corners = _sorted_edges(triangles)
    np.testing.assert_array_equal(edges, expected_edges)
    np.testing.assert_array_equal(edge_of_corner, expected_corners)

    faces = np.bincount(edge_of_corner.ravel(), minlength=len(edges))
    slots = np.flatnonzero(faces[edge_of_corner.ravel()] == 2)
    slots = slots[np.argsort(edge_of_corner.ravel()[slots], kind="stable")]
    graph = sparse.coo_matrix(
        (np.ones(len(slots) // 2), (slots[0::2] // 3, slots[1::2] // 3)), shape=(len(triangles),) * 2
    )
    expected_count, expected_labels = csgraph.connected_components(graph, directed=False)
    count, labels = face_components(triangles)
    assert count == expected_count
    np.testing.assert_array_equal(labels, expected_labels)

    expected_split = int(np.count_nonzero(_fans_per_vertex(triangles, n) > 1))
    assert count_non_manifold_vertices(triangles, edge_of_corner, faces, n) == expected_split


def test_duplicate_triangles_are_those_numpy_unique_does_not_keep():
    """Against np.unique of the sorted rows (first occurrences kept), on soups and a fan of 300 copies."""
    fan = np.tile([[0, 1, 2]], (300, 1))
    fan[::2] = fan[::2, ::-1]  # the same vertices in the other order
    for triangles in [*_soups(), np.vstack([fan, [[0, 2, 3], [3, 2, 0]]])]:
        _, first = np.unique(np.sort(triangles, axis=1), axis=0, return_index=True)
        expected = np.ones(len(triangles), dtype=bool)
        expected[first] = False
        assert np.array_equal(duplicate_triangles(triangles), expected)


def test_first_at_same_position_matches_numpy_unique_on_the_bytes():
    """Against np.unique of the coordinates' bytes (-0.0 made 0.0), with many repeats and signed zeros."""
    rng = np.random.default_rng(4)
    points = rng.integers(-2, 3, size=(5000, 3)).astype(np.float64) * 0.5
    points[::3] *= -1.0  # -0.0 where a coordinate is 0
    rows = np.ascontiguousarray(points + 0.0).view(np.dtype((np.void, 24))).ravel()
    _, first, inverse = np.unique(rows, return_index=True, return_inverse=True)
    assert np.array_equal(first_at_same_position(points), first[inverse.ravel()])
    distinct = rng.normal(size=(1000, 3))
    assert np.array_equal(first_at_same_position(distinct), np.arange(1000))


def test_corner_edge_numbers_are_unique_edges_numbers_in_int32():
    """The near field's tables take only the corners' edge numbers and their count: the same as unique_edges', in
    int32 (edges counted against a set of vertex pairs)."""
    from translucency.geometry.topology import corner_edge_numbers, unique_edges

    rng = np.random.default_rng(4)
    triangles = rng.integers(0, 60, size=(400, 3))
    numbers, count = corner_edge_numbers(triangles)
    edges, expected = unique_edges(triangles)
    assert numbers.dtype == np.int32 and np.array_equal(numbers, expected)
    pairs = {tuple(sorted((int(t[i]), int(t[(i + 1) % 3])))) for t in triangles for i in range(3)}
    assert count == len(edges) == len(pairs)


def test_index_dtype_is_int32_while_every_number_fits_it():
    """Numbers ``0 .. count - 1`` are stored in int32 while ``count - 1`` is below int32's largest value (with one to
    spare), in int64 from there on."""
    largest = np.iinfo(np.int32).max
    assert index_dtype(0) is np.int32 and index_dtype(largest - 1) is np.int32
    assert index_dtype(largest) is np.int64 and index_dtype(3 * largest) is np.int64
