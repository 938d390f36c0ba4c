"""The source tree's structure, checked node by node against its definition (hierarchy module docstring)."""

import numpy as np
import pytest

from translucency.scatter.hierarchy import LEAF_SIZE, SourceTree
from translucency.scatter.materials import material
from translucency.scatter.medium import Medium

MARBLE = material("marble").medium()


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


def _walk_by_definition(tree, node_flux, lit, centre, spread, rule, allow=None, reach=np.inf, listed=None):
    """Sources plus clusters one group (a sphere: ``centre``, ``spread``, mm) evaluates, walked node by node
    as :class:`~translucency.scatter.hierarchy.Opening` defines it (``allow`` per channel, None: no limit; nodes
    beyond ``reach`` skipped); ``listed``, a list, receives the columns (source ``j``, cluster ``n + node``)."""
    from translucency.scatter.cutoff import largest_values, pair_bound
    from translucency.scatter.hierarchy import LARGEST_MARGIN

    listed = [] if listed is None else listed
    stack = [0]
    while stack:
        k = stack.pop()
        if node_flux[k].sum() <= 0:
            continue
        near = np.linalg.norm(centre - tree.centre[k]) - spread
        r = tree.radius[k]
        if near > reach + r:
            continue
        accept = near > r + rule.min_distance and r < rule.theta * near
        if accept and allow is not None:
            # the bound at the table's distance at or below near - r (the table is log-spaced)
            steps = int(np.floor((np.log(near - r) - rule.log_first) * rule.per_log))
            at = np.exp(rule.log_first + min(max(steps, 0), rule.bound.shape[1] - 1) / rule.per_log)
            bound = np.minimum(
                pair_bound(MARBLE, "directional", at), LARGEST_MARGIN * largest_values(MARBLE, "directional", at)
            )[:, 0]
            error = r**2 * (1.0 / near**2 + MARBLE.sigma_tr**2) * node_flux[k] * bound
            accept = bool(np.all(error <= allow))
        if accept:
            listed.append(lit.size + k)
        elif tree.left[k] < 0:
            members = tree.order[tree.start[k] : tree.end[k]]
            listed.extend(members[lit[members]].tolist())
        else:
            stack += [tree.left[k], tree.right[k]]
    return len(listed)


def _lit_sphere(n=3000, seed=5):
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(n, 3))
    points = 20.0 * points / np.linalg.norm(points, axis=1, keepdims=True)  # a sphere of 20 mm
    flux = np.where(points[:, 2:3] > 0, rng.uniform(0.1, 1.0, (n, 3)), 0.0)  # the lower half unlit
    return rng, points, points / 20.0, flux


def test_both_walks_list_what_their_definition_lists():
    """The first walk (opening ratio and distance) and the second (the aggregate's error within each group's
    allowance) count, per group, the sources and clusters of the criterion's definition."""
    from translucency.scatter.hierarchy import node_sums, opening
    from translucency.scatter.treewalk import GROUP_RECEIVERS, walk_lists

    rng, points, _, flux = _lit_sphere()
    tree = SourceTree(points)
    rule = opening(MARBLE, "directional", 0.01)
    node_flux = node_sums(tree, flux)
    lit = flux.sum(axis=1) > 0
    receivers = points[rng.choice(points.shape[0], 401, replace=False)]
    allow = 10.0 ** rng.uniform(-9.0, -5.0, (401, 3))
    first = walk_lists(tree, node_flux, lit, receivers, rule, count_only=True)
    second = walk_lists(tree, node_flux, lit, receivers, rule, allow, count_only=True)
    for g in range(0, 401, GROUP_RECEIVERS):
        members = receivers[g : g + GROUP_RECEIVERS]
        centre = members.mean(axis=0)
        spread = np.linalg.norm(members - centre, axis=1).max()
        least = allow[g : g + GROUP_RECEIVERS].min(axis=0)
        k = g // GROUP_RECEIVERS
        assert first[1][k] + first[2][k] == _walk_by_definition(tree, node_flux, lit, centre, spread, rule)
        assert second[1][k] + second[2][k] == _walk_by_definition(tree, node_flux, lit, centre, spread, rule, least)
    assert second[2].sum() < first[2].sum()  # the allowance opened clusters the first walk took


@pytest.mark.parametrize("reach", [np.inf, 12.0])
def test_groups_that_share_their_walk_list_what_each_lists_alone(reach):
    """Runs of neighbouring groups decide together what each of their groups would decide alike
    (:func:`~translucency.scatter.treewalk.shared_walks`): every group's list holds the sources and clusters of the
    criterion's definition for that group alone, with allowances that vary from receiver to receiver and nodes
    skipped beyond a reach."""
    from translucency.geometry.morton import morton_order
    from translucency.scatter.hierarchy import node_sums, opening
    from translucency.scatter.treewalk import GROUP_RECEIVERS, walk_lists

    rng, points, _, flux = _lit_sphere(6000, seed=9)
    tree = SourceTree(points)
    rule = opening(MARBLE, "directional", 0.01)
    node_flux = node_sums(tree, flux)
    lit = flux.sum(axis=1) > 0
    receivers = points[morton_order(points)][::7]  # neighbours follow each other, as the solver orders them
    n = receivers.shape[0]
    allow = 10.0 ** rng.uniform(-7.0, -5.0, (n, 3)) * (1.0 + (receivers[:, 2:3] < 0) * 1e-3)  # the dark side: less
    for limit in (None, allow):
        starts, direct, clustered, columns = walk_lists(tree, node_flux, lit, receivers, rule, limit, reach)
        for g, first in enumerate(range(0, n, GROUP_RECEIVERS)):
            members = receivers[np.minimum(np.arange(first, first + GROUP_RECEIVERS), n - 1)]  # the last repeated
            centre = members.mean(axis=0)
            spread = np.linalg.norm(members - centre, axis=1).max()
            least = None if limit is None else limit[first : first + GROUP_RECEIVERS].min(axis=0)
            expected = []
            _walk_by_definition(tree, node_flux, lit, centre, spread, rule, least, reach, expected)
            got = columns[starts[g] : starts[g] + direct[g] + clustered[g]]
            assert np.array_equal(np.sort(got), np.sort(expected)), g


def test_the_budget_counts_what_the_tree_sum_evaluates():
    """The budget's sample (:func:`sampled_evaluations`: the nodes' aggregates and a table of the listed columns
    alone) counts, per group of receivers, as many sources and clusters as :func:`tree_sum` evaluates there, both
    walks (the first walk's, at each group's first receiver, shared out over the group by the count)."""
    from translucency.scatter import kernels
    from translucency.scatter.hierarchy import (
        ListedWalk,
        aggregated_sources,
        brightest,
        first_estimate,
        opening,
        sampled_evaluations,
        tree_sum,
    )
    from translucency.scatter.treewalk import GROUP_RECEIVERS

    _, points, normals, flux = _lit_sphere()
    tree = SourceTree(points)
    rule = opening(MARBLE, "directional", 0.01)
    params = kernels.channel_parameters(MARBLE.sigma_a, MARBLE.sigma_s, MARBLE.g, MARBLE.eta)
    w12 = -normals
    rcv = np.arange(0, 3000, 7)
    bright = brightest(flux, np.ones(3000))
    counted = sampled_evaluations(0, tree, points, normals, w12, flux, rcv, bright, params, np.arange(3), rule, 1e-4)

    sources = aggregated_sources(tree, points, normals, w12, flux)
    walked = ListedWalk(0, tree, sources, params, np.arange(3), rule)
    estimate = first_estimate(walked, points[bright], normals[bright])
    floor = 1e-4 * estimate.max(axis=0)
    _, direct, clustered = tree_sum(walked, points[rcv], normals[rcv], floor)
    groups = np.arange(0, rcv.size, GROUP_RECEIVERS)
    assert np.allclose(np.add.reduceat(counted, groups), np.add.reduceat(direct + clustered, groups), rtol=1e-12)
    assert np.all(clustered[groups] > 0)  # the first walk's at the groups' first receivers


def test_a_receiver_or_an_allowance_at_nan_changes_no_other_groups_list(monkeypatch):
    """A group whose allowance is NaN takes every node it meets, and one whose receiver is at NaN opens every node:
    the runs they are in leave to each group what they cannot decide for all, so every other group lists what it
    lists walking alone (the runs turned off)."""
    from translucency.geometry.morton import morton_order
    from translucency.scatter import treewalk
    from translucency.scatter.hierarchy import node_sums, opening

    rng, points, _, flux = _lit_sphere(4000, seed=3)
    points = points[morton_order(points)]
    tree = SourceTree(points)
    rule = opening(MARBLE, "directional", 0.01)
    node_flux = node_sums(tree, flux)
    lit = flux.sum(axis=1) > 0
    receivers = points[::5].copy()
    allow = 10.0 ** rng.uniform(-5.0, -3.0, (receivers.shape[0], 3))  # about half the nodes opened
    allow[5] = np.nan
    receivers[-1] = np.nan

    def lists(levels):
        monkeypatch.setattr(treewalk, "SHARED_LEVELS", levels)
        starts, direct, clustered, columns = treewalk.walk_lists(tree, node_flux, lit, receivers, rule, allow)
        return [np.sort(columns[s : s + n]) for s, n in zip(starts, direct + clustered)]

    levels = treewalk.SHARED_LEVELS
    assert levels > 0
    alone, shared = lists(0), lists(levels)
    assert all(np.array_equal(a, b) for a, b in zip(alone, shared, strict=True))


def test_float32_sums_stay_within_1e_4_of_float64_at_every_vertex_of_a_coarse_torus(monkeypatch):
    """``tree`` sums its clusters in float32 and the mesh's own sources in float64 (docs/physics.md §8.3): on a
    coarse torus in marble (edges about 2.6 mm, six mean free paths), lit with its own shadows, every vertex's
    ``B`` stays within 1e-4 of the sums all in float64. Sources summed in float32 where a bound of their error
    was within a tenth of the allowance were 3.4 % off there: the near field's correction takes their values off
    again, and in float32 what is left of them is not ``B``."""
    from translucency.geometry.mesh import TriangleMesh
    from translucency.geometry.synthetic import torus
    from translucency.scatter import hierarchy
    from translucency.scatter.irradiance import incident_flux
    from translucency.scatter.lights import DirectionalLight
    from translucency.scatter.solve import SurfaceGeometry, solve

    mesh = TriangleMesh(*torus(20.0, 8.0, 48, 24))
    geometry = SurfaceGeometry(mesh.points, mesh.triangles, mesh.vertex_normals())
    light = incident_flux(
        geometry.points, geometry.normals, geometry.vertex_areas, [DirectionalLight((0.3, 0.5, 0.8), 1.0)],
        MARBLE.eta, triangles=mesh.triangles,
    )  # fmt: skip
    single = solve(geometry, light.phi_rgb, light.w12, MARBLE, method="tree", tol=0.01)
    monkeypatch.setattr(hierarchy, "FLOAT32_TOL", 1.0)
    double = solve(geometry, light.phi_rgb, light.w12, MARBLE, method="tree", tol=0.01)
    assert single.stats["cluster_evaluations"] > 0
    assert np.max(np.abs(single.B - double.B) / double.B) <= 1e-4
    assert not np.array_equal(single.B, double.B)  # the clusters were summed in float32


def _media():
    """The media the sampled values are checked in: three of the tables, light at grazing index (eta 1), and marble
    made a hundred thousand times denser (mean free paths of nanometres, where the sampled distances must follow)."""
    marble = material("marble")
    return {
        "marble": MARBLE,
        "ketchup": material("ketchup").medium(),
        "skim_milk": material("skim_milk").medium(),
        "eta 1": Medium(np.array(marble.sigma_a), np.array(marble.sigma_s), np.array(marble.g), 1.0),
        "dense marble": MARBLE.scaled(1e5),
    }


@pytest.mark.parametrize("name", ["marble", "ketchup", "skim_milk", "eta 1", "dense marble"])
def test_the_largest_sampled_values_hold_other_geometries_and_stay_under_the_bound(name):
    """``cutoff.largest_values`` (the criterion's magnitude, docs/physics.md §8.3): 20,000 random geometries, each with
    its own source normal, are within 1.5 times it at every distance from a tenth of a mean free path to 300 of them;
    and the largest sampled values themselves are below the bound of §8.4 (which they are not clipped to)."""
    from tests.scatter.pairs import model_pairs
    from translucency.scatter import cutoff, kernels

    medium = _media()[name]
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta, "directional")
    rng = np.random.default_rng(41)
    k = 20_000

    def on_sphere():
        x = rng.normal(size=(k, 3))
        return x / np.linalg.norm(x, axis=1, keepdims=True)

    n_i, u, n_o, tilt = on_sphere(), on_sphere(), on_sphere(), on_sphere()
    # a refracted direction within the cone of light from outside about -n_i
    side = np.cross(n_i, tilt)
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    cos_t = 1.0 - rng.uniform(0, 1, k) * (1.0 - np.cos(np.arcsin(min(1.0, 1.0 / medium.eta))))
    w12 = -cos_t[:, None] * n_i + np.sqrt(1.0 - cos_t**2)[:, None] * side
    mean_free_path = 1.0 / float(np.max(medium.sigma_t_reduced))
    for r in mean_free_path * np.array([0.1, 1.0, 5.0, 20.0, 80.0, 300.0]):
        fresh = model_pairs(0, np.zeros((k, 3)), n_i, w12, r * u, n_o, params).max(axis=0)
        largest = cutoff.largest_values(medium, "directional", np.array([r]))[:, 0]
        assert np.all(fresh <= 1.5 * largest), (r, fresh / largest)
    _, shares = cutoff._largest_shares(medium)
    assert np.all(shares[np.isfinite(shares)] <= 1.0)


@pytest.mark.parametrize("model", ["standard", "better"])
def test_the_radial_models_magnitude_is_their_profile(model):
    from translucency.scatter.cutoff import largest_values, pair_bound

    r = np.geomspace(0.01, 100.0, 9)
    assert np.array_equal(largest_values(MARBLE, model, r), pair_bound(MARBLE, model, r))


def test_the_bound_drops_more_with_the_distance_than_the_largest_values():
    """Why the criterion takes the sampled values (docs/physics.md §8.3): in marble the bound of §8.4 is 2-5 times the
    largest ``S_d`` at 1 mm and over 50 times at 32 mm."""
    from translucency.scatter.cutoff import largest_values, pair_bound

    r = np.array([1.0, 32.0])
    ratio = pair_bound(MARBLE, "directional", r) / largest_values(MARBLE, "directional", r)
    assert np.all((ratio[:, 0] > 2.0) & (ratio[:, 0] < 5.0))
    assert np.all(ratio[:, 1] > 50.0)
