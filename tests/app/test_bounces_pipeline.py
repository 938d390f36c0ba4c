"""Bounces in the pipeline: 0 is the single solve bit for bit, 1 only adds light, API and CLI agree."""

import argparse

import numpy as np
import pytest

from translucency.app import options
from translucency.app.shading.scene import Scene, shade, shade_scan
from translucency.app.shading.settings import ShadeSettings
from translucency.errors import InvalidParameterError, TranslucencyError
from translucency.geometry.mesh import TriangleMesh
from translucency.geometry.synthetic import icosphere
from translucency.scatter.lights import DirectionalLight

LIGHT = DirectionalLight((0.2, 1.0, 0.3), 1.0)


def two_spheres():
    """Two spheres 4 mm apart side by side: each sees the other (a concave pair)."""
    a, ta = icosphere(3, radius=10.0, centre=(-12.0, 0.0, 0.0))
    b, tb = icosphere(3, radius=10.0, centre=(12.0, 0.0, 0.0))
    return TriangleMesh(np.concatenate([a, b]), np.concatenate([ta, tb + len(a)]))


def test_no_bounce_is_the_single_solve_bit_for_bit():
    from translucency.scatter.solve import solve

    mesh = two_spheres()
    scene = Scene(mesh)
    result = scene.shade("marble", LIGHT, bounces=0)
    _, _, _, geometry, _ = scene.solver_mesh(result_medium(), "full")
    incident, _ = scene.light_cache.incident(geometry, mesh.triangles, (LIGHT,), result_medium().eta)
    alone = solve(
        geometry, incident.phi_rgb, incident.w12, result_medium(), model="directional", method="tree", tol=0.01
    )
    assert np.array_equal(result.B, alone.B)
    assert result.reentered is None and result.stats["bounces"] == {"bounces": 0}
    assert result.metadata["bounces"] == 0


def result_medium():
    return ShadeSettings().material


def test_one_bounce_only_adds_light_and_says_how_much():
    mesh = two_spheres()
    scene = Scene(mesh)
    none = scene.shade("marble", LIGHT, bounces=0)
    one = scene.shade("marble", LIGHT, bounces=1)
    np.testing.assert_allclose(one.B, none.B + one.reentered, rtol=1e-12, atol=0)
    assert np.all(one.B >= none.B) and np.all(one.reentered >= 0)
    # the faces that look at the other sphere gain most
    facing = np.abs(mesh.points[:, 0]) < 4.0
    assert one.reentered[facing].mean() > 3 * one.reentered[~facing].mean() > 0
    stats = one.stats["bounces"]
    assert stats["bounces"] == 1 and stats["rays"] > 0 and set(stats["seconds"]) == {"gather", "specular", "solve"}
    share = np.array(stats["share_of_B"])
    np.testing.assert_allclose(share, one.reentered.sum(axis=0) / one.B.sum(axis=0), rtol=1e-12)
    assert np.all((share > 0) & (share < 0.5))
    assert one.metadata["bounces"] == 1 and "bounce_gather" in one.timings and "bounce_solve" in one.timings
    assert np.array_equal(one.to_pyvista().point_data["reentered"], one.reentered)
    assert "reentered" not in none.to_pyvista().point_data
    two = scene.shade("marble", LIGHT, bounces=2)
    assert np.all(two.B >= one.B - 1e-12 * one.B.max())


def test_a_convex_object_gets_exactly_no_reentered_light():
    points, triangles = icosphere(3, radius=10.0)
    result = shade(TriangleMesh(points, triangles), "marble", LIGHT, bounces=1)
    assert np.all(result.reentered == 0.0) and result.stats["bounces"]["share_of_B"] == [0.0, 0.0, 0.0]


def parse(*argv):
    parser = argparse.ArgumentParser()
    options.add_solver_options(parser)
    return parser.parse_args(list(argv))


def test_the_command_line_and_the_api_agree():
    mesh = two_spheres()
    settings = options.solver_settings(parse("--bounces", "2"))
    assert settings.bounces == 2 and settings.metadata((LIGHT,), "full")["bounces"] == 2
    from_cli = shade_scan(mesh, settings, LIGHT)
    from_api = shade(mesh, "marble", LIGHT, bounces=2)
    assert np.array_equal(from_cli.B, from_api.B) and from_cli.metadata["bounces"] == 2
    assert options.solver_settings(parse()).bounces == ShadeSettings().bounces


@pytest.mark.parametrize("value", ["-1", "9", "1.5", "many"])
def test_bad_bounces_on_the_command_line_are_one_sentence(value):
    with pytest.raises(TranslucencyError, match="--bounces"):
        options.solver_settings(parse("--bounces", value))


@pytest.mark.parametrize("value", [-1, 9, 1.5, True])
def test_bad_bounces_in_python_are_one_sentence(value):
    with pytest.raises(InvalidParameterError, match="^bounces must be a whole number"):
        ShadeSettings(bounces=value)


def test_a_bake_on_the_command_line_records_and_equals_the_api(tmp_path):
    from translucency.app import cli
    from translucency.io.baked import read_baked_ply
    from translucency.io.polydata import to_pyvista

    scan = tmp_path / "pair.ply"
    to_pyvista(two_spheres()).save(str(scan))
    out = tmp_path / "pair_marble.ply"
    argv = ["bake", str(scan), "-o", str(out), "--unit", "mm", "--light-dir", "0.2,1,0.3", "--bounces", "2", "-q"]
    assert cli.main(argv) == 0
    baked = read_baked_ply(out)
    api = shade_scan(scan, ShadeSettings(bounces=2), LIGHT, unit="mm")
    assert baked.metadata["bounces"] == 2
    np.testing.assert_allclose(baked.b, api.B, rtol=1e-6, atol=1e-7 * api.B.max())  # stored as float32
