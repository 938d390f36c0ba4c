"""The bounce gather (light that leaves the surface and enters again) against view factors and convexity."""

import numpy as np
import pytest

from translucency.errors import InvalidParameterError
from translucency.geometry.measure import barycentric_vertex_areas, triangle_areas, vertex_normals
from translucency.geometry.synthetic import disc, icosphere
from translucency.scatter.bounces import cosine_directions, gather_exitance, specular_reflection
from translucency.scatter.lights import DirectionalLight, EnvironmentLight
from translucency.scatter.names import MAX_BOUNCES, check_bounces
from translucency.scatter.visibility import Occluder


def facing_discs(radius, height, small, rings=24):
    """A small disc (radius ``small``) at z = 0 facing +z, under a large disc (``radius``) at z = ``height``
    facing -z: ``(points, triangles, normals, emitter mask)``."""
    low_points, low_triangles = disc(small, 4)
    high_points, high_triangles = disc(radius, rings)
    high_points[:, 2] = height
    points = np.concatenate([low_points, high_points])
    triangles = np.concatenate([low_triangles, high_triangles[:, ::-1] + len(low_points)])
    normals = np.zeros_like(points)
    normals[: len(low_points), 2] = 1.0
    normals[len(low_points) :, 2] = -1.0
    emitter = np.arange(len(points)) >= len(low_points)
    return points, triangles, normals, emitter


def polygon_view_factor(radius, height, sides):
    """View factor from a point on the axis to a regular polygon (circumradius ``radius``) at ``height``:
    the Lambert polygon formula, F = (1 / 2 pi) sum over edges of the angle they subtend times cos of
    the tilt of their plane (here by symmetry: ``sides`` equal edges)."""
    half = np.pi / sides
    a = radius * np.array([1.0, 0.0, 0.0]) + np.array([0.0, 0.0, height])
    b = radius * np.array([np.cos(2 * half), np.sin(2 * half), 0.0]) + np.array([0.0, 0.0, height])
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    gamma = np.arccos(np.clip(a @ b, -1.0, 1.0))
    plane = np.cross(a, b) / np.linalg.norm(np.cross(a, b))
    return sides * gamma * abs(plane[2]) / (2 * np.pi)


@pytest.mark.parametrize("rays", [16, 64])
def test_gathered_flux_from_a_facing_disc_is_pi_b_times_the_view_factor(rays):
    radius, height, small = 100.0, 60.0, 0.5
    points, triangles, normals, emitter = facing_discs(radius, height, small)
    B = np.where(emitter[:, None], 1.0, 0.0) * np.ones((1, 3))
    occluder = Occluder(points, triangles)
    phi, _, stats = gather_exitance(occluder, points, normals, triangles, B, 1.0, rays=rays)
    receivers = ~emitter
    # the outer ring of the disc is a regular polygon of 6 * rings sides; at eta = 1 no Fresnel loss
    expected = np.pi * polygon_view_factor(radius, height, 6 * 24)
    assert expected == pytest.approx(np.pi * radius**2 / (radius**2 + height**2), rel=1e-3)  # near the circle's
    # each ray brings pi / K or 0: a binomial of p = F over K rays per receiver, receivers independent
    p = expected / np.pi
    sigma = np.pi * np.sqrt(p * (1 - p) / (rays * receivers.sum()))
    got = phi[receivers, 0].mean()
    assert abs(got - expected) < 4 * sigma + 1e-3 * expected
    assert np.all(phi[emitter] == 0.0)  # the emitter faces away from the small disc and from the sky
    assert stats["rays"] == rays * len(points)


def test_gathered_flux_with_fresnel_matches_the_cosine_integral_of_t12_t21():
    from scipy.integrate import quad

    from translucency.scatter.fresnel import fresnel_transmittance

    radius, height, small, eta, rays = 100.0, 60.0, 0.5, 1.4, 64
    points, triangles, normals, emitter = facing_discs(radius, height, small)
    B = np.where(emitter[:, None], 2.0, 0.0) * np.ones((1, 3))
    occluder = Occluder(points, triangles)
    phi, _, _ = gather_exitance(occluder, points, normals, triangles, B, eta, rays=rays)
    # parallel discs: the ray leaves the small disc and meets the large one at the same cosine c, so
    # phi = B * 2 pi * integral over c from cos(edge) to 1 of T(c)^2 c dc (disc of the circle's radius)
    edge = height / np.hypot(radius, height)
    expected = 2.0 * 2 * np.pi * quad(lambda c: fresnel_transmittance(c, eta) ** 2 * c, edge, 1.0)[0]
    got = phi[~emitter, 0].mean()
    # each ray brings a value in [0, 2 pi]: its standard deviation is at most pi
    sigma = np.pi / np.sqrt(rays * np.count_nonzero(~emitter))
    assert abs(got - expected) < 4 * sigma + 2e-3 * expected


def test_a_convex_object_receives_exactly_nothing():
    points, triangles = icosphere(3, radius=20.0)
    normals = vertex_normals(points, triangles)
    areas = barycentric_vertex_areas(triangles, triangle_areas(points, triangles), len(points))
    occluder = Occluder(points, triangles)
    B = np.random.default_rng(1).random((len(points), 3)) + 1.0
    phi, weighted_w12, stats = gather_exitance(occluder, points, normals, triangles, B, 1.3, rays=32)
    assert stats["rays"] == 32 * len(points) and stats["hits"] == 0
    assert np.all(phi == 0.0) and np.all(weighted_w12 == 0.0)
    lights = [DirectionalLight((0.3, 1.0, 0.2), 1.0), EnvironmentLight(1.0, n_directions=16)]
    phi, _, stats = specular_reflection(occluder, points, normals, areas, triangles, lights, 1.3)
    assert stats["hits"] == 0 and np.all(phi == 0.0)
    assert sum(stats["reflected_flux"]) > 0.0  # light was reflected; none of it came back


def test_cosine_directions_are_outward_and_cosine_distributed():
    normals = np.tile([0.0, 0.6, 0.8], (2000, 1))
    w = cosine_directions(normals, 16, np.random.default_rng(0).random((2000, 2))).reshape(-1, 3)
    np.testing.assert_allclose(np.linalg.norm(w, axis=1), 1.0, atol=1e-12)
    cos = w @ normals[0]
    assert cos.min() >= 0.0
    # under pdf cos/pi: E[cos] = 2/3 and E[cos^2] = 1/2
    assert cos.mean() == pytest.approx(2 / 3, abs=3e-3) and (cos**2).mean() == pytest.approx(0.5, abs=3e-3)


def test_specular_reflection_into_a_right_angle_deposits_the_fresnel_share():
    # a floor (normal +z, x from 5 to 45 mm) before a taller wall (the x = 0 plane, normal +x, z up to
    # 80 mm), the light at 45 degrees above the floor beyond it: the floor reflects F_r(c) E c (c = cos 45)
    # along (-1, 0, 1)/sqrt 2, which meets the wall at height x and cosine c, nothing in the way
    from translucency.geometry.synthetic import grid
    from translucency.scatter.fresnel import fresnel_reflectance, fresnel_transmittance

    floor, floor_triangles = grid(40.0, 1.0)
    floor[:, 0] += 25.0
    wall, wall_triangles = grid(80.0, 1.0)
    wall = wall[:, [2, 1, 0]] + [0.0, 0.0, 40.0]
    points = np.concatenate([floor, wall])
    triangles = np.concatenate([floor_triangles, wall_triangles[:, ::-1] + len(floor)])
    on_wall = np.arange(len(points)) >= len(floor)
    normals = np.where(on_wall[:, None], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0])
    areas = barycentric_vertex_areas(triangles, triangle_areas(points, triangles), len(points))
    light = DirectionalLight((1.0, 0.0, 1.0), 1.0)
    phi, _, stats = specular_reflection(Occluder(points, triangles), points, normals, areas, triangles, light, 1.3)
    c = 1 / np.sqrt(2)
    assert stats["reflected_flux"][0] == pytest.approx(fresnel_reflectance(c, 1.3) * c * areas.sum(), rel=1e-12)
    from_floor = fresnel_reflectance(c, 1.3) * c * areas[~on_wall].sum()
    assert (phi[on_wall, 0] * areas[on_wall]).sum() == pytest.approx(
        from_floor * fresnel_transmittance(c, 1.3), rel=1e-9
    )
    assert stats["deposited_flux"][0] == pytest.approx((phi[:, 0] * areas).sum(), rel=1e-12)


@pytest.mark.parametrize("bad", [-1, MAX_BOUNCES + 1, 1.5, True, "2", None])
def test_bad_bounces_are_one_sentence_naming_the_setting(bad):
    with pytest.raises(InvalidParameterError, match="bounces"):
        check_bounces(bad)
    assert check_bounces(np.int64(2)) == 2


def test_one_drawn_light_sample_per_vertex_reflects_the_right_flux_on_average():
    # a plane under a coloured directional light and a coloured point light: each vertex reflects one
    # sample drawn by its share of the reflected flux; the sum over the vertices must match the flux
    # both reflect (F_r c E per light) within four standard deviations of that draw
    from translucency.geometry.synthetic import grid
    from translucency.scatter.fresnel import fresnel_reflectance
    from translucency.scatter.lights import PointLight

    points, triangles = grid(200.0, 2.0)
    normals = np.tile([0.0, 0.0, 1.0], (len(points), 1))
    areas = barycentric_vertex_areas(triangles, triangle_areas(points, triangles), len(points))
    sun = DirectionalLight((0.6, 0.0, 1.0), (1.0, 0.2, 0.05))
    lamp = PointLight((30.0, -20.0, 80.0), (0.002, 0.008, 0.004))
    eta = 1.4
    c_sun = np.full(len(points), sun.direction[2])
    to_lamp = lamp.position_mm - points
    d = np.linalg.norm(to_lamp, axis=1)
    c_lamp = to_lamp[:, 2] / d
    f = np.stack(
        [
            (fresnel_reflectance(c_sun, eta) * c_sun)[:, None] * sun.irradiance_rgb,
            (fresnel_reflectance(c_lamp, eta) * c_lamp)[:, None] * lamp.intensity_rgb / (d[:, None] / 1000.0) ** 2,
        ],
        axis=1,
    )  # (n, 2 samples, 3)
    s = f.sum(axis=2)
    total = s.sum(axis=1)
    expected = (areas[:, None] * f.sum(axis=1)).sum(axis=0)
    second_moment = total[:, None] * (f**2 / s[..., None]).sum(axis=1)
    sigma = np.sqrt((areas[:, None] ** 2 * (second_moment - f.sum(axis=1) ** 2)).sum(axis=0))
    _, _, stats = specular_reflection(Occluder(points, triangles), points, normals, areas, triangles, [sun, lamp], eta)
    assert np.all(sigma > 0) and np.all(np.abs(np.array(stats["reflected_flux"]) - expected) < 4 * sigma)
    assert stats["hits"] == 0  # a plane: every mirror ray escapes
