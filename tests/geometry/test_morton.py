"""The Morton order against the bit interleaving written out, and the triangles by their lowest vertex."""

import numpy as np

from translucency.geometry.morton import by_lowest_vertex, morton_order


def test_the_morton_order_interleaves_the_bits_of_the_three_cells():
    rng = np.random.default_rng(4)
    points = np.vstack([rng.normal(size=(3000, 3)) * [5.0, 1.0, 0.2], np.zeros((5, 3))])  # flat, with ties
    bits = 16
    cells = ((points - points.min(axis=0)) / np.ptp(points, axis=0).max() * (1 << bits)).astype(np.uint64)
    cells = np.minimum(cells, (1 << bits) - 1)
    codes = [
        sum(int((int(c[axis]) >> bit) & 1) << (3 * bit + axis) for bit in range(bits) for axis in range(3))
        for c in cells
    ]
    expected = sorted(range(len(points)), key=lambda i: (codes[i], i))
    np.testing.assert_array_equal(morton_order(points, bits), expected)
    # one axis per bit in turn: x is the lowest bit, so two points apart only along x by one cell are neighbours
    assert list(morton_order(np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), 1)) == [1, 0, 2]


def test_triangles_by_their_lowest_vertex_keep_the_order_of_ties():
    rng = np.random.default_rng(7)
    triangles = rng.integers(0, 50, size=(2000, 3))
    expected = triangles[np.argsort(triangles.min(axis=1), kind="stable")]
    np.testing.assert_array_equal(by_lowest_vertex(triangles, 50), expected)
    assert by_lowest_vertex(np.zeros((0, 3), dtype=np.int64), 0).shape == (0, 3)
