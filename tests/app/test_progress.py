"""Progress on the console: bars on a terminal only, one plain line per stage in a pipe or a log, none with --quiet."""

import io
import re
import subprocess
import sys

import pytest

from translucency.app import bake as batch
from translucency.app import cli
from translucency.app.progress import StageProgress, is_terminal, progress_mode

ESCAPES = ("\r", "\x1b[")


def write_sphere(path, level=3, radius=20.0):
    """An icosphere (radius in mm) written as a PLY by PyVista; returns the path."""
    from translucency.geometry.mesh import TriangleMesh
    from translucency.geometry.synthetic import icosphere
    from translucency.io.polydata import to_pyvista

    points, triangles = icosphere(level, radius)
    to_pyvista(TriangleMesh(points, triangles)).save(str(path))
    return path


class Terminal(io.StringIO):
    """A stream that says it is a terminal."""

    def isatty(self):
        return True


def test_the_mode_follows_the_stream_and_quiet():
    assert progress_mode(io.StringIO()) == "lines"
    assert progress_mode(Terminal()) == "bars"
    assert progress_mode(Terminal(), quiet=True) == "off"
    assert progress_mode(io.StringIO(), terminal=True) == "bars"
    closed = io.StringIO()
    closed.close()
    assert not is_terminal(closed) and not is_terminal(object())


def test_lines_mode_writes_one_plain_line_per_stage():
    stream = io.StringIO()
    progress = StageProgress("scan.ply", stream)
    for stage in ("far field", "near field"):
        for fraction in (0.0, 0.25, 0.5, 1.0):
            progress(stage, fraction)
    progress("near field", 1.0)  # a stage reported done twice is one line
    progress.close()
    lines = stream.getvalue().splitlines()
    assert [re.sub(r"\(\d+\.\d\d s\)$", "(t)", line) for line in lines] == [
        "scan.ply: far field done (t)",
        "scan.ply: near field done (t)",
    ]
    assert not any(code in stream.getvalue() for code in ESCAPES)


def test_a_stage_that_comes_back_adds_up_to_one_line():
    """One solve per light direction: far and near field alternate, each reaching 1 at the last direction."""
    stream = io.StringIO()
    progress = StageProgress("scan.ply", stream)
    for k in range(3):
        for stage in ("far field", "near field"):
            progress(stage, k / 3)
            progress(stage, (k + 1) / 3)
    assert stream.getvalue().count("far field done") == 1 and stream.getvalue().count("near field done") == 1
    assert set(progress.seconds) == {"far field", "near field"}


def test_bars_mode_draws_bars_and_quiet_draws_nothing():
    terminal = Terminal()
    with StageProgress("scan.ply", terminal) as progress:
        progress("far field", 0.5)
    assert "scan.ply: far field" in terminal.getvalue() and "\r" in terminal.getvalue()
    quiet = Terminal()
    with StageProgress("scan.ply", quiet, quiet=True) as progress:
        progress("far field", 1.0)
    assert quiet.getvalue() == ""


def test_console_progress_of_worker_files_is_one_line_per_file():
    """Files baked in worker processes or on Dask report no stages: their progress is the file line."""
    stream = io.StringIO()
    progress = batch.ConsoleProgress(file=stream)
    progress.start(["a/a.ply", "b.ply"], ["o/a.ply", "o/b.ply"])
    progress.finished(1, batch.BakeRecord("b.ply", error="b.ply is empty.", seconds=0.01))
    progress.finished(0, batch.BakeRecord("a/a.ply", "o/a.ply", seconds=1.5))
    progress.end()
    assert stream.getvalue().splitlines() == [
        "translucency: error: b.ply is empty.",
        "[1/2] b.ply: failed (0.01 s)",
        "[2/2] a.ply: baked (1.50 s)",
    ]


def test_console_progress_quiet_keeps_errors_and_warnings_only():
    stream = io.StringIO()
    progress = batch.ConsoleProgress(file=stream, quiet=True)
    progress.start(["a.ply", "b.ply"], ["o/a.ply", "o/b.ply"])
    progress.stage(0, "far field", 1.0)
    progress.finished(0, batch.BakeRecord("a.ply", "o/a.ply", warnings=("a.ply is 0.2 mm across; did you mean m?",)))
    progress.finished(1, batch.BakeRecord("b.ply", error="b.ply is empty."))
    progress.end()
    assert stream.getvalue().splitlines() == [
        "translucency: warning: a.ply is 0.2 mm across; did you mean m?",
        "translucency: error: b.ply is empty.",
    ]


def test_bake_into_a_pipe_prints_one_line_per_stage_and_no_escape_codes(tmp_path):
    sphere = write_sphere(tmp_path / "sphere.ply")
    done = subprocess.run(
        [sys.executable, "-m", "translucency", "bake", str(sphere), "--unit", "mm", "-o", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    assert not any(code in done.stderr + done.stdout for code in ESCAPES)
    lines = [line for line in done.stderr.splitlines() if not line.startswith("translucency: ")]  # first-run notice
    stages = [line.split(" done ")[0] for line in lines if " done (" in line]
    expected = ("loading", "far field", "near field", "bounces", "writing")  # bounces: the default 1
    assert stages == [f"sphere.ply: {stage}" for stage in expected]
    assert re.fullmatch(r"\[1/1\] sphere\.ply: baked \(\d+\.\d\d s\)", lines[-1])
    assert len(lines) == len(expected) + 1
    assert "baked 1 of 1 files" in done.stdout


def test_bake_says_the_inferred_unit_before_the_solve_as_view_does(tmp_path):
    sphere = write_sphere(tmp_path / "sphere.ply")  # no --unit: 40 units across, read as millimetres
    done = subprocess.run(
        [sys.executable, "-m", "translucency", "bake", str(sphere), "-o", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    lines = done.stderr.splitlines()
    unit = [k for k, line in enumerate(lines) if "no --unit given" in line]
    far = [k for k, line in enumerate(lines) if "far field done" in line]
    assert len(unit) == 1 and far and unit[0] < far[0]  # said as it happens, once
    assert lines[unit[0]].startswith("translucency: sphere.ply: no --unit given;")  # a note, as in view


def test_quiet_prints_no_progress(tmp_path, capsys):
    sphere = write_sphere(tmp_path / "sphere.ply")
    assert cli.main(["bake", str(sphere), "--unit", "mm", "-o", str(tmp_path / "a"), "-q"]) == 0
    captured = capsys.readouterr()
    assert " done (" not in captured.err and "[1/1]" not in captured.err
    assert "baked 1 of 1 files" in captured.out
    # before the subcommand too
    assert cli.main(["-q", "bake", str(sphere), "--unit", "mm", "-o", str(tmp_path / "b")]) == 0
    assert " done (" not in capsys.readouterr().err
    # and without it the same run does print its stages
    assert cli.main(["bake", str(sphere), "--unit", "mm", "-o", str(tmp_path / "c")]) == 0
    assert "sphere.ply: far field done (" in capsys.readouterr().err


@pytest.mark.slow
def test_bake_in_worker_processes_follows_the_same_rule(tmp_path, capsys):
    inputs = [str(write_sphere(tmp_path / f"s{k}.ply", 2, 20.0 + k)) for k in range(2)]
    assert cli.main(["bake", *inputs, "--unit", "mm", "-o", str(tmp_path / "out"), "--workers", "2"]) == 0
    err = capsys.readouterr().err
    assert not any(code in err for code in ESCAPES)
    progress = sorted(line for line in err.splitlines() if not line.startswith("translucency: "))
    assert [line[:6] for line in progress] == ["[1/2] ", "[2/2] "]
    assert {line.split(": ")[0][6:] for line in progress} == {"s0.ply", "s1.ply"}


def test_quiet_is_read_before_or_after_the_command():
    parser = cli.build_parser()
    assert parser.parse_args(["-q"]).quiet and parser.parse_args(["-q"]).func is cli.cmd_main_job
    assert not hasattr(parser.parse_args([]), "quiet")
    for argv in (["-q", "bake"], ["bake", "-q"], ["compare", "--quiet"]):
        assert parser.parse_args(argv).quiet
    assert not hasattr(parser.parse_args(["bake"]), "quiet")
