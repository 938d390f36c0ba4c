"""``translucency reference`` and :func:`trace_reference`: the file it writes, read back, agrees with the API."""

import numpy as np
import pytest

from translucency.app import cli
from translucency.app.ground_truth import trace_reference, write_reference
from translucency.errors import InvalidParameterError, MeshError
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


def _reference_arrays(n=4):
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=float)[:n]
    radiance = np.full((n, 3), 0.1)
    return {
        "points": points,
        "triangles": np.array([[0, 1, 2], [1, 3, 2]])[: max(0, n - 2)],
        "normals": np.tile([0.0, 0.0, 1.0], (n, 1)),
        "radiance": radiance,
        "radiance_stderr": radiance / 10,
        "radiance_reentered": radiance / 100,
        "metadata": np.array("{}"),
    }


@pytest.mark.parametrize(
    "change, words",
    [
        ({"radiance": np.full((4, 3), np.inf)}, "radiance has infinite, NaN or negative values"),
        ({"radiance": np.full((4, 3), -1.0)}, "radiance has infinite, NaN or negative values"),
        ({"radiance": np.full((4, 3), np.nan)}, "no vertex was traced"),
        ({"radiance_stderr": np.full((3, 3), 0.1)}, r"radiance_stderr has shape \(3, 3\), not \(4, 3\)"),
        ({"triangles": np.array([[0, 1, 7]])}, "triangles are not an"),
        ({"metadata": np.array("not json")}, "settings .metadata. are not a JSON table"),
        ({"metadata": np.array("[1, 2]")}, "settings .metadata. are not a JSON table"),
    ],
)
def test_a_corrupt_reference_is_refused_in_one_sentence(tmp_path, change, words):
    """Corrupt references are refused when read (they used to be compared with exit 0): infinite, negative or
    never-traced radiance, arrays whose rows disagree with the mesh, settings that are not JSON."""
    np.savez(tmp_path / "bad.npz", **{**_reference_arrays(), **change})
    with pytest.raises(MeshError, match=words) as caught:
        read_reference_file(tmp_path / "bad.npz")
    assert "make the reference again" in str(caught.value)


@pytest.mark.parametrize("content", [b"", b"PK\x03\x04 truncated", bytes(range(256)) * 4])
def test_an_npz_that_is_not_an_archive_is_one_sentence_without_library_text(tmp_path, content):
    (tmp_path / "r.npz").write_bytes(content)
    with pytest.raises(MeshError) as caught:
        read_reference_file(tmp_path / "r.npz")
    text = str(caught.value)
    assert "not an .npz archive of arrays" in text
    assert "pickle" not in text and "allow_pickle" not in text and "Error" not in text


def test_a_reference_that_is_a_fifo_is_refused_without_opening_it(fifo):
    with pytest.raises(InvalidParameterError, match=r"is a FIFO \(named pipe\), not a regular file"):
        read_reference_file(fifo("r.npz"))


def test_the_advice_for_an_open_scan_closes_it(shared_meshes, tmp_path, capsys):
    """``reference`` on the open shared angel names the command that closes it, and that command does: the
    reference of its output gets past the check (and stops at the tiny time limit instead)."""
    import re

    angel = shared_meshes / "ggg_angel_sfm.ply"
    assert cli.main(["reference", str(angel), "--spp", "2", "-o", str(tmp_path / "r.npz")]) != 0
    line = capsys.readouterr().err.strip().splitlines()[-1]
    command = re.search(r"'translucency (inspect MESH [^']*)'", line).group(1).split()
    command = [
        str(angel) if word == "MESH" else str(tmp_path / word) if word == "closed.ply" else word for word in command
    ]
    assert cli.main(command) == 0
    capsys.readouterr()
    closed = str(tmp_path / "closed.ply")
    cli.main(["reference", closed, "--spp", "2", "--time-limit", "0.01", "-o", str(tmp_path / "r.npz")])
    err = capsys.readouterr().err
    assert "holes" not in err and "edges with one triangle" not in err
    assert "over the time limit" in err
