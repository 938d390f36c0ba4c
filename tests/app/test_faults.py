"""Faults leave nothing behind: killed runs, FIFOs, full and read-only disks, long names, odd vectors.

Each test asserts the exit code, the sentence and what is (not) left in the output folder. The runs
killed with SIGKILL are real processes: a small driver starts the command line in a subprocess and,
for the points that are too short to hit by chance (the solve, the write), makes that step wait so
the test can kill the process there; the next run is the ordinary command line.
"""

import contextlib
import errno
import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from tests.app.test_bake import write_sphere
from translucency.app import cli
from translucency.io import atomic
from translucency.io.baked import read_baked_ply

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="process and mount checks use Linux")

# the driver: cli.main(argv) with one step made to wait (pause point "none", "load", "shade" or "fsync")
DRIVER = textwrap.dedent("""
    import sys, time
    point, argv = sys.argv[1], sys.argv[2:]
    def pause(function):
        def waiting(*args, **kwargs):
            print("PAUSED", flush=True)
            time.sleep(600)
            return function(*args, **kwargs)
        return waiting
    if point == "load":
        from translucency.app.shading import scan
        scan.load_scan = pause(scan.load_scan)
    elif point == "shade":
        from translucency.app.shading import scene
        scene.Scene.shade_with = pause(scene.Scene.shade_with)
    elif point == "fsync":
        from translucency.io import atomic
        atomic._fsync = pause(atomic._fsync)
    from translucency.app import cli
    sys.exit(cli.main(argv))
""")


@pytest.fixture(scope="module")
def sphere(tmp_path_factory):
    return write_sphere(tmp_path_factory.mktemp("scan") / "sphere.ply")


def error_lines(text):
    pieces = re.split(r"[\r\n]", re.sub(r"\x1b\[[0-9;]*[A-Za-z]", "", text))
    return [piece.strip() for piece in pieces if piece.strip().startswith("translucency: error:")]


def one_sentence(text):
    """The one error line of a run's stderr (no traceback)."""
    lines = error_lines(text)
    assert len(lines) == 1, text
    assert "Traceback" not in text
    return lines[0]


def leftovers(*folders):
    """Every name starting with the tool's temporary prefix in the folders (recursively)."""
    found = []
    for folder in folders:
        for path in Path(folder).rglob("*") if Path(folder).is_dir() else []:
            if path.name.startswith(atomic.TEMPORARY_PREFIX):
                found.append(path)
    return found


def start_driver(point, *argv, cwd):
    return subprocess.Popen(
        [sys.executable, "-c", DRIVER, point, *map(str, argv)],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )


def wait_for_pause(process, timeout=180):
    """Read the driver's stdout until it says PAUSED."""
    deadline = time.monotonic() + timeout
    for line in process.stdout:
        if line.startswith("PAUSED"):
            return
        assert time.monotonic() < deadline, "the driver did not reach its pause"
    raise AssertionError(f"the driver ended (exit {process.wait()}) before its pause")


def kill(process):
    process.kill()
    process.wait(timeout=30)
    process.stdout.close()


# --------------------------------------------------------------------------------------------------
# kill -9, then the next run sweeps
# --------------------------------------------------------------------------------------------------
@pytest.mark.slow
@pytest.mark.parametrize("point", ["start", "shade", "fsync"], ids=["at-start", "during-solve", "during-write"])
def test_a_killed_bake_leaves_nothing_the_next_run_keeps(sphere, tmp_path, capsys, point):
    out = tmp_path / "out"
    # "start": as the scan is read (a plain sleep before the kill let a warm bake of the small sphere finish)
    process = start_driver(
        "load" if point == "start" else point, "bake", sphere, "-o", out, "--no-shadows", cwd=tmp_path
    )
    wait_for_pause(process)
    if point == "fsync":  # the complete PLY is on disk under its temporary name, as in the issue
        (temporary,) = leftovers(out)
        assert temporary.stat().st_size > 40_000 and atomic.parse_temporary_name(temporary.name)["pid"] == process.pid
    kill(process)
    assert not (out / "sphere_marble.ply").exists()
    code = cli.main(["bake", str(sphere), "-o", str(out), "--no-shadows"])
    assert code == 0 and capsys.readouterr().err.count("translucency: error") == 0
    assert os.listdir(out) == ["sphere_marble.ply"]  # the stale temporary was swept
    assert leftovers(tmp_path) == []


@pytest.mark.slow
def test_a_compare_killed_while_writing_is_swept_by_the_next_with_the_same_output(sphere, tmp_path, capsys):
    out = tmp_path / "cmp"
    argv = ["compare", sphere, "-o", out, "--cell-size", "64x64", "--no-shadows"]
    process = start_driver("fsync", *argv, cwd=tmp_path)
    wait_for_pause(process)
    (staging,) = [p for p in tmp_path.iterdir() if p.name.startswith(atomic.TEMPORARY_PREFIX)]
    assert staging.name.endswith(".partial") and staging.is_dir()
    kill(process)
    assert not out.exists()
    assert cli.main([str(a) for a in argv]) == 0
    capsys.readouterr()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cmp"] and leftovers(tmp_path) == []
    assert "grid.png" in os.listdir(out)


def descendants(pid):
    """Every live process below ``pid`` (from /proc)."""
    parents = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        with contextlib.suppress(OSError, IndexError, ValueError):
            fields = stat.read_bytes().rsplit(b")", 1)[1].split()
            if fields[0] != b"Z":
                parents[int(stat.parent.name)] = int(fields[1])
    found, frontier = [], [pid]
    while frontier:
        frontier = [child for child, parent in parents.items() if parent in frontier]
        found += frontier
    return found


def alive(pid):
    try:
        return Path(f"/proc/{pid}/stat").read_bytes().rsplit(b")", 1)[1].split()[0] != b"Z"
    except OSError:
        return False


@pytest.mark.slow
def test_the_workers_end_within_5_s_of_their_parents_kill(tmp_path):
    scans = [write_sphere(tmp_path / f"{name}.ply", 6, 30.0) for name in ("a", "b")]  # 40,962 vertices each
    out = tmp_path / "out"
    process = start_driver("none", "bake", *scans, "-o", out, "--workers", "2", cwd=tmp_path)
    deadline = time.monotonic() + 180
    while len([p for p in descendants(process.pid) if b"_answer" in Path(f"/proc/{p}/cmdline").read_bytes()]) < 2:
        assert time.monotonic() < deadline and process.poll() is None, "the workers did not start"
        time.sleep(0.2)
    time.sleep(3.0)  # the workers import the package and start on their files
    children = descendants(process.pid)
    kill(process)
    killed = time.monotonic()
    while any(alive(pid) for pid in children) and time.monotonic() < killed + 5.0:
        time.sleep(0.1)
    assert [pid for pid in children if alive(pid)] == []
    assert not out.exists() or [p for p in out.iterdir() if p.suffix == ".ply"] == []


# --------------------------------------------------------------------------------------------------
# only regular files are read
# --------------------------------------------------------------------------------------------------
@contextlib.contextmanager
def deadline(seconds):
    """Fail instead of hanging (opening a FIFO blocks until a writer comes)."""

    def expired(*_):
        raise TimeoutError(f"still running after {seconds} s")

    previous = signal.signal(signal.SIGALRM, expired)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def test_a_fifo_fails_at_once_and_the_batch_goes_on(sphere, tmp_path, capsys, fifo):
    fifo = fifo("pipe.ply")
    out = tmp_path / "out"
    with deadline(120):
        code = cli.main(["bake", str(fifo), str(sphere), "-o", str(out), "--no-shadows"])
    assert code == 1
    line = one_sentence(capsys.readouterr().err)
    assert line == (  # the path once
        f"translucency: error: {fifo} is a FIFO (named pipe), not a regular file; pass a mesh file stored on disk."
    )
    assert os.listdir(out) == ["sphere_marble.ply"]
    with deadline(60):
        assert cli.main(["inspect", str(fifo)]) == 2
    assert "is a FIFO (named pipe)" in one_sentence(capsys.readouterr().err)
    with deadline(60):
        assert cli.main(["inspect", "/dev/zero"]) == 2
    assert "is a character device, not a regular file" in one_sentence(capsys.readouterr().err)


# --------------------------------------------------------------------------------------------------
# full and read-only disks
# --------------------------------------------------------------------------------------------------
@contextlib.contextmanager
def mounted_tmpfs(folder, options):
    """A small tmpfs at ``folder`` (root only; the test is skipped where mounting is not allowed)."""
    folder.mkdir()
    if (
        os.geteuid() != 0
        or subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(folder)], capture_output=True).returncode
        != 0
    ):
        pytest.skip("mounting a tmpfs needs root")
    try:
        yield folder
    finally:
        subprocess.run(["umount", "-l", str(folder)], check=False)


def commands(sphere, output):
    """Every command that writes, with ``output`` as where it writes (a folder for bake and compare)."""
    return {
        "bake": ["bake", str(sphere), "-o", str(output / "baked"), "--no-shadows"],
        "compare": ["compare", str(sphere), "-o", str(output / "cmp"), "--cell-size", "64x64", "--no-shadows"],
        "inspect": ["inspect", str(sphere), "-o", str(output / "repaired.ply")],
        "view": [
            "view",
            str(sphere),
            "--screenshot",
            str(output / "view.png"),
            "--window-size",
            "64x64",
            "--no-shadows",
        ],
        "main job": [],
    }


@pytest.mark.slow
@pytest.mark.parametrize("command", ["bake", "compare", "inspect", "view", "main job"])
def test_a_full_disk_is_one_sentence_with_exit_1_and_leaves_nothing(sphere, tmp_path, capsys, monkeypatch, command):
    with mounted_tmpfs(tmp_path / "disk", "size=64k") as disk:
        filler = disk / "filler"
        with contextlib.suppress(OSError), open(filler, "wb", buffering=0) as stream:
            while True:  # the disk is full from here on
                stream.write(b"\0" * 1024)
        monkeypatch.chdir(disk)  # the main job writes into translucency-output/ here
        code = cli.main(commands(sphere, disk)[command])
        line = one_sentence(capsys.readouterr().err)
        assert code == 1, line
        assert (
            "failed (No space left on device): the disk is full; free some space or write the output elsewhere." in line
        )
        assert leftovers(disk) == []
        assert [p for p in disk.rglob("*") if p.is_file()] == [filler]


@pytest.mark.parametrize(
    "command", ["bake", "compare", "inspect", "view", pytest.param("main job", marks=pytest.mark.slow)]
)
def test_a_simulated_full_disk_is_exit_1_for_every_command(sphere, tmp_path, capsys, monkeypatch, command):
    def full(*args):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(atomic, "_fsync", full)
    monkeypatch.chdir(tmp_path)
    code = cli.main(commands(sphere, tmp_path)[command])
    line = one_sentence(capsys.readouterr().err)
    assert code == 1 and "(No space left on device): the disk is full" in line
    assert [p for p in tmp_path.rglob("*") if p.is_file()] == []


@pytest.mark.parametrize("command", ["bake", "compare", "inspect", "view", "main job"])
def test_a_read_only_disk_is_found_before_any_work(sphere, tmp_path, capsys, monkeypatch, command):
    from translucency.app.shading import scene as pipeline

    def no_work(*args, **kwargs):
        raise AssertionError("the work started")

    monkeypatch.setattr(pipeline.Scene, "shade", no_work)
    monkeypatch.setattr(pipeline, "shade", no_work)
    with mounted_tmpfs(tmp_path / "ro", "ro,size=16k") as disk:
        monkeypatch.chdir(disk)
        code = cli.main(commands(sphere, disk)[command])
        line = one_sentence(capsys.readouterr().err)
        assert code == 2 and "(Read-only file system): the file system is read-only" in line, line
        assert os.listdir(disk) == []


# --------------------------------------------------------------------------------------------------
# names and vectors
# --------------------------------------------------------------------------------------------------
def test_a_240_character_stem_bakes(sphere, tmp_path, capsys):
    long = tmp_path / ("s" * 240 + ".ply")
    long.write_bytes(sphere.read_bytes())
    out = tmp_path / "out"
    assert cli.main(["bake", str(long), "-o", str(out), "--no-shadows"]) == 0
    capsys.readouterr()
    assert os.listdir(out) == ["s" * 240 + "_marble.ply"]


def test_a_huge_or_tiny_light_vector_bakes_the_same_as_the_unit_vector(sphere, tmp_path, capsys):
    radiance = {}
    for name, vector in (
        ("unit", "0.7071067811865476,0.7071067811865476,0"),
        ("huge", "1e300,1e300,0"),
        ("tiny", "1e-300,1e-300,0"),
    ):
        output = tmp_path / f"{name}.ply"
        assert cli.main(["bake", str(sphere), "-o", str(output), "--light-dir", vector]) == 0
        radiance[name] = read_baked_ply(output).radiance
    capsys.readouterr()
    assert radiance["unit"].max() > 0
    np.testing.assert_array_equal(radiance["huge"], radiance["unit"])
    np.testing.assert_array_equal(radiance["tiny"], radiance["unit"])


@pytest.mark.parametrize("vector", ["-1,0.3,-0.5", "-1e300,0,0"])
def test_a_negative_vector_is_taken_as_written(sphere, tmp_path, capsys, vector):
    separate, joined = tmp_path / "separate.ply", tmp_path / "joined.ply"
    assert cli.main(["bake", str(sphere), "-o", str(separate), "--light-dir", vector, "--no-shadows"]) == 0
    assert cli.main(["bake", str(sphere), "-o", str(joined), f"--light-dir={vector}", "--no-shadows"]) == 0
    capsys.readouterr()
    np.testing.assert_array_equal(read_baked_ply(separate).radiance, read_baked_ply(joined).radiance)


@pytest.mark.parametrize("vector, words", [("0,0,0", "zero vector"), ("-inf,0,0", "finite"), ("-nan,1,0", "finite")])
def test_only_zero_or_non_finite_vectors_are_refused(sphere, tmp_path, capsys, vector, words):
    assert cli.main(["bake", str(sphere), "-o", str(tmp_path / "out"), "--light-dir", vector]) == 2
    assert words in one_sentence(capsys.readouterr().err) and not (tmp_path / "out").exists()


def test_the_help_says_the_frame_and_how_to_write_a_negative_direction(capsys):
    with pytest.raises(SystemExit):
        cli.main(["bake", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "in the scan's own frame" in text and "-1,0.3,-0.5" in text


# --------------------------------------------------------------------------------------------------
# messages without library internals
# --------------------------------------------------------------------------------------------------
def test_five_faces_without_vertices_give_one_sentence_and_no_warnings(tmp_path, capsys):
    path = tmp_path / "five.ply"
    path.write_text(
        "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 5\nproperty list uchar int vertex_indices\nend_header\n" + "0\n" * 5
    )
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert cli.main(["inspect", str(path)]) == 2
    assert [str(w.message) for w in caught] == []
    err = capsys.readouterr().err
    assert one_sentence(err) == "translucency: error: five.ply has no vertices; pass a mesh with at least one triangle."
    assert "loadtxt" not in err


def test_a_random_vtk_file_error_has_no_vtk_text(tmp_path, capsys):
    path = tmp_path / "noise.vtk"
    path.write_bytes(np.random.default_rng(1).integers(0, 256, 4000, dtype=np.uint8).tobytes())
    assert cli.main(["inspect", str(path)]) == 2
    line = one_sentence(capsys.readouterr().err)
    assert line == "translucency: error: noise.vtk is not a readable legacy VTK file; check or export the file again."
