"""Relighting operators: their fitted coefficients against the pair kernel, and relit B against direct solves."""

import numba
import numpy as np
import pytest

from tests.scatter import pairs
from translucency.errors import BudgetError
from translucency.geometry.measure import vertex_normals
from translucency.geometry.synthetic import icosphere, torus
from translucency.scatter import fits, kernels
from translucency.scatter.fresnel import fresnel_transmittance, refract
from translucency.scatter.irradiance import incident_flux
from translucency.scatter.lights import DirectionalLight, EnvironmentLight, PointLight
from translucency.scatter.materials import material
from translucency.scatter.relight import kept_operator
from translucency.scatter.solve import SurfaceGeometry, near_radius, solve
from translucency.scatter.surface import spatial_order
from translucency.scatter.visibility import VisibilityCache

MARBLE = material("marble").medium()


@numba.njit(cache=True)
def _fits(model, x, ni, no, params, dirs, pinv, terms):
    out = np.zeros((params.shape[0], terms))
    work = np.empty((max(dirs.shape[0], 9), pairs.FIT_WORK_COLUMNS))
    pairs.fitted_pairs(model, x[0], x[1], x[2], ni[0], ni[1], ni[2], no[0], no[1], no[2], params, dirs, pinv, work, out)
    return out


def _monomials(w):
    return np.array([1.0, *w, w[0] ** 2, w[1] ** 2, w[2] ** 2, w[0] * w[1], w[0] * w[2], w[1] * w[2]])


def _random_pairs(rng, distance, count=200):
    """Receivers near a gently curved surface at ``distance`` mm from the source, lit from random directions
    above the source (the refracted direction of docs/physics.md §3.2)."""
    for _ in range(count):
        ni = np.array([0.0, 0.0, 1.0]) + 0.1 * rng.normal(size=3)
        no = np.array([0.0, 0.0, 1.0]) + 0.1 * rng.normal(size=3)
        ni, no = ni / np.linalg.norm(ni), no / np.linalg.norm(no)
        x = rng.normal(size=3) * (1.0, 1.0, 0.1)
        x *= distance / np.linalg.norm(x)
        light = rng.normal(size=3)
        light[2] = abs(light[2])
        light /= np.linalg.norm(light)
        if light @ ni > 0.05:
            yield x, ni, no, refract(light, ni, MARBLE.eta)


@pytest.mark.parametrize(
    "terms, distance, bound",
    [
        (fits.AFFINE_TERMS, 2.0, 0.01),
        (fits.AFFINE_TERMS, 20.0, 0.004),
        (fits.QUADRATIC_TERMS, 1.0, 0.01),
        (fits.QUADRATIC_TERMS, 5.0, 0.002),
    ],
)
def test_fitted_coefficients_follow_the_pair_kernel_over_refracted_directions(terms, distance, bound):
    # measured (docs/physics.md §8.7): affine p99 0.45 % at 2 mm, 0.15 % at 20 mm; quadratic 0.49 % at 1 mm
    params = kernels.channel_parameters(MARBLE.sigma_a, MARBLE.sigma_s, MARBLE.g, MARBLE.eta, "directional")
    dirs, pinv = fits.fit_directions(MARBLE.eta, terms)
    errors = []
    for x, ni, no, w in _random_pairs(np.random.default_rng(7), distance):
        exact = pairs.model_pairs(0, np.zeros((1, 3)), ni[None], w[None], x[None], no[None], params)[0]
        if np.all(exact > 0):
            fitted = _fits(0, x, ni, no, params, dirs, pinv, terms) @ _monomials(w)[:terms]
            errors.append(np.max(np.abs(fitted / exact - 1.0)))
    assert len(errors) > 100
    assert np.percentile(errors, 99) < bound


@pytest.mark.parametrize("model", ["standard", "better"])
def test_radial_models_fit_exactly_with_no_direction_terms(model):
    params = kernels.channel_parameters(MARBLE.sigma_a, MARBLE.sigma_s, MARBLE.g, MARBLE.eta, model)
    dirs, pinv = fits.fit_directions(MARBLE.eta, fits.QUADRATIC_TERMS)
    x, ni, no = np.array([1.5, -0.4, 0.1]), np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.1, 0.995])
    code = kernels.MODELS[model]
    fitted = _fits(code, x, ni, no, params, dirs, pinv, fits.QUADRATIC_TERMS)
    exact = pairs.model_pairs(code, np.zeros((1, 3)), ni[None], -ni[None], x[None], no[None], params)[0]
    np.testing.assert_allclose(fitted[:, 0], exact, rtol=1e-12)
    assert np.all(fitted[:, 1:] == 0.0)


@pytest.mark.parametrize("model", ["directional", "standard"])
@pytest.mark.parametrize("sources_vary", [True, False])
def test_a_run_of_fits_equals_the_fits_of_its_pairs(model, sources_vary):
    # receivers from 0.05 mm to 40 mm away, every one through the run's vectorised steps
    rng = np.random.default_rng(3)
    n = 300
    points = rng.normal(size=(n, 3)) * np.geomspace(0.05, 40.0, n)[:, None]
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    params = kernels.channel_parameters(MARBLE.sigma_a, MARBLE.sigma_s, MARBLE.g, MARBLE.eta, model)
    dirs, pinv = fits.fit_directions(MARBLE.eta, fits.AFFINE_TERMS)
    code = kernels.MODELS[model]
    out = np.empty((n - 1, 3, fits.AFFINE_TERMS))
    fits.fitted_run(code, points, normals, 0, 1, n, sources_vary, params, dirs, pinv, fits.run_scratch(7, n), out)
    for q in range(n - 1):
        o, i = (0, q + 1) if sources_vary else (q + 1, 0)
        expected = _fits(code, points[o] - points[i], normals[i], normals[o], params, dirs, pinv, fits.AFFINE_TERMS)
        scale = np.abs(expected).max(axis=1, keepdims=True)
        assert np.all(np.abs(out[q] - expected) <= 1e-10 * scale), (q, out[q], expected)


@pytest.mark.parametrize("model", ["directional", "better"])
def test_quadratic_fits_of_a_batch_of_points_equal_the_fits_of_its_pairs(model):
    # near-field pairs, 0.02-3 mm: the batch is each pair's fit to rounding
    rng = np.random.default_rng(5)
    n = 400
    x = rng.normal(size=(n, 3)) * np.geomspace(0.02, 3.0, n)[:, None]
    ni = rng.normal(size=(n, 3)) * 0.3 + (0.0, 0.0, 1.0)
    no = rng.normal(size=(n, 3)) * 0.3 + (0.0, 0.0, 1.0)
    ni, no = ni / np.linalg.norm(ni, axis=1)[:, None], no / np.linalg.norm(no, axis=1)[:, None]
    params = kernels.channel_parameters(MARBLE.sigma_a, MARBLE.sigma_s, MARBLE.g, MARBLE.eta, model)
    dirs, pinv = fits.fit_directions(MARBLE.eta, fits.QUADRATIC_TERMS)
    code = kernels.MODELS[model]
    scratch = fits.run_scratch(dirs.shape[0], n)
    scratch[0][0:3, :n], scratch[0][3:6, :n], scratch[0][6:9, :n] = x.T, ni.T, no.T
    out = np.empty((n, 3, fits.QUADRATIC_TERMS))
    fits.fitted_points(code, n, params, dirs, pinv, scratch, out)
    errors = []
    for q in range(n):
        expected = _fits(code, x[q], ni[q], no[q], params, dirs, pinv, fits.QUADRATIC_TERMS)
        errors.append(np.max(np.abs(out[q] - expected) / np.abs(expected).max(axis=1, keepdims=True)))
    assert np.max(errors) < 1e-10


def _surface(points, triangles):
    from translucency.geometry.mesh import TriangleMesh

    mesh = TriangleMesh(points, triangles)
    return mesh, SurfaceGeometry(mesh.points, mesh.triangles, mesh.vertex_normals())


def _per_vertex_error(B, reference):
    """The error tol bounds (docs/physics.md §8.5): |B / B_ref - 1| over vertices with B_ref >= 1e-4 max."""
    keep = reference >= 1e-4 * reference.max(axis=0)
    return np.abs(B - reference)[keep] / reference[keep]


LIGHTS = {
    "directional": DirectionalLight((0.3, 0.5, 0.8), 1.0),
    "point": PointLight((25.0, -10.0, 30.0), 1.0),
    "environment": EnvironmentLight(radiance_rgb=(0.3, 0.3, 0.3), n_directions=24),
}


@pytest.mark.parametrize(
    "light",
    ["directional", pytest.param("environment", marks=pytest.mark.slow), pytest.param("point", marks=pytest.mark.slow)],
)
def test_relit_B_matches_a_direct_solve_within_tol(light):
    mesh, geometry = _surface(*torus(20.0, 8.0, 48, 24))  # shadows of its own, 1152 vertices
    incident = incident_flux(
        geometry.points,
        geometry.normals,
        geometry.vertex_areas,
        [LIGHTS[light]],
        MARBLE.eta,
        triangles=mesh.triangles,
        cache=VisibilityCache(),
    )
    reference = solve(geometry, incident.phi_rgb, incident.w12, MARBLE, method="exact").B
    relit = solve(geometry, incident.phi_rgb, incident.w12, MARBLE, method="relight", tol=0.01)
    assert np.percentile(_per_vertex_error(relit.B, reference), 99) < 0.01


def _random_light(kind, rng):
    """A light of ``kind`` drawn at random: a direction, a position 40-80 mm from the torus' centre, or a small
    radiance map with a bright patch somewhere; colours drawn too."""
    colour = tuple(rng.uniform(0.2, 1.0, 3))
    if kind == "directional":
        return DirectionalLight(tuple(rng.normal(size=3)), colour)
    if kind == "point":
        towards = rng.normal(size=3)
        return PointLight(tuple(rng.uniform(40.0, 80.0) * towards / np.linalg.norm(towards)), colour)
    radiance = rng.uniform(0.0, 0.1, (8, 16, 3))
    row, column = rng.integers(0, 8), rng.integers(0, 16)
    radiance[row, column] = 5.0 * np.array(colour)
    return EnvironmentLight(radiance_map=radiance, n_directions=32, seed=int(rng.integers(1 << 30)))


@pytest.mark.slow
def test_one_set_of_operators_relights_random_lights_within_tol():
    """Prepared once, the operators relight lights of every kind drawn at random (directions, positions, radiance
    maps and colours), each within tol of ``exact`` at the 99th percentile."""
    mesh, geometry = _surface(*torus(20.0, 8.0, 48, 24))
    rng = np.random.default_rng(20261205)
    cache = VisibilityCache()
    for k, kind in enumerate(("directional", "point", "environment") * 2):
        light = _random_light(kind, rng)
        incident = incident_flux(
            geometry.points, geometry.normals, geometry.vertex_areas, [light], MARBLE.eta,
            triangles=mesh.triangles, cache=cache,
        )  # fmt: skip
        reference = solve(geometry, incident.phi_rgb, incident.w12, MARBLE, method="exact").B
        relit = solve(geometry, incident.phi_rgb, incident.w12, MARBLE, method="relight", tol=0.01)
        assert relit.stats["operators_reused"] == (k > 0)
        error = np.percentile(_per_vertex_error(relit.B, reference), 99)
        assert error < 0.01, f"{kind} light {light}: p99 {error:.2%}"


def test_relit_B_on_a_coarse_mesh_matches_a_direct_solve_within_tol():
    # edges of 30 mm, far over marble's diffusion length: nearly all of B is the near field, where the vertex
    # sum's own pairs and the near triangles' vertex rule cancel to 1e-4 of themselves; held in the far
    # operator's 15 bits and the near one's float32 apart, that cancellation left B 63 % off
    points, triangles = icosphere(3, 160.0)
    mesh, geometry = _surface(points, triangles)
    lit = _lit(mesh, geometry, MARBLE)
    reference = solve(*lit, MARBLE, method="exact").B
    relit = solve(*lit, MARBLE, method="relight", tol=0.01)
    assert np.percentile(_per_vertex_error(relit.B, reference), 99) < 0.01


def test_operators_are_prepared_once_and_a_new_material_replaces_them():
    _, geometry = _surface(*icosphere(3, 10.0))
    lights = [np.array(d, dtype=float) for d in ((0, 0, 1), (1, 0, 0), (0.6, 0.0, -0.8))]
    first = None
    for k, direction in enumerate(lights):
        phi = np.repeat(np.clip(geometry.normals @ direction, 0.0, None)[:, None], 3, axis=1)
        w12 = refract(np.broadcast_to(direction, geometry.normals.shape), geometry.normals, MARBLE.eta)
        relit = solve(geometry, phi, w12, MARBLE, method="relight", tol=0.03)
        assert relit.stats["operators_reused"] == (k > 0)
        assert (relit.timings["prepare"] > 0) == (k == 0)
        first = first or relit
        # a tree solve in between keeps them
        solve(geometry, phi, w12, MARBLE, method="tree", tol=0.03)
    milk = material("skim_milk").medium()
    other = solve(geometry, phi, w12, milk, method="relight", tol=0.03)
    assert not other.stats["operators_reused"]
    assert not solve(geometry, phi, w12, MARBLE, method="relight", tol=0.03).stats["operators_reused"]


def test_operators_over_the_memory_budget_are_refused_before_they_are_made():
    _, geometry = _surface(*icosphere(3, 10.0))
    phi = np.ones((geometry.n_vertices, 3))
    with pytest.raises(BudgetError, match="memory"):
        solve(geometry, phi, -geometry.normals, MARBLE, method="relight", tol=0.01, memory_limit=1e-4)
    assert kept_operator(spatial_order(geometry)[0]) is None


def test_the_plan_of_the_operators_counts_their_peak_above_what_they_hold(monkeypatch):
    from translucency import memory
    from translucency.scatter import relight
    from translucency.scatter.budget import GB
    from translucency.scatter.solve import relight_plan

    monkeypatch.setattr(memory, "available_memory", lambda: None)  # the limit alone decides
    monkeypatch.setattr(memory, "resident_memory", lambda: 0)
    size, counts = 2.0 * GB, {"far_fits": 1e6, "near_entries": 1000}
    between = (1.0 + 0.5 * relight.PEAK_SHARE) * size  # holds the operators, not the preparation's peak
    refused = relight_plan(size, counts, between / GB, None)
    assert not refused.fits and refused.peak_bytes == (1.0 + relight.PEAK_SHARE) * size
    assert relight_plan(size, counts, (1.0 + 2.0 * relight.PEAK_SHARE) * size / GB, None).fits


def test_operators_far_over_the_budget_are_refused_on_a_first_small_count_and_the_others_counted_in_full(monkeypatch):
    from translucency.scatter import crosses, relight

    _, geometry = _surface(*torus(20.0, 8.0, 64, 32))
    ordered = spatial_order(geometry)[0]
    radius = near_radius(ordered, MARBLE)
    sampled = []
    count = crosses.sampled_count
    monkeypatch.setattr(crosses, "sampled_count", lambda *a, blocks: sampled.append(blocks) or count(*a, blocks=blocks))
    size, counts = relight.operator_bytes(ordered, MARBLE, "directional", 0.01, radius)
    assert sampled == [crosses.SAMPLED_BLOCKS]
    asked = []

    def refuse(b, c):
        asked.append((b, c["far_fits"]))
        return False

    # over the budget on the first count, even at FIRST_UNDER of it: that count, and no larger sample
    first, first_counts = relight.operator_bytes(ordered, MARBLE, "directional", 0.01, radius, within=refuse)
    assert sampled[1:] == [relight.FIRST_BLOCKS] and 0.7 * size < first < 1.3 * size
    assert asked == [(relight.FIRST_UNDER * first, relight.FIRST_UNDER * first_counts["far_fits"])]
    # within it: the larger sample decides
    within = relight.operator_bytes(ordered, MARBLE, "directional", 0.01, radius, within=lambda b, c: True)
    assert sampled[2:] == [relight.FIRST_BLOCKS, crosses.SAMPLED_BLOCKS] and within == (size, counts)


@pytest.mark.slow
def test_fresh_operators_check_their_first_light_and_say_when_the_direction_fit_misses_tol():
    from translucency.errors import TranslucencyWarning

    mesh, geometry = _surface(*torus(20.0, 8.0, 48, 24))
    marble = solve(*_lit(mesh, geometry, MARBLE), MARBLE, method="relight", tol=0.01)
    assert 0 < marble.stats["checked_p99"] < 0.01 and marble.timings["check"] > 0
    ketchup = material("ketchup").medium()  # reduced albedo 0.02 in blue: S_d far from affine in w12
    with pytest.warns(TranslucencyWarning, match="relighting operators are .* off a tree solve .* over the tol"):
        kept = solve(*_lit(mesh, geometry, ketchup), ketchup, method="relight", tol=0.01)
    assert "relight_fallback" not in kept.stats  # off, but not so far that tree takes over


def _index_matched_sphere():
    """A 20 mm marble sphere of 642 vertices with an index of refraction of 1 (the refracted directions fill the
    hemisphere, where the fits of S_d to them fail, docs/physics.md §8.7): geometry and medium."""
    from translucency.scatter.medium import Medium

    marble = material("marble").medium()
    medium = Medium(marble.sigma_a, marble.sigma_s, marble.g, 1.0, "index-matched marble")
    points, triangles = icosphere(3, 10.0)
    return SurfaceGeometry(points, triangles, vertex_normals(points, triangles)), medium


def _lit_without_shadows(geometry, medium, light):
    """``phi, w12`` of a unit directional ``light`` on ``geometry`` without shadows."""
    light = np.asarray(light, dtype=float) / np.linalg.norm(light)
    cos = geometry.normals @ light
    phi = np.where(cos > 0.0, fresnel_transmittance(np.clip(cos, 0.0, 1.0), medium.eta) * cos, 0.0)
    w12 = refract(np.broadcast_to(light, geometry.normals.shape), geometry.normals, medium.eta)
    return np.repeat(phi[:, None], 3, axis=1), w12


def test_operators_far_off_their_first_light_give_way_to_tree_and_say_so():
    """Operators whose first light is ten times tol or more off tree are not kept: that light's answer is the
    check's tree solve, every later light is solved by tree (within tol of exact), and one sentence says so."""
    import warnings

    from translucency.errors import TranslucencyWarning

    geometry, medium = _index_matched_sphere()
    for k, light in enumerate([(0.0, 0.0, 1.0), (0.6, 0.0, 0.8)]):
        phi, w12 = _lit_without_shadows(geometry, medium, light)
        if k == 0:
            with pytest.warns(TranslucencyWarning, match=r"off a tree solve .* every light of this surface and mat"):
                relit = solve(geometry, phi, w12, medium, method="relight", tol=0.01)
            assert relit.stats["checked_p99"] >= 0.1 and not relit.stats["operators_reused"]
            assert relit.stats["bytes"] == 0 and relit.stats["pairs_evaluated"] < geometry.n_vertices**2
            held = kept_operator(spatial_order(geometry)[0])
            assert type(held).__name__ == "TreeInstead" and held.nbytes == 0
        else:  # a later light: tree's answer, nothing prepared again, nothing said again
            with warnings.catch_warnings():
                warnings.simplefilter("error", TranslucencyWarning)
                relit = solve(geometry, phi, w12, medium, method="relight", tol=0.01)
            assert relit.stats["operators_reused"]
            tree = solve(geometry, phi, w12, medium, method="tree", tol=0.01).B
            np.testing.assert_allclose(relit.B, tree, rtol=1e-12, atol=0.0)
        assert relit.stats["relight_fallback"] == "tree"
        exact = solve(geometry, phi, w12, medium, method="exact").B
        assert np.percentile(_per_vertex_error(relit.B, exact), 99) <= 0.01


def _crumpled_sphere(crumpled):
    """A 20 mm sphere of 10,242 vertices (edges of about 0.75 mm) lit from above: with ``crumpled``, half of the
    vertices of a patch at its top (drawn at random) have their normals turned by 120 degrees, as on a crumpled
    patch of a scan."""
    points, triangles = icosphere(5, 20.0)
    normals = vertex_normals(points, triangles)
    if crumpled:
        patch = np.flatnonzero(points[:, 2] > 0.995 * 20.0)
        turned = patch[np.random.default_rng(0).uniform(size=patch.size) < 0.5]
        angle = np.radians(120.0)
        turn = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(angle), -np.sin(angle)], [0.0, np.sin(angle), np.cos(angle)]])
        normals[turned] = normals[turned] @ turn.T
    geometry = SurfaceGeometry(points, triangles, normals)
    return geometry, *_lit_without_shadows(geometry, MARBLE, (0.3, 0.2, 1.0))


@pytest.mark.slow
def test_fresh_operators_say_when_a_few_vertices_are_far_off_though_the_percentile_holds():
    """Where neighbouring normals turn against each other (a crumpled patch), the fits of S_d to the refracted
    direction miss a few vertices by tens of percent while the 99th percentile holds: the first light's check
    against tree says how many, in one sentence; a smooth sphere has none."""
    import warnings

    from translucency.errors import TranslucencyWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        smooth = solve(*_crumpled_sphere(False), MARBLE, method="relight", tol=0.01)
    assert smooth.stats["checked_outliers"] == 0 and smooth.stats["checked_p99"] < 0.01
    assert not [w for w in caught if issubclass(w.category, TranslucencyWarning)]
    with pytest.warns(TranslucencyWarning, match=r"up to \d+ % off a tree solve of the first light at \d+ of 10242 "):
        crumpled = solve(*_crumpled_sphere(True), MARBLE, method="relight", tol=0.01)
    assert crumpled.stats["checked_p99"] < 0.01 and crumpled.stats["checked_outliers"] > 0


def _lit(mesh, geometry, medium):
    incident = incident_flux(
        geometry.points,
        geometry.normals,
        geometry.vertex_areas,
        [LIGHTS["directional"]],
        medium.eta,
        triangles=mesh.triangles,
        cache=VisibilityCache(),
    )
    return geometry, incident.phi_rgb, incident.w12


def test_the_near_operator_takes_the_degree3_rule_where_the_solve_does():
    """The near field's operator with the degree-3 rule of shared points on the triangles the solve takes it on
    (``tree``'s near field) relights a light as it does with Dunavant's degree-5 rule there: both integrate the
    same fitted kernel, and the two rules differ by far less than tol on triangles that far away."""
    from translucency.scatter import nearfield
    from translucency.scatter.relight import _apply_rows, _inputs
    from translucency.scatter.solve import NEAR_BETA, degree3_rule

    mesh, geometry = _surface(*torus(20.0, 8.0, 96, 48))  # triangles narrower than the rule's widest (1.98 mm)
    _, phi, w12 = _lit(mesh, geometry, MARBLE)
    n = geometry.n_vertices
    receivers = np.arange(n)
    offsets, ids = nearfield.lists_of(geometry, receivers, near_radius(geometry, MARBLE))
    params = kernels.channel_parameters(MARBLE.sigma_a, MARBLE.sigma_s, MARBLE.g, MARBLE.eta, "directional")
    fit = fits.fit_directions(MARBLE.eta, fits.QUADRATIC_TERMS)
    tables = nearfield.triangle_tables(geometry.points, geometry.triangles)
    common = (geometry.points, geometry.triangles, geometry.triangle_areas, geometry.normals, geometry.vertex_areas)
    degree3 = degree3_rule(MARBLE, "tree")
    shared = sum(
        nearfield.by_degree3(
            tables.diameters[t], tables.centroids[t], geometry.points[r], min(degree3["degree3_ratio"], NEAR_BETA),
            degree3["degree3_diameter"], float(np.min(MARBLE.D)),
        ) and r not in geometry.triangles[t]
        for r in range(0, n, 37) for t in ids[offsets[r] : offsets[r + 1]]
    )  # fmt: skip
    assert shared > 100  # the rule is taken on this surface
    relit = []
    for rule in ({}, degree3):
        starts, columns, coefs = nearfield.near_field_operator(
            0, *common, receivers, offsets, ids, params, NEAR_BETA, float(np.min(MARBLE.D)), fit, tables=tables, **rule
        )
        values = np.empty((n, 3 * fits.QUADRATIC_TERMS))
        lit = np.empty(n, dtype=bool)
        _inputs(geometry.vertex_areas, phi, w12, values, lit)
        B = np.zeros((n, 3))
        rows = starts[:-1].copy()
        _apply_rows(0, 0, n, rows, np.diff(starts), columns.astype(np.int32), rows, coefs, values, lit, B)
        relit.append(B)
    # the near rows alone (their far part is the far field's): a fifth of tol; a rule's weight astray is tens of %
    assert np.percentile(_per_vertex_error(relit[1], relit[0]), 99) < 2e-3
    assert np.abs(relit[1] - relit[0]).max() > 0.0
