"""Near-field quadrature rules against independent integrals (scipy, closed forms)."""

import numpy as np
import pytest
from scipy import integrate

from translucency.scatter import dipoles, fresnel, nearfield
from translucency.scatter.materials import material


def _fan_points(triangle, corner, scale_min, nodes=(nearfield.FAN_ANGULAR, nearfield.FAN_RADIAL), beta=1.5):
    ang = nearfield.gauss_legendre_unit(nodes[0])
    rad = nearfield.gauss_legendre_unit(nodes[1])
    tri = np.array([0, 1, 2])
    out = np.empty((nearfield.fan_count(triangle, tri, corner, beta * scale_min, *nodes), 4))
    nearfield.fan_rule(triangle, tri, corner, beta, scale_min, *ang, *rad, out)
    points = out[:, :3] @ triangle
    area = 0.5 * np.linalg.norm(np.cross(triangle[1] - triangle[0], triangle[2] - triangle[0]))
    return points, out[:, 3] * area


def _scipy_integral(triangle, corner, f):
    """Integral of f over the triangle in Duffy coordinates about ``corner`` (adaptive scipy quadrature)."""
    p0 = triangle[corner]
    e1 = triangle[(corner + 1) % 3] - p0
    e2 = triangle[(corner + 2) % 3] - p0
    area2 = np.linalg.norm(np.cross(e1, e2))

    def integrand(s, t):
        return f(p0 + s * ((1 - t) * e1 + t * e2)) * area2 * s

    # the peak sits at s = 0: split there so the adaptive rule sees it
    total = 0.0
    for lo, hi in ((0.0, 0.02), (0.02, 0.2), (0.2, 1.0)):
        total += integrate.dblquad(integrand, 0.0, 1.0, lo, hi, epsabs=0, epsrel=1e-10)[0]
    return total


TRIANGLES = {
    "equilateral": np.array([[0.0, 0.0, 0.0], [1.5, 0.0, 0.0], [0.75, 1.3, 0.0]]),
    "obtuse at the receiver (150 deg, three sectors)": np.array([[0.0, 0.0, 0.0], [1.5, 0.0, 0.0], [-1.2, 0.7, 0.0]]),
    "thin": np.array([[0.0, 0.0, 0.0], [2.0, 0.1, 0.0], [1.9, 0.3, 0.0]]),
}


@pytest.mark.parametrize("material_name", ["marble", "ketchup"])
@pytest.mark.parametrize("name", TRIANGLES)
# corner 0 of every shape (obtuse, thin) is in the quick subset; corner 1 runs with the slow tests
@pytest.mark.parametrize("corner", [0, pytest.param(1, marks=pytest.mark.slow)])
def test_fan_rule_integrates_the_peak_at_the_receiver(material_name, name, corner):
    """S_d of the reference formula (dipoles.py, bluest channel: the narrowest peak, D = 0.11 mm for
    marble) from every point of a 1.5-2 mm triangle to the receiver at its corner, light at 30 deg:
    the fan rule's default nodes (15 per sector) match scipy's adaptive integral to 5e-4, and more
    nodes converge to it (1e-5)."""
    medium = material(material_name).medium()
    triangle = TRIANGLES[name]
    receiver = triangle[corner]
    normal = np.array([0.0, 0.0, 1.0])
    w12 = fresnel.refract(np.array([-0.5, 0.0, np.sqrt(0.75)]), normal, medium.eta)

    def f(x):
        x = np.atleast_2d(x)
        return np.squeeze(
            dipoles.directional_dipole(
                x,
                np.broadcast_to(normal, x.shape),
                np.broadcast_to(w12, x.shape),
                receiver,
                normal,
                medium.sigma_a[2],
                medium.sigma_s[2],
                0.0,
                medium.eta,
            )
        )

    reference = _scipy_integral(triangle, corner, f)
    points, weights = _fan_points(triangle, corner, float(medium.D.min()))
    assert weights.min() > 0
    assert np.isclose(weights @ f(points), reference, rtol=5e-4)
    points, weights = _fan_points(triangle, corner, float(medium.D.min()), nodes=(6, 10))
    assert np.isclose(weights @ f(points), reference, rtol=1e-5)


def test_fan_rule_of_a_degenerate_triangle_weighs_nothing():
    triangle = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    tri = np.array([0, 1, 2])
    assert nearfield.fan_count(triangle, tri, 0, 0.15, 3, 5) == 0


def test_degree3_rule_is_exact_for_cubics():
    """Corner, midpoint and centroid weights integrate every monomial of degree <= 3 exactly over the
    unit right triangle (closed form a! b! / (a + b + 2)!), and miss a quartic."""
    from math import factorial

    corners = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    mids = 0.5 * (corners + np.roll(corners, -1, axis=0))
    centroid = corners.mean(axis=0)
    points = np.vstack([corners, mids, centroid])
    weights = 0.5 * np.array(
        [nearfield.CORNER_WEIGHT] * 3 + [nearfield.MIDPOINT_WEIGHT] * 3 + [nearfield.CENTROID_WEIGHT]
    )
    for a in range(5):
        for b in range(5 - a):
            exact = factorial(a) * factorial(b) / factorial(a + b + 2)
            rule = weights @ (points[:, 0] ** a * points[:, 1] ** b)
            if a + b <= 3:
                assert np.isclose(rule, exact, rtol=1e-13), (a, b)
    assert not np.isclose(weights @ points[:, 0] ** 4, 1 / 30, rtol=1e-3)


@pytest.mark.parametrize("radius", [0.0, 0.3, 1.0, 50.0])
def test_near_triangles_are_those_with_a_vertex_within_the_radius(radius):
    """The grid search equals a brute-force distance check (every receiver, every vertex)."""
    from translucency.geometry.synthetic import icosphere

    points, triangles = icosphere(2, 5.0)
    points = points * np.array([1.0, 0.7, 1.3])  # not a sphere: cells fill unevenly
    receivers = np.array([0, 5, 17, len(points) - 1])
    offsets, ids = nearfield.near_triangles(points, triangles, receivers, radius)
    for q, v in enumerate(receivers):
        close = np.linalg.norm(points - points[v], axis=1) <= radius
        expected = np.flatnonzero(close[triangles].any(axis=1))
        found = ids[offsets[q] : offsets[q + 1]]
        assert len(found) == len(set(found.tolist()))  # each triangle once
        assert np.array_equal(np.sort(found), expected)


def test_one_grid_lists_blocks_of_receivers_as_one_call_lists_them_all():
    """A grid made once serves block after block (its stamps carry on): the same lists as all at once."""
    from translucency.geometry.synthetic import icosphere

    points, triangles = icosphere(3, 5.0)
    receivers = np.random.default_rng(2).permutation(len(points))
    offsets, ids = nearfield.near_triangles(points, triangles, receivers, 1.2)
    grid = nearfield.near_grid(points, triangles, 1.2)
    for block in np.array_split(np.arange(len(receivers)), 7):
        counts = grid.counts(receivers[block])
        o, i = grid.lists(receivers[block])
        assert np.array_equal(np.diff(o), counts)
        for q, r in enumerate(block):
            assert np.array_equal(np.sort(i[o[q] : o[q + 1]]), np.sort(ids[offsets[r] : offsets[r + 1]]))


def test_the_grid_starts_its_stamps_again_before_they_pass_int32():
    """The stamps are int32: a grid listed near their largest value starts them again from -1 (a stamp that wrapped
    would match an old one and drop triangles), with the same lists as a fresh grid."""
    from translucency.geometry.synthetic import icosphere

    points, triangles = icosphere(2, 5.0)
    receivers = np.arange(len(points))
    fresh = nearfield.near_grid(points, triangles, 1.5).lists(receivers)
    grid = nearfield.near_grid(points, triangles, 1.5)
    grid.lists(receivers)  # stamps set
    grid.next_stamp = np.iinfo(grid.stamps.dtype).max - len(receivers) // 2
    offsets, ids = grid.lists(receivers)
    assert grid.next_stamp <= 2 * len(receivers)  # started again
    assert np.array_equal(offsets, fresh[0]) and np.array_equal(ids, fresh[1])


def test_blocks_that_share_the_column_maps_get_what_each_gets_alone_and_leave_them_clean():
    """The near field's blocks share one light's column maps (vertex, triangle and edge to the columns of the
    block's point table), each putting back what it set: the same correction as with fresh maps per block, and the
    maps as made once every block is done."""
    from translucency.geometry.measure import vertex_normals
    from translucency.geometry.synthetic import icosphere
    from translucency.scatter import kernels

    points, triangles = icosphere(3, 4.0)
    normals = vertex_normals(points, triangles)
    areas = np.linalg.norm(np.cross(*(points[triangles[:, 1:]] - points[triangles[:, :1]]).transpose(1, 0, 2)), axis=1)
    medium = material("marble").medium()
    light = np.array([0.0, 0.0, 1.0])
    cos = normals @ light
    phi = np.repeat(np.where(cos > 0, cos, 0.0)[:, None], 3, axis=1)
    w12 = fresnel.refract(np.broadcast_to(light, normals.shape), normals, medium.eta)
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta)
    tables = nearfield.triangle_tables(points, triangles)
    maps = nearfield.column_maps(phi, len(triangles), tables.n_edges)
    grid = nearfield.near_grid(points, triangles, 1.0)
    for block in np.array_split(np.random.default_rng(3).permutation(len(points)), 5):
        offsets, ids = grid.lists(block)
        args = (0, points, triangles, 0.5 * areas, normals, w12, phi, block, offsets, ids, params, np.arange(3))
        args += (1.5, float(np.min(medium.D)))
        alone, _ = nearfield.near_field_correction(*args, tables=tables)
        shared, _ = nearfield.near_field_correction(*args, tables=tables, maps=maps)
        assert np.array_equal(alone, shared)
    assert np.all(maps.vertex_column == -1) and np.all(maps.first_rule == -1)
    assert np.all(maps.midpoint_column == -1) and not maps.listed.any()
    # maps a block left set (an error between setting and clearing) are refused, not read
    nearfield.source_point_table(points, normals, w12, phi, triangles, 0.5 * areas, tables, within=ids, maps=maps)
    with pytest.raises(RuntimeError, match="not cleared"):
        nearfield.near_field_correction(*args, tables=tables, maps=maps)


@pytest.mark.parametrize("unlit", [(), (2,), (0, 1, 2)])
@pytest.mark.parametrize("corner", [0, 1, 2])
def test_the_fan_gathered_a_ray_at_a_time_is_the_fan_rule_gathered_point_by_point(corner, unlit):
    """:func:`nearfield.fan_gathered` writes the columns that :func:`nearfield.fan_rule` and
    :func:`nearfield.gather_point` write for each of its points (an obtuse triangle with bent normals, spread
    refracted directions and a flux per channel; a corner or every corner unlit)."""
    rng = np.random.default_rng(corner)
    points = np.array([[0.0, 0.0, 0.0], [2.0, 0.1, 0.0], [-0.6, 0.9, 0.2]])
    normals = np.array([[0.1, 0.0, 1.0], [0.0, 0.3, 1.0], [-0.2, 0.1, 1.0]])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    w12 = -normals + 0.2 * rng.normal(size=(3, 3))
    w12 /= np.linalg.norm(w12, axis=1)[:, None]
    phi = rng.uniform(0.5, 2.0, size=(3, 3))
    phi[list(unlit)] = 0.0
    tri = np.array([0, 1, 2])
    beta, scale_min, area = 1.5, 0.05, 0.9
    fan = (*nearfield.gauss_legendre_unit(nearfield.FAN_ANGULAR), *nearfield.gauss_legendre_unit(nearfield.FAN_RADIAL))
    n = nearfield.fan_count(points, tri, corner, beta * scale_min, nearfield.FAN_ANGULAR, nearfield.FAN_RADIAL)
    rows = np.empty((n, 4))
    nearfield.fan_rule(points, tri, corner, beta, scale_min, *fan, rows)
    expected = np.zeros((9, n + 1)), np.zeros((3, n + 1))
    for j in range(n):
        nearfield.gather_point(points, normals, w12, phi, tri, *rows[j, :3], rows[j, 3] * area, *expected, j + 1)
    got = np.zeros((9, n + 1)), np.zeros((3, n + 1))
    end = nearfield.fan_gathered(points, normals, w12, phi, tri, corner, area, beta, scale_min, fan, *got, 1)
    assert end == n + 1
    assert n > 15  # more than one set of nodes: sectors (the obtuse corner) or stretches (long edges)
    for g, e in zip(got, expected, strict=True):
        np.testing.assert_allclose(g, e, rtol=1e-12, atol=1e-14)
