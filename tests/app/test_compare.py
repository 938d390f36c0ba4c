"""Comparisons: the files, the grid's size, statistics that tell materials apart, atomic output, the CLI."""

import csv
import json
import re

import numpy as np
import pytest

from translucency.app import cli
from translucency.app import compare as compare_module
from translucency.app.compare import compare, profile_cut, radiance_statistics, relative_difference
from translucency.errors import TranslucencyError
from translucency.geometry.mesh import TriangleMesh
from translucency.geometry.synthetic import icosphere
from translucency.io.polydata import to_pyvista
from translucency.scatter.lights import DirectionalLight

CELL = (120, 100)


@pytest.fixture(scope="module")
def sphere():
    points, triangles = icosphere(3, 20.0)  # 642 vertices, 40 mm across
    return TriangleMesh(points, triangles)


@pytest.fixture(scope="module")
def two_by_two(sphere, tmp_path_factory):
    out = tmp_path_factory.mktemp("compare") / "out"
    return compare(sphere, ["marble", "ketchup"], ["directional", "standard"], output=out, cell_size=CELL), out


def test_files_and_the_grid_size(two_by_two):
    import imageio.v3 as iio

    result, out = two_by_two
    assert sorted(p.name for p in out.iterdir()) == [
        "differences.png",
        "grid.png",
        "profile.png",
        "statistics.csv",
        "statistics.json",
    ]
    assert result.files["grid"] == out / "grid.png"
    grid = iio.imread(out / "grid.png")
    assert grid.shape[:2] == (2 * CELL[1], 2 * CELL[0])  # rows: models, columns: materials
    # each cell holds its object: pixels around the centre of every cell are lit
    for row in range(2):
        for column in range(2):
            y, x = row * CELL[1] + CELL[1] // 2, column * CELL[0] + CELL[0] // 2
            assert grid[y - 20 : y + 20, x - 20 : x + 20].max() > 20
    differences = iio.imread(out / "differences.png")
    assert differences.shape[1] == 2 * CELL[0] and differences.shape[0] > CELL[1]


def test_statistics_tell_the_materials_apart(two_by_two):
    result, out = two_by_two
    rows = list(csv.DictReader(open(out / "statistics.csv", encoding="utf-8")))
    assert len(rows) == 2 * 2 * 2 * 3  # material x model x subset x channel
    document = json.loads((out / "statistics.json").read_text())
    assert document["statistics"] == json.loads(json.dumps(result.statistics))
    assert document["exposure"]["value"] == result.exposure
    marble, ketchup = result.mean("marble", "directional"), result.mean("ketchup", "directional")
    assert ketchup[0] / ketchup[2] > 1.5 * marble[0] / marble[2]  # ketchup is red, marble white
    row = next(
        r
        for r in rows
        if (r["material"], r["model"], r["subset"], r["channel"]) == ("marble", "directional", "lit", "R")
    )
    assert np.isclose(float(row["mean"]), marble[0]) and float(row["time_s"]) > 0
    assert int(row["n_vertices"]) < 642  # only the lit half
    # the statistics are those of the returned radiance
    radiance = result.results["ketchup", "standard"].radiance
    assert np.isclose(result.mean("ketchup", "standard", "all")[1], radiance[:, 1].mean())


def test_the_difference_maps_measure_the_model_change(two_by_two):
    result, _ = two_by_two
    rows = {(r["material"], r["subset"]): r for r in result.differences}
    assert len(rows) == 4 and all(r["model"] == "standard" and r["reference"] == "directional" for r in rows.values())
    d = relative_difference(
        result.results["marble", "standard"].radiance, result.results["marble", "directional"].radiance
    )
    assert np.isclose(rows["marble", "all"]["mean"], d.mean())
    assert rows["marble", "lit"]["n_vertices"] < rows["marble", "all"]["n_vertices"] == 642
    # at high albedo the standard dipole is darker than the directional one on the lit side
    assert rows["marble", "lit"]["mean"] < -0.05 and rows["ketchup", "lit"]["mean_abs"] > 0.05


def test_one_exposure_for_every_cell(two_by_two):
    result, _ = two_by_two
    pooled = np.concatenate([r.radiance for r in result.results.values()])
    level = np.percentile(pooled.max(axis=1), 99.5)
    assert np.isclose(result.exposure, 0.9 / level)


def test_the_profile_cuts_across_the_light_boundary(two_by_two, sphere):
    result, _ = two_by_two
    # light along +z, up +y: the cut is the circle x = 0 of radius 20 mm; position 0 faces the light,
    # the terminator lies a quarter of the circle away on either side
    position, samples, plane = profile_cut(sphere, {"z": sphere.points[:, 2]}, (0, 0, 1), up=(0, 1, 0))
    assert np.all(np.diff(position) >= 0)
    assert np.isclose(plane["length_mm"], 2 * np.pi * 20, rtol=0.01)
    assert samples["z"][np.argmin(np.abs(position))] > 19.5
    quarter = np.abs(np.abs(position) - 0.5 * np.pi * 20) < 1.0
    assert quarter.sum() >= 2 and np.all(np.abs(samples["z"][quarter]) < 1.5)
    # compare's own cut: the lit stretch around 0 is bounded by two light boundaries, and the radiance
    # is highest near the point that faces the light
    boundaries = np.array(result.profile_plane["light_boundaries_mm"])
    assert len(boundaries) == 2 and boundaries[0] < 0 < boundaries[1]
    position, radiance = result.profiles["marble", "directional"]
    assert radiance[np.abs(position) < 5].mean() > 20 * radiance[np.abs(position) > boundaries[1] + 15].mean()


def test_statistics_of_an_empty_subset_are_none():
    stats = radiance_statistics(np.ones((4, 3)), np.zeros(4, dtype=bool))
    assert stats["R"]["n_vertices"] == 0 and stats["G"]["mean"] is None
    assert radiance_statistics(np.arange(12.0).reshape(4, 3))["B"]["median"] == 6.5


def test_a_failed_run_leaves_the_output_folder_as_it_was(sphere, tmp_path, monkeypatch):
    out = tmp_path / "out"
    out.mkdir()
    (out / "grid.png").write_bytes(b"old")

    def broken(*args, **kwargs):
        raise RuntimeError("disk full")

    monkeypatch.setattr(compare_module, "_profile_plot", broken)
    with pytest.raises(RuntimeError):
        compare(sphere, ["marble"], output=out, cell_size=CELL)
    assert [p.name for p in out.iterdir()] == ["grid.png"] and (out / "grid.png").read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no staging folder left


def test_one_model_gives_no_difference_map_and_reuses_the_scene(sphere, tmp_path, monkeypatch):
    built = []
    scene_for = compare_module.scene_for
    monkeypatch.setattr(compare_module, "scene_for", lambda *a, **k: built.append(1) or scene_for(*a, **k))
    result = compare(sphere, "marble,skim_milk,ketchup", "directional", output=tmp_path / "o", cell_size=CELL)
    assert len(built) == 1
    assert "differences" not in result.files and not (tmp_path / "o" / "differences.png").exists()
    import imageio.v3 as iio

    assert iio.imread(result.files["grid"]).shape[:2] == (CELL[1], 3 * CELL[0])


@pytest.mark.parametrize(
    "kwargs, fragment",
    [
        ({"materials": []}, "at least one material"),
        ({"materials": ["marble", "marble"]}, "repeat"),
        ({"models": ["directional", "photon"]}, "unknown model"),
        ({"materials": ["no such thing"]}, "unknown material"),
        ({"exposure": -1.0}, "exposure"),
        ({"cell_size": (8, 8)}, "cell_size"),
    ],
)
def test_bad_arguments_are_refused_before_any_work(sphere, kwargs, fragment, tmp_path):
    with pytest.raises(TranslucencyError, match=fragment):
        compare(sphere, **{"materials": ["marble"], **kwargs}, output=tmp_path / "o")
    assert not (tmp_path / "o").exists()


def test_the_cli_writes_what_the_api_computes(sphere, tmp_path, capsys):
    path = tmp_path / "sphere.ply"
    to_pyvista(sphere).save(path)
    out = tmp_path / "cli"
    code = cli.main(
        [
            "compare",
            str(path),
            "--materials",
            "marble,ketchup",
            "--models",
            "directional,standard",
            "--light-dir",
            "0,0,1",
            "--method",
            "exact",
            "--cell-size",
            "64x48",
            "--up",
            "-x",
            "-o",
            str(out),
        ]
    )
    assert code == 0
    captured = capsys.readouterr()
    stdout = captured.out
    assert "ketchup" in stdout and "statistics.json" in stdout
    document = json.loads((out / "statistics.json").read_text())
    # every cell's means say over what: the lit vertices (with their count) and all; the numbers are the JSON's
    rows = {(r["material"], r["model"], r["subset"], r["channel"]): r for r in document["statistics"]}
    for material in ("marble", "ketchup"):
        for model in ("directional", "standard"):
            line = next(x for x in stdout.splitlines() if x.split()[:2] == [material, model])
            lit, every = line.split(";  all: ")
            n_lit = rows[material, model, "lit", "R"]["n_vertices"]
            assert f" lit ({n_lit}): " in lit and 0 < n_lit < rows[material, model, "all", "R"]["n_vertices"]
            for part, subset in ((lit, "lit"), (every, "all")):
                printed = [float(v) for v in re.findall(r"[RGB] (\S+)", part)]
                expected = [rows[material, model, subset, c]["mean"] for c in "RGB"]
                assert printed == pytest.approx(expected, rel=5e-3)  # printed to three significant digits
    # progress: one line per solve on stderr, none on stdout
    assert sum(line.startswith("solved ") for line in captured.err.splitlines()) == 4
    assert "solved " not in stdout
    from translucency.app.shading.scan import load_scan

    mesh, _, _ = load_scan(path)
    api = compare(
        mesh, ["marble", "ketchup"], ["directional", "standard"], DirectionalLight((0, 0, 1), 1.0), method="exact"
    )
    for cli_row, api_row in zip(document["statistics"], api.statistics):
        assert cli_row["material"] == api_row["material"] and cli_row["subset"] == api_row["subset"]
        for key in ("mean", "median", "p95"):
            assert cli_row[key] == pytest.approx(api_row[key], rel=1e-12, abs=1e-15)
    assert document["settings"]["method"] == "exact"
    assert document["settings"]["up"] == "-x" and document["settings"]["up_inferred"] is False  # --up -x as written
    assert document["mesh"]["source_unit_inferred"] is True  # the 40-unit file was read in millimetres


def test_cli_errors_are_one_sentence_with_exit_code_2(tmp_path, capsys):
    assert cli.main(["compare", "--models", "directional,nope", "-o", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("translucency: error:") and "nope" in err[0]
    assert cli.main(["compare", "--cell-size", "0x0"]) == 2
    assert "--cell-size" in capsys.readouterr().err


def test_json_records_the_unit_and_the_up_axis(two_by_two):
    _, out = two_by_two
    document = json.loads((out / "statistics.json").read_text())
    assert document["mesh"]["source_unit"] == "mm" and document["mesh"]["source_mm_per_unit"] == 1.0
    assert document["mesh"]["source_unit_inferred"] is False and document["mesh"]["source_unit_name"] == "millimetres"
    assert document["mesh"]["length_unit"] == "mm"
    assert document["settings"]["up"] == "+y" and document["settings"]["up_inferred"] is True  # a ball: the fallback


def test_up_sets_the_default_light_and_the_profile_plane(sphere):
    from translucency.app.compare import compare_light_direction

    result = compare(sphere, ["marble"], up="z", method="exact")
    metadata = result.results["marble", "directional"].metadata
    assert metadata["up"] == "+z"
    light = compare_light_direction("+z") / np.linalg.norm(compare_light_direction("+z"))
    np.testing.assert_allclose(metadata["lights"][0]["direction"], light)
    assert abs(np.dot(result.profile_plane["normal"], (0, 0, 1))) < 1e-12  # the cut contains the up axis


def test_the_profile_legend_lies_beside_the_data(two_by_two):
    from translucency.app.compare import profile_figure

    figure = profile_figure(two_by_two[0])
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    legend = figure.legends[0].get_window_extent(renderer)
    assert all(not legend.overlaps(ax.get_window_extent(renderer)) for ax in figure.axes)
    assert not legend.overlaps(figure.get_suptitle() and figure._suptitle.get_window_extent(renderer))
    assert figure.axes[0].get_xlabel().startswith("position along the cut (mm")


def test_the_default_light_puts_a_tenth_of_what_the_camera_sees_in_shadow():
    from translucency.app.compare import visible_shadow_fraction, visible_vertices
    from translucency.app.framing import camera_position
    from translucency.app.shading.scan import load_scan
    from translucency.app.shading.settings import DEFAULT_LIGHT_DIRECTION
    from translucency.io.upright import to_scan_frame

    mesh, _, _ = load_scan(None)
    shadowed = visible_shadow_fraction(mesh)
    assert 0.10 <= shadowed < 0.6  # a shadow edge to see, and still most of the scan lit
    # the main job's key light, from above and in front, leaves less than half as much in shadow
    light = DirectionalLight(to_scan_frame(DEFAULT_LIGHT_DIRECTION, "+y"), 1.0)
    assert visible_shadow_fraction(mesh, light) < 0.5 * shadowed
    # visibility itself: a sphere of radius r seen from a distance d shows the cap cos(theta) > r / d,
    # (1 - r / d) / 2 of its surface
    points, triangles = icosphere(3, 20.0)
    ball = TriangleMesh(points, triangles)
    eye = np.asarray(camera_position((0, 0, 0), 40.0, (0, 0, 1))[0])
    seen = visible_vertices(ball, eye)
    assert np.all(points[seen][:, 2] > 0) and abs(seen.mean() - (1 - 20.0 / eye[2]) / 2) < 0.03
    # a second ball in front hides part of the first
    hidden = visible_vertices(
        TriangleMesh(np.vstack([points, points + (0, 0, 45)]), np.vstack([triangles, triangles + len(points)])), eye
    )
    assert hidden[: len(points)].sum() < 0.5 * seen.sum()
