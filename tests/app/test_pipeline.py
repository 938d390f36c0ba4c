"""The pipeline's Scene: reused work gives the same numbers as fresh work; per-direction summation."""

import numpy as np
import pytest

from translucency.app.shading.scene import Scene, shade
from translucency.app.shading.settings import resolve_medium
from translucency.geometry.mesh import TriangleMesh
from translucency.geometry.synthetic import icosphere
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


def _plinth(up_index=2):
    """A closed stepped solid standing on a wide plinth at its lowest coordinate along ``up_index`` (mm)."""
    import pyvista

    poly = pyvista.Box((-30, 30, -30, 30, 0, 10)).triangulate().merge(pyvista.Box((-8, 8, -8, 8, 10, 90)).triangulate())
    poly = poly.subdivide(2)
    points = np.roll(np.array(poly.points), up_index - 2, axis=1)
    return TriangleMesh(points, np.asarray(poly.faces).reshape(-1, 4)[:, 1:])


def test_default_light_is_above_and_in_front_for_the_up_axis_and_recorded():
    from translucency.app.shading.settings import DEFAULT_LIGHT_DIRECTION, default_light_direction

    np.testing.assert_array_equal(default_light_direction("+y"), DEFAULT_LIGHT_DIRECTION)  # unchanged for +y
    np.testing.assert_allclose(default_light_direction("+z"), (0.35, -0.45, 1.0))  # above: +z, in front: -y
    mesh = _plinth()
    result = Scene(mesh).shade("marble", method="exact")  # up auto: the plinth is at the lowest z
    assert result.metadata["up"] == "+z" and result.metadata["up_inferred"] is True
    light = np.asarray(result.metadata["lights"][0]["direction"])
    np.testing.assert_allclose(light, default_light_direction("+z") / np.linalg.norm(default_light_direction("+z")))
    given = Scene(mesh, up="y").shade("marble", method="exact")
    assert given.metadata["up"] == "+y" and given.metadata["up_inferred"] is False


def test_the_solver_does_not_depend_on_up():
    mesh, light = _plinth(), DirectionalLight((0.2, -0.5, 1.0), 1.0)
    np.testing.assert_array_equal(
        shade(mesh, "marble", light, method="exact", up="y").B, shade(mesh, "marble", light, method="exact", up="-x").B
    )


def test_unit_is_recorded_in_the_metadata():
    mesh = sphere().replace(mm_per_unit=1000.0, unit_inferred=True)
    metadata = shade(mesh, "marble", method="exact").metadata
    source = ("source_unit", "source_unit_name", "source_mm_per_unit", "source_unit_inferred")
    assert tuple(metadata[key] for key in source) == ("m", "metres", 1000.0, True)
    assert metadata["length_unit"] == "mm" and "unit" not in metadata and "mm_per_unit" not in metadata
    assert metadata["radiance_unit"] == "W/(m^2 sr) per W/m^2 of irradiance of the light"


def test_auto_keeps_every_vertex_at_the_default_tolerance_and_a_looser_one_gets_a_proxy_within_it():
    from translucency.app.shading.settings import ShadeSettings
    from translucency.scatter.solve import TOL_FLOOR

    mesh = sphere(5, 8.0)  # 0.30 mm edges: far finer than marble's diffusion length, coarser than 1 % needs
    light = DirectionalLight((0.3, 0.5, 1.0), 1.0)
    scene = Scene(mesh)
    exact = scene.shade("marble", light, method="exact", resolution="full", bounces=0).B
    keep = exact >= TOL_FLOOR * exact.max(axis=0)
    assert scene.shade("marble", light, bounces=0).stats["solver_vertices"] == mesh.n_points  # the default: auto
    for tol in (0.3, 0.6):  # measured: 0.09 and 0.34
        result = scene.shade("marble", light, tol=tol, bounces=0)
        assert result.metadata["resolution"].startswith("proxy") and result.stats["solver_vertices"] < mesh.n_points / 5
        assert np.percentile(np.abs(result.B - exact)[keep] / exact[keep], 99) <= tol
    lines = []  # the proxy it chose is said, with its expected error (1.25 sigma_tr h, h = tol / (1.25 sigma_tr))
    scene.shade_with(ShadeSettings("marble", tol=0.3, bounces=0), light, note=lines.append)
    assert len(lines) == 1 and "which tol=0.3 allows" in lines[0] and "up to about 30 %" in lines[0]


def test_auto_counts_a_light_that_hardly_diffuses_and_exact_keeps_every_vertex():
    from translucency.scatter.definition import varied
    from translucency.scatter.solve import TOL_FLOOR

    mesh = sphere(5, 8.0)
    light = DirectionalLight((0.3, 0.5, 1.0), 1.0)
    scene = Scene(mesh)
    bright = varied(resolve_medium("marble"), "reflectance", 0.99)  # sigma_tr 0.009/mm, mean free path 0.33 mm
    exact = scene.shade(bright, light, method="exact", resolution="full", bounces=0).B
    keep = exact >= TOL_FLOOR * exact.max(axis=0)
    result = scene.shade(bright, light, tol=0.3, bounces=0)  # 0.8 mm, 9 % off; sigma_tr alone allowed 1.66 mm: 31 %
    assert result.stats["solver_vertices"] < mesh.n_points / 4
    assert np.percentile(np.abs(result.B - exact)[keep] / exact[keep], 99) <= 0.3
    # exact has no tolerance: auto takes the default's, every vertex here
    assert scene.shade("marble", light, method="exact", tol=0.6, bounces=0).stats["solver_vertices"] == mesh.n_points


def test_a_tiny_object_gets_a_proxy_it_allows_and_a_given_edge_too_coarse_is_one_sentence():
    import pytest

    from translucency.app.shading.resolution import PROXY_MIN_TRIANGLES
    from translucency.errors import InvalidParameterError, command_line_spelling

    tiny = sphere(4, 0.08)  # 0.16 mm across (a bunny read in the wrong unit): smaller than marble's diffusion length
    result = Scene(tiny).shade("marble", method="exact", resolution="auto")
    assert PROXY_MIN_TRIANGLES / 2 <= result.stats["solver_vertices"] < tiny.n_points
    with command_line_spelling(), pytest.raises(InvalidParameterError) as info:
        Scene(tiny).shade("marble", method="exact", resolution=1.66)
    message = str(info.value)
    assert "--resolution 1.66" in message and "pass --resolution below" in message and "--unit" in message
    assert "target_edge_length" not in message


def test_a_scene_relights_with_operators_it_prepares_once_and_matches_an_exact_solve():
    from translucency.geometry.synthetic import torus

    mesh = TriangleMesh(*torus(20.0, 8.0, 48, 24))  # shadows and bounces of its own
    scene = Scene(mesh)
    first = scene.shade("marble", DirectionalLight((0.3, 0.5, 0.8), 1.0), method="relight", tol=0.01)
    assert "relight operators" not in first.stats["reused"] and first.timings["solve_prepare"] > 0
    light = DirectionalLight((-0.7, 0.2, 0.4), 1.0)
    moved = scene.shade("marble", light, method="relight", tol=0.01)  # the bounce relights with them too
    assert "relight operators" in moved.stats["reused"] and moved.timings["solve_prepare"] == 0
    assert moved.stats["bounces"]["bounces"] == 1
    exact = scene.shade("marble", light, method="exact").B
    keep = exact >= 1e-4 * exact.max(axis=0)
    assert np.percentile(np.abs(moved.B - exact)[keep] / exact[keep], 99) < 0.01


def test_the_default_method_solves_a_scenes_first_light_by_tree_and_relights_once_that_paid(monkeypatch):
    """With the operators' preparation estimated at no time and the estimate asked after one light, a Scene's second
    light (and its bounce) prepares them and its third relights with them; each records the method it used."""
    import dataclasses

    from translucency.geometry.synthetic import torus
    from translucency.scatter import method_choice
    from translucency.scatter import solve as solve_module

    def instant(*args, **kwargs):
        plan, counts = solve_module.relight_estimate(*args, **kwargs)
        return dataclasses.replace(plan, seconds=0.0), counts

    monkeypatch.setattr(method_choice, "relight_estimate", instant)
    monkeypatch.setattr(method_choice, "ESTIMATE_AFTER", 1)
    scene = Scene(TriangleMesh(*torus(20.0, 8.0, 48, 24)))
    lights = [DirectionalLight(d, 1.0) for d in ((0.3, 0.5, 0.8), (-0.7, 0.2, 0.4), (0.1, -0.6, 0.7))]
    results = [scene.shade("marble", light, device="cpu") for light in lights]
    assert [r.metadata["method"] for r in results] == ["auto"] * 3
    assert [r.metadata["method_used"] for r in results] == ["tree", "relight", "relight"]
    assert results[0].stats["method_choice"]["tree_lights"] == 1
    assert "relight operators" in results[2].stats["reused"] and results[2].stats["bounces"]["bounces"] == 1
    exact = scene.shade("marble", lights[2], method="exact").B
    keep = exact >= 1e-4 * exact.max(axis=0)
    assert np.percentile(np.abs(results[2].B - exact)[keep] / exact[keep], 99) < 0.01


def test_a_scan_size_scene_lets_its_embree_scene_go_during_the_solve_and_gives_the_same_answer(monkeypatch):
    """From RELEASE_SCENE_VERTICES on the Embree scene is not held through the solve's set-up: the bounce
    builds it again, and the answer is the one of a scene that kept it."""
    from translucency.app.shading import scene as scene_module
    from translucency.scatter import visibility

    built = []

    class Counted(visibility.Occluder):
        def __init__(self, *args, **kwargs):
            built.append(1)
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(visibility, "Occluder", Counted)
    mesh = sphere()
    kept = Scene(mesh).shade("marble", method="tree", bounces=1)
    assert len(built) == 1  # the incident light's scene, used again by the bounce
    monkeypatch.setattr(scene_module, "RELEASE_SCENE_VERTICES", 0)
    released = Scene(mesh).shade("marble", method="tree", bounces=1)
    assert len(built) == 3  # let go after the incident light, built again for the bounce
    np.testing.assert_array_equal(released.B, kept.B)


def test_the_scene_sums_its_scans_vertex_areas_once(monkeypatch):
    """The full mesh's vertex areas are summed once per Scene: the solver at full resolution and the light traced at
    every vertex take the same (read-only) array."""
    from translucency.geometry import measure
    from translucency.scatter import surface

    summed = []
    real = measure.barycentric_vertex_areas

    def counting(*args):
        summed.append(1)
        return real(*args)

    monkeypatch.setattr(surface, "barycentric_vertex_areas", counting)
    monkeypatch.setattr(measure, "barycentric_vertex_areas", counting)
    mesh = sphere()
    scene = Scene(mesh)
    result = scene.shade("marble", method="tree", bounces=0)
    assert result.stats["solver_vertices"] == mesh.n_points and len(summed) == 1
    geometry = scene.solver_mesh(resolve_medium("marble"), "full")[3]
    np.testing.assert_array_equal(geometry.vertex_areas, mesh.vertex_areas())
    assert not geometry.vertex_areas.flags.writeable


def test_the_scene_measures_its_scans_edges_once(monkeypatch):
    """The mean edge the Scene measures to choose a resolution is the solver's too (7 s at 10M vertices each)."""
    from translucency.geometry.measure import mean_edge_length
    from translucency.scatter import solve, surface
    from translucency.scatter.surface import spatial_order

    measured = []
    monkeypatch.setattr(surface, "mean_edge_length", lambda *args: measured.append(1) or mean_edge_length(*args))
    mesh = sphere()
    result = Scene(mesh).shade("marble", method="tree", bounces=0)
    assert measured == [] and result.stats["solver_vertices"] == mesh.n_points
    given = solve.SurfaceGeometry(mesh.points, mesh.triangles, mesh.vertex_normals(), 1.25)
    assert given.mean_edge_length == 1.25 and spatial_order(given)[0].mean_edge_length == 1.25
    assert solve.SurfaceGeometry(mesh.points, mesh.triangles, mesh.vertex_normals()).mean_edge_length == pytest.approx(
        mean_edge_length(mesh.points, mesh.triangles), rel=1e-15
    )
