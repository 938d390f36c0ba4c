"""The budget seen from the commands and the pipeline: over it, a coarser proxy that says so, or one
sentence and exit code 2; ordinary scans untouched."""

import re

import numpy as np
import pytest

from tests.app.test_bake import write_sphere
from translucency.app import cli
from translucency.app.shading.scene import Scene
from translucency.errors import BudgetError
from translucency.geometry.mesh import TriangleMesh
from translucency.geometry.synthetic import icosphere


@pytest.mark.parametrize("command", ["bake", "compare"])
def test_a_tiny_memory_limit_stops_with_one_sentence_and_exit_2(command, tmp_path, capsys):
    """--memory-limit below what the process holds: nothing is solved, one sentence names the options."""
    scan = write_sphere(tmp_path / "sphere.ply", 3)
    code = cli.main([command, str(scan), "--memory-limit", "0.001", "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "--memory-limit" in err and "--resolution" in err and "Traceback" not in err
    sentence = next(line for line in err.splitlines() if "--memory-limit" in line)
    assert sentence.rstrip().endswith(".") and "memory_limit=" not in sentence
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").glob("*.p*"))


def test_a_bad_limit_is_a_usage_sentence(tmp_path, capsys):
    """--time-limit 0 is refused before any work, naming the flag."""
    code = cli.main(["bake", str(write_sphere(tmp_path / "s.ply", 2)), "--time-limit", "0", "-o", str(tmp_path / "o")])
    assert code == 2 and "--time-limit must be a positive number" in capsys.readouterr().err


def test_over_the_time_budget_the_scan_is_solved_on_a_coarser_proxy():
    """A time limit below the full solve's estimate: a proxy that fits is solved instead, interpolated
    to every vertex, and one line says so with the expected error."""
    points, triangles = icosphere(5, 20.0)  # 10242 vertices
    scene = Scene(TriangleMesh(points, triangles), shadows=False)
    full = scene.shade("marble", bounces=0, time_limit=None)
    estimate = full.stats["solver"]["budget"]["seconds"]
    lines = []
    result = scene.shade("marble", bounces=0, time_limit=0.3 * estimate, warn=lines.append)
    assert len(lines) == 1 and "proxy" in lines[0] and "time_limit=" in lines[0] and "RMS" not in lines[0]
    # the per-vertex error of docs/physics.md §8.6's rule: 1.25 * 0.3/mm (marble's rate) * the proxy's edge
    edge = float(re.search(r"\(edge ([0-9.]+) mm\)", lines[0]).group(1))
    expected = float(
        re.search(r"expected up to about ([0-9.]+) % at the 99th percentile of vertices", lines[0]).group(1)
    )
    assert expected == pytest.approx(100 * 1.25 * 0.3007 * edge, rel=0.05)
    assert result.stats["solver_vertices"] < full.stats["solver_vertices"] == 10242
    assert result.stats["solver"]["budget"]["seconds"] <= 0.3 * estimate
    assert result.B.shape == full.B.shape and np.all(np.isfinite(result.B)) and result.B.max() > 0
    # a smooth sphere: the proxy's B stays close to the full solve's
    assert np.sqrt(np.mean((result.B - full.B) ** 2) / np.mean(full.B**2)) < 0.1
    assert result.metadata["budget"]["coarser"] == lines[0] and result.metadata["resolution"].startswith("proxy")


def test_the_resolution_that_did_not_fit_is_freed_before_the_proxy():
    """The full resolution's geometry (and with it its caches) is let go when its solve does not fit: at scan
    size it is most of the memory, and the proxy's decimation needs that memory."""
    import gc
    import weakref

    points, triangles = icosphere(5, 20.0)
    scene = Scene(TriangleMesh(points, triangles), shadows=False)
    full = scene.shade("marble", bounces=0, time_limit=None)
    from translucency.app.shading.settings import resolve_medium

    geometry = weakref.ref(scene.solver_mesh(resolve_medium("marble"))[3])
    scene.shade("marble", bounces=0, time_limit=0.3 * full.stats["solver"]["budget"]["seconds"], warn=lambda line: None)
    gc.collect()
    assert geometry() is None


def test_too_coarse_a_proxy_is_refused_instead():
    """When the proxy that would fit keeps too few vertices, the sentence of the solver is raised."""
    points, triangles = icosphere(3, 20.0)  # 642 vertices: below the fewest a proxy may keep
    with pytest.raises(BudgetError, match="time_limit="):
        Scene(TriangleMesh(points, triangles), shadows=False).shade("marble", bounces=0, time_limit=1e-9)


def test_a_refused_resolution_s_light_is_the_one_its_proxy_gets(monkeypatch):
    """The light traced at every vertex for the resolution asked for is kept when that resolution is refused, and
    carried onto the proxy (a proxy refused in turn traces it again at every vertex, against its own surface): the
    proxy's flux is the full mesh's, in total, and the result's flux is the full mesh's."""
    from translucency.app.shading import resolution
    from translucency.scatter import transport as irradiance

    monkeypatch.setattr(resolution, "CARRIED_LIGHT_MAX_SIGMA_TR_EDGE", np.inf)  # whatever the proxy's edge
    points, triangles = icosphere(5, 20.0)
    mesh = TriangleMesh(points, triangles)
    estimate = Scene(mesh).shade("marble", bounces=0, time_limit=None).stats["solver"]["budget"]["seconds"]
    traced = []
    incident_flux = irradiance.incident_flux

    def counted(points, *args, **kwargs):
        traced.append(len(points))
        return incident_flux(points, *args, **kwargs)

    monkeypatch.setattr(irradiance, "incident_flux", counted)
    carried = []
    carried_light = irradiance.carried_light
    monkeypatch.setattr(
        irradiance,
        "carried_light",
        lambda light, *a: carried.append((light, carried_light(light, *a))) or carried[-1][1],
    )
    lines = []
    result = Scene(mesh).shade("marble", bounces=0, time_limit=0.3 * estimate, warn=lines.append)
    assert result.stats["solver_vertices"] < mesh.n_points
    assert traced[0] == mesh.n_points and set(traced) == {mesh.n_points}  # at every vertex, never on a proxy
    assert "99th percentile of vertices, given the light traced at every vertex" in lines[0]
    assert carried[0][0].stats.scene == "built"  # the first proxy gets the light traced against the full mesh
    for full, proxy_light in carried:
        np.testing.assert_allclose(proxy_light.flux_rgb.sum(axis=0), full.flux_rgb.sum(axis=0), rtol=1e-12)
    np.testing.assert_array_equal(result.incident_flux, carried[-1][0].phi_rgb)
    monkeypatch.setattr(resolution, "CARRIED_LIGHT_MAX_SIGMA_TR_EDGE", 0.0)  # a proxy traces its own light
    traced.clear(), carried.clear()
    result = Scene(mesh).shade("marble", bounces=0, time_limit=0.3 * estimate, warn=lambda line: None)
    assert not carried and traced[0] == mesh.n_points and result.stats["solver_vertices"] in traced[1:]


def test_far_over_its_time_budget_a_scan_is_refused_before_its_shadows_are_traced(monkeypatch):
    """From EARLY_PLAN_VERTICES on, a solve planned with every facing vertex lit and over EARLY_REFUSAL_FACTOR times
    the time limit is refused before any shadow ray, and no Embree scene of the full mesh is built: its proxy's light
    is traced at every vertex against the proxy. On a convex mesh nothing casts a shadow, so that light is the full
    mesh's (no vertex under the proxy's surface shadowed by it) and the answer is the one refused after tracing, to
    the grazing rays."""
    from translucency.app.shading import resolution
    from translucency.app.shading import scene as scene_module
    from translucency.scatter import transport, visibility

    monkeypatch.setattr(resolution, "CARRIED_LIGHT_MAX_SIGMA_TR_EDGE", np.inf)  # whatever the proxy's edge
    points, triangles = icosphere(5, 20.0)
    mesh = TriangleMesh(points, triangles)
    estimate = Scene(mesh).shade("marble", bounces=0, time_limit=None).stats["solver"]["budget"]["seconds"]
    scenes = []
    occluder = visibility.Occluder.__init__
    monkeypatch.setattr(
        visibility.Occluder, "__init__", lambda self, p, *a, **k: scenes.append(len(p)) or occluder(self, p, *a, **k)
    )
    late = Scene(mesh).shade("marble", bounces=0, time_limit=0.3 * estimate, warn=lambda line: None)
    assert scenes[0] == mesh.n_points and late.stats["solver_vertices"] < mesh.n_points
    monkeypatch.setattr(scene_module, "EARLY_PLAN_VERTICES", 0)
    planned = []
    check = transport.check_unshadowed
    monkeypatch.setattr(transport, "check_unshadowed", lambda g, *a: planned.append(g.n_vertices) or check(g, *a))
    scenes.clear()
    early = Scene(mesh).shade("marble", bounces=0, time_limit=0.3 * estimate, warn=lambda line: None)
    assert mesh.n_points not in scenes and early.stats["solver_vertices"] == late.stats["solver_vertices"]
    assert planned == [mesh.n_points]  # the proxy, sized to fit, is not planned twice
    # the same light but where a ray grazes the surface (the flux there is within 1e-2 of nothing: less than 0.6°
    # from the tangent plane): the proxy's chords and the mesh's facets meet such a ray at different places
    differ = np.any(early.incident_flux != late.incident_flux, axis=1)
    assert differ.mean() < 1e-3 and np.all(late.incident_flux[differ] < 1e-2 * late.incident_flux.max())
    # B moves by what those rays bring: a few millionths of the light in all, a few ten-thousandths of B at most
    moved = np.abs(early.incident_flux - late.incident_flux).sum() / late.incident_flux.sum()
    assert moved < 1e-5 and np.abs(early.B - late.B).sum() < 1e-5 * late.B.sum()
    np.testing.assert_allclose(early.B, late.B, rtol=1e-6, atol=1e-3 * late.B.max())
    scenes.clear()
    Scene(mesh).shade(
        "marble", bounces=0, time_limit=0.9 * estimate, warn=lambda line: None
    )  # over, by less than the factor
    assert scenes[0] == mesh.n_points


def test_the_same_solve_asked_again_goes_straight_to_the_proxy(monkeypatch):
    """A Scene remembers that the resolution asked for did not fit these settings and lights: asked again, it
    solves the proxy at once (the same answer and the same line), and says it reused the refusal; another light
    or another limit is planned again at the resolution asked for."""
    from translucency.scatter import transport
    from translucency.scatter.lights import DirectionalLight

    points, triangles = icosphere(5, 20.0)
    mesh = TriangleMesh(points, triangles)
    scene = Scene(mesh, shadows=False)
    limit = 0.3 * scene.shade("marble", bounces=0, time_limit=None).stats["solver"]["budget"]["seconds"]
    tried = []
    carry = transport.transport
    monkeypatch.setattr(
        transport, "transport", lambda geometry, *a, **k: tried.append(geometry.n_vertices) or carry(geometry, *a, **k)
    )
    lines = []
    first = scene.shade("marble", bounces=0, time_limit=limit, warn=lines.append)
    assert tried[0] == mesh.n_points and first.stats["solver_vertices"] < mesh.n_points
    tried.clear()
    again = scene.shade("marble", bounces=0, time_limit=limit, warn=lines.append)
    assert mesh.n_points not in tried and tried  # the proxy only
    np.testing.assert_array_equal(again.B, first.B)
    assert len(lines) == 2 and lines[1] == lines[0]
    assert "the refusal of the resolution asked for" in again.stats["reused"]
    assert "the refusal of the resolution asked for" not in first.stats["reused"]
    tried.clear()
    scene.shade("marble", DirectionalLight([0.0, 1.0, 0.0]), bounces=0, time_limit=limit, warn=lines.append)
    assert tried[0] == mesh.n_points
    tried.clear()
    scene.shade("marble", bounces=0, time_limit=0.9 * limit, warn=lines.append)
    assert tried[0] == mesh.n_points


def test_a_proxy_s_light_shadows_no_vertex_under_the_proxy():
    """On a rough sphere half the vertices lie under the proxy's surface. The light a proxy is given is traced at
    every vertex against the proxy, each ray started off its vertex by the vertex's distance from the proxy, so the
    proxy stops none of them: away from grazing light it is the light traced against the mesh itself."""
    from translucency.app.shading.settings import resolve_medium
    from translucency.scatter.lights import DirectionalLight

    points, triangles = icosphere(4, 20.0)  # 2562 vertices, 1.2 mm edges
    points = points * (1.0 + np.random.default_rng(3).normal(0.0, 0.004, len(points)))[:, None]  # 0.08 mm
    scene = Scene(TriangleMesh(points, triangles))
    medium = resolve_medium("marble")
    lights = [DirectionalLight((0.3, 1.0, 0.5), 1.0)]
    proxy, decimation, _, geometry, _ = scene.solver_mesh(medium, 3.0)
    assert (decimation.mapping.distance > 0.02).mean() > 0.2  # far under or over the proxy, next to the 4 µm offset
    light, _ = scene.light_cache.full_light_for_proxy(geometry, proxy, decimation, lights, medium.eta)
    reference, _ = scene.light_cache.incident_on_mesh(medium, lights)
    facing = reference.phi_rgb[:, 0] > 0.2 * reference.phi_rgb[:, 0].max()  # the relief shadows grazing light only
    assert facing.sum() > 500
    np.testing.assert_array_equal(light.phi_rgb[facing], reference.phi_rgb[facing])


def test_a_proxy_the_budget_forces_is_solved_at_the_tolerance_asked_for(monkeypatch):
    """Only a proxy that resolution "auto" chose holds its far field to the default tolerance (it spends the
    tolerance on its own error); one the budget forced, after "auto" kept every vertex, is solved at the ``tol``
    asked for."""
    from translucency.scatter import transport

    points, triangles = icosphere(5, 20.0)  # 0.75 mm edges: "auto" at 0.3 keeps every vertex in marble
    mesh = TriangleMesh(points, triangles)
    scene = Scene(mesh, shadows=False)
    full = scene.shade("marble", tol=0.3, bounces=0, time_limit=None)
    assert full.stats["solver_vertices"] == mesh.n_points
    tols = []
    carry = transport.transport
    monkeypatch.setattr(
        transport,
        "transport",
        lambda g, light, m, options, **k: tols.append(options.tol) or carry(g, light, m, options, **k),
    )
    limit = 0.3 * full.stats["solver"]["budget"]["seconds"]
    result = scene.shade("marble", tol=0.3, bounces=0, time_limit=limit, warn=lambda line: None)
    assert result.stats["solver_vertices"] < mesh.n_points and len(tols) > 1 and set(tols) == {0.3}


def test_a_proxy_the_budget_forces_is_said_before_its_solve_works():
    """The line naming the proxy comes before the proxy's far field starts, not after the bake's work."""
    points, triangles = icosphere(5, 20.0)
    scene = Scene(TriangleMesh(points, triangles), shadows=False)
    estimate = scene.shade("marble", bounces=0, time_limit=None).stats["solver"]["budget"]["seconds"]
    events = []
    scene.shade(
        "marble",
        bounces=0,
        time_limit=0.3 * estimate,
        warn=lambda line: events.append("said"),
        progress=lambda stage, fraction: events.append(stage),
    )
    assert events.count("said") == 1
    assert events.index("said") < events.index("far field")


def test_a_light_s_bounce_counts_against_the_time_limit():
    """The time limit holds a light's solves together: a limit between one solve's estimate and two is enough for
    the light without a bounce (every vertex) and too little with one (a proxy, said with the light's estimate,
    about twice the solve's); with no proxy possible, the sentence names the bounce."""
    points, triangles = icosphere(5, 20.0)
    mesh = TriangleMesh(points, triangles)
    scene = Scene(mesh, shadows=False)
    solve_seconds = scene.shade("marble", bounces=0, time_limit=None).stats["solver"]["budget"]["seconds"]
    limit = 1.5 * solve_seconds
    alone = scene.shade("marble", bounces=0, time_limit=limit, warn=lambda line: None)
    assert alone.stats["solver_vertices"] == mesh.n_points
    lines = []
    bounced = scene.shade("marble", bounces=1, time_limit=limit, warn=lines.append)
    assert bounced.stats["solver_vertices"] < mesh.n_points and len(lines) == 1
    said = float(re.search(r"would take about ([0-9.]+) s with its bounce \(time_limit=", lines[0]).group(1))
    assert said == pytest.approx(2 * solve_seconds, rel=0.2)  # the plan is sampled again: not to the digit
    small, faces = icosphere(3, 20.0)  # too few vertices for a proxy
    with pytest.raises(BudgetError, match="with its bounce, over the limit"):
        Scene(TriangleMesh(small, faces), shadows=False).shade("marble", bounces=1, time_limit=1e-9)


def test_a_proxy_over_time_fits_what_is_left_after_its_making():
    """The proxy is sized to the time left of the limit once its making is counted (at least LEAST_TIME_SHARE of
    the limit): the more is spent, the coarser the edge, down to that share."""
    from types import SimpleNamespace

    from translucency.app.shading.fallback import (
        COARSER_TIME_EXPONENT,
        LEAST_TIME_SHARE,
        coarser_edge,
        proxy_seconds,
    )

    plan = SimpleNamespace(over_memory=False, over_time=True, time_limit=300.0, seconds=1000.0)
    exc = BudgetError("over", plan)
    edges = [coarser_edge(10**6, 10**6, 0.1, exc, 0, "tree", spent) for spent in (0.0, 100.0, 150.0, 299.0, 1e4)]
    assert edges[0] < edges[1] < edges[2] == edges[3] == edges[4]
    # time as n^k (COARSER_TIME_EXPONENT): the vertices kept, edge^-2, fall as (time left)^(1 / k)
    k = COARSER_TIME_EXPONENT["tree"]
    assert (edges[0] / edges[1]) ** 2 == pytest.approx((200.0 / 300.0) ** (1.0 / k), rel=1e-4)  # vertices rounded
    assert (edges[0] / edges[2]) ** 2 == pytest.approx(LEAST_TIME_SHARE ** (1.0 / k), rel=1e-4)
    assert proxy_seconds(10**7, 4) > 0 and proxy_seconds(10**7, 2) == pytest.approx(2 * proxy_seconds(10**7, 4))
