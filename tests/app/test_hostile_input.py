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


def _write(path, points, triangles):
    import pyvista as pv

    pv.PolyData(points, np.hstack([np.full((len(triangles), 1), 3), triangles]).ravel()).save(path)
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
        r"translucency: error: --spp 100000000 would take at least .* over the time limit of 60 s; lower --spp to \d+, "
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


# -------------------------------------------------------------------------------------------------
# corrupt data in a scan
# -------------------------------------------------------------------------------------------------
def _coloured_sphere(tmp_path, colors_of):
    """A sphere PLY with float red, green, blue per vertex (0.5, then changed by ``colors_of``)."""
    from plyfile import PlyData, PlyElement

    points, triangles = icosphere(2, radius=6.0)
    colors = np.full((len(points), 3), 0.5)
    colors_of(colors)
    vertex = np.empty(len(points), dtype=[(k, "f4") for k in ("x", "y", "z", "red", "green", "blue")])
    for k, column in zip(("x", "y", "z"), points.T):
        vertex[k] = column
    for k, column in zip(("red", "green", "blue"), colors.T):
        vertex[k] = column
    faces = np.empty(len(triangles), dtype=[("vertex_indices", "i4", (3,))])
    faces["vertex_indices"] = triangles
    path = tmp_path / "coloured.ply"
    PlyData([PlyElement.describe(vertex, "vertex"), PlyElement.describe(faces, "face")]).write(str(path))
    return path


@pytest.mark.parametrize("value", [np.nan, np.inf])
def test_colours_that_are_not_numbers_are_left_out_with_a_warning(tmp_path, capsys, value):
    """A NaN colour was read as black, and one infinite colour made every float colour read on the 0-255 scale
    (every vertex dark). Now the scan's colours are left out with a warning, and an albedo from the colours is
    refused in one sentence."""

    def spoil(colors):
        colors[3] = value

    path = _coloured_sphere(tmp_path, spoil)
    code = cli.main(["bake", str(path), "--unit", "mm", "--albedo-from-colors", "-o", str(tmp_path / "o.ply")])
    err = capsys.readouterr().err
    assert code != 0
    assert "translucency: warning: coloured.ply: 1 of 162 vertex colours are NaN or infinite" in err
    assert "has no vertex colours" in err and "Traceback" not in err


def test_a_few_bright_outliers_do_not_turn_0_to_1_colours_dark(tmp_path):
    from translucency.io.load import load_mesh

    def spoil(colors):
        colors[0] = 7.0  # one vertex over 1 on a 0-1 scan: clipped to white, the others stay mid grey

    mesh = load_mesh(_coloured_sphere(tmp_path, spoil), unit="mm")
    colors = mesh.point_data["colors"]
    assert np.all(colors[1:, :3] == 128) and np.all(colors[0, :3] == 255)


# -------------------------------------------------------------------------------------------------
# library text
# -------------------------------------------------------------------------------------------------
def test_a_corrupt_vtp_reference_is_one_sentence_without_vtk_s_messages(small_sphere, tmp_path, capfd):
    import pyvista as pv

    pv.Sphere().save(tmp_path / "good.vtp")
    data = (tmp_path / "good.vtp").read_bytes()
    (tmp_path / "cut.vtp").write_bytes(data[: len(data) // 2])
    code = cli.main(["compare", "--reference", str(tmp_path / "cut.vtp"), "-o", str(tmp_path / "out")])
    err = capfd.readouterr().err
    assert code == 2
    assert one_sentence(err) == (
        "translucency: error: cannot read cut.vtp as VTK PolyData; is it a .vtp written by 'translucency reference'?"
    )
    assert "vtk" not in err.replace(".vtp", "").replace("VTK PolyData", "").lower()


@pytest.mark.parametrize(
    "flag, words", [("---o", "unknown option ---o (did you mean -o?)"), ("--tool", "(did you mean --tol?)")]
)
def test_a_misspelt_option_names_the_nearest_one(small_sphere, tmp_path, capsys, flag, words):
    with pytest.raises(SystemExit) as stopped:
        cli.main(["bake", str(small_sphere), flag, "0.1"])
    assert stopped.value.code == 2
    assert words in capsys.readouterr().err


def test_a_mesh_of_another_format_names_the_renaming_not_python_keywords(tmp_path, small_sphere, capsys):
    misnamed = tmp_path / "sphere.abc"
    misnamed.write_bytes(small_sphere.read_bytes())
    assert cli.main(["bake", str(misnamed), "--unit", "mm", "-o", str(tmp_path / "o.ply")]) != 0
    out = capsys.readouterr().out
    assert "rename it to sphere.ply" in out
    assert "format=" not in out and "SUPPORTED_FORMATS" not in out


# -------------------------------------------------------------------------------------------------
# numbers where the model's answer means nothing
# -------------------------------------------------------------------------------------------------
def test_coefficients_beyond_any_material_are_refused_before_the_solve():
    from translucency.scatter.medium import Medium

    with pytest.raises(InvalidParameterError, match=r"sigma_s = 1e\+300/mm is beyond any material.*at most 1e12\."):
        Medium([1e-3] * 3, [1e300] * 3, [0.0] * 3, 1.3, "absurd")


def test_a_nearly_transparent_medium_warns_that_the_answer_means_little():
    import translucency as tl
    from translucency.errors import TranslucencyWarning

    points, triangles = icosphere(2, radius=6.0)
    medium = tl.Medium([0.0] * 3, [1e-9] * 3, [0.0] * 3, 1.3, "clear")
    with pytest.warns(TranslucencyWarning, match=r"clear: a mean free path longer than the object"):
        tl.shade(tl.TriangleMesh(points, triangles), medium, bounces=0)


def test_a_point_light_on_the_surface_warns(tmp_path):
    import translucency as tl
    from translucency.errors import TranslucencyWarning

    points, triangles = icosphere(2, radius=6.0)
    on_surface = tl.PointLight(points[0] * (1 + 1e-12), 1.0)
    with pytest.warns(TranslucencyWarning, match=r"a point light at .* mm from the surface, nearer than its vertex"):
        tl.shade(tl.TriangleMesh(points, triangles), "marble", lights=[on_surface], bounces=0)


# -------------------------------------------------------------------------------------------------
# invariants of a long solve
# -------------------------------------------------------------------------------------------------
def test_barycentric_weights_off_the_triangle_by_rounding_are_clipped():
    """Embree's (u, v) can leave a triangle by a rounding error on an edge; a negative weight made the light that
    enters again negative at a vertex of the 2.1M-vertex Igea, and the bounce refused it after minutes of work."""
    from types import SimpleNamespace

    from translucency.scatter.bounces import _at_hits

    triangles = np.array([[0, 1, 2]])
    normals = np.tile([0.0, 0.0, 1.0], (3, 1))
    hits = SimpleNamespace(triangle=np.array([0, 0, -1]), u=np.array([0.6, 1.0 + 1e-9, 0.3]), v=np.array([0.4, 0, 0.3]))
    _, weights, _ = _at_hits(triangles, normals, hits)
    assert np.all(weights >= 0)
    assert np.allclose(weights.sum(axis=1), [1, 1, 0])


def test_a_bounce_that_breaks_keeps_the_first_order_result_and_says_so(monkeypatch):
    import translucency as tl
    from translucency.errors import TranslucencyWarning
    from translucency.scatter import bounces

    points, triangles = icosphere(2, radius=20.0)
    mesh = tl.TriangleMesh(points, triangles)
    first = tl.shade(mesh, "marble", bounces=0)

    def broken(*args, **kwargs):
        raise InvalidParameterError("phi (incident flux density) must be finite and >= 0.")

    monkeypatch.setattr(bounces, "solve_bounces", broken)
    with pytest.warns(TranslucencyWarning, match=r"was not added .*the first-order light alone \(bounces=0 asks"):
        kept = tl.shade(mesh, "marble", bounces=1)
    assert np.array_equal(kept.B, first.B)


@pytest.mark.parametrize("sigma_a, sigma_s", [(0.0, 1e-300), (1e12, 1e-300), (1e-300, 1e-300)])
def test_a_medium_that_scatters_too_little_for_arithmetic_is_refused(sigma_a, sigma_s):
    """A reduced scattering coefficient of 1e-300/mm made the kernels' arithmetic overflow after the solve (NaN
    radiance, numpy's warnings); it is refused when the medium is made."""
    from translucency.scatter.medium import Medium

    with pytest.raises(InvalidParameterError, match=r"scatters too little for any diffuse light.*at least 1e-20/mm"):
        Medium([sigma_a] * 3, [sigma_s] * 3, [0.0] * 3, 1.3, "thin")


def test_the_package_s_warnings_point_at_the_user_s_line():
    """Python shows a warning with the file and line it is attributed to: the caller's own line, not the package's
    source (``.../pipeline.py:883`` then ``solve(``), however deep in the package it was raised."""
    import translucency as tl

    points, triangles = icosphere(2, radius=6.0)
    medium = tl.Medium([0.0] * 3, [1e-6] * 3, [0.0] * 3, 1.3, "clearer")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        tl.shade(tl.TriangleMesh(points, triangles), medium, bounces=0)
    ours = [w for w in caught if "mean free path longer" in str(w.message)]
    assert ours and all(w.filename == __file__ for w in ours)


def _bake_with_material_file(small_sphere, tmp_path, capsys) -> tuple[int, str]:
    """``bake`` of the small sphere with ``--material jade.json`` (in ``tmp_path``): the exit code and the one error
    line."""
    code = cli.main(
        [
            "bake",
            str(small_sphere),
            "--unit",
            "mm",
            "--material",
            str(tmp_path / "jade.json"),
            "-o",
            str(tmp_path / "o"),
        ]
    )
    return code, one_sentence(capsys.readouterr().err)


@pytest.mark.parametrize(
    "content, words",
    [
        (b"\xff\xfe\x00binary", "is not UTF-8 text; save it as a TOML or JSON text file"),
        (b'{"reflectance": 0.5, "mfp":', "is not valid JSON"),
        (b"[1, 2, 3]", "must hold one table of keys and values"),
    ],
)
def test_a_corrupt_material_file_is_one_sentence_without_an_exception_name(
    tmp_path, small_sphere, capsys, content, words
):
    (tmp_path / "jade.json").write_bytes(content)
    code, line = _bake_with_material_file(small_sphere, tmp_path, capsys)
    assert code == 2 and words in line
    assert "Error" not in line.replace("translucency: error:", "")


def test_a_material_file_that_is_a_folder_is_one_sentence(tmp_path, small_sphere, capsys):
    (tmp_path / "jade.json").mkdir()
    code, line = _bake_with_material_file(small_sphere, tmp_path, capsys)
    assert code == 2
    assert "is a directory, not a TOML or JSON file" in line


# -------------------------------------------------------------------------------------------------
# small faults of the command line
# -------------------------------------------------------------------------------------------------
def test_an_output_that_names_a_file_a_bake_does_not_write_is_refused(small_sphere, tmp_path, capsys):
    """``-o x.obj`` used to bake into a folder named ``x.obj``."""
    code = cli.main(["bake", str(small_sphere), "--unit", "mm", "-o", str(tmp_path / "x.obj")])
    assert code == 2
    assert "names a .obj file, which a bake does not write" in one_sentence(capsys.readouterr().err)
    assert not (tmp_path / "x.obj").exists()


def test_no_output_folder_is_left_when_every_input_failed(tmp_path, capsys):
    out = tmp_path / "made" / "deeper"
    assert cli.main(["bake", str(tmp_path / "missing.ply"), "-o", str(out)]) != 0
    err = capsys.readouterr().err
    assert not (tmp_path / "made").exists()
    line = one_sentence(err)
    assert line.count("missing.ply") == 1, line  # the path once, not "missing.ply: .../missing.ply does not exist"


def test_a_low_albedo_is_not_rounded_up_to_the_threshold_it_is_below():
    import translucency as tl
    from translucency.errors import TranslucencyWarning

    points, triangles = icosphere(2, radius=20.0)
    medium = tl.Medium([0.5004] * 3, [0.4996] * 3, [0.0] * 3, 1.3, "at the edge")
    with pytest.warns(
        TranslucencyWarning, match=r"reduced albedo below 0\.5 \(red 0\.4996, green 0\.4996, blue 0\.4996\)"
    ):
        tl.shade(tl.TriangleMesh(points, triangles), medium, bounces=0)


def test_a_second_compare_into_the_same_folder_says_it_replaces_the_first(small_sphere, tmp_path, capsys):
    out = str(tmp_path / "out")
    assert cli.main(["compare", str(small_sphere), "--unit", "mm", "-q", "-o", out]) == 0
    assert "earlier compare" not in capsys.readouterr().err
    assert cli.main(["compare", str(small_sphere), "--unit", "mm", "-q", "-o", out]) == 0
    assert "holds an earlier compare's results (statistics.json, grid.png); they will be replaced" in (
        capsys.readouterr().err
    )
