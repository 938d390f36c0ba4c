"""The pipeline's Scene: reused work gives the same numbers as fresh work; per-direction summation."""

import numpy as np

from tests.synthetic import icosphere
from translucency.app.pipeline import Scene, shade
from translucency.io.mesh import TriangleMesh
from translucency.scatter.lights import DirectionalLight


def sphere(level=3, radius=10.0):
    points, triangles = icosphere(level, radius)
    return TriangleMesh(points, triangles)


def test_a_material_change_traces_no_ray_and_matches_a_fresh_solve():
    mesh = sphere()
    scene = Scene(mesh)
    first = scene.shade("marble", method="exact")
    assert first.stats["incident"]["n_rays"] > 0 and first.stats["reused"] == []
    second = scene.shade("ketchup", method="exact")
    assert second.stats["incident"]["n_rays"] == 0  # visibility came from the cache
    assert "geometry" in second.stats["reused"] and "Embree scene" in second.stats["reused"]
    fresh = shade(mesh, "ketchup", method="exact")
    np.testing.assert_allclose(second.B, fresh.B, rtol=1e-12, atol=0)
    assert not np.allclose(first.B, second.B, rtol=0.1)  # the material did change the answer


def test_a_light_change_reuses_the_geometry_and_matches_a_fresh_solve():
    mesh = sphere()
    scene = Scene(mesh)
    scene.shade("marble", DirectionalLight((0, 0, 1), 1.0), method="tree")
    moved = scene.shade("marble", DirectionalLight((1, 0, 0), 1.0), method="tree")
    assert "geometry" in moved.stats["reused"] and moved.stats["incident"]["n_rays"] > 0
    fresh = shade(mesh, "marble", DirectionalLight((1, 0, 0), 1.0), method="tree")
    np.testing.assert_allclose(moved.B, fresh.B, rtol=1e-12, atol=0)
    # the same light again: nothing about the light is recomputed
    again = scene.shade("marble", DirectionalLight((1, 0, 0), 1.0), method="tree")
    assert "incident light" in again.stats["reused"]


def test_per_direction_summation_is_the_sum_of_single_light_solves():
    mesh = sphere()
    a, b = DirectionalLight((0, 0, 1), 1.0), DirectionalLight((1, 0, 0.2), (0.5, 0.8, 1.0))
    both = shade(mesh, "marble", [a, b], method="exact", per_direction=True)
    single = shade(mesh, "marble", a, method="exact").B + shade(mesh, "marble", b, method="exact").B
    np.testing.assert_allclose(both.B, single, rtol=1e-10, atol=1e-12 * single.max())
    assert both.metadata["light_summation"] == "per direction"
    aggregated = shade(mesh, "marble", [a, b], method="exact")
    # aggregating both lights per vertex approximates only the real-source term: close, not equal
    difference = np.linalg.norm(aggregated.B - single) / np.linalg.norm(single)
    assert 0 < difference < 0.05


def test_a_repeated_proxy_resolution_decimates_once(monkeypatch):
    from translucency.io import decimate

    calls = []
    real = decimate.decimate_mesh
    monkeypatch.setattr(decimate, "decimate_mesh", lambda *a, **k: calls.append(k) or real(*a, **k))
    scene = Scene(sphere(level=5, radius=20.0))  # 0.6 mm edges
    first = scene.shade("marble", DirectionalLight((0, 0, 1), 1.0), method="exact", resolution=3.0)
    moved = scene.shade("ketchup", DirectionalLight((1, 0, 0), 1.0), method="exact", resolution=3.0)
    assert len(calls) == 1 and "geometry" in moved.stats["reused"]
    assert moved.stats["solver_vertices"] == first.stats["solver_vertices"] < scene.mesh.n_points / 4
