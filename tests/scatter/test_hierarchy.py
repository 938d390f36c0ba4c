"""The source tree's structure, checked node by node against its definition (hierarchy module docstring)."""

import numpy as np
import pytest

from translucency.scatter.hierarchy import LEAF_SIZE, SourceTree


@pytest.mark.parametrize("n", [1, 5, 8, 9, 17, 1000, 20000])
def test_every_node_splits_its_points_at_the_median_of_its_longest_axis(n):
    rng = np.random.default_rng(n)
    points = rng.normal(size=(n, 3)) * [30.0, 10.0, 3.0]
    points[: n // 4] = points[0]  # ties: a quarter of the points coincide
    tree = SourceTree(points)
    assert np.array_equal(np.sort(tree.order), np.arange(n))
    assert tree.start[0] == 0 and tree.end[0] == n
    for k in range(tree.n_nodes):
        members = points[tree.order[tree.start[k] : tree.end[k]]]
        box = members.max(axis=0) - members.min(axis=0)
        np.testing.assert_allclose(tree.centre[k], 0.5 * (members.max(axis=0) + members.min(axis=0)))
        assert np.all(np.linalg.norm(members - tree.centre[k], axis=1) <= tree.radius[k] * (1 + 1e-12))
        a, b = tree.left[k], tree.right[k]
        if a < 0:
            assert b < 0 and len(members) <= LEAF_SIZE
            continue
        assert len(members) > LEAF_SIZE and a > k and b > a  # depth first: parent, left subtree, right
        assert tree.start[a] == tree.start[k] and tree.end[a] == tree.start[b] and tree.end[b] == tree.end[k]
        assert tree.end[a] - tree.start[a] == len(members) // 2
        axis = int(np.argmax(box))
        lower = points[tree.order[tree.start[a] : tree.end[a]], axis]
        upper = points[tree.order[tree.start[b] : tree.end[b]], axis]
        assert lower.max() <= upper.min()
