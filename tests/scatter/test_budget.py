"""The solve's memory and time budget: sampled counts against measured ones, blocks that change nothing,
refusal before the work, and progress during the solve."""

import numpy as np
import pytest

from translucency import memory
from translucency.errors import BudgetError, InvalidParameterError
from translucency.geometry.measure import vertex_normals
from translucency.geometry.synthetic import icosphere
from translucency.scatter import budget, fresnel, solve
from translucency.scatter.hierarchy import tree_of
from translucency.scatter.materials import material
from translucency.scatter.surface import ordered_bytes, spatial_order


def _scene(level, radius, name="marble"):
    """An icosphere (mm) lit from +z without shadows: geometry, phi, w12, medium."""
    medium = material(name).medium()
    points, triangles = icosphere(level, radius)
    normals = vertex_normals(points, triangles)
    light = np.array([0.0, 0.3, 1.0]) / np.hypot(0.3, 1.0)
    cos = normals @ light
    phi = np.repeat(np.where(cos > 0, fresnel.fresnel_transmittance(cos, medium.eta) * cos, 0.0)[:, None], 3, axis=1)
    w12 = fresnel.refract(np.broadcast_to(light, normals.shape), normals, medium.eta)
    return solve.SurfaceGeometry(points, triangles, normals), phi, w12, medium


@pytest.mark.parametrize("level, radius, method", [(4, 20.0, "tree"), (5, 20.0, "tree"), (4, 3.0, "cutoff")])
def test_sampled_counts_match_the_counts_of_the_whole_solve(level, radius, method):
    """The counts the budget samples (near triangles, near-field points, far-field evaluations per
    receiver) are within 25 % of what the whole solve counts on every receiver."""
    geometry, phi, w12, medium = _scene(level, radius)
    solution = solve.solve(geometry, phi, w12, medium, method=method, tol=1e-2)
    n = geometry.n_vertices
    stats = solution.stats
    sampled = stats["budget"]["counts"]
    assert sampled["near_triangles"] == pytest.approx(stats["near_triangles"] / n, rel=0.25)
    assert sampled["near_points"] == pytest.approx(stats["near_points"] / n, rel=0.25)
    assert sampled["far_evaluations"] == pytest.approx(stats["pairs_evaluated"] / n, rel=0.25)
    assert stats["budget"]["fits"] and stats["budget"]["keep_lists"]


def test_estimate_is_refused_over_the_time_limit_before_the_work():
    """A time limit below the estimate stops the solve at once with a sentence naming the options."""
    geometry, phi, w12, medium = _scene(3, 20.0)
    calls = []
    with pytest.raises(BudgetError, match=r"resolution=.*time_limit=") as info:
        solve.solve(
            geometry,
            phi,
            w12,
            medium,
            method="tree",
            time_limit=1e-9,
            progress=lambda stage, fraction: calls.append(stage),
        )
    assert info.value.estimate.over_time and not info.value.estimate.fits
    assert calls == []  # refused before the far field started


def test_a_plan_makes_no_near_grid_of_the_whole_surface(monkeypatch):
    """A solve refused by its plan has made no near-field grid of the whole surface (at scan size: GBs), only
    of the triangles around the sampled receivers; and its plan counts the near field."""
    geometry, phi, w12, medium = _scene(7, 20.0)
    from translucency.scatter import nearfield

    grids, near_grid = [], nearfield.near_grid
    monkeypatch.setattr(
        nearfield,
        "near_grid",
        lambda points, triangles, radius: grids.append(len(triangles)) or near_grid(points, triangles, radius),
    )
    with pytest.raises(BudgetError, match="time_limit=") as info:
        solve.solve(geometry, phi, w12, medium, method="tree", tol=1e-2, time_limit=1e-3)
    assert grids and max(grids) < 0.25 * len(geometry.triangles)
    assert info.value.estimate.over_time and info.value.estimate.own_points > 0


def test_the_near_sample_on_the_surface_around_the_sample_counts_as_on_the_whole(monkeypatch):
    """The near field's sample taken on the triangles around the sampled receivers (as at scan size, without
    the whole surface's grid and tables) counts the same near triangles, points and own points, to the bit."""
    geometry, phi, w12, medium = _scene(5, 20.0)
    counts = {}
    for share in (0.0, 1.0):  # 0: always the whole surface; 1: always the part around the sample
        monkeypatch.setattr(solve, "SAMPLE_SURFACE_SHARE", share)
        fresh = solve.SurfaceGeometry(geometry.points, geometry.triangles, geometry.normals)
        counts[share] = solve.solve(fresh, phi, w12, medium, method="tree", tol=1e-2).stats["budget"]["counts"]
    assert counts[0.0]["near_triangles"] > 0 and counts[0.0]["own_points"] > 0
    assert counts[1.0] == counts[0.0]


def test_memory_budget_of_zero_is_refused():
    """No memory left to the solve: refused with the memory sentence (naming memory_limit=)."""
    geometry, phi, w12, medium = _scene(3, 20.0)
    with pytest.raises(BudgetError, match=r"memory_limit=") as info:
        solve.solve(geometry, phi, w12, medium, method="tree", memory_limit=1e-6)
    assert info.value.estimate.over_memory


@pytest.mark.parametrize("value", [0, -1, float("nan"), "a lot", True])
def test_limits_must_be_positive_numbers(value):
    """memory_limit and time_limit that are not positive numbers are refused in one sentence."""
    geometry, phi, w12, medium = _scene(2, 20.0)
    with pytest.raises(InvalidParameterError, match="must be a positive number"):
        solve.solve(geometry, phi, w12, medium, memory_limit=value)
    with pytest.raises(InvalidParameterError, match="must be a positive number"):
        solve.solve(geometry, phi, w12, medium, time_limit=value)


def test_receivers_in_blocks_give_the_same_result_to_the_bit(monkeypatch):
    """When the near lists of every receiver do not fit, receivers go in blocks with their own lists:
    B is identical to the solve that keeps every list."""
    geometry, phi, w12, medium = _scene(4, 8.0, "skim milk")
    whole = solve.solve(geometry, phi, w12, medium, method="tree", tol=1e-2)
    plan = whole.stats["budget"]
    assert plan["keep_lists"]
    # an available memory that leaves room for a few blocks but not for every list
    room = plan["base_bytes"] + plan["far_bytes"] + 0.1 * plan["lists_bytes"] + 64 * plan["receiver_bytes"]
    available = (room + budget.HEADROOM_BYTES) / (1 - budget.HEADROOM_FRACTION) + budget.HEADROOM_BYTES
    monkeypatch.setattr(memory, "available_memory", lambda: room + budget.HEADROOM_BYTES)
    calls = []
    blocked = solve.solve(
        solve.SurfaceGeometry(geometry.points, geometry.triangles, geometry.normals),
        phi,
        w12,
        medium,
        method="tree",
        tol=1e-2,
        progress=lambda stage, f: calls.append((stage, f)),
    )
    assert available > room
    assert not blocked.stats["near_lists_kept"]
    assert blocked.stats["budget"]["block_receivers"] < geometry.n_vertices
    np.testing.assert_array_equal(blocked.B, whole.B)
    assert blocked.stats["near_triangles"] == whole.stats["near_triangles"]
    near = [f for stage, f in calls if stage == "near field" and 0 < f < 1]
    assert len(near) >= 3  # one call per block


def test_progress_is_reported_many_times_during_one_solve():
    """The progress callback moves within the far field and the near field (per block of receivers),
    not only at their ends, and its fractions never go back."""
    geometry, phi, w12, medium = _scene(5, 20.0)  # 10242 receivers: 3 far-field chunks, 5 near-field blocks
    calls = []
    solve.solve(geometry, phi, w12, medium, method="tree", tol=1e-2, progress=lambda stage, f: calls.append((stage, f)))
    for stage in ("far field", "near field"):
        fractions = [f for s, f in calls if s == stage]
        assert len([f for f in fractions if 0 < f < 1]) >= 2
        assert fractions == sorted(fractions) and fractions[0] == 0.0 and fractions[-1] == 1.0


def test_estimate_arithmetic():
    """More near triangles per receiver cost memory and time; a budget below the lists of every receiver
    gives blocks that fit it; the byte and second texts read as expected."""
    counts = budget.SolveCounts(10_000, 20_000, 10_000, 5_000, 3, 2, "tree", 200.0, 400.0, 50.0, 1_000.0)
    small = budget.estimate(counts)
    large = budget.estimate(budget.SolveCounts(*[*counts.__dict__.values()][:7], 20_000.0, 40_000.0, 50.0, 1_000.0))
    assert large.peak_bytes > small.peak_bytes and large.seconds > small.seconds
    cap = small.base_bytes + 0.5 * large.lists_bytes
    blocked = budget.estimate(
        budget.SolveCounts(*[*counts.__dict__.values()][:7], 20_000.0, 40_000.0, 50.0, 1_000.0), cap
    )
    assert not blocked.keep_lists and blocked.fits and blocked.peak_bytes <= cap
    assert budget.memory_budget(4, None, budget.GB) == 3 * budget.GB
    assert budget.memory_budget(None, 10 * budget.GB) == pytest.approx(9 * budget.GB)
    assert budget.memory_budget(None, None) is None
    assert budget.format_bytes(3.2 * budget.GB) == "3.2 GB" and budget.format_seconds(720) == "12 min"


@pytest.mark.parametrize("method", ["exact", "cutoff", "tree"])
def test_the_size_floor_is_below_every_estimate_of_that_size(method):
    """The floor (no near or far work per receiver) never asks more memory or time than the plan with any
    sampled counts, and is over a budget the plan is over only when it is over it itself."""
    rng = np.random.default_rng(3)
    for _ in range(20):
        near, points, own, far = rng.uniform(0, 500, 4)
        counts = budget.SolveCounts(50_000, 100_000, 50_000, 20_000, 3, 2, method, near, points + own, own, far)
        plan = budget.estimate(counts, None, None)
        floor = budget.size_floor(counts)
        assert floor.peak_bytes <= plan.peak_bytes and floor.seconds <= plan.seconds
    floor = budget.size_floor(counts, budget_bytes=0.5 * floor.peak_bytes)
    assert not floor.fits and floor.over_memory


def test_a_refusal_on_the_size_floor_says_it_is_the_least_not_the_plan():
    """The floor counts no near or far work, so a sentence made from it says "at least"; a plan's says "about"."""
    from translucency.app.shading.fallback import budget_phrase

    counts = budget.SolveCounts(50_000, 100_000, 50_000, 20_000, 3, 2, "tree", 100.0, 300.0, 50.0, 1000.0)
    floor, plan = budget.size_floor(counts, None, 1e-9), budget.estimate(counts, None, 1e-9)
    assert "would take at least " in solve.over_budget_sentence(floor, 50_000)
    assert "would take about " in solve.over_budget_sentence(plan, 50_000)
    assert budget_phrase(floor).startswith("would take at least ") and budget_phrase(plan).startswith(
        "would take about "
    )
    small = budget.size_floor(counts, budget_bytes=1.0)
    assert "needs at least " in solve.over_budget_sentence(small, 50_000)


def test_a_size_no_solve_fits_traces_no_light(monkeypatch):
    """Under a time limit that even the set-up of a full solve is over, the pipeline goes for a proxy (or
    says it cannot) without tracing the light for the full mesh first."""
    from translucency.app.shading.scene import Scene
    from translucency.geometry.mesh import TriangleMesh
    from translucency.scatter import irradiance

    points, triangles = icosphere(5, 20.0)
    traced = []
    original = irradiance.incident_flux
    monkeypatch.setattr(irradiance, "incident_flux", lambda p, *a, **k: traced.append(len(p)) or original(p, *a, **k))
    with pytest.raises(BudgetError, match="would take at least"):  # the floor's, not a plan's, seconds
        Scene(TriangleMesh(points, triangles), shadows=False).shade("marble", time_limit=1e-9)
    assert len(points) not in traced


def test_the_budget_is_the_memory_free_before_the_solve_allocates(monkeypatch):
    """The plan counts the solve's own set-up (ordered copy, tree, the sample's grid) in its base, so the
    budget it is held against is what was free before that set-up, not after (which counted it twice)."""
    geometry, phi, w12, medium = _scene(3, 20.0)
    free = {"bytes": 8e9}
    ordered_work = solve._ordered_work

    def allocating(*args, **kwargs):  # the set-up takes 4 GB of what was free
        free["bytes"] = 4e9
        return ordered_work(*args, **kwargs)

    monkeypatch.setattr(solve, "_ordered_work", allocating)
    monkeypatch.setattr(memory, "available_memory", lambda: free["bytes"])
    monkeypatch.setattr(memory, "resident_memory", lambda: 1e9)
    solution = solve.solve(geometry, phi, w12, medium, method="tree", tol=0.01)
    assert solution.stats["budget"]["budget_bytes"] == budget.memory_budget(None, 8e9, 1e9)


def test_a_solve_after_its_plan_has_the_budget_of_the_first(monkeypatch):
    """Where plan() (or an earlier solve) made the ordered copy and the tree already, the process holds them, and
    the solve's plan counts them again: the budget is measured as if they were not held, the same as the first."""
    geometry, phi, w12, medium = _scene(4, 20.0)
    # the operating system's view: what the geometry's ordered copy and tree hold is resident, no longer available
    monkeypatch.setattr(memory, "available_memory", lambda: 8e9 - ordered_bytes(geometry))
    monkeypatch.setattr(memory, "resident_memory", lambda: 1e9 + ordered_bytes(geometry))
    first = solve.plan(geometry, phi, w12, medium, method="tree", tol=0.01, memory_limit=4.0)
    assert ordered_bytes(geometry) > 1e5  # its ordered copy and tree are held now
    after = solve.solve(geometry, phi, w12, medium, method="tree", tol=0.01, memory_limit=4.0).stats["budget"]
    assert after["budget_bytes"] == first.budget_bytes == budget.memory_budget(4.0, 8e9, 1e9)


def test_a_second_solve_has_the_budget_of_the_first(monkeypatch):
    """A viewer's next solve finds the ordered copy and everything cached on it (tree, triangle tables, near grid
    and lists) made; its budget is measured as if they were not held. The operating system's view here is what
    tracemalloc counts as allocated since the start (numpy's arrays included), independent of ordered_bytes()."""
    import gc
    import tracemalloc

    solve.solve(*_scene(3, 20.0), method="tree", tol=0.01)  # compiled code and its caches made before counting
    geometry, phi, w12, medium = _scene(4, 20.0)
    tracemalloc.start()
    try:
        start = tracemalloc.get_traced_memory()[0]
        monkeypatch.setattr(memory, "available_memory", lambda: 8e9 - (tracemalloc.get_traced_memory()[0] - start))
        monkeypatch.setattr(memory, "resident_memory", lambda: 1e9 + (tracemalloc.get_traced_memory()[0] - start))
        first = solve.solve(geometry, phi, w12, medium, method="tree", tol=0.01, memory_limit=4.0).stats["budget"]
        gc.collect()
        held = tracemalloc.get_traced_memory()[0] - start
        second = solve.solve(geometry, phi, w12, medium, method="tree", tol=0.01, memory_limit=4.0).stats["budget"]
    finally:
        tracemalloc.stop()
    assert held > 1e6  # the first solve left its ordered copy and caches behind
    assert abs(second["budget_bytes"] - first["budget_bytes"]) < 0.1 * held


@pytest.mark.parametrize("method", ["tree", "exact"])
def test_plan_is_the_plan_the_solve_makes_and_what_it_makes_the_solve_reuses(method):
    """solve.plan() estimates what solve() estimates before it starts (the same sample, the same counts), without
    solving; the ordered surface and the source tree it made are the ones the solve then uses."""
    geometry, phi, w12, medium = _scene(4, 20.0)
    planned = solve.plan(geometry, phi, w12, medium, method=method, tol=1e-2, time_limit=1e6).as_dict()
    ordered = spatial_order(geometry)[0]
    tree = tree_of(ordered) if method == "tree" else None
    solved = solve.solve(geometry, phi, w12, medium, method=method, tol=1e-2, time_limit=1e6).stats["budget"]
    for key in ("base_bytes", "far_bytes", "receiver_bytes", "own_points", "seconds", "keep_lists", "fits"):
        assert solved[key] == pytest.approx(planned[key], rel=1e-12), key
    assert spatial_order(geometry)[0] is ordered and (tree is None or tree_of(ordered) is tree)
    with pytest.raises(InvalidParameterError, match="relight"):
        solve.plan(geometry, phi, w12, medium, method="relight")


@pytest.mark.parametrize("method", ["exact", "tree"])
def test_the_far_field_on_a_gpu_is_timed_at_its_rate(method):
    """On a GPU the far field's evaluations go at the device's rate, ``tree``'s walk as much slower than ``exact``'s
    pairs as on the CPU (a million receivers, 1,000 evaluations each, nothing else to time)."""
    from dataclasses import replace

    cpu = budget.SolveCounts(0, 0, 1_000_000, 1_000_000, 3, 2, method, 0.0, 0.0, 0.0, 1_000.0)
    gpu = replace(cpu, device="gpu")
    per_pair = {"exact": 1 / 2e10, "tree": 40 / 25 / 2e10}[method]
    assert budget.solve_seconds(gpu) == pytest.approx(1e9 * per_pair, rel=1e-12)
    assert budget.solve_seconds(cpu) == pytest.approx(1e9 / (2 * budget.FAR_RATE[method]), rel=1e-12)
    # 500 near-field points a receiver: on the GPU at the tree's rate there, on the CPU at NEAR_RATE per thread
    near_gpu, near_cpu = (
        replace(gpu, far_evaluations=0.0, near_points=500.0),
        replace(cpu, far_evaluations=0.0, near_points=500.0),
    )
    assert budget.solve_seconds(near_gpu) == pytest.approx(5e8 * 40 / 25 / 2e10, rel=1e-12)
    assert budget.solve_seconds(near_cpu) == pytest.approx(5e8 / (2 * budget.NEAR_RATE), rel=1e-12)
