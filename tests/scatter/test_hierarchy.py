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


def _walk_by_definition(tree, weight, lit, centre, spread, theta, min_distance):
    """Sources plus clusters one group (a sphere: ``centre``, ``spread``, mm) evaluates, walked node by node
    as the module docstring defines it."""
    count, stack = 0, [0]
    while stack:
        k = stack.pop()
        if weight[k] <= 0:
            continue
        near = np.linalg.norm(centre - tree.centre[k]) - spread
        if near > tree.radius[k] + min_distance and tree.radius[k] < theta * near:
            count += 1
        elif tree.left[k] < 0:
            count += int(lit[tree.order[tree.start[k] : tree.end[k]]].sum())
        else:
            stack += [tree.left[k], tree.right[k]]
    return count


def test_the_budget_counts_what_the_tree_sum_evaluates():
    """The walk alone (:func:`evaluations_per_receiver`, what the solve's budget samples) counts, per receiver,
    the sources and clusters of the walk's definition, and as many as :func:`tree_sum` evaluates there."""
    from translucency.scatter import kernels
    from translucency.scatter.hierarchy import (
        GROUP_RECEIVERS,
        aggregated_sources,
        evaluations_per_receiver,
        node_sums,
        tree_sum,
    )
    from translucency.scatter.materials import material

    rng = np.random.default_rng(5)
    points = rng.normal(size=(3000, 3))
    points = 20.0 * points / np.linalg.norm(points, axis=1, keepdims=True)  # a sphere of 20 mm
    normals = points / 20.0
    flux = np.where(points[:, 2:3] > 0, rng.uniform(0.1, 1.0, (3000, 3)), 0.0)  # the lower half unlit
    tree = SourceTree(points)
    theta, min_distance = 0.3, 1.0
    receivers = points[rng.choice(3000, 401, replace=False)]
    counted = evaluations_per_receiver(tree, flux, receivers, theta, min_distance)

    weight = node_sums(tree, flux.sum(axis=1)[:, None])[:, 0]
    lit = flux.sum(axis=1) > 0
    for g in range(0, 401, GROUP_RECEIVERS):
        members = receivers[g : g + GROUP_RECEIVERS]
        centre = members.mean(axis=0)
        spread = np.linalg.norm(members - centre, axis=1).max()
        expected = _walk_by_definition(tree, weight, lit, centre, spread, theta, min_distance)
        assert np.all(counted[g : g + GROUP_RECEIVERS] == expected)

    medium = material("marble").medium()
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta)
    w12 = -normals
    sources = aggregated_sources(tree, points, normals, w12, flux)
    _, direct, clustered = tree_sum(
        0, tree, sources, receivers, receivers / 20.0, params, np.arange(3), theta, min_distance=min_distance
    )
    assert np.array_equal(direct + clustered, counted)
