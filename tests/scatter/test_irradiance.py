"""Incident flux per vertex: analytic cases, lights add, visibility on/off, cache reuse."""

import numpy as np
import pytest
import trimesh
from scipy.integrate import quad

from translucency.errors import InvalidParameterError
from translucency.scatter.fresnel import fresnel_transmittance, refract
from translucency.scatter.irradiance import carried_light, incident_flux
from translucency.scatter.lights import DirectionalLight, EnvironmentLight, PointLight, cosine_integral_error
from translucency.scatter.visibility import Occluder, VisibilityCache

ETA = 1.3


def grid_plane(half_size=20.0, n=21):
    """A flat square in z = 0 facing +z: points (mm), triangles, normals, vertex areas (mm²)."""
    x = np.linspace(-half_size, half_size, n)
    X, Y = np.meshgrid(x, x, indexing="ij")
    points = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    index = np.arange(n * n).reshape(n, n)
    a, b, c, d = index[:-1, :-1].ravel(), index[1:, :-1].ravel(), index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    triangles = np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return points, triangles, np.tile([0.0, 0.0, 1.0], (len(points), 1)), vertex_areas(points, triangles)


def vertex_areas(points, triangles):
    mesh = trimesh.Trimesh(points, triangles, process=False)
    return np.bincount(triangles.ravel(), weights=np.repeat(mesh.area_faces / 3.0, 3), minlength=len(points))


def icosphere(radius=10.0, subdivisions=3):
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    points, triangles = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    return points, triangles, np.asarray(mesh.vertex_normals), vertex_areas(points, triangles)


def test_flat_plane_lit_at_an_angle_is_exact():
    points, triangles, normals, areas = grid_plane()
    w = np.array([0.6, 0.0, 0.8])
    E = np.array([3.0, 2.0, 1.0])
    for kwargs in ({}, {"triangles": triangles}):  # visibility off and on: a plane cannot shadow itself
        result = incident_flux(points, normals, areas, DirectionalLight(w, E), ETA, **kwargs)
        expected_phi = fresnel_transmittance(0.8, ETA) * 0.8 * E  # T12 E cos(theta)
        assert np.allclose(result.phi_rgb, expected_phi, rtol=1e-14)
        assert np.allclose(result.flux_rgb, areas[:, None] * expected_phi, rtol=1e-14)
        assert np.allclose(result.w12, refract(w, np.array([0.0, 0.0, 1.0]), ETA), atol=1e-14)
        assert np.allclose(result.w12, result.w12_mean, atol=1e-14)  # one light: mean is unit
        assert result.stats.n_lit == len(points) and result.stats.n_shadowed == 0


def test_back_facing_vertices_get_nothing_and_no_ray():
    points, triangles, normals, areas = grid_plane(n=5)
    result = incident_flux(points, normals, areas, DirectionalLight((0, 0.2, -1), 1.0), ETA, triangles=triangles)
    assert np.all(result.flux_rgb == 0) and result.stats.n_rays == 0
    assert result.stats.n_backfacing == len(points) and result.stats.n_lit == 0
    assert np.allclose(result.w12, -normals)  # where nothing enters: the inward normal


def test_point_light_follows_the_inverse_square_law():
    points, triangles, normals, areas = grid_plane()
    light = PointLight((5.0, -3.0, 100.0), (2.0, 1.0, 0.5))  # W/sr, position in mm
    result = incident_flux(points, normals, areas, light, ETA, triangles=triangles)
    to_light = light.position_mm - points
    d = np.linalg.norm(to_light, axis=1)
    cos = to_light[:, 2] / d
    expected = (fresnel_transmittance(cos, ETA) * cos / (d / 1000.0) ** 2)[:, None] * light.intensity_rgb
    assert np.allclose(result.phi_rgb, expected, rtol=1e-12)
    assert np.allclose(result.w12, refract(to_light / d[:, None], normals, ETA), atol=1e-12)


def _hemispherical_T12_cosine(eta):
    """int over the upper hemisphere of T12(cos) cos dw = 2 pi int_0^1 T12(mu) mu dmu."""
    value, _ = quad(lambda mu: float(fresnel_transmittance(mu, eta)) * mu, 0.0, 1.0, epsabs=1e-13)
    return 2.0 * np.pi * value


@pytest.mark.parametrize("eta", [1.0, 1.3])
def test_constant_environment_on_an_open_plane(eta):
    points, _, normals, areas = grid_plane(n=3)
    L = np.array([0.5, 1.0, 2.0])  # W/(m² sr)
    light = EnvironmentLight(L, n_directions=256)
    stated = cosine_integral_error(light.directional_samples())
    result = incident_flux(points, normals, areas, light, eta)
    exact = L * _hemispherical_T12_cosine(eta)  # pi L at eta = 1
    if eta == 1.0:
        assert np.allclose(exact, np.pi * L, rtol=1e-12)
    # The T12 weight is smooth, so the error stays within the stated (cosine) sampling error.
    assert np.allclose(result.phi_rgb, exact, rtol=max(stated, 1e-3) * 1.5)
    # The mean refracted direction of a symmetric sky points straight in.
    assert np.allclose(result.w12, -normals, atol=0.02)
    assert np.all(np.linalg.norm(result.w12_mean, axis=1) < 0.95)  # a spread of directions


def test_several_lights_add():
    points, triangles, normals, areas = icosphere()
    lights = [
        DirectionalLight((0, 0, 1), (1.0, 2.0, 3.0)),
        DirectionalLight((1, 1, 0), 0.5),
        PointLight((0, 40, 10), 2.0),
        EnvironmentLight(0.1, n_directions=32),
    ]
    together = incident_flux(points, normals, areas, lights, ETA, triangles=triangles)
    apart = [incident_flux(points, normals, areas, light, ETA, triangles=triangles) for light in lights]
    assert np.allclose(together.flux_rgb, sum(r.flux_rgb for r in apart), rtol=1e-12)
    weights = [r.phi_rgb.sum(axis=1, keepdims=True) * r.w12_mean for r in apart]
    total = together.phi_rgb.sum(axis=1, keepdims=True)
    assert np.allclose(together.w12_mean * total, sum(weights), atol=1e-12)
    assert np.allclose(np.linalg.norm(together.w12, axis=1), 1.0)
    assert together.stats.n_samples == 3 + 32


def test_convex_mesh_with_and_without_visibility_agree():
    points, triangles, normals, areas = icosphere(subdivisions=4)
    lights = [
        DirectionalLight((0.2, -0.5, 1.0), 2.0),
        PointLight((30, 20, -25), 5.0),
        EnvironmentLight(0.3, n_directions=64),
    ]
    on = incident_flux(points, normals, areas, lights, ETA, triangles=triangles)
    off = incident_flux(points, normals, areas, lights, ETA)
    assert on.stats.n_rays > 0 and on.stats.n_shadowed == 0 and off.stats.scene == "off"
    assert np.array_equal(on.flux_rgb, off.flux_rgb)
    assert np.array_equal(on.w12, off.w12)


def test_sphere_behind_a_box_is_dark_where_shadowed():
    p, t, n, a = icosphere()
    box = trimesh.creation.box(extents=(12.0, 9.0, 4.0))
    box.apply_translation((1.0, -2.0, 30.0))
    points = np.vstack([p, box.vertices])
    triangles = np.vstack([t, np.asarray(box.faces) + len(p)])
    occluder = Occluder(points, triangles)
    result = incident_flux(p, n, a, DirectionalLight((0, 0, 1), 1.0), ETA, occluder=occluder)
    front = n[:, 2] > 0.05  # clearly lit side (the equator has cos ~ 0)
    in_shadow = front & (np.abs(p[:, 0] - 1.0) < 6.0 - 1e-3) & (np.abs(p[:, 1] + 2.0) < 4.5 - 1e-3)
    in_light = front & ((np.abs(p[:, 0] - 1.0) > 6.0 + 1e-3) | (np.abs(p[:, 1] + 2.0) > 4.5 + 1e-3))
    assert in_shadow.sum() > 20 and in_light.sum() > 20
    assert np.all(result.flux_rgb[in_shadow] == 0)
    assert np.all(result.flux_rgb[in_light] > 0)
    assert result.stats.n_shadowed >= in_shadow.sum() and result.stats.scene == "given"


def test_cache_reuses_scene_and_visibility_when_only_the_material_changes():
    points, triangles, normals, areas = icosphere()
    lights = [DirectionalLight((0, 1, 1), 1.0), EnvironmentLight(0.2, n_directions=16)]
    cache = VisibilityCache()
    first = incident_flux(points, normals, areas, lights, 1.3, triangles=triangles, cache=cache)
    second = incident_flux(points, normals, areas, lights, 1.5, triangles=triangles, cache=cache)
    assert first.stats.scene == "built" and first.stats.n_rays > 0 and first.stats.n_visibility_reused == 0
    assert second.stats.scene == "reused" and second.stats.n_rays == 0
    assert second.stats.n_visibility_reused == second.stats.n_samples == 17
    fresh = incident_flux(points, normals, areas, lights, 1.5, triangles=triangles)
    assert np.array_equal(second.flux_rgb, fresh.flux_rgb)
    # Another light direction is not in the cache: its rays are traced.
    third = incident_flux(points, normals, areas, DirectionalLight((1, 0, 0)), 1.5, triangles=triangles, cache=cache)
    assert third.stats.n_rays > 0 and third.stats.scene == "reused"


def test_per_direction_contributions_sum_to_the_aggregate():
    points, _, normals, areas = icosphere()
    lights = [
        DirectionalLight((0, 0, 1), 1.0),
        DirectionalLight((1, 0, 0.2), (0.2, 0.4, 0.9)),
        PointLight((0, 0, -50), 3.0),
    ]
    result = incident_flux(points, normals, areas, lights, ETA, per_direction=True)
    assert len(result.contributions) == 3
    flux = np.zeros_like(result.flux_rgb)
    for c in result.contributions:
        np.add.at(flux, c.vertices, c.flux_rgb)
        assert np.allclose(c.flux_rgb, areas[c.vertices, None] * c.phi_rgb)
    assert np.allclose(flux, result.flux_rgb)
    assert result.contributions[2].direction is None and result.contributions[2].light == 2


def test_degenerate_input_gives_no_nan():
    points, _, normals, areas = grid_plane(n=3)
    normals = normals.copy()
    normals[0] = 0.0  # an isolated vertex without a normal
    areas = areas.copy()
    areas[1] = 0.0
    result = incident_flux(points, normals, areas, [DirectionalLight((0, 0, 1)), PointLight(points[2], 1.0)], ETA)
    for value in (result.phi_rgb, result.flux_rgb, result.w12, result.w12_mean):
        assert np.all(np.isfinite(value))
    assert np.all(result.flux_rgb[0] == 0) and np.all(result.flux_rgb[1] == 0) and np.all(result.phi_rgb[1] > 0)
    assert result.stats.n_degenerate_normals == 1
    assert np.allclose(np.linalg.norm(result.w12, axis=1), 1.0)


def test_float32_input_matches_float64():
    points, triangles, normals, areas = icosphere()
    light = DirectionalLight((0.3, 0.2, 1.0), 1.0)
    a = incident_flux(points, normals, areas, light, ETA)
    b = incident_flux(points.astype(np.float32), normals.astype(np.float32), areas.astype(np.float32), light, ETA)
    assert np.allclose(a.flux_rgb, b.flux_rgb, rtol=1e-5, atol=1e-9)


@pytest.mark.parametrize(
    "change, words",
    [
        ({"points": np.zeros((4, 2))}, r"points must have shape \(n, 3\)"),
        ({"normals": np.zeros((3, 3))}, "normals must have shape"),
        ({"areas": -np.ones(9)}, "areas must be >= 0"),
        ({"areas": np.full(9, np.nan)}, "NaN"),
        ({"eta": 0.8}, "eta = n_inside / n_outside must be"),
        ({"eta": [1.3, 1.4]}, "single number"),
        ({"lights": ["sun"]}, "DirectionalLight, PointLight or EnvironmentLight"),
        ({"occluder": "box"}, "occluder must be an Occluder"),
    ],
)
def test_validation_errors_are_sentences(change, words):
    points, _, normals, areas = grid_plane(n=3)
    args = {"points": points, "normals": normals, "areas": areas, "lights": DirectionalLight((0, 0, 1)), "eta": ETA}
    occluder = change.pop("occluder", None)
    args.update(change)
    with pytest.raises(InvalidParameterError, match=words) as info:
        incident_flux(args["points"], args["normals"], args["areas"], args["lights"], args["eta"], occluder=occluder)
    assert str(info.value).endswith(".")


def test_ray_batching_does_not_change_the_result(monkeypatch):
    from translucency.scatter import irradiance

    points, triangles, normals, areas = icosphere()
    box = trimesh.creation.box(extents=(30.0, 30.0, 2.0))
    box.apply_translation((0.0, 0.0, 25.0))
    occluder = Occluder(np.vstack([points, box.vertices]), np.vstack([triangles, np.asarray(box.faces) + len(points)]))
    lights = [EnvironmentLight(0.5, n_directions=24), PointLight((0, 5, 40), 3.0), DirectionalLight((0, 0, 1))]
    one_call = incident_flux(points, normals, areas, lights, ETA, occluder=occluder)
    monkeypatch.setattr(irradiance, "RAYS_PER_BATCH", 100)
    many_calls = incident_flux(points, normals, areas, lights, ETA, occluder=occluder)
    assert one_call.stats.n_shadowed > 0
    assert np.allclose(one_call.flux_rgb, many_calls.flux_rgb, rtol=1e-14, atol=0)
    assert one_call.stats.as_dict()["n_shadowed"] == many_calls.stats.n_shadowed


def test_carried_light_keeps_the_flux_and_its_direction():
    """A fine mesh's light carried onto a coarse one (each fine vertex shared among coarse vertices with weights summing
    to 1) keeps the flux in total and per coarse vertex as given, the flux-weighted direction, and per sample."""
    points, _, normals, areas = icosphere(10.0, 3)
    lights = [DirectionalLight((0.3, 0.2, 1.0), 1.0), DirectionalLight((-1.0, 0.1, 0.2), 0.5)]
    light = incident_flux(points, normals, areas, lights, 1.3, per_direction=True)
    n = len(points)
    owner = np.arange(n) % 40  # every fine vertex split between two of 40 coarse vertices, 0.7 / 0.3
    partner = (owner + 1) % 40

    def gather(values):
        values = np.asarray(values, dtype=float)
        out = np.zeros((40,) + values.shape[1:])
        np.add.at(out, owner, 0.7 * values)
        np.add.at(out, partner, 0.3 * values)
        return out

    coarse_normals = np.tile((0.0, 0.0, 1.0), (40, 1))
    coarse_areas = np.full(40, areas.sum() / 40)
    coarse = carried_light(light, gather, coarse_normals, coarse_areas)
    np.testing.assert_allclose(coarse.flux_rgb, gather(light.flux_rgb), rtol=1e-12)
    np.testing.assert_allclose(coarse.flux_rgb.sum(axis=0), light.flux_rgb.sum(axis=0), rtol=1e-12)
    np.testing.assert_allclose(coarse.phi_rgb, coarse.flux_rgb / coarse_areas[:, None], rtol=1e-12)
    weight = light.flux_rgb.sum(axis=1)
    expected = gather(weight[:, None] * light.w12_mean) / gather(weight)[:, None]
    np.testing.assert_allclose(coarse.w12_mean, expected, rtol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(coarse.w12, axis=1), 1.0, rtol=1e-12)
    total = np.zeros((40, 3))
    for part, fine in zip(coarse.contributions, light.contributions, strict=True):
        total[part.vertices] += part.flux_rgb
        fine_flux = np.zeros((n, 3))
        fine_flux[fine.vertices] = fine.flux_rgb
        np.testing.assert_allclose(part.flux_rgb, gather(fine_flux)[part.vertices], rtol=1e-12)
        np.testing.assert_allclose(part.phi_rgb, part.flux_rgb / coarse_areas[part.vertices, None], rtol=1e-12)
        fine_w12 = np.zeros((n, 3))
        fine_w12[fine.vertices] = fine.w12 * fine.flux_rgb.sum(axis=1)[:, None]
        direction = gather(fine_w12)[part.vertices]
        np.testing.assert_allclose(part.w12, direction / np.linalg.norm(direction, axis=1)[:, None], rtol=1e-12)
    np.testing.assert_allclose(total, coarse.flux_rgb, rtol=1e-12)
    dark = carried_light(incident_flux(points, normals, areas, [], 1.3), gather, coarse_normals, coarse_areas)
    assert not dark.phi_rgb.any() and np.array_equal(dark.w12, -coarse_normals)
