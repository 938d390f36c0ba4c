"""``compare --reference``: regions from geometry, ratios against a reference made to measure, the files, the CLI."""

import csv
import json

import numpy as np
import pytest

from translucency.app import cli
from translucency.app.compare import compare
from translucency.app.reference_compare import (
    ALL_REGION,
    MIN_PRECISE_VERTICES,
    REGIONS,
    assign_regions,
    reference_figure_size,
    reference_table_text,
)
from translucency.app.shading.scene import Scene
from translucency.app.shading.settings import resolve_medium
from translucency.errors import InvalidParameterError
from translucency.geometry.mesh import TriangleMesh
from translucency.geometry.synthetic import icosphere, torus
from translucency.io.reference_file import read_reference_file, write_reference_file
from translucency.scatter.lights import DirectionalLight

CELL = (160, 140)
LIGHT = np.array([0.0, 0.0, 1.0])
NAMES = [name for name, _ in REGIONS] + [ALL_REGION]


@pytest.fixture(scope="module")
def sphere():
    points, triangles = icosphere(3, 20.0)  # 642 vertices, 40 mm across
    return TriangleMesh(points, triangles)


@pytest.fixture(scope="module")
def model_radiance(sphere):
    """The standard dipole's radiance on the sphere in marble, lit from +z (what compare will compute)."""
    return Scene(sphere).shade("marble", DirectionalLight(LIGHT, 1.0), model="standard").radiance


def _write(path, mesh, radiance, *, stderr=None, reentered=None, material="marble", light=LIGHT):
    medium = resolve_medium(material)
    radiance = np.asarray(radiance, dtype=np.float64)
    arrays = {
        "radiance": radiance,
        "radiance_stderr": 0.01 * radiance if stderr is None else stderr,
        "radiance_reentered": 0.1 * radiance if reentered is None else reentered,
    }
    metadata = {
        "material": medium.name,
        "sigma_a_per_mm": medium.sigma_a.tolist(),
        "sigma_s_per_mm": medium.sigma_s.tolist(),
        "g": medium.g.tolist(),
        "eta": medium.eta,
        "light_direction": list(np.asarray(light, dtype=float) / np.linalg.norm(light)),
        "irradiance_w_per_m2": 1.0,
        "spp": 64,
        "seed": 0,
        "seconds": 12.5,
        "median_relative_stderr": 0.01,
    }
    return write_reference_file(path, mesh.points, mesh.triangles, mesh.vertex_normals(), arrays, metadata)


@pytest.fixture(scope="module")
def doubled(sphere, model_radiance, tmp_path_factory):
    """A reference at exactly twice the model, NaN (not traced) at every tenth vertex, compared with output."""
    folder = tmp_path_factory.mktemp("reference")
    radiance = 2.0 * model_radiance
    radiance[::10] = np.nan
    path = _write(folder / "ref.npz", sphere, radiance)
    result = compare(None, models=["standard"], reference=path, output=folder / "out", cell_size=CELL)
    return result, path, folder / "out"


def test_regions_on_a_sphere_follow_the_height(doubled, sphere):
    """Lit from +z, a sphere casts no shadow: a vertex's region is set by its height z / r alone."""
    result, _, _ = doubled
    c = sphere.points[:, 2] / 20.0
    expected = np.select([c > 0.2, c > 0, c >= -0.3, c >= -0.6], [0, 1, 3, 4], default=5)
    # the vertex normals are radial to within `slack`: nearer a bound than that, the height cannot decide
    slack = np.max(np.linalg.norm(sphere.vertex_normals() - sphere.points / 20.0, axis=1))
    clear = np.min(np.abs(c[:, None] - np.array([0.2, 0.0, -0.3, -0.6])), axis=1) > slack
    assert np.count_nonzero(clear) > 0.8 * len(c)
    assert np.array_equal(result.regions[clear], expected[clear])
    traced = np.arange(len(c)) % 10 != 0  # every tenth vertex is not traced
    for k, name in enumerate(NAMES[:-1]):
        row = next(r for r in result.reference_rows if (r["region"], r["channel"]) == (name, "G"))
        low = np.count_nonzero((expected == k) & clear & traced)
        assert low <= row["n_vertices"] <= low + np.count_nonzero(~clear & traced)
        assert row["n_vertices"] == np.count_nonzero((result.regions == k) & traced)
    assert not np.any((result.regions == 2) & clear)  # nothing shadowed on a sphere but at the very terminator
    assert sum(np.count_nonzero(result.regions == k) for k in range(len(REGIONS))) == len(c)


def test_shadowed_vertices_of_a_torus_lit_from_the_side():
    """Lit along +x, the inside of the ring on the -x half faces the light across the hole and is shadowed by
    the +x half; every other vertex facing the light is lit."""
    points, triangles = torus(20.0, 6.0)
    mesh = TriangleMesh(points, triangles)
    light = np.array([1.0, 0.0, 0.0])
    lit = (
        Scene(mesh)
        .light_cache.incident_on_mesh(resolve_medium("marble"), DirectionalLight(light, 1.0))[0]
        .phi_rgb.max(axis=1)
        > 0
    )
    regions = assign_regions(mesh.vertex_normals(), light, lit)
    u = np.arctan2(points[:, 1], points[:, 0])
    ring = np.hypot(points[:, 0], points[:, 1]) - 20.0
    cos_v, sin_v = ring / 6.0, points[:, 2] / 6.0
    c = np.cos(u) * cos_v  # the analytic n . w_L
    clear = (np.abs(c) > 0.05) & (np.abs(sin_v) < 0.9) & (np.abs(c - 0.2) > 0.05)  # away from every bound
    shadowed = (np.cos(u) < 0) & (cos_v < 0)
    expected = np.select([shadowed, c > 0.2, c > 0, c >= -0.3, c >= -0.6], [2, 0, 1, 3, 4], default=5)
    assert np.count_nonzero(clear & shadowed) > 50
    assert np.array_equal(regions[clear], expected[clear])


def test_a_reference_at_twice_the_model_gives_half_in_every_region(doubled, sphere):
    result, _, _ = doubled
    rows = result.reference_rows
    assert {(r["region"], r["channel"]) for r in rows} == {(n, c) for n in NAMES for c in "RGB"}
    for row in rows:
        if row["n_vertices"] == 0:
            assert row["ratio"] is None and row["region"] == "shadowed"
            continue
        assert row["ratio"] == pytest.approx(0.5, rel=1e-12)
        assert row["reentered_share"] == pytest.approx(0.1, rel=1e-12)
        assert row["ratio_without_reentered"] == pytest.approx(0.5 / 0.9, rel=1e-12)
        # |m - 2m| / 2m on every vertex; the NaN ones are left out, and so are regions of too few vertices
        if row["n_vertices"] < MIN_PRECISE_VERTICES:
            assert row["relative_error_median"] is None and row["n_precise"] == 0
            continue
        assert row["relative_error_median"] == pytest.approx(0.5) and row["relative_error_p90"] == pytest.approx(0.5)
        assert row["n_precise"] == row["n_vertices"]
        # standard error of a mean of n vertices with errors 1 % of 2m: 0.5 * sqrt(sum (0.02 m)^2) / n / mean(2m)
        assert 0 < row["ratio_stderr"] < 0.5 * 0.01
    every = next(r for r in rows if (r["region"], r["channel"]) == (ALL_REGION, "R"))
    assert every["n_vertices"] == len(sphere.points) - len(sphere.points[::10])
    assert np.allclose(result.ratio("standard", "lit"), 0.5)


def test_noisy_and_dark_vertices_stay_out_of_the_per_vertex_errors(sphere, model_radiance, tmp_path):
    radiance = 2.0 * model_radiance
    stderr = 0.01 * radiance
    stderr[::3] = 0.5 * radiance[::3]  # a third too noisy to judge one by one
    path = _write(tmp_path / "ref.vtp", sphere, radiance, stderr=stderr)
    result = compare(sphere, models=["standard"], reference=path)
    row = next(r for r in result.reference_rows if (r["region"], r["channel"]) == (ALL_REGION, "G"))
    assert row["n_vertices"] == len(sphere.points)
    assert row["n_precise"] == len(sphere.points) - len(sphere.points[::3])
    assert row["ratio"] == pytest.approx(0.5)  # the means keep every vertex
    se = 0.5 * np.sqrt(np.sum(stderr[:, 1] ** 2)) / len(stderr) / radiance[:, 1].mean()
    assert row["ratio_stderr"] == pytest.approx(se)


def test_the_files_hold_the_tables(doubled):
    import imageio.v3 as iio

    result, path, out = doubled
    names = {p.name for p in out.iterdir()}
    assert {"reference.csv", "reference.json", "reference_errors.png", "grid.png", "statistics.csv"} <= names
    rows = list(csv.DictReader(open(out / "reference.csv", encoding="utf-8")))
    assert len(rows) == len(result.reference_rows) == len(NAMES) * 3
    assert float(rows[0]["ratio"]) == pytest.approx(result.reference_rows[0]["ratio"])
    document = json.loads((out / "reference.json").read_text())
    assert document["rows"] == json.loads(json.dumps(result.reference_rows))
    assert document["times_s"]["path_tracer"] == 12.5 and document["times_s"]["models"]["standard"] > 0
    assert document["reference"]["material"] == "marble" and document["untraced_vertices"] == 65
    assert "noise" in document["figures"]
    image = iio.imread(out / "reference_errors.png")[..., :3]
    width, height = reference_figure_size(1, CELL)
    assert image.shape[:2] == (height, width)
    # the model's ratio view (bottom row, right): 0.5 everywhere is the map's darkest blue, on most of the sphere
    view = image[height // 3 : height - 150, width // 2 :].astype(int)
    blue = (view[..., 2] - view[..., 0] > 40) & (view[..., 0] < 40) & (view[..., 1] < 90)
    disc = np.pi * (0.25 * CELL[1]) ** 2 / 2  # the sphere, at least half a view across, shrunk by the layout
    assert np.count_nonzero(blue) > disc
    grey = np.all(np.abs(image - 128) <= 2, axis=2)  # the untraced vertices, in every view
    assert np.count_nonzero(grey) > 0.05 * disc
    assert np.count_nonzero(image.min(axis=2) < 200) > 0.2 * image.shape[0] * image.shape[1]  # not a blank page


def test_cli_prints_and_writes_what_the_api_computes(doubled, tmp_path, capsys):
    result, path, _ = doubled
    out = tmp_path / "cli"
    args = ["compare", "--reference", str(path), "--models", "standard", "--cell-size", "160x140", "-o", str(out)]
    assert cli.main([*args, "-q"]) == 0
    printed = capsys.readouterr().out
    rows = list(csv.DictReader(open(out / "reference.csv", encoding="utf-8")))
    for row, api in zip(rows, result.reference_rows):
        assert (row["region"], row["channel"]) == (api["region"], api["channel"])
        if api["ratio"] is None:
            assert row["ratio"] == ""
        else:
            assert float(row["ratio"]) == pytest.approx(api["ratio"], rel=1e-12)
    assert "standard dipole against the reference" in printed and "W/(m^2 sr) per W/m^2" in printed
    table = printed[printed.index("regions by c") : printed.index("common display exposure")]
    assert all(len(line) <= 100 for line in table.splitlines())
    lit = next(line for line in table.splitlines() if line.strip().startswith("lit "))
    assert lit.count("0.500+-") == 3


@pytest.mark.parametrize(
    "extra, fragment",
    [
        (["--material", "ketchup"], "was traced in marble"),
        (["--light-dir", "0,1,0"], "traced with one directional light"),
        (["--models", "nonsense"], "nonsense"),
    ],
)
def test_cli_refuses_what_disagrees_with_the_reference(doubled, tmp_path, capsys, extra, fragment):
    _, path, _ = doubled
    assert cli.main(["compare", "--reference", str(path), *extra, "-o", str(tmp_path / "o")]) == 2
    error = capsys.readouterr().err.strip()
    assert fragment in error and error.count("\n") == 0
    assert not (tmp_path / "o" / "reference.csv").exists()


def test_cli_refuses_another_mesh(doubled, tmp_path, capsys):
    import pyvista as pv

    _, path, _ = doubled
    points, triangles = icosphere(2, 20.0)
    other = tmp_path / "other.ply"
    pv.PolyData(points, np.hstack([np.full((len(triangles), 1), 3), triangles]).ravel()).save(other)
    assert cli.main(["compare", str(other), "--unit", "mm", "--reference", str(path), "-o", str(tmp_path / "o")]) == 2
    error = capsys.readouterr().err.strip()
    assert "162 vertices" in error and "642" in error and error.count("\n") == 0


def test_the_api_takes_the_same_mesh_and_light_and_refuses_others(doubled, sphere, model_radiance):
    _, path, _ = doubled
    reference = read_reference_file(path)
    same = compare(sphere, ["marble"], ["standard"], DirectionalLight(2 * LIGHT, 1.0), reference=reference)
    assert np.array_equal(same.results["marble", "standard"].radiance, model_radiance)
    assert same.reference.path == "in memory"
    moved = TriangleMesh(sphere.points + 1e-3, sphere.triangles)
    with pytest.raises(InvalidParameterError, match="mm from those of the reference"):
        compare(moved, models=["standard"], reference=reference)
    with pytest.raises(InvalidParameterError, match="traced in marble, not skim_milk"):
        compare(sphere, ["skim_milk"], ["standard"], reference=reference)
    with pytest.raises(InvalidParameterError, match="directional light"):
        compare(sphere, models=["standard"], lights=DirectionalLight(LIGHT, 2.0), reference=reference)


def test_normals_that_are_not_the_meshs_are_refused(sphere, model_radiance, tmp_path):
    path = _write(tmp_path / "ref.npz", sphere, model_radiance)
    read = read_reference_file(path)
    tilted = read.normals.copy()
    tilted[0] = [1.0, 0.0, 0.0]
    arrays = {
        "radiance": read.radiance,
        "radiance_stderr": read.radiance_stderr,
        "radiance_reentered": read.radiance_reentered,
    }
    bad = write_reference_file(tmp_path / "bad.npz", read.points, read.triangles, tilted, arrays, read.metadata)
    with pytest.raises(InvalidParameterError, match="normals"):
        compare(models=["standard"], reference=bad)


@pytest.mark.slow
def test_a_traced_reference_compares_within_a_factor_of_two(tmp_path):
    """A real trace, through a .vtp file: the models and the path tracer agree to within a factor of 2 where lit."""
    from translucency.app.ground_truth import trace_reference, write_reference

    points, triangles = icosphere(2, 6.0)
    truth = trace_reference(TriangleMesh(points, triangles), "skimmilk", [0.3, 0.2, 1.0], spp=8)
    path = write_reference(truth, tmp_path / "ref.vtp")
    result = compare(models=["directional", "standard"], reference=path, output=tmp_path / "out", cell_size=CELL)
    assert result.materials == ["skim_milk"]
    for model in result.models:
        assert np.all((result.ratio(model, "lit") > 0.5) & (result.ratio(model, "lit") < 2.0))
    assert (tmp_path / "out" / "reference_errors.png").exists()


def test_the_table_keeps_its_columns_whatever_the_noise():
    """A median error of 172,592 % (a reference of a few paths in a dark region) printed whole broke the table's
    alignment; beyond 999 % it reads ">999"."""
    row = {
        "ratio": 1.02,
        "ratio_stderr": 0.01,
        "relative_error_median": 1725.92,
        "reentered_share": 0.05,
        "n_vertices": 10,
    }
    rows = [
        {**row, "model": "directional", "region": region, "channel": c}
        for region in [name for name, _ in REGIONS] + [ALL_REGION]
        for c in "RGB"
    ]
    lines = reference_table_text(rows, ["directional"], {"directional": 1.0})
    body = [line for line in lines if line.startswith("  ") and "region" not in line]
    assert body and all(">999/>999/>999 %" in line for line in body)
    assert len({len(line) for line in body}) == 1  # aligned


def test_the_profile_carries_the_reference_along_the_same_cut(doubled):
    result, _, folder = doubled
    position, radiance, stderr = result.reference_profile
    model_position, model = result.profiles[result.materials[0], "standard"]
    np.testing.assert_array_equal(position, model_position)
    traced = np.all(np.isfinite(radiance), axis=1)
    assert traced.mean() > 0.5  # every tenth vertex is untraced: the cut passes some of their triangles
    # the reference is twice the model wherever the cut crosses only traced vertices' triangles
    np.testing.assert_allclose(radiance[traced], 2.0 * model[traced], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(stderr[traced], 0.01 * radiance[traced], rtol=1e-9, atol=1e-12)
    from translucency.app.compare_figures import profile_figure

    labels = [line.get_label() for line in profile_figure(result).axes[0].get_lines()]
    assert any(label.startswith("reference (path traced") for label in labels)
    assert (folder / "profile.png").exists()
