"""One scan on a Dask cluster: its receivers solved in blocks by the workers, equal to the local solve."""

import numpy as np
import pytest

from translucency.app import cli
from translucency.geometry.mesh import TriangleMesh
from translucency.geometry.synthetic import torus
from translucency.io.baked import read_baked_ply
from translucency.io.polydata import to_pyvista
from translucency.scatter.irradiance import incident_flux
from translucency.scatter.lights import DirectionalLight
from translucency.scatter.materials import material
from translucency.scatter.solve import SurfaceGeometry, solve

distributed = pytest.importorskip("distributed")
pytestmark = pytest.mark.slow  # a cluster of two worker processes takes seconds to start

MARBLE = material("marble").medium()


@pytest.fixture(scope="module")
def cluster():
    """Two worker processes: the surface and the light travel to them as a real cluster's would."""
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None) as running:
        yield running


@pytest.fixture(scope="module")
def lit_torus():
    mesh = TriangleMesh(*torus(20.0, 8.0, 48, 24))  # 1152 vertices, shadows of its own
    geometry = SurfaceGeometry(mesh.points, mesh.triangles, mesh.vertex_normals())
    light = incident_flux(
        geometry.points,
        geometry.normals,
        geometry.vertex_areas,
        [DirectionalLight((0.3, 0.5, 0.8), 1.0)],
        MARBLE.eta,
        triangles=mesh.triangles,
    )
    return geometry, light.phi_rgb, light.w12


@pytest.mark.parametrize("method", ["tree", "exact"])
def test_blocks_on_the_cluster_equal_the_local_solve(cluster, lit_torus, method):
    from translucency.app.shading.distributed import BlockSolver

    geometry, phi, w12 = lit_torus
    local = solve(geometry, phi, w12, MARBLE, method=method, tol=0.01)
    receivers = np.random.default_rng(3).permutation(geometry.n_vertices)[:700]  # any order, not all
    # the tree's groups of receivers are those of a local solve of the same receivers
    local_some = solve(geometry, phi, w12, MARBLE, method=method, tol=0.01, receivers=receivers)
    with distributed.Client(cluster) as client:
        solver = BlockSolver(client, block_receivers=104)  # a multiple of the tree's groups of 8
        spread = solver(geometry, phi, w12, MARBLE, method=method, tol=0.01, receivers=receivers)
        again = solver(geometry, 0.5 * phi, w12, MARBLE, method=method, tol=0.01)  # the surface sent once
    assert spread.stats["blocks"] == 7 and again.stats["blocks"] == 12
    # the same sources and clusters, listed by runs of other groups in another order: tree sums its clusters in
    # float32 (docs/physics.md §8.3), so the order shows at 1e-7
    rtol = 1e-6 if method == "tree" else 1e-12
    np.testing.assert_allclose(spread.B, local_some.B, rtol=rtol, atol=0)
    np.testing.assert_allclose(again.B, 0.5 * local.B, rtol=rtol, atol=0)
    assert spread.stats["pairs_evaluated"] < local.stats["pairs_evaluated"]


def test_bake_of_one_scan_with_a_scheduler_solves_it_on_the_workers(cluster, tmp_path, capsys):
    path = tmp_path / "torus.ply"
    to_pyvista(TriangleMesh(*torus(20.0, 8.0, 48, 24))).save(str(path))
    assert cli.main(["bake", str(path), "-o", str(tmp_path / "here")]) == 0
    assert cli.main(["bake", str(path), "-o", str(tmp_path / "there"), "--scheduler", cluster.scheduler_address]) == 0
    here = read_baked_ply(tmp_path / "here" / "torus_marble.ply")
    there = read_baked_ply(tmp_path / "there" / "torus_marble.ply")
    np.testing.assert_allclose(there.radiance, here.radiance, rtol=1e-6, atol=1e-15)  # tree's float32 sums' order
    assert "blocks on the cluster" in capsys.readouterr().err


def test_a_batch_on_the_cluster_says_its_sentences_as_the_command_line_does(cluster, tmp_path, capsys):
    """Scans baked by the workers tell, in the terminal, the flags of the command line (``--unit``), not the
    Python keywords of the library they run (``unit=``)."""
    paths = []
    for name in ("a", "b"):
        paths.append(tmp_path / f"{name}.ply")
        to_pyvista(TriangleMesh(*torus(20.0, 8.0, 24, 12))).save(str(paths[-1]))
    code = cli.main(["bake", *map(str, paths), "-o", str(tmp_path / "out"), "--scheduler", cluster.scheduler_address])
    err = capsys.readouterr().err
    assert code == 0 and "no --unit given" in err and "unit=" not in err
