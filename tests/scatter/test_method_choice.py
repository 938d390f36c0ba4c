"""Method ``auto``: ``tree`` for a surface's first lights, relighting's operators once those lights took as long as
preparing them would (docs/physics.md §8.10), never an error where ``tree`` would solve."""

import numpy as np
import pytest

from translucency.geometry.measure import vertex_normals
from translucency.geometry.synthetic import icosphere
from translucency.scatter import method_choice, relight
from translucency.scatter.budget import SolveEstimate
from translucency.scatter.irradiance import incident_flux
from translucency.scatter.lights import DirectionalLight
from translucency.scatter.materials import material
from translucency.scatter.solve import SurfaceGeometry, solve
from translucency.scatter.surface import spatial_order
from translucency.scatter.transport import TransportOptions, transport

MARBLE = material("marble").medium()
POTATO = material("potato").medium()


def _sphere():
    points, triangles = icosphere(3, 10.0)  # 642 vertices, 20 mm
    return SurfaceGeometry(points, triangles, vertex_normals(points, triangles))


def _light(geometry, direction, medium=MARBLE):
    """A unit directional light from ``direction`` on ``geometry`` (a sphere: no shadows of its own)."""
    return incident_flux(
        geometry.points, geometry.normals, geometry.vertex_areas, [DirectionalLight(direction, 1.0)], medium.eta
    )


DIRECTIONS = [(0.0, 0.0, 1.0), (0.6, 0.0, 0.8), (0.0, 0.6, 0.8), (-0.6, 0.0, 0.8), (0.0, -0.6, 0.8), (0.3, 0.3, 0.9)]


def _options(**changes) -> TransportOptions:
    return TransportOptions(**{"model": "directional", "method": "auto", "tol": 0.01, **changes})


@pytest.fixture
def estimate(monkeypatch):
    """The operators' estimated preparation set to ``estimate.seconds`` (s) and ``estimate.fits``, the rest of the plan
    as the budget makes it; the estimate asked after the first light."""
    from translucency.scatter import solve as solve_module

    class Fixed:
        seconds = 0.0
        fits = True

    def fixed(*args, **kwargs):
        plan, counts = solve_module.relight_estimate(*args, **kwargs)
        values = {**vars(plan), "seconds": Fixed.seconds, "fits": Fixed.fits}
        return SolveEstimate(**values), counts

    monkeypatch.setattr(method_choice, "relight_estimate", fixed)
    monkeypatch.setattr(method_choice, "ESTIMATE_AFTER", 1)
    return Fixed


def test_the_first_light_is_solved_by_tree_with_trees_answer(estimate):
    geometry = _sphere()
    light = _light(geometry, DIRECTIONS[0])
    carried = transport(geometry, light, MARBLE, _options())
    direct = solve(geometry, light.phi_rgb, light.w12, MARBLE, method="tree", tol=0.01)
    assert carried.method == "tree"
    np.testing.assert_array_equal(carried.B, direct.B)
    assert carried.method_choice["tree_lights"] == 1
    assert relight.kept_operator(spatial_order(geometry)[0]) is None


def test_the_operators_are_prepared_once_the_tree_lights_took_as_long_and_then_reused(estimate):
    """With the preparation estimated at no time, the light after the first (whose tally the estimate waits for)
    prepares the operators, and every later light is relit with them, within tol of ``tree``'s answer."""
    geometry = _sphere()
    estimate.seconds = 1e-9
    methods = []
    for k, direction in enumerate(DIRECTIONS[:4]):
        light = _light(geometry, direction)
        carried = transport(geometry, light, MARBLE, _options())
        methods.append((carried.method, carried.operators_reused))
        if k == 3:
            direct = solve(geometry, light.phi_rgb, light.w12, MARBLE, method="tree", tol=1e-3).B
            keep = direct >= 1e-4 * direct.max(axis=0)
            assert np.percentile(np.abs(carried.B - direct)[keep] / direct[keep], 99) < 0.01
    assert methods == [("tree", False), ("relight", False), ("relight", True), ("relight", True)]


def test_operators_over_the_memory_budget_leave_every_light_to_tree_without_an_error(estimate):
    geometry = _sphere()
    estimate.seconds, estimate.fits = 1e-9, False
    for direction in DIRECTIONS[:3]:
        carried = transport(geometry, _light(geometry, direction), MARBLE, _options())
        assert carried.method == "tree"
    assert carried.method_choice["refused"] is not None
    assert relight.kept_operator(spatial_order(geometry)[0]) is None


def test_a_budget_error_while_preparing_is_solved_by_tree_and_remembered(estimate, monkeypatch):
    """Where the estimate fitted but the preparation's own plan is over the budget (memory taken meanwhile), that
    light is solved by ``tree`` and the operators are not tried again."""
    from translucency.errors import BudgetError
    from translucency.scatter import solve as solve_module

    geometry = _sphere()
    estimate.seconds = 1e-9
    transport(geometry, _light(geometry, DIRECTIONS[0]), MARBLE, _options())

    def over(*args, **kwargs):
        raise BudgetError("over the memory budget.")

    monkeypatch.setattr(solve_module, "relight_operator", over)
    light = _light(geometry, DIRECTIONS[1])
    carried = transport(geometry, light, MARBLE, _options())
    assert carried.method == "tree"
    assert "over the memory budget" in carried.method_choice["refused"]
    tree = solve(geometry, light.phi_rgb, light.w12, MARBLE, method="tree", tol=0.01)
    np.testing.assert_array_equal(carried.B, tree.B)
    assert transport(geometry, _light(geometry, DIRECTIONS[2]), MARBLE, _options()).method == "tree"


def test_a_reflectance_per_vertex_is_always_solved_by_tree(estimate):
    """One medium per reflectance level: their operators would replace each other at every light."""
    geometry = _sphere()
    estimate.seconds = 1e-9
    reflectance = np.full((geometry.n_vertices, 3), 0.5)
    for direction in DIRECTIONS[:3]:
        carried = transport(geometry, _light(geometry, direction), MARBLE, _options(), reflectance=reflectance)
        assert carried.method == "tree"


def test_preparing_one_mediums_operators_starts_the_other_mediums_count_again(estimate):
    """Lights that take turns between marble and potato: marble's operators, once prepared, are not replaced by
    potato's at the next light (its count starts again), so that the two do not prepare at every light."""
    geometry = _sphere()
    estimate.seconds = 1e-9
    transport(geometry, _light(geometry, DIRECTIONS[0], POTATO), POTATO, _options())
    transport(geometry, _light(geometry, DIRECTIONS[0]), MARBLE, _options())
    assert transport(geometry, _light(geometry, DIRECTIONS[1]), MARBLE, _options()).method == "relight"
    again = transport(geometry, _light(geometry, DIRECTIONS[1], POTATO), POTATO, _options())
    assert again.method == "tree" and again.method_choice["tree_lights"] == 1
    assert relight.kept_operator(spatial_order(geometry)[0], relight.operator_key(MARBLE, "directional", 0.01))
    assert transport(geometry, _light(geometry, DIRECTIONS[2]), MARBLE, _options()).operators_reused


def test_solve_by_itself_takes_auto_as_tree():
    geometry = _sphere()
    light = _light(geometry, DIRECTIONS[1])
    auto = solve(geometry, light.phi_rgb, light.w12, MARBLE, method="auto", tol=0.01)
    tree = solve(geometry, light.phi_rgb, light.w12, MARBLE, method="tree", tol=0.01)
    np.testing.assert_array_equal(auto.B, tree.B)
    assert auto.settings["method"] == "tree"
