"""Batch baking: the CLI agrees with the API, failures stay per file, output names, processes and Dask."""

import os
import re
from concurrent.futures.process import BrokenProcessPool

import numpy as np
import pytest

import translucency
from translucency.app import bake as batch
from translucency.app import cli
from translucency.errors import InvalidParameterError, UnknownMaterialError
from translucency.io.baked import read_baked_ply

BROKEN_PLY = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n"


def write_sphere(path, level=3, radius=20.0):
    """An icosphere (radius in mm) written as a PLY; returns the path."""
    from translucency.geometry.mesh import TriangleMesh
    from translucency.geometry.synthetic import icosphere
    from translucency.io.polydata import to_pyvista

    points, triangles = icosphere(level, radius)
    to_pyvista(TriangleMesh(points, triangles)).save(str(path))
    return path


@pytest.fixture(scope="module")
def scans(tmp_path_factory):
    """Two small spheres and a broken file, in one folder."""
    folder = tmp_path_factory.mktemp("scans")
    (folder / "broken.ply").write_bytes(BROKEN_PLY)
    return {
        "small": write_sphere(folder / "small.ply", 3),
        "large": write_sphere(folder / "large.ply", 4, 30.0),
        "broken": folder / "broken.ply",
    }


def error_lines(text):
    """The error lines of stderr, apart from the progress bars drawn around them (carriage returns, cursor moves)."""
    pieces = re.split(r"[\r\n]", re.sub(r"\x1b\[[0-9;]*[A-Za-z]", "", text))
    return [piece.strip() for piece in pieces if piece.strip().startswith("translucency: error:")]


# --------------------------------------------------------------------------------------------------
# the command line against the API
# --------------------------------------------------------------------------------------------------
def test_cli_bake_equals_shade_on_the_same_mesh(scans, tmp_path, capsys):
    from translucency.io.clean import clean_mesh
    from translucency.io.load import load_mesh
    from translucency.scatter.lights import DirectionalLight

    out = tmp_path / "sphere.ply"
    code = cli.main(
        [
            "bake",
            str(scans["large"]),
            "--unit",
            "cm",
            "--material",
            "skim milk",
            "--light-dir",
            "0,2,1",
            "--method",
            "cutoff",
            "--tol",
            "0.02",
            "-o",
            str(out),
        ]
    )
    assert code == 0, capsys.readouterr().err
    baked = read_baked_ply(out)

    mesh, _ = clean_mesh(load_mesh(scans["large"], unit="cm"))
    expected = translucency.shade(mesh, "skim_milk", DirectionalLight((0, 2, 1), 1.0), method="cutoff", tol=0.02)
    np.testing.assert_allclose(baked.points, mesh.points, rtol=1e-6)
    np.testing.assert_allclose(baked.radiance, expected.radiance, rtol=1e-6, atol=1e-6 * expected.radiance.max())
    np.testing.assert_allclose(baked.b, expected.B, rtol=1e-6, atol=1e-6 * expected.B.max())
    # --unit cm: the sphere of radius 30 file units is 300 mm in radius
    assert np.linalg.norm(baked.points, axis=1).max() == pytest.approx(300.0, rel=1e-5)
    meta = baked.metadata
    assert meta["material"] == "skim_milk" and meta["method"] == "cutoff" and meta["tolerance"] == 0.02
    np.testing.assert_allclose(meta["lights"][0]["direction"], np.array([0, 2, 1]) / np.sqrt(5))
    # the side facing the light is the bright one
    facing = baked.normals @ (np.array([0, 2, 1]) / np.sqrt(5))
    assert baked.radiance[facing > 0.5].mean() > 5 * baked.radiance[facing < -0.5].mean()
    out_text = capsys.readouterr().out
    assert "baked 1 of 1 files" in out_text and str(out) in out_text


def test_the_api_bake_is_exposed_and_agrees_with_the_records(scans, tmp_path):
    records = translucency.bake([scans["small"]], tmp_path, "marble", method="exact", shadows=False)
    (record,) = records
    assert record.ok and record.status == "baked" and record.error is None
    assert record.output == str(tmp_path / "small_marble.ply")
    baked = read_baked_ply(record.output)
    assert record.vertices == len(baked.points) == 642
    # no shadows, one directional light: exactly the vertices whose normal faces it are lit
    light = np.array(baked.metadata["lights"][0]["direction"])
    assert record.lit_sources == np.count_nonzero(baked.normals @ light > 0)
    assert baked.metadata["shadows"] is False


def test_api_errors_before_the_batch_create_nothing(scans, tmp_path):
    out = tmp_path / "never"
    with pytest.raises(UnknownMaterialError):
        translucency.bake([scans["small"]], out, "plutonium")
    with pytest.raises(InvalidParameterError, match="unit"):
        translucency.bake([scans["small"]], out, unit="furlong")
    with pytest.raises(InvalidParameterError, match="tol"):
        translucency.bake([scans["small"]], out, tol=2.0)
    with pytest.raises(InvalidParameterError, match="workers"):
        translucency.bake([scans["small"]], out, workers=0)
    with pytest.raises(InvalidParameterError, match="either"):
        translucency.bake([scans["small"]], out, workers=2, scheduler="tcp://127.0.0.1:1")
    assert not out.exists()


# --------------------------------------------------------------------------------------------------
# failures stay with their file
# --------------------------------------------------------------------------------------------------
def test_a_broken_file_in_the_middle_fails_alone(scans, tmp_path, capsys):
    inputs = [scans["small"], scans["broken"], scans["large"]]
    before = [path.read_bytes() for path in inputs]
    out = tmp_path / "out"
    code = cli.main(["bake", *map(str, inputs), "-o", str(out), "--no-shadows"])
    captured = capsys.readouterr()
    assert code == 1
    assert sorted(os.listdir(out)) == ["large_marble.ply", "small_marble.ply"]  # nothing for broken.ply, no temp file
    assert read_baked_ply(out / "large_marble.ply").metadata["source"] == "large.ply"
    assert [path.read_bytes() for path in inputs] == before
    assert "Traceback" not in captured.err + captured.out
    (row,) = [line for line in captured.out.splitlines() if line.startswith(str(scans["broken"]))]
    assert "failed: " in row and "truncated" in row
    (error,) = error_lines(captured.err)
    assert str(scans["broken"]) in error and "truncated" in error
    assert "baked 2 of 3 files" in captured.out and "1 failed" in captured.out


def test_an_output_name_taken_by_a_folder_stops_the_batch_before_any_work(scans, tmp_path):
    out = tmp_path / "out"
    (out / "small_marble.ply").mkdir(parents=True)
    with pytest.raises(InvalidParameterError, match="small_marble.ply is a folder"):
        batch.bake_files([scans["small"], scans["large"]], out, batch.BakeSettings(shadows=False))
    assert sorted(os.listdir(out)) == ["small_marble.ply"] and os.listdir(out / "small_marble.ply") == []


def test_a_failure_while_writing_leaves_nothing(scans, tmp_path, monkeypatch):
    from translucency.io import atomic

    real_fsync = atomic._fsync

    def full_disk_for_the_small_scan(path, *args):
        if os.path.getsize(path) < 100_000:  # the small sphere's PLY (44 kB), not the large one's (170 kB)
            raise OSError(28, "No space left on device")
        real_fsync(path, *args)

    monkeypatch.setattr(atomic, "_fsync", full_disk_for_the_small_scan)
    out = tmp_path / "out"
    records = batch.bake_files([scans["small"], scans["large"]], out, batch.BakeSettings(shadows=False))
    assert [r.ok for r in records] == [False, True]
    assert (
        records[0].error == "writing small_marble.ply failed (No space left on device): the disk is full; "
        "free some space or write the output elsewhere."
    )
    assert records[0].vertices == 642 and records[0].output is None  # it failed after loading and solving
    assert sorted(os.listdir(out)) == ["large_marble.ply"]  # no temporary file left
    assert batch.exit_code(records) == 1 and batch.exit_code(records[1:]) == 0


def test_an_unexpected_error_is_one_line():
    sentence = batch.failure_sentence(RuntimeError("first line\n  second line"))
    assert "\n" not in sentence and "RuntimeError" in sentence and "second line" in sentence
    assert batch.failure_sentence(InvalidParameterError("bad thing; fix it.")) == "bad thing; fix it."
    assert "worker process" in batch.failure_sentence(BrokenProcessPool())
    assert "install translucency" in batch.failure_sentence(ModuleNotFoundError("no", name="translucency"))


@pytest.mark.parametrize("text", ["1,2", "0,0,0", "north"])
def test_a_bad_light_direction_is_exit_2_and_one_sentence(scans, tmp_path, capsys, text):
    code = cli.main(["bake", str(scans["small"]), "-o", str(tmp_path / "out"), "--light-dir", text])
    captured = capsys.readouterr()
    assert code == 2
    assert captured.err.strip().count("\n") == 0 and "--light-dir" in captured.err
    assert captured.err.startswith("translucency: error:")
    assert not (tmp_path / "out").exists()


# --------------------------------------------------------------------------------------------------
# output names
# --------------------------------------------------------------------------------------------------
def test_output_is_a_file_for_one_input_and_a_folder_otherwise(tmp_path):
    a, b = tmp_path / "a.ply", tmp_path / "b.obj"
    assert batch.output_paths([a], tmp_path / "x.PLY", "marble") == [tmp_path / "x.PLY"]
    assert batch.output_paths([a, b], tmp_path / "o", "skim_milk") == [
        tmp_path / "o" / "a_skim_milk.ply",
        tmp_path / "o" / "b_skim_milk.ply",
    ]
    assert batch.output_paths([a], str(tmp_path / "x.ply") + os.sep, "m") == [tmp_path / "x.ply" / "a_m.ply"]
    (tmp_path / "dir.ply").mkdir()
    assert batch.output_paths([a], tmp_path / "dir.ply", "m") == [tmp_path / "dir.ply" / "a_m.ply"]
    assert batch.output_paths([None], tmp_path, "marble") == [tmp_path / "bunny_marble.ply"]


def test_same_stems_and_input_names_are_never_overwritten(tmp_path):
    inputs = [
        tmp_path / "one" / "scan.ply",
        tmp_path / "two" / "scan.obj",
        tmp_path / "scan_m.ply",
        tmp_path / "scan-2.ply",
    ]
    names = [p.name for p in batch.output_paths(inputs, tmp_path, "m")]
    # scan_m.ply is an input in the output folder: the first scan gets another name
    assert names == ["scan-2_m.ply", "scan-3_m.ply", "scan_m_m.ply", "scan-2-2_m.ply"]
    assert len(set(names)) == len(names)


def test_bad_output_names_are_one_sentence(tmp_path):
    a, b = tmp_path / "a.ply", tmp_path / "b.ply"
    with pytest.raises(InvalidParameterError, match="names one file, but 2 meshes"):
        batch.output_paths([a, b], tmp_path / "all.ply", "m")
    (tmp_path / "notes.txt").write_text("x")
    with pytest.raises(InvalidParameterError, match="existing file, not a folder"):
        batch.output_paths([a, b], tmp_path / "notes.txt", "m")
    with pytest.raises(InvalidParameterError, match="is the input"):
        batch.output_paths([a], a, "m")


def test_cli_refuses_one_file_for_several_meshes(scans, tmp_path, capsys):
    code = cli.main(["bake", str(scans["small"]), str(scans["large"]), "-o", str(tmp_path / "both.ply")])
    captured = capsys.readouterr()
    assert code == 2 and len(error_lines(captured.err)) == 1 and "names one file" in captured.err
    assert captured.err.strip().count("\n") == 0
    assert os.listdir(tmp_path) == []


def test_the_output_suffix_or_format_names_the_format(tmp_path):
    a, b = tmp_path / "a.ply", tmp_path / "b.obj"
    for suffix in (".vtp", ".VTK", ".glb", ".gltf"):
        assert batch.output_paths([a], tmp_path / f"x{suffix}", "m") == [tmp_path / f"x{suffix}"]
    assert batch.output_paths([a, b], tmp_path / "o", "m", "glb") == [
        tmp_path / "o" / "a_m.glb",
        tmp_path / "o" / "b_m.glb",
    ]
    assert batch.output_paths([a], tmp_path / "x.vtp", "m", "vtp") == [tmp_path / "x.vtp"]
    with pytest.raises(InvalidParameterError, match=r"names a \.obj file, which a bake does not write"):
        batch.output_paths([a], tmp_path / "x.obj", "m")  # a mesh's suffix names a file, not a folder
    with pytest.raises(InvalidParameterError, match="names a .vtp file but format='glb' was given"):
        batch.output_paths([a], tmp_path / "x.vtp", "m", "glb")
    with pytest.raises(InvalidParameterError, match="format must be one of ply, vtp, vtk, glb, gltf"):
        batch.output_paths([a], tmp_path / "o", "m", "obj")


def test_cli_bakes_one_scan_to_vtp_glb_and_ply_with_the_same_numbers(scans, tmp_path, capsys):
    import json
    import struct

    import plyfile
    import pyvista
    import trimesh

    arguments = ["bake", str(scans["small"]), "--unit", "mm", "--method", "exact", "--no-shadows"]
    for name in ("x.vtp", "x.glb", "x.ply"):
        assert cli.main([*arguments, "-o", str(tmp_path / name)]) == 0, capsys.readouterr().err
    assert sorted(os.listdir(tmp_path)) == ["x.glb", "x.ply", "x.vtp"]
    vertex = plyfile.PlyData.read(str(tmp_path / "x.ply"))["vertex"]
    radiance = np.stack([vertex[f"radiance_{c}"] for c in "rgb"], axis=1)  # float32
    colours = np.stack([vertex[c] for c in ("red", "green", "blue")], axis=1)
    vtp = pyvista.read(str(tmp_path / "x.vtp"))
    np.testing.assert_array_equal(vtp.point_data["radiance"].astype(np.float32), radiance)
    np.testing.assert_array_equal(vtp.point_data["colors"], colours)
    np.testing.assert_allclose(vtp.point_data["luminance"], vertex["quality"], rtol=1e-6)
    (glb,) = trimesh.load(str(tmp_path / "x.glb"), process=False).geometry.values()
    np.testing.assert_array_equal(glb.vertex_attributes["_RADIANCE"], radiance)
    np.testing.assert_array_equal(glb.vertices, np.stack([vertex[a] for a in "xyz"], axis=1) / np.float32(1000))
    data = (tmp_path / "x.glb").read_bytes()
    (length,) = struct.unpack_from("<I", data, 12)
    extras = json.loads(data[20 : 20 + length])["scenes"][0]["extras"]
    assert extras["method"] == vtp.field_data["method"][0] == "exact" and extras["shadows"] is False


def test_cli_format_names_the_files_in_a_folder_and_a_conflict_is_one_sentence(scans, tmp_path, capsys):
    import pyvista

    out = tmp_path / "out"
    assert (
        cli.main(["bake", str(scans["small"]), "--unit", "mm", "--no-shadows", "--format", "vtk", "-o", str(out)]) == 0
    )
    assert os.listdir(out) == ["small_marble.vtk"]
    assert pyvista.read(str(out / "small_marble.vtk")).point_data["radiance"].shape == (642, 3)
    capsys.readouterr()
    code = cli.main(["bake", str(scans["small"]), "--format", "glb", "-o", str(tmp_path / "x.vtp")])
    captured = capsys.readouterr()
    assert code == 2 and len(error_lines(captured.err)) == 1 and "names a .vtp file but --format glb" in captured.err
    assert not (tmp_path / "x.vtp").exists()


def test_no_mesh_bakes_the_embedded_default_to_the_default_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["bake", "--resolution", "8", "--no-shadows"]) == 0, capsys.readouterr().err
    baked = read_baked_ply(tmp_path / "translucency-output" / "bunny_marble.ply")
    assert baked.metadata["source"] == "bunny.obj" and "proxy" in baked.metadata["resolution"]
    assert np.ptp(baked.points, axis=0).max() == pytest.approx(155.0, rel=1e-3)  # the bunny is 155 mm across
    assert "embedded default scan" in capsys.readouterr().out


# --------------------------------------------------------------------------------------------------
# progress
# --------------------------------------------------------------------------------------------------
class Recorder(batch.BakeProgress):
    def __init__(self):
        self.events = []

    def start(self, sources, outputs):
        self.events.append(("start", len(sources)))

    def stage(self, index, stage, fraction):
        self.events.append((index, stage, fraction))

    def finished(self, index, record):
        self.events.append((index, "finished", record.ok))

    def end(self):
        self.events.append(("end",))


def test_progress_reports_every_stage_and_every_file(scans, tmp_path):
    recorder = Recorder()
    batch.bake_files([scans["small"], scans["broken"]], tmp_path, batch.BakeSettings(), progress=recorder)
    events = recorder.events
    assert events[0] == ("start", 2) and events[-1] == ("end",)
    stages = [e[1] for e in events if e[0] == 0 and e[1] != "finished"]
    assert stages[0] == "loading" and stages[-1] == "writing" and "far field" in stages and "near field" in stages
    assert (0, "finished", True) in events and (1, "finished", False) in events
    assert events.index((0, "finished", True)) < events.index((1, "loading", 0.0))


def test_console_progress_prints_failures_and_warnings(tmp_path):
    import io

    stream = io.StringIO()
    progress = batch.ConsoleProgress(file=stream, terminal=True)  # bars, as on a terminal
    progress.start(["a.ply", "b.ply"], ["o/a.ply", "o/b.ply"])
    progress.stage(0, "far field", 0.5)
    progress.finished(0, batch.BakeRecord("a.ply", "o/a.ply", warnings=("a is 0.2 mm across; did you mean m?",)))
    progress.finished(1, batch.BakeRecord("b.ply", error="b.ply is empty."))
    progress.end()
    text = stream.getvalue()
    assert "a.ply: far field" in text and "2/2" in text
    assert "translucency: warning: a.ply: a is 0.2 mm across" in text
    assert "translucency: error: b.ply is empty." in text


def test_summary_table():
    records = [
        batch.BakeRecord("a.ply", "o/a_m.ply", 642, 300, 1.26),
        batch.BakeRecord("long/name/b.ply", None, None, None, 0.04, "b.ply is empty; export it again."),
    ]
    lines = batch.format_summary(records, 3.0).splitlines()
    assert lines[0].split() == ["file", "vertices", "lit", "solver", "vertices", "time", "[s]", "output", "status"]
    assert lines[2].split() == ["a.ply", "642", "300", "1.3", "o/a_m.ply", "baked"]
    assert lines[3].split()[:5] == ["long/name/b.ply", "-", "-", "0.0", "-"]
    assert lines[3].endswith("failed: b.ply is empty; export it again.")
    assert lines[2].index("o/a_m.ply") == lines[3].index("-", len("long/name/b.ply") + 20)  # columns line up
    assert lines[2].index("baked") == lines[3].index("failed")
    assert lines[-1] == "baked 1 of 2 files in 3.0 s (wall time); 1 failed"


# --------------------------------------------------------------------------------------------------
# processes and Dask
# --------------------------------------------------------------------------------------------------
def test_two_workers_give_the_same_files_as_one(scans, tmp_path, capsys):
    inputs = [str(scans["small"]), str(scans["broken"]), str(scans["large"])]
    serial = batch.bake_files(inputs, tmp_path / "serial", batch.BakeSettings())
    parallel = batch.bake_files(inputs, tmp_path / "parallel", batch.BakeSettings(), workers=2)
    assert [r.ok for r in parallel] == [True, False, True]
    assert parallel[1].error == serial[1].error
    for a, b in zip(serial, parallel):
        assert (a.source, a.vertices, a.lit_sources) == (b.source, b.vertices, b.lit_sources)
    for name in ("small_marble.ply", "large_marble.ply"):
        assert (tmp_path / "serial" / name).read_bytes() == (tmp_path / "parallel" / name).read_bytes()
    # each of the two workers runs numba on half the cores
    assert parallel[0].threads == max(1, batch.available_cores() // 2)


def square_or_die(x):
    """A job for the process runner: x squared, or the worker process dies when x < 0."""
    if x < 0:
        os._exit(3)
    return x * x


def test_a_dying_worker_loses_only_its_own_job():
    results = {}
    batch._run_in_processes(square_or_die, [(1,), (2,), (-1,), (4,), (5,)], 2, results.__setitem__)
    assert sorted(results) == [0, 1, 2, 3, 4]
    assert [results[i] for i in (0, 1, 3, 4)] == [1, 4, 16, 25]
    assert isinstance(results[2], ChildProcessError) and "stopped while baking this file" in str(results[2])


def test_dask_cluster_bakes_the_same_files(scans, tmp_path, capsys):
    distributed = pytest.importorskip("distributed")
    inputs = [str(scans["small"]), str(scans["broken"]), str(scans["large"])]
    serial = batch.bake_files(inputs, tmp_path / "serial", batch.BakeSettings())
    with distributed.LocalCluster(
        n_workers=1, processes=False, threads_per_worker=1, dashboard_address=None
    ) as cluster:
        code = cli.main(["bake", *inputs, "-o", str(tmp_path / "dask"), "--scheduler", cluster.scheduler_address])
    captured = capsys.readouterr()
    assert code == 1 and len(error_lines(captured.err)) == 1 and "broken.ply" in error_lines(captured.err)[0]
    for record in serial:
        if record.ok:
            name = os.path.basename(record.output)
            assert (tmp_path / "dask" / name).read_bytes() == (tmp_path / "serial" / name).read_bytes()
            assert str(tmp_path / "dask" / name) in captured.out
    assert sorted(os.listdir(tmp_path / "dask")) == ["large_marble.ply", "small_marble.ply"]


def test_dask_records_come_back_through_a_client(scans, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=1, processes=False, threads_per_worker=1, dashboard_address=None
    ) as cluster:
        with distributed.Client(cluster) as client:
            records = translucency.bake([scans["small"]], tmp_path, scheduler=client, shadows=False)
            assert client.status == "running"  # a client passed in stays open
    (record,) = records
    assert record.ok and record.source == str(scans["small"]) and record.vertices == 642
    assert record.threads == batch.available_cores()  # one task at a time per worker: every core
    assert read_baked_ply(tmp_path / "small_marble.ply").metadata["material"] == "marble"


def test_an_unreachable_scheduler_is_exit_2(scans, tmp_path, capsys, monkeypatch):
    pytest.importorskip("distributed")
    monkeypatch.setattr(batch, "DASK_CONNECT_TIMEOUT_S", 1.0)
    code = cli.main(["bake", str(scans["small"]), "-o", str(tmp_path / "out"), "--scheduler", "tcp://127.0.0.1:9"])
    captured = capsys.readouterr()
    assert code == 2 and "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in captured.err
    assert len(error_lines(captured.err)) == 1 and not (tmp_path / "out").exists()


def test_bake_is_in_the_public_api():
    assert "bake" in translucency.__all__ and translucency.bake is batch.bake


# --------------------------------------------------------------------------------------------------
# units and orientation
# --------------------------------------------------------------------------------------------------
def test_bake_without_unit_infers_says_it_once_and_records_it(tmp_path, capsys):
    path = write_sphere(tmp_path / "ball.ply", 3, 0.02)  # 0.04 units across: read as metres, 40 mm
    out = tmp_path / "out"
    assert cli.main(["bake", str(path), "--no-shadows", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    line = "ball.ply: no --unit given; 0.04 units across, read as metres (40 mm); pass --unit to override"
    assert err.count(line) == 1 and "ball.ply: ball.ply" not in err
    baked = read_baked_ply(out / "ball_marble.ply")
    assert baked.metadata["source_unit"] == "m" and baked.metadata["source_unit_name"] == "metres"
    assert baked.metadata["source_mm_per_unit"] == 1000.0 and baked.metadata["source_unit_inferred"] is True
    assert baked.metadata["length_unit"] == "mm"
    assert baked.metadata["up"] == "+y" and np.ptp(baked.points[:, 0]) == pytest.approx(40.0, rel=1e-3)
    given = translucency.bake([path], tmp_path / "given", unit="m", shadows=False, up="z")
    metadata = read_baked_ply(given[0].output).metadata
    assert metadata["source_unit_inferred"] is False and metadata["up"] == "+z" and metadata["up_inferred"] is False


@pytest.mark.slow
def test_worker_processes_spell_the_flag_as_the_command_line_does(tmp_path, capsys):
    paths = [write_sphere(tmp_path / f"ball{k}.ply", 2, 0.02) for k in range(2)]
    assert cli.main(["bake", *map(str, paths), "--no-shadows", "--workers", "2", "-o", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    assert err.count("no --unit given") == 2 and "unit=" not in err


def test_bad_up_is_one_sentence():
    with pytest.raises(InvalidParameterError, match="up axis must be one of"):
        batch.BakeSettings(up="sideways")


@pytest.mark.slow  # two worker processes: about 20 s
def test_preview_writes_the_picture_beside_each_bake_also_from_worker_processes(scans, tmp_path, capsys):
    import imageio.v3 as iio

    inputs = [str(scans["small"]), str(scans["large"])]
    code = cli.main(["bake", *inputs, "-o", str(tmp_path), "--preview", "--workers", "2", "--method", "exact"])
    assert code == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "large_marble.ply",
        "large_marble.png",
        "small_marble.ply",
        "small_marble.png",
    ]
    for name in ("small_marble.png", "large_marble.png"):
        image = iio.imread(tmp_path / name)
        assert image.ndim == 3 and image.shape[1] > image.shape[0] > 300  # two views side by side
    # without --preview no picture
    records = translucency.bake([scans["small"]], tmp_path / "plain", "marble", method="exact")
    assert records[0].ok and [p.suffix for p in (tmp_path / "plain").iterdir()] == [".ply"]
    assert batch.BakeSettings(preview=True).preview and not batch.BakeSettings().preview


def test_the_parallel_bake_works_from_a_plain_script(tmp_path):
    """The README's ``tl.bake([...], "baked/", "marble", workers=2)`` in a script without an
    ``if __name__ == "__main__":`` guard: the workers are ``python -c`` children, which do not import the script
    again (spawned ones did, and every file was reported as a crashed worker, with exit 0 and nothing baked)."""
    import subprocess
    import sys
    import textwrap

    scans = [write_sphere(tmp_path / f"{name}.ply", 2, 20.0) for name in ("a", "b")]
    script = tmp_path / "plain.py"
    script.write_text(
        textwrap.dedent(f"""
            import translucency as tl
            records = tl.bake({[str(s) for s in scans]!r}, {str(tmp_path / "baked")!r}, "marble", unit="mm",
                              workers=2, shadows=False)
            print("baked", sum(r.ok for r in records))
        """)
    )
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "baked 2" in done.stdout
    assert sorted(os.listdir(tmp_path / "baked")) == ["a_marble.ply", "b_marble.ply"]
    assert "Traceback" not in done.stderr
