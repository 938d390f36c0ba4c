"""The README's shell commands run as written, in a folder holding small stand-ins for the files they name.

Every command of every ``sh`` block in README.md is run with bash (``translucency`` from the set-up's
virtual environment on the ``PATH``), in README order in one folder, so that one command's output can be the
next one's input. The files the README supposes (``scan.ply``, ``scans/*.ply``, ``textured_scan.obj``,
``jade.toml``, ...) are small stand-ins; placeholders that name another machine are pointed at this one
(:data:`PLACEHOLDERS`). The commands not run here are listed in :data:`NOT_RUN_HERE` with the reason and the
test that runs the same path on a small input instead; a command that is in neither fails this test, so a
new README command cannot go untested.
"""

import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"

#: Commands the set-up and CI run themselves: each with why it is not run here and where it is tested.
NOT_RUN_HERE = {
    "./run.sh": "the set-up and the main job: what a clean clone runs first (tests/app/test_cli.py: the main job)",
    "./test.sh": "this test suite itself",
    '.venv/bin/python -m pip install -e ".[gpu]"': "installs the GPU extra (about 0.5 GB): its kernel is tested in "
    "numba's CUDA simulator, which needs none of it (tests/scatter/test_gpu.py)",
    "translucency bake scan.ply --device gpu": "needs an NVIDIA GPU (here it is the sentence saying so): the same "
    "solve runs in numba's CUDA simulator (tests/scatter/test_gpu.py, tree on the GPU against the CPU)",
}
#: Placeholders of the README for another machine, and what they become here.
PLACEHOLDERS = {"tcp://host:8786": "tcp://127.0.0.1:{port}", "/shared/baked/": "shared/baked/"}
#: Commands that open the desktop viewer's window: run until it has been open this long (s), then closed.
WINDOW_SECONDS = 25


def readme_commands() -> list[str]:
    """Every command of the README's ``sh`` blocks, continuation lines joined, in order."""
    commands = []
    for block in re.findall(r"```sh\n(.*?)```", README.read_text(), re.S):
        for command in re.sub(r"\\\n\s*", " ", block).splitlines():
            if command.strip():
                commands.append(command.strip())
    return commands


def _without_comment(command: str) -> str:
    return command.split("  #")[0].split(" # ")[0].strip()


def _write_sphere(path: Path, radius: float, colours: bool = False) -> None:
    import pyvista

    sphere = pyvista.Sphere(radius=radius, theta_resolution=24, phi_resolution=24)
    if not colours:
        sphere.save(path)
        return
    points = np.asarray(sphere.points)
    faces = np.asarray(sphere.faces).reshape(-1, 4)[:, 1:] + 1
    rgb = 0.3 + 0.6 * (points - points.min(axis=0)) / np.ptp(points, axis=0)
    if path.suffix == ".ply":  # vertex colours in the PLY's red, green, blue
        sphere.point_data["RGB"] = np.round(255 * rgb).astype(np.uint8)
        sphere.save(path, texture="RGB")
        return
    lines = [f"v {x:.6f} {y:.6f} {z:.6f} {r:.3f} {g:.3f} {b:.3f}" for (x, y, z), (r, g, b) in zip(points, rgb)]
    lines += [f"f {a} {b} {c}" for a, b, c in faces]
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture
def workspace(tmp_path):
    """A folder with the files the README's commands name, and the set-up's environment linked in."""
    (tmp_path / "scans").mkdir()
    for name in ("a", "b"):
        _write_sphere(tmp_path / "scans" / f"{name}.ply", 0.02)  # metres, as the README's --unit m says
    _write_sphere(tmp_path / "scan.ply", 0.02)
    _write_sphere(tmp_path / "large_scan.ply", 0.03)
    _write_sphere(tmp_path / "textured_scan.obj", 0.02, colours=True)
    toml = re.search(r"```toml\n(.*?)```", README.read_text(), re.S).group(1)
    (tmp_path / "jade.toml").write_text(toml)
    (tmp_path / ".venv").symlink_to(ROOT / ".venv")
    return tmp_path


@pytest.fixture
def dask_scheduler():
    """A Dask scheduler and one worker on this machine, for the README's cluster commands: its port."""
    import socket

    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    dask = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
    scheduler = subprocess.Popen(
        [*dask, "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    worker = subprocess.Popen(
        [sys.executable, "-m", "distributed.cli.dask_worker", f"tcp://127.0.0.1:{port}", "--nthreads", "1"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        yield port
    finally:
        for process in (worker, scheduler):
            process.terminate()
            process.wait(timeout=30)


@pytest.mark.slow
def test_every_readme_command_runs_as_written(workspace, dask_scheduler):
    commands = readme_commands()
    assert len(commands) > 15
    environment = {**os.environ, "PATH": f"{ROOT / '.venv' / 'bin'}:{os.environ['PATH']}"}
    ran = []
    for command in commands:
        if _without_comment(command) in NOT_RUN_HERE:
            continue
        line = command
        for placeholder, here in PLACEHOLDERS.items():
            line = line.replace(placeholder, here.format(port=dask_scheduler))
        window = re.match(r"translucency view(?!.*--screenshot)", line) is not None
        if window and not os.environ.get("DISPLAY"):
            continue  # the desktop viewer needs a display; ./test.sh runs the suite under xvfb-run
        process = subprocess.Popen(
            ["bash", "-c", line],
            cwd=workspace,
            env=environment,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            start_new_session=True,  # the command and whatever it starts end together below
        )
        try:
            out, err = process.communicate(timeout=WINDOW_SECONDS if window else 600)
        except subprocess.TimeoutExpired:  # the window stayed open: it started and waits for the user
            os.killpg(process.pid, signal.SIGKILL)
            out, err = process.communicate()
            assert window, f"{command!r} did not finish in 600 s"
            assert "error" not in err.lower(), f"{command!r} said: {err}"
            ran.append(command)
            continue
        assert process.returncode == 0, f"{command!r} failed ({process.returncode}):\n{out}\n{err}"
        ran.append(command)
    assert len(ran) + len(NOT_RUN_HERE) >= len(commands)
    assert (workspace / "out" / "reference.csv").exists() and (workspace / "scan_reference.npz").exists()
    # what the commands say they write is there
    baked = {path.name for path in (workspace / "baked").iterdir()}
    assert {"a_skim_milk.ply", "b_skim_milk.ply", "a_marble.ply", "bunny10k_textured_skim_milk.png"} <= baked
    for name in ("bunny.png", "out/grid.png", "sweep/grid.png", "shared/baked/a_marble.ply", "ref.npz"):
        assert (workspace / name).exists(), name


def test_the_commands_not_run_here_are_in_the_readme():
    """A README command taken out leaves :data:`NOT_RUN_HERE`, so that the list says what it skips."""
    written = {_without_comment(command) for command in readme_commands()}
    assert set(NOT_RUN_HERE) <= written


def readme_snippets() -> list[str]:
    """Every ``python`` block of the README, in order."""
    return re.findall(r"```python\n(.*?)```", README.read_text(), re.S)


@pytest.mark.slow
def test_every_readme_snippet_runs_as_written(workspace, monkeypatch, capsys):
    """The Python blocks run in order in one namespace (a block may use what an earlier one made), in the
    folder of stand-ins; PyVista draws off-screen."""
    import pyvista

    _write_sphere(workspace / "scan.ply", 0.02, colours=True)  # the last snippet shades the scan's own colours
    monkeypatch.setattr(pyvista, "OFF_SCREEN", True)
    monkeypatch.chdir(workspace)
    namespace = {"__name__": "__main__"}
    snippets = readme_snippets()
    assert len(snippets) >= 10
    for number, code in enumerate(snippets, start=1):
        try:
            exec(compile(code, f"README.md python block {number}", "exec"), namespace)
        except Exception as exc:  # the block and its error, not a bare traceback into README.md
            pytest.fail(f"README python block {number} failed: {type(exc).__name__}: {exc}\n{code}")
    for name in ("scan_baked.ply", "scan_baked.glb", "scan_reference.npz", "bunny.png", "out/grid.png"):
        assert (workspace / name).exists(), name
