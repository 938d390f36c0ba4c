"""Hostile input, by kind: each refusal is one sentence with the right exit code, no library text, and comes
before the work that depends on it; corrupt data is never used in silence; numbers that make the model's answer
meaningless get a warning.
"""

import re
import time
import warnings

import numpy as np
import pytest

from tests.app.test_faults import one_sentence
from translucency.app import cli
from translucency.errors import InvalidParameterError
from translucency.geometry.synthetic import icosphere


def _write(path, points, triangles, colors=None):
    import pyvista as pv

    poly = pv.PolyData(points, np.hstack([np.full((len(triangles), 1), 3), triangles]).ravel())
    if colors is not None:
        poly.point_data["RGB"] = colors
    poly.save(path)
    return path


@pytest.fixture(scope="module")
def small_sphere(tmp_path_factory):
    points, triangles = icosphere(2, radius=6.0)
    return _write(tmp_path_factory.mktemp("scan") / "sphere.ply", points, triangles)


# -------------------------------------------------------------------------------------------------
# options
# -------------------------------------------------------------------------------------------------
def test_a_negative_seed_is_one_sentence_before_any_tracing(small_sphere, tmp_path, capsys):
    code = cli.main(["reference", str(small_sphere), "--unit", "mm", "--seed", "-1", "-o", str(tmp_path / "r.npz")])
    err = capsys.readouterr().err
    assert code == 2
    assert one_sentence(err) == "translucency: error: seed (--seed) must be an integer of at least 0, got -1."


def test_a_reference_into_a_missing_folder_makes_the_folder(small_sphere, tmp_path, capsys):
    """The folder is made when the reference is written, as for bake's outputs (it used to trace everything and
    then fail with exit 1)."""
    out = tmp_path / "missing" / "deeper" / "r.npz"
    assert cli.main(["reference", str(small_sphere), "--unit", "mm", "--spp", "2", "-q", "-o", str(out)]) == 0
    assert out.is_file()


def test_an_spp_over_the_time_limit_is_refused_after_the_first_seconds(small_sphere, tmp_path, capsys):
    """An ``--spp`` whose paths would take hours (and whose queue used to be allocated whole: 1.4 TiB) is
    refused once the first seconds of tracing have told the rate, naming the ``--spp`` that fits."""
    start = time.perf_counter()
    code = cli.main(
        ["reference", str(small_sphere), "--unit", "mm", "--spp", "100000000", "--time-limit", "60", "-q"]
        + ["-o", str(tmp_path / "r.npz")]
    )
    err = capsys.readouterr().err
    assert code != 0 and time.perf_counter() - start < 60
    assert re.fullmatch(
        r"translucency: error: --spp 100000000 would take about .* over the time limit of 60 s; lower --spp to \d+, "
        r"or raise --time-limit\.",
        one_sentence(err),
    )
    assert not (tmp_path / "r.npz").exists()


def test_material_and_its_numbers_together_are_refused(small_sphere, tmp_path, capsys):
    """``--material ketchup --reflectance 0.5 --mfp 1`` used to bake the numbers and drop ``--material`` in
    silence."""
    code = cli.main(
        ["bake", str(small_sphere), "--unit", "mm", "--material", "ketchup", "--reflectance", "0.5", "--mfp", "1"]
        + ["-o", str(tmp_path / "o.ply")]
    )
    assert code == 2
    assert "give --material ketchup or the material's numbers" in one_sentence(capsys.readouterr().err)
    assert not (tmp_path / "o.ply").exists()


@pytest.mark.parametrize("eta, words", [("nan", "eta must be finite"), ("0.5", "must be >= 1")])
def test_a_bad_eta_with_a_look_is_one_sentence_not_a_root_finder_s_error(small_sphere, tmp_path, capsys, eta, words):
    code = cli.main(
        ["bake", str(small_sphere), "--unit", "mm", "--reflectance", "0.5", "--mfp", "1", "--eta", eta]
        + ["-o", str(tmp_path / "o.ply")]
    )
    line = one_sentence(capsys.readouterr().err)
    assert code == 2 and words in line and "solver cannot continue" not in line


# -------------------------------------------------------------------------------------------------
# files: FIFOs wherever a path is read
# -------------------------------------------------------------------------------------------------
def test_a_material_file_that_is_a_fifo_is_refused_without_waiting(small_sphere, tmp_path, capsys, fifo):
    fifo = fifo("jade.json")
    start = time.perf_counter()
    code = cli.main(["bake", str(small_sphere), "--unit", "mm", "--material", str(fifo), "-o", str(tmp_path / "o.ply")])
    assert code == 2 and time.perf_counter() - start < 60
    assert "is a FIFO (named pipe), not a regular file" in one_sentence(capsys.readouterr().err)


# -------------------------------------------------------------------------------------------------
# numerics of the statistics
# -------------------------------------------------------------------------------------------------
def test_compare_on_a_mesh_with_no_lit_vertex_prints_no_nan_and_no_numpy_warning(tmp_path, capsys):
    path = _write(tmp_path / "tri.ply", np.array([[0, 0, 0], [10, 0, 0], [0, 10, 0.0]]), np.array([[0, 1, 2]]))
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        code = cli.main(["compare", str(path), "--unit", "mm", "-q", "-o", str(tmp_path / "out")])
    out = capsys.readouterr().out
    assert code == 0
    assert "no vertex is lit" in out and "nan" not in out


# -------------------------------------------------------------------------------------------------
# the API
# -------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("value", ["2", [2], True])
def test_a_memory_limit_that_is_not_a_number_is_one_sentence(value):
    import translucency as tl

    points, triangles = icosphere(1, radius=6.0)
    with pytest.raises(InvalidParameterError, match="memory_limit= must be a positive number of GB"):
        tl.shade(tl.TriangleMesh(points, triangles), memory_limit=value)
