"""The command line: exit codes, one-sentence errors, output that agrees with the API, the main job."""

import subprocess
import sys

import numpy as np
import pytest

from translucency.app import cli
from translucency.io.baked import read_baked_ply
from translucency.scatter.materials import catalogue


def run_cli(*args, cwd=None):
    """Run ``python -m translucency`` in a fresh process; returns (exit code, stdout, stderr)."""
    done = subprocess.run(
        [sys.executable, "-m", "translucency", *args], capture_output=True, text=True, cwd=cwd, timeout=300
    )
    return done.returncode, done.stdout, done.stderr


def test_materials_lists_the_catalogue(capsys):
    assert cli.main(["materials"]) == 0
    out = capsys.readouterr().out
    for entry in catalogue():
        assert entry.key in out
    marble = next(line for line in out.splitlines() if line.startswith("marble "))
    assert "0.0021, 0.0041, 0.0071" in marble and "2.19, 2.62, 3" in marble
    # reduced mean free path 1/sigma_t' of marble red = 1 / 2.1921 mm
    assert f"{1 / 2.1921:.3g}" in marble


def test_unknown_material_table_is_a_usage_error():
    code, _, err = run_cli("materials", "--table", "nope")
    assert code == 2 and "invalid choice" in err


@pytest.mark.parametrize(
    "content, fragment",
    [
        (b"", "empty"),
        (b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n", "truncated"),
        (b"solid x\nendsolid x\n", "no vertices"),
    ],
)
def test_inspect_bad_files_give_one_sentence_and_exit_2(tmp_path, content, fragment):
    path = tmp_path / ("broken.stl" if content.startswith(b"solid") else "broken.ply")
    path.write_bytes(content)
    code, out, err = run_cli("inspect", str(path))
    assert code == 2
    assert "Traceback" not in err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("translucency: error:")
    assert fragment in lines[0].lower()
    assert path.read_bytes() == content  # input untouched


def test_inspect_missing_file():
    code, _, err = run_cli("inspect", "does-not-exist.ply")
    assert code == 2 and "does not exist" in err and "Traceback" not in err


def test_inspect_repairs_a_shared_scan(shared_meshes, tmp_path):
    out = tmp_path / "fixed.ply"
    code, stdout, err = run_cli(
        "inspect", str(shared_meshes / "stanford_bunny_zipper.ply"), "--unit", "m", "-o", str(out)
    )
    assert code == 0, err
    assert "unreferenced vertices removed            1113" in stdout
    assert out.exists()


def test_inspect_without_unit_says_the_inferred_unit_in_one_line(shared_meshes):
    code, stdout, err = run_cli("inspect", str(shared_meshes / "stanford_bunny_zipper.ply"))
    assert code == 0, err
    assert err.splitlines() == [
        "translucency: stanford_bunny_zipper.ply: no --unit given; 0.156 units across, "
        "read as metres (156 mm); pass --unit to override"
    ]
    assert "155.7 mm across" in stdout and "up axis for --up auto: +y" in stdout


def test_inspect_with_a_wrong_unit_warns_with_the_flag(shared_meshes):
    code, _, err = run_cli("inspect", str(shared_meshes / "stanford_bunny_zipper.ply"), "--unit", "mm")
    assert code == 0
    assert "0.16 mm across, implausible for a scan in mm; if the file is in metres pass --unit m." in err
    assert "unit='m'" not in err


def test_the_same_line_in_python_names_the_keyword(shared_meshes):
    from translucency.io import load_mesh
    from translucency.io.units import UnitInferredWarning

    with pytest.warns(UnitInferredWarning) as caught:
        load_mesh(shared_meshes / "stanford_bunny_zipper.ply")
    assert str(caught[0].message) == (
        "stanford_bunny_zipper.ply: no unit= given; 0.156 units across, read as metres (156 mm); pass unit= to override"
    )


def test_a_size_no_unit_makes_plausible_is_refused_and_a_given_unit_only_warns(tmp_path):
    from translucency.geometry.mesh import TriangleMesh
    from translucency.geometry.synthetic import icosphere
    from translucency.io.polydata import to_pyvista

    points, triangles = icosphere(2, 10000.0)  # 20000 units across: 20 m in mm, 20 km in metres
    path = tmp_path / "huge.ply"
    to_pyvista(TriangleMesh(points, triangles)).save(str(path))
    code, _, err = run_cli("inspect", str(path))
    assert code == 2 and len(err.splitlines()) == 1 and "Traceback" not in err
    assert "huge.ply is 2e+04 units across and no --unit was given" in err and "pass --unit with" in err
    code, _, err = run_cli("inspect", str(path), "--unit", "mm")
    assert code == 0 and "translucency: warning: huge.ply is 2e+04 mm across, implausible" in err


def test_report_prints_versions_and_offscreen_status():
    code, out, _ = run_cli("report")
    assert "numpy" in out and "pymeshlab" in out and "off-screen rendering" in out
    assert code in (0, 1)


def test_main_job_bakes_the_embedded_default(tmp_path):
    code, out, err = run_cli(cwd=tmp_path)
    assert code == 0, err
    ply = tmp_path / "translucency-output" / "bunny_marble.ply"
    png = tmp_path / "translucency-output" / "bunny_marble.png"
    assert ply.exists() and png.exists()
    baked = read_baked_ply(ply)
    assert baked.metadata["material"] == "marble" and baked.metadata["method"] == "tree"
    # the embedded default keeps its size (given, not inferred) and stands +y up under the unchanged light
    assert baked.metadata["up"] == "+y" and baked.metadata["source_unit_inferred"] is False
    assert baked.metadata["lights"][0]["direction"] == pytest.approx(
        np.array([0.35, 1.0, 0.45]) / np.linalg.norm([0.35, 1.0, 0.45])
    )
    radiance = baked.radiance
    assert np.all(np.isfinite(radiance)) and np.all(radiance >= 0)
    light = np.array(baked.metadata["lights"][0]["direction"])
    facing = baked.normals @ light
    assert radiance[facing > 0.5].mean() > 5 * radiance[facing < -0.5].mean()
    # marble scatters red farther than blue: relative to the lit side, the dark side is redder
    dark, bright = radiance[facing < -0.5].mean(axis=0), radiance[facing > 0.5].mean(axis=0)
    assert dark[0] / bright[0] > dark[2] / bright[2]


def test_shade_on_a_proxy_interpolates_back_to_every_vertex():
    from translucency.app.pipeline import shade
    from translucency.geometry.mesh import TriangleMesh
    from translucency.geometry.synthetic import icosphere

    points, triangles = icosphere(5, 20.0)  # 0.6 mm edges
    mesh = TriangleMesh(points, triangles)
    full = shade(mesh, "skim_milk", resolution="full", method="exact")
    proxy = shade(mesh, "skim_milk", resolution=2.0, method="exact")
    assert proxy.stats["solver_vertices"] < mesh.n_points / 4
    assert proxy.B.shape == full.B.shape and np.all(np.isfinite(proxy.B)) and np.all(proxy.B >= 0)
    assert np.linalg.norm(proxy.B - full.B) / np.linalg.norm(full.B) < 0.05
    assert "proxy" in proxy.metadata["resolution"]
