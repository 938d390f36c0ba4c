"""``translucency reference`` and :func:`trace_reference`: the file it writes, read back, agrees with the API."""

import numpy as np
import pytest

from translucency.app import cli
from translucency.app.ground_truth import trace_reference, write_reference
from translucency.errors import InvalidParameterError
from translucency.geometry.mesh import TriangleMesh
from translucency.geometry.synthetic import icosphere
from translucency.io.reference_file import REFERENCE_ARRAYS, read_reference_file


@pytest.fixture(scope="module")
def sphere_file(tmp_path_factory):
    import pyvista as pv

    points, triangles = icosphere(2, radius=6.0)
    path = tmp_path_factory.mktemp("scan") / "sphere.ply"
    pv.PolyData(points, np.hstack([np.full((len(triangles), 1), 3), triangles]).ravel()).save(path)
    return path


@pytest.mark.parametrize("suffix", [".npz", ".vtp"])
def test_the_command_writes_what_the_api_computes(sphere_file, tmp_path, suffix, capsys):
    out = tmp_path / f"ref{suffix}"
    args = ["reference", str(sphere_file), "--unit", "mm", "--material", "skimmilk", "--light-dir", "0,0.5,1"]
    assert cli.main([*args, "--spp", "4", "--seed", "3", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "paths per vertex" in printed and f"wrote {out}" in printed
    read = read_reference_file(out)
    mesh = TriangleMesh(read.points, read.triangles)
    api = trace_reference(mesh, "skimmilk", [0, 0.5, 1], spp=4, seed=3)
    for name in REFERENCE_ARRAYS:
        assert getattr(read, name).shape == (len(read.points), 3)
        assert np.allclose(getattr(read, name), getattr(api, name), rtol=1e-12, atol=0)
    assert np.all(read.radiance >= 0) and np.any(read.radiance > 0)
    assert np.all(read.radiance_reentered == 0)  # a convex object
    assert read.metadata["spp"] == 4 and read.metadata["material"] == "skim_milk"
    assert np.allclose(read.metadata["light_direction"], np.array([0, 0.5, 1]) / np.sqrt(1.25))


def test_write_and_read_round_trip_every_array(tmp_path):
    points, triangles = icosphere(1, radius=3.0)
    truth = trace_reference(TriangleMesh(points, triangles), "marble", [0, 0, 1], spp=2)
    for suffix in (".npz", ".vtp"):
        path = write_reference(truth, tmp_path / f"r{suffix}")
        read = read_reference_file(path)
        assert np.array_equal(read.points, truth.mesh.points)
        assert np.array_equal(read.triangles, truth.mesh.triangles)
        assert np.array_equal(read.radiance, truth.radiance)
        assert np.array_equal(read.normals, truth.normals)
        assert read.metadata["eta"] == 1.5


def test_bad_input_is_one_sentence(sphere_file, tmp_path, capsys):
    assert cli.main(["reference", str(sphere_file), "--unit", "mm", "--spp", "1", "-o", str(tmp_path / "r.npz")]) == 2
    assert "--spp" in capsys.readouterr().err
    assert cli.main(["reference", str(sphere_file), "--unit", "mm", "-o", str(tmp_path / "r.ply")]) == 2
    assert ".npz or .vtp" in capsys.readouterr().err
    with pytest.raises(InvalidParameterError, match="translucency reference"):
        read_reference_file(tmp_path / "missing.npz")
    np.savez(tmp_path / "other.npz", a=np.zeros(3))
    with pytest.raises(InvalidParameterError, match="not a reference file"):
        read_reference_file(tmp_path / "other.npz")
