"""Method ``auto``: ``tree`` for a surface's first lights, relighting's operators once those lights took as long as
preparing them would (docs/physics.md §8.10), never an error where ``tree`` would solve."""

import dataclasses

import numpy as np
import pytest

from translucency.geometry.measure import vertex_normals
from translucency.geometry.synthetic import icosphere
from translucency.scatter import method_choice, relight
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
    return TransportOptions(**{"model": "directional", "method": "auto", "tol": 0.01, "device": "cpu", **changes})


@pytest.fixture
def estimate(monkeypatch):
    """The operators' estimated preparation set to ``estimate.seconds`` (s) and ``estimate.fits``, the rest of the plan
    as the budget makes it; the estimate asked after the first light."""
    from translucency.scatter import solve as solve_module

    class Fixed:
        seconds = 0.0
        fits = True
        asked = 0

    def fixed(*args, **kwargs):
        Fixed.asked += 1
        plan, counts = solve_module.relight_estimate(*args, **kwargs)
        return dataclasses.replace(plan, seconds=Fixed.seconds, fits=Fixed.fits), counts

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
    assert relight.kept_operator(spatial_order(geometry)[0], relight.operator_key(MARBLE, "directional", 0.01, "cpu"))
    assert transport(geometry, _light(geometry, DIRECTIONS[2]), MARBLE, _options()).operators_reused


def test_solve_by_itself_takes_auto_as_tree():
    geometry = _sphere()
    light = _light(geometry, DIRECTIONS[1])
    auto = solve(geometry, light.phi_rgb, light.w12, MARBLE, method="auto", tol=0.01)
    tree = solve(geometry, light.phi_rgb, light.w12, MARBLE, method="tree", tol=0.01)
    np.testing.assert_array_equal(auto.B, tree.B)
    assert auto.settings["method"] == "tree"


def test_tree_lights_add_up_until_the_estimate_and_other_limits_estimate_again(estimate):
    """The tally grows by each tree light's time (the estimate's own time in it); with the preparation estimated at
    longer than the lights take, every light stays with tree; the estimate is asked once per limits."""
    geometry = _sphere()
    estimate.seconds = 1e9
    tallies = [transport(geometry, _light(geometry, d), MARBLE, _options()).method_choice for d in DIRECTIONS[:3]]
    assert [t["tree_lights"] for t in tallies] == [1, 2, 3]
    assert 0 < tallies[0]["tree_seconds"] < tallies[1]["tree_seconds"] < tallies[2]["tree_seconds"]
    assert [t["preparation_estimate_s"] for t in tallies] == [None, 1e9, 1e9]
    assert estimate.asked == 1
    limited = transport(geometry, _light(geometry, DIRECTIONS[3]), MARBLE, _options(memory_limit=16.0))
    assert limited.method == "tree" and estimate.asked == 2


def test_a_dark_light_at_the_switch_prepares_nothing_and_the_next_light_does(estimate):
    geometry = _sphere()
    estimate.seconds = 1e-9
    transport(geometry, _light(geometry, DIRECTIONS[0]), MARBLE, _options())
    lit = _light(geometry, DIRECTIONS[1])
    dark = dataclasses.replace(lit, phi_rgb=np.zeros_like(lit.phi_rgb), flux_rgb=np.zeros_like(lit.flux_rgb))
    carried = transport(geometry, dark, MARBLE, _options())
    assert not carried.B.any() and carried.method_choice["tree_lights"] == 1  # the tally is kept
    assert relight.kept_operator(spatial_order(geometry)[0]) is None
    after = transport(geometry, lit, MARBLE, _options())
    assert after.method == "relight" and not after.operators_reused


def test_a_reflectance_per_vertex_after_operators_were_prepared_is_still_tree(estimate):
    geometry = _sphere()
    estimate.seconds = 1e-9
    for direction in DIRECTIONS[:2]:
        transport(geometry, _light(geometry, direction), MARBLE, _options())
    reflectance = np.full((geometry.n_vertices, 3), 0.5)
    carried = transport(geometry, _light(geometry, DIRECTIONS[2]), MARBLE, _options(), reflectance=reflectance)
    assert carried.method == "tree"
    assert transport(geometry, _light(geometry, DIRECTIONS[3]), MARBLE, _options()).operators_reused


def test_a_light_solved_per_direction_that_prepares_starts_the_other_counts_again(estimate):
    """Its first sample prepares the operators and the others reuse them: still a preparation for the tallies."""
    from translucency.scatter.lights import EnvironmentLight

    geometry = _sphere()
    estimate.seconds = 1e-9
    transport(geometry, _light(geometry, DIRECTIONS[0], POTATO), POTATO, _options())
    transport(geometry, _light(geometry, DIRECTIONS[0]), MARBLE, _options())
    sky = incident_flux(
        geometry.points, geometry.normals, geometry.vertex_areas,
        [EnvironmentLight(radiance_rgb=(0.3, 0.3, 0.3), n_directions=4)], MARBLE.eta, per_direction=True,
    )  # fmt: skip
    carried = transport(geometry, sky, MARBLE, _options(per_direction=True))
    assert carried.method == "relight" and len(carried.solutions) > 1
    again = transport(geometry, _light(geometry, DIRECTIONS[1], POTATO), POTATO, _options())
    assert again.method == "tree" and again.method_choice["tree_lights"] == 1


def test_operators_whose_first_light_misses_tol_give_way_to_tree_for_good(estimate, monkeypatch, recwarn):
    """``auto`` holds tol: operators whose first light's check against ``tree`` finds them ``tol`` or more off (made so
    here) are given up without a warning, that light is the check's ``tree`` answer at ``tol / 4``, every later light
    of the medium is ``tree``, also after another medium's operators were prepared; ``relight`` asked by name prepares
    them again (it keeps them up to 10 tol), and ``auto`` does not use those either."""
    from translucency.scatter import solve as solve_module

    checked, missing = solve_module._relight_error, [True]

    def check(B, reference, tol):
        found = checked(B, reference, tol)
        return {**found, "checked_p99": 2 * tol} if missing[0] else found

    monkeypatch.setattr(solve_module, "_relight_error", check)
    geometry = _sphere()
    estimate.seconds = 1e-9
    transport(geometry, _light(geometry, DIRECTIONS[0]), MARBLE, _options())
    light = _light(geometry, DIRECTIONS[1])
    carried = transport(geometry, light, MARBLE, _options())
    assert carried.method == "tree" and "not under 0.75 of the tolerance" in carried.method_choice["refused"]
    assert carried.method_choice["tree_lights"] == 2  # the light before and this one: the count goes on
    tree = solve(geometry, light.phi_rgb, light.w12, MARBLE, method="tree", tol=0.01 / 4)
    np.testing.assert_array_equal(carried.B, tree.B)
    assert not [w for w in recwarn if "relighting operators" in str(w.message)]
    missing[0] = False
    transport(geometry, _light(geometry, DIRECTIONS[0], POTATO), POTATO, _options())
    assert transport(geometry, _light(geometry, DIRECTIONS[1], POTATO), POTATO, _options()).method == "relight"
    missing[0] = True
    again = transport(geometry, _light(geometry, DIRECTIONS[2]), MARBLE, _options())
    assert again.method == "tree" and again.method_choice["refused"]
    ordered = spatial_order(geometry)[0]
    by_name = transport(geometry, _light(geometry, DIRECTIONS[3]), MARBLE, _options(method="relight"))
    assert by_name.method == "relight" and not by_name.operators_reused
    assert isinstance(relight.kept_operator(ordered), relight.RelightOperator)
    assert [w for w in recwarn if "over the tolerance" in str(w.message)]
    assert transport(geometry, _light(geometry, DIRECTIONS[4]), MARBLE, _options()).method == "tree"


def test_operators_made_by_relight_that_miss_tol_are_not_used_by_auto(monkeypatch, recwarn):
    from translucency.scatter import solve as solve_module

    checked = solve_module._relight_error
    monkeypatch.setattr(
        solve_module, "_relight_error", lambda B, reference, tol: {**checked(B, reference, tol), "checked_p99": 2 * tol}
    )
    geometry = _sphere()
    transport(geometry, _light(geometry, DIRECTIONS[0]), MARBLE, _options(method="relight"))
    carried = transport(geometry, _light(geometry, DIRECTIONS[1]), MARBLE, _options())
    assert carried.method == "tree" and not carried.operators_reused


@pytest.mark.parametrize("share, kept", [(0.5, True), (0.8, False)])
def test_auto_keeps_operators_whose_first_light_holds_tol_with_a_margin(estimate, monkeypatch, share, kept):
    """One light's check does not bound another's: ``auto`` keeps operators only where their first light is under
    AUTO_KEEP_SHARE (0.75) of ``tol`` off ``tree``; at 0.8 of ``tol`` they are given up and the light is ``tree``'s."""
    from translucency.scatter import solve as solve_module

    assert relight.AUTO_KEEP_SHARE == 0.75
    checked = solve_module._relight_error
    monkeypatch.setattr(
        solve_module,
        "_relight_error",
        lambda B, reference, tol: {**checked(B, reference, tol), "checked_p99": share * tol},
    )
    geometry = _sphere()
    estimate.seconds = 1e-9
    transport(geometry, _light(geometry, DIRECTIONS[0]), MARBLE, _options())
    transport(geometry, _light(geometry, DIRECTIONS[1]), MARBLE, _options())  # prepares them
    later = transport(geometry, _light(geometry, DIRECTIONS[2]), MARBLE, _options())
    assert later.method == ("relight" if kept else "tree")
    assert (later.method_choice["refused"] is None) == kept
