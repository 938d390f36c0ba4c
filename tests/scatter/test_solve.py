"""The solver: near-field integration, tessellation independence, energy, methods within their tolerance."""

import numpy as np
import pytest

from tests.scatter import pairs
from translucency.errors import InvalidParameterError
from translucency.geometry.measure import vertex_normals
from translucency.geometry.synthetic import disc, grid, icosphere, subdivide
from translucency.scatter import dipoles, fresnel, solve
from translucency.scatter.materials import material
from translucency.scatter.medium import Medium
from translucency.scatter.surface import spatial_order


def _lit(points, triangles, medium, light):
    """phi = T12 cos(theta) for a unit directional light without shadows, and w12 (convex or flat meshes)."""
    normals = vertex_normals(points, triangles)
    cos = normals @ light
    phi = np.where(cos > 0, fresnel.fresnel_transmittance(cos, medium.eta) * cos, 0.0)
    w12 = fresnel.refract(np.broadcast_to(light, normals.shape), normals, medium.eta)
    return normals, np.repeat(phi[:, None], medium.n_channels, axis=1), w12


def _every_pair(code, points, normals, w12, o, j, params):
    """The kernel of model ``code`` at every (receiver ``o``, source ``j``) pair of two index grids: (*o.shape, C)."""

    return pairs.model_pairs(
        code,
        points[j].reshape(-1, 3),
        normals[j].reshape(-1, 3),
        w12[j].reshape(-1, 3),
        points[o].reshape(-1, 3),
        normals[o].reshape(-1, 3),
        params,
    ).reshape(*o.shape, params.shape[0])


def _unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


@pytest.mark.parametrize("spacing", [2.0, 1.0])
def test_flat_plane_matches_the_integral_of_the_model(spacing):
    """On a plane under uniform oblique light B equals phi * integral of S_d over the plane (quadrature of
    the reference formula), to 0.5 %, while a plain vertex sum is off by up to 50x at these spacings."""
    medium = material("ketchup").medium()
    points, triangles = grid(60.0, spacing)
    light = _unit([-np.sin(np.radians(30)), 0, np.cos(np.radians(30))])
    normals = np.tile([0.0, 0.0, 1.0], (len(points), 1))
    w12 = fresnel.refract(np.broadcast_to(light, normals.shape), normals, medium.eta)
    phi = np.ones((len(points), 3))
    centre = np.array([np.argmin(np.linalg.norm(points - [0.3 * spacing, 0.2 * spacing, 0], axis=1))])
    geometry = solve.SurfaceGeometry(points, triangles, normals)
    B = solve.solve(geometry, phi, w12, medium, receivers=centre).B[0]
    norm = 1 / (4 * fresnel.C_phi(1 / medium.eta))
    expected = [
        dipoles.directional_dipole_total_reflectance(medium.sigma_a[c], medium.sigma_s[c], 0.0, medium.eta, 30.0)
        * norm
        / np.pi
        for c in range(3)
    ]
    # red has a 4.8 mm diffusion length: the 60 mm square misses ~0.1 % of the infinite plane
    assert np.allclose(B, expected, rtol=5e-3)
    plain = (phi * geometry.vertex_areas[:, None]).T @ dipoles.directional_dipole(
        points,
        normals,
        w12,
        points[centre[0]],
        normals[centre[0]],
        medium.sigma_a[2],
        medium.sigma_s[2],
        0.0,
        medium.eta,
    )
    assert plain[2] / expected[2] > 3.0  # the point-sampled self term makes the plain sum several times too bright


def test_tessellation_independence():
    """Subdividing (x4 triangles, twice) changes B at the original vertices by less than 1 % (relative RMS)."""
    medium = material("marble").medium()
    light = _unit([0.0, 0.3, 1.0])
    points, triangles = icosphere(3, 10.0)
    originals = np.arange(len(points))
    results = []
    for _ in range(3):
        normals, phi, w12 = _lit(points, triangles, medium, light)
        geometry = solve.SurfaceGeometry(points, triangles, normals)
        results.append(solve.solve(geometry, phi, w12, medium, receivers=originals).B)
        points, triangles = subdivide(points, triangles)
    for finer in results[1:]:
        assert np.linalg.norm(finer - results[0]) / np.linalg.norm(results[0]) < 0.01


def test_energy_of_a_flat_disc_lit_normally():
    """sum_o B_o A_o 4 pi C_phi(1/eta) = total reflectance x sum_j Phi_j (light only near the centre)."""
    medium = material("ketchup").medium()
    points, triangles = disc(60.0, 60)
    normals = np.tile([0.0, 0.0, 1.0], (len(points), 1))
    w12 = np.tile([0.0, 0.0, -1.0], (len(points), 1))
    inside = np.linalg.norm(points, axis=1) < 15.0
    phi = np.repeat(inside[:, None].astype(float), 3, axis=1)
    geometry = solve.SurfaceGeometry(points, triangles, normals)
    solution = solve.solve(geometry, phi, w12, medium, method="tree", tol=1e-4)
    areas = geometry.vertex_areas
    exitance = (solution.B * areas[:, None]).sum(axis=0) * 4 * np.pi * fresnel.C_phi(1 / medium.eta)
    incident = (phi * areas[:, None]).sum(axis=0)
    expected = [
        dipoles.directional_dipole_total_reflectance(medium.sigma_a[c], medium.sigma_s[c], 0.0, medium.eta)
        for c in range(3)
    ]
    assert np.allclose(exitance / incident, expected, rtol=0.02)


@pytest.fixture(scope="module")
def sphere_case():
    medium = material("marble").medium()
    points, triangles = icosphere(4, 10.0)
    normals, phi, w12 = _lit(points, triangles, medium, _unit([0.2, 0.3, 1.0]))
    geometry = solve.SurfaceGeometry(points, triangles, normals)
    exact = solve.solve(geometry, phi, w12, medium, method="exact")
    return geometry, phi, w12, medium, exact


@pytest.mark.parametrize("method", ["tree", "cutoff"])
@pytest.mark.parametrize("tol", [0.1, 0.01, 0.001])
def test_methods_stay_within_their_tolerance(sphere_case, method, tol):
    geometry, phi, w12, medium, exact = sphere_case
    approx = solve.solve(geometry, phi, w12, medium, method=method, tol=tol)
    error = np.linalg.norm(approx.B - exact.B) / np.linalg.norm(exact.B)
    assert error <= tol
    assert approx.stats["pairs_evaluated"] + approx.stats["pairs_skipped"] >= approx.stats["receivers"]


def test_cutoff_skips_pairs_for_a_short_diffusion_length():
    """Ketchup on a 200 mm sphere: its longest diffusion length (red, 1/sigma_tr ~ 5 mm) is short beside
    the object, so most pairs are skipped even at the receivers that need a wider radius than R(tol)."""
    medium = material("ketchup").medium()
    points, triangles = icosphere(4, 100.0)
    normals, phi, w12 = _lit(points, triangles, medium, _unit([0.0, 0.0, 1.0]))
    geometry = solve.SurfaceGeometry(points, triangles, normals)
    exact = solve.solve(geometry, phi, w12, medium, method="exact")
    cut = solve.solve(geometry, phi, w12, medium, method="cutoff", tol=1e-3)
    assert cut.stats["pairs_skipped"] > 0.3 * exact.stats["pairs_evaluated"]
    assert np.linalg.norm(cut.B - exact.B) / np.linalg.norm(exact.B) < 1e-3


@pytest.mark.parametrize("method", ["exact", "tree"])
def test_vertex_and_receiver_order_do_not_matter(method):
    """The solver works on its own spatially ordered copy of the mesh: relabelling the vertices and
    triangles, or asking for the receivers in another order, gives the same B row for row (``tree``:
    to within its tolerance, since the receivers that share a walk of the tree may change)."""
    medium = material("marble").medium()
    points, triangles = icosphere(3, 10.0)
    normals, phi, w12 = _lit(points, triangles, medium, _unit([0.2, 0.3, 1.0]))
    tol = 1e-2
    reference = solve.solve(solve.SurfaceGeometry(points, triangles, normals), phi, w12, medium, method=method, tol=tol)
    rtol = 1e-9 if method == "exact" else tol
    rng = np.random.default_rng(1)
    perm = rng.permutation(len(points))  # new vertex i is old vertex perm[i]
    rank = np.argsort(perm)
    shuffled = solve.SurfaceGeometry(points[perm], rank[triangles][rng.permutation(len(triangles))], normals[perm])
    relabelled = solve.solve(shuffled, phi[perm], w12[perm], medium, method=method, tol=tol)
    scale = np.linalg.norm(reference.B)
    assert np.linalg.norm(relabelled.B - reference.B[perm]) <= rtol * scale
    receivers = rng.permutation(len(points))[:50]
    subset = solve.solve(shuffled, phi[perm], w12[perm], medium, method=method, tol=tol, receivers=receivers)
    assert np.array_equal(subset.receivers, receivers)
    assert np.linalg.norm(subset.B - relabelled.B[receivers]) <= rtol * np.linalg.norm(relabelled.B[receivers])


def test_skips_are_reported_and_identical_channels_computed_once():
    grey = Medium(0.01, 1.0, 0.0, 1.3)  # the three channels are the same
    points, triangles = icosphere(2, 5.0)
    normals, phi, w12 = _lit(points, triangles, grey, _unit([0.0, 0.0, 1.0]))
    geometry = solve.SurfaceGeometry(points, triangles, normals)
    solution = solve.solve(geometry, phi, w12, grey)
    assert solution.stats["channels_computed"] == 1
    assert solution.stats["channels_skipped_identical"] == 2
    assert solution.stats["sources_skipped_no_flux"] == int(np.sum(~np.any(phi > 0, axis=1)))
    assert np.allclose(solution.B[:, 0], solution.B[:, 1]) and np.allclose(solution.B[:, 0], solution.B[:, 2])
    single = solve.solve(geometry, phi[:, :1].repeat(3, 1), w12, grey)
    assert np.array_equal(single.B, solution.B)


def test_models_are_selectable_and_differ():
    medium = material("skim_milk").medium()
    points, triangles = icosphere(3, 10.0)
    normals, phi, w12 = _lit(points, triangles, medium, _unit([1.0, 0.0, 0.3]))
    geometry = solve.SurfaceGeometry(points, triangles, normals)
    results = {m: solve.solve(geometry, phi, w12, medium, model=m).B for m in solve.MODELS}
    for B in results.values():
        assert np.all(np.isfinite(B)) and np.all(B >= 0) and B.max() > 0
    assert not np.allclose(results["directional"], results["standard"], rtol=0.05)
    assert not np.allclose(results["standard"], results["better"], rtol=0.05)


def test_bad_arguments_are_sentences():
    medium = material("marble").medium()
    points, triangles = icosphere(1, 5.0)
    normals, phi, w12 = _lit(points, triangles, medium, _unit([0.0, 0.0, 1.0]))
    geometry = solve.SurfaceGeometry(points, triangles, normals)
    with pytest.raises(InvalidParameterError, match="unknown method"):
        solve.solve(geometry, phi, w12, medium, method="fast")
    with pytest.raises(InvalidParameterError, match="unknown model"):
        solve.solve(geometry, phi, w12, medium, model="photon")
    with pytest.raises(InvalidParameterError, match="tol"):
        solve.solve(geometry, phi, w12, medium, tol=0.0)
    with pytest.raises(InvalidParameterError, match="phi"):
        solve.solve(geometry, -phi, w12, medium)
    with pytest.raises(InvalidParameterError, match="shape"):
        solve.solve(geometry, phi[:, :2], w12, medium)
    with pytest.raises(InvalidParameterError, match="outside"):
        solve.SurfaceGeometry(points, triangles + 1000, normals)


def test_vertex_areas_given_are_the_ones_used_and_checked():
    # the areas a caller holds (the Scene's of the full mesh) stand in for the summed ones: in the caller's order, in
    # the spatially ordered copy the solver works on, and in the solve (the same areas: the same B to the bit; twice
    # the areas: twice each vertex's flux in the vertex sum, so more B wherever light arrives)
    medium = material("marble").medium()
    points, triangles = icosphere(2, 5.0)
    normals, phi, w12 = _lit(points, triangles, medium, _unit([0.0, 0.3, 1.0]))
    summed = solve.SurfaceGeometry(points, triangles, normals)
    doubled = 2.0 * summed.vertex_areas
    given = solve.SurfaceGeometry(points, triangles, normals, vertex_areas_mm2=doubled)
    assert np.array_equal(given.vertex_areas, doubled)
    ordered, order, _ = spatial_order(given)
    assert np.array_equal(ordered.vertex_areas, doubled[order])
    B = solve.solve(summed, phi, w12, medium, method="exact").B
    same = solve.SurfaceGeometry(points, triangles, normals, vertex_areas_mm2=summed.vertex_areas.copy())
    np.testing.assert_array_equal(solve.solve(same, phi, w12, medium, method="exact").B, B)
    more = solve.solve(given, phi, w12, medium, method="exact").B
    assert np.all(more[B > 0] > B[B > 0])
    with pytest.raises(InvalidParameterError, match="vertex_areas_mm2"):
        solve.SurfaceGeometry(points, triangles, normals, vertex_areas_mm2=np.ones(3))


@pytest.mark.parametrize("model", ["directional", "standard"])
def test_cutoff_kernel_is_the_sum_over_pairs_within_the_radius(model):
    from translucency.scatter import cutoff, kernels

    medium = material("ketchup").medium()
    points, triangles = icosphere(3, 15.0)
    normals, phi, w12 = _lit(points, triangles, medium, _unit([0.3, 0.0, 1.0]))
    geometry = solve.SurfaceGeometry(points, triangles, normals)
    flux = phi * geometry.vertex_areas[:, None]
    lit = np.flatnonzero(flux.max(axis=1) > 0)
    radius = 6.0
    grid = cutoff.SourceGrid(points[lit], radius)
    code = kernels.MODELS[model]
    o, j = np.meshgrid(np.arange(len(points)), lit, indexing="ij")
    inside = np.linalg.norm(points[o] - points[j], axis=2) <= radius
    for rows, channel_of in ((3, np.arange(3)), (1, np.zeros(3, dtype=np.int64))):
        params = kernels.channel_parameters(
            medium.sigma_a[:rows], medium.sigma_s[:rows], medium.g[:rows], medium.eta, model
        )
        B, evaluated = cutoff.cutoff_sum(
            code,
            grid.order,
            grid.start,
            grid.origin,
            grid.cell,
            grid.dims,
            radius,
            points[lit],
            normals[lit],
            w12[lit],
            flux[lit],
            points,
            normals,
            params,
            channel_of,
        )
        S = _every_pair(code, points, normals, w12, o, j, params)
        brute = np.einsum("oj,ojc,jc->oc", inside, S[:, :, channel_of], flux[lit])
        assert np.allclose(B, brute, rtol=1e-12, atol=1e-300)
        assert np.array_equal(evaluated, inside.sum(axis=1)) and evaluated.sum() < len(lit) * len(points)


@pytest.mark.parametrize("method", solve.METHODS)
def test_no_light_gives_zero_and_complete_stats(method):
    medium = material("marble").medium()
    points, triangles = icosphere(2, 5.0)
    normals = vertex_normals(points, triangles)
    geometry = solve.SurfaceGeometry(points, triangles, normals)
    solution = solve.solve(geometry, np.zeros((len(points), 3)), -normals, medium, method=method, tol=0.01)
    assert np.array_equal(solution.B, np.zeros((len(points), 3)))
    assert solution.stats["pairs_evaluated"] == 0 and solution.stats["pairs_skipped"] == 0
    assert solution.stats["sources_skipped_no_flux"] == len(points)


def test_local_part_grows_by_exactly_the_sources_between_two_reaches():
    """``reach_mm`` keeps the sources within that distance of each receiver: the near field is the same at
    two reaches, so the difference of the two answers is the vertex sum over the sources between them."""
    from translucency.scatter import kernels

    medium = material("ketchup").medium()
    points, triangles = icosphere(3, 15.0)
    normals, phi, w12 = _lit(points, triangles, medium, _unit([0.3, 0.0, 1.0]))
    geometry = solve.SurfaceGeometry(points, triangles, normals)
    floor = solve.local_reach_floor(geometry, medium, 1e-3)  # solve's own tol
    near, far = floor + 0.5, floor + 6.0
    B_near = solve.solve(geometry, phi, w12, medium, method="cutoff", reach_mm=near).B
    B_far = solve.solve(geometry, phi, w12, medium, method="cutoff", reach_mm=far).B
    flux = phi * geometry.vertex_areas[:, None]
    lit = np.flatnonzero(flux.max(axis=1) > 0)
    o, j = np.meshgrid(np.arange(len(points)), lit, indexing="ij")
    distance = np.linalg.norm(points[o] - points[j], axis=2)
    between = (distance > near) & (distance <= far)
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta, "directional")
    S = _every_pair(kernels.MODELS["directional"], points, normals, w12, o, j, params)
    added = np.einsum("oj,ojc,jc->oc", between, S, flux[lit])
    assert added.max() > 0.03 * B_far.max()  # the band between the reaches matters
    assert np.allclose(B_far - B_near, added, rtol=1e-9, atol=1e-12 * B_far.max())


def test_a_reach_over_the_object_is_the_whole_answer(sphere_case):
    geometry, phi, w12, medium, exact = sphere_case
    whole = solve.solve(geometry, phi, w12, medium, method="cutoff", reach_mm=100.0)
    # the cutoff's near field takes the degree-3 rule on small far triangles (2-4e-4 from degree 5)
    assert np.linalg.norm(whole.B - exact.B) / np.linalg.norm(exact.B) < 1e-3


@pytest.mark.parametrize(
    "kwargs, words",
    [({"method": "tree", "reach_mm": 50.0}, "method='cutoff'"), ({"method": "cutoff", "reach_mm": 0.1}, "at least")],
)
def test_a_reach_the_solve_cannot_honour_is_a_sentence(sphere_case, kwargs, words):
    geometry, phi, w12, medium, _ = sphere_case
    with pytest.raises(InvalidParameterError, match=words):
        solve.solve(geometry, phi, w12, medium, **kwargs)
