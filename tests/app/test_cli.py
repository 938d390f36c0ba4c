"""The command line: exit codes, one-sentence errors, output that agrees with the API, the main job."""

import re
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


def test_materials_wide_lists_the_catalogue_with_every_column(capsys):
    assert cli.main(["materials", "--wide"]) == 0
    out = capsys.readouterr().out
    for entry in catalogue():
        assert entry.key in out
    header = out.splitlines()[0].split("  ")
    assert {"table", "sigma_s [1/mm]", "g", "1/sigma_t' [mm]", "1/sigma_tr [mm]"} <= {h.strip() for h in header}
    marble = next(line for line in out.splitlines() if line.startswith("marble "))
    assert "0.0021, 0.0041, 0.0071" in marble and "2.19, 2.62, 3" in marble
    # reduced mean free path 1/sigma_t' of marble red = 1 / 2.1921 mm
    assert f"{1 / 2.1921:.3g}" in marble


def test_materials_default_table_fits_100_columns(capsys):
    assert cli.main(["materials"]) == 0
    out = capsys.readouterr().out
    assert max(len(line) for line in out.splitlines()) <= 100
    for entry in catalogue():
        assert entry.key in out
    header = [h.strip() for h in out.splitlines()[1].split("  ") if h.strip()]
    assert header == ["name", "eta", "sigma_a [1/mm]", "sigma_s' [1/mm]", "1/sigma_tr [mm]"]
    assert "1/sigma_t' [mm]" not in out and "[jensen2001]" in out and "[narasimhan2006]" in out
    # marble (Jensen et al. 2001, Table 2: reduced sigma_s' = 2.19, 2.62, 3.00 and sigma_a = 0.0021, 0.0041,
    # 0.0071 per mm): diffusion length 1/sigma_tr = 1/sqrt(3 sigma_a sigma_t') = 8.51, 5.57, 3.95 mm
    sigma_a, sigma_s = np.array([0.0021, 0.0041, 0.0071]), np.array([2.19, 2.62, 3.00])
    diffusion = [f"{d:.2g}" for d in 1 / np.sqrt(3 * sigma_a * (sigma_a + sigma_s))]
    marble = next(line for line in out.splitlines() if line.startswith("marble ")).split()
    assert marble[1:] == ["1.5", "0.0021", "0.0041", "0.0071", "2.2", "2.6", "3", *diffusion]
    # an unreduced table is shown reduced: lowfat milk sigma_s = 0.9124 per mm red with g = 0.932 -> 0.062
    milk = next(line for line in out.splitlines() if line.startswith("lowfat_milk ")).split()
    assert milk[5] == "0.062"


def test_every_option_with_a_default_says_it_in_help(capsys):
    """``--help`` of the command and of every subcommand: each option with a default states it."""
    import argparse

    parser = cli.build_parser()
    commands = {"": parser}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            commands.update(action.choices)
    assert {"bake", "view", "compare", "materials", "inspect"} <= set(commands)
    checked = 0
    for name, command in commands.items():
        with pytest.raises(SystemExit):
            cli.main([name, "--help"] if name else ["--help"])
        text = capsys.readouterr().out
        for action in command._actions:
            if not action.option_strings or action.nargs == 0 or action.default in (None, argparse.SUPPRESS):
                continue
            flag = action.option_strings[-1]
            # the option's entry: from its line to the next option's, on one line
            entry = re.search(rf"\n  (?:[^\n]*?[ ,])?{re.escape(flag)}(?=[ ,=\n]).*?(?=\n  -|\n\n|\Z)", text, re.S)
            assert entry is not None, f"{name} {flag} is missing from --help"
            # argparse wraps lines at spaces and after hyphens: compare without any white space
            entry = "".join(entry.group(0).split())
            assert "default" in entry and "".join(str(action.default).split()) in entry, f"{name} {flag}: {entry}"
            checked += 1
    assert checked >= 20


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
    assert "GPU for exact and relight (--device auto): " in out
    assert code in (0, 1)


def test_main_job_bakes_the_embedded_default(tmp_path):
    code, out, err = run_cli(cwd=tmp_path)
    assert code == 0, err
    ply = tmp_path / "translucency-output" / "bunny_marble.ply"
    png = tmp_path / "translucency-output" / "bunny_marble.png"
    assert ply.exists() and png.exists()
    baked = read_baked_ply(ply)
    assert baked.metadata["material"] == "marble" and baked.metadata["method"] == "auto"
    assert baked.metadata["method_used"] == "tree"  # one light
    # the embedded default keeps its size (given, not inferred) and stands +y up; its light comes from behind
    # (-z for the bunny, which faces +z), to the left and above, to show the glow through the ears
    assert baked.metadata["up"] == "+y" and baked.metadata["source_unit_inferred"] is False
    assert baked.metadata["lights"][0]["direction"] == pytest.approx(
        np.array([-0.5, 0.45, -0.8]) / np.linalg.norm([-0.5, 0.45, -0.8])
    )
    radiance = baked.radiance
    assert np.all(np.isfinite(radiance)) and np.all(radiance >= 0)
    light = np.array(baked.metadata["lights"][0]["direction"])
    facing = baked.normals @ light
    assert radiance[facing > 0.5].mean() > 5 * radiance[facing < -0.5].mean()
    # marble scatters red farther than blue: relative to the lit side, the dark side is redder
    dark, bright = radiance[facing < -0.5].mean(axis=0), radiance[facing > 0.5].mean(axis=0)
    assert dark[0] / bright[0] > dark[2] / bright[2]
    # each mean says over what it is taken; the one over all vertices is the file's, read back by plyfile
    from plyfile import PlyData

    vertex = PlyData.read(str(ply))["vertex"]
    stored = np.stack([np.asarray(vertex[f"radiance_{c}"], dtype=np.float64) for c in "rgb"], axis=1)
    means = {
        m.group(1): np.array([float(m.group(k)) for k in (2, 3, 4)])
        for m in re.finditer(
            r"\n    over (.+?): R (\S+), G (\S+), B (\S+)", out.split("mean radiance toward the normal")[1]
        )
    }
    n_lit = int(re.search(r"vertices lit \(incident flux > 0\): (\d+) of (\d+)", out).group(1))
    assert set(means) == {f"the {n_lit} lit vertices", f"all {len(stored)} vertices"}
    assert means[f"all {len(stored)} vertices"] == pytest.approx(stored.mean(axis=0), abs=6e-5)
    assert 0 < n_lit < len(stored) and np.all(means[f"the {n_lit} lit vertices"] > stored.mean(axis=0))
    # the solve's progress: one line per stage on stderr (a pipe here), no escape codes anywhere
    marked = [repr(line) for line in (out + err).split("\n") if "\r" in line or "\x1b[" in line]
    assert not marked, marked  # the lines themselves, to say where they came from
    assert err.count("bunny: far field done (") == 1 and err.count("bunny: near field done (") == 1


def test_shade_on_a_proxy_interpolates_back_to_every_vertex():
    from translucency.app.shading.scene import shade
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
