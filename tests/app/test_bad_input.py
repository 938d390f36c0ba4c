"""Bad input, nothing lost: every bad file, output path or parameter gives one sentence, and through the
command line exit code 2, no traceback, no output file, and the input file's bytes and mtime unchanged.

The files are the loader's corpus of ``tests/io/test_broken_files.py`` (where each message is checked
against the loader) plus unreadable paths, all generated in temporary folders.
"""

import hashlib
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from tests.io.test_broken_files import CORPUS, POINTS, TRIANGLES, binary_ply, binary_stl
from translucency.app import cli
from translucency.app.shading.scene import shade
from translucency.errors import InvalidParameterError, TranslucencyError, UnknownMaterialError
from translucency.io import TriangleMesh, load_mesh, save_mesh
from translucency.scatter.materials import material
from translucency.scatter.medium import Medium


def _fingerprint(path):
    """Bytes hash and modification time of a file (None for a path that is not a file)."""
    if not os.path.isfile(path):
        return None
    return hashlib.sha256(path.read_bytes()).hexdigest(), os.stat(path).st_mtime_ns


def _one_sentence(text, name):
    lines = [line for line in text.splitlines() if line.strip()]
    assert len(lines) == 1, text
    assert lines[0].startswith("translucency: error: ") and lines[0].endswith("."), text
    assert name in lines[0] and "Traceback" not in text, text
    return lines[0]


def _inspect(capsys, path, output, *extra):
    """``translucency inspect PATH -o OUTPUT`` in this process: (exit code, the one error line)."""
    before = _fingerprint(path)
    code = cli.main(["inspect", str(path), "-o", str(output), *extra])
    err = capsys.readouterr().err
    assert _fingerprint(path) == before  # the input is untouched (bytes and mtime)
    return code, err


@pytest.mark.parametrize("name, content, expected", CORPUS, ids=[c[0] for c in CORPUS])
def test_cli_bad_file(tmp_path, capsys, name, content, expected):
    path = tmp_path / name
    path.write_bytes(content)
    output = tmp_path / "repaired.ply"
    code, err = _inspect(capsys, path, output)
    assert code == 2
    line = _one_sentence(err, name)
    assert re.search(expected, line), line
    assert not output.exists() and sorted(p.name for p in tmp_path.iterdir()) == [name]


def test_cli_directory_named_like_a_mesh(tmp_path, capsys):
    folder = tmp_path / "x.ply"
    folder.mkdir()
    code, err = _inspect(capsys, folder, tmp_path / "out.ply")
    assert code == 2 and "is a directory" in _one_sentence(err, "x.ply")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.ply"]


def test_cli_dangling_symlink(tmp_path, capsys):
    link = tmp_path / "scan.ply"
    link.symlink_to(tmp_path / "elsewhere.ply")
    code, err = _inspect(capsys, link, tmp_path / "out.ply")
    assert code == 2 and "does not exist" in _one_sentence(err, "scan.ply")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scan.ply"]


# ------------------------------------------------------------------------------ bad output paths


@pytest.fixture
def good_file(tmp_path):
    path = tmp_path / "scan.ply"
    path.write_bytes(binary_ply(POINTS, TRIANGLES))
    return path


@pytest.mark.parametrize(
    "output, named, expected",
    [
        ("scan.ply", "scan.ply", "is the input file"),
        ("missing/out.ply", "missing", "does not exist"),
        ("folder.ply", "folder.ply", "is a folder"),
        ("out.xyz", "out.xyz", "cannot write"),
    ],
    ids=["same-as-input", "missing-folder", "folder", "unknown-suffix"],
)
def test_cli_bad_output_path(tmp_path, capsys, good_file, output, named, expected):
    (tmp_path / "folder.ply").mkdir()
    before = sorted(p.name for p in tmp_path.iterdir())
    code, err = _inspect(capsys, good_file, tmp_path / output)
    assert code == 2 and expected in _one_sentence(err, named)
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_cli_same_file_through_a_symlink(tmp_path, capsys, good_file):
    alias = tmp_path / "alias.ply"
    alias.symlink_to(good_file)
    code, err = _inspect(capsys, good_file, alias)
    assert code == 2 and "is the input file" in _one_sentence(err, "alias.ply")


def test_failed_write_leaves_nothing_and_keeps_the_old_output(tmp_path, monkeypatch, good_file):
    """A write that fails half-way (the disk fills up): the previous output is intact, no temporary file is left."""
    from translucency.io import atomic

    output = tmp_path / "out.ply"
    output.write_bytes(b"previous result")
    mesh = load_mesh(good_file, unit="mm")

    def full_disk(path, *args):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(atomic, "_fsync", full_disk)
    with pytest.raises(TranslucencyError, match="writing out.ply failed"):
        save_mesh(output, mesh)
    assert output.read_bytes() == b"previous result"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.ply", "scan.ply"]


def test_cli_good_file_writes_the_repaired_mesh(tmp_path, capsys, good_file):
    """The control: the same command on a good file exits 0 and writes a mesh that loads."""
    output = tmp_path / "repaired.stl"
    code, _ = _inspect(capsys, good_file, output)
    assert code == 0
    assert load_mesh(output, unit="mm").n_triangles == len(TRIANGLES)


# ---------------------------------------------------------------------------- separate processes


def _run(*args):
    done = subprocess.run(
        [sys.executable, "-m", "translucency", *map(str, args)], capture_output=True, text=True, timeout=300
    )
    return done.returncode, done.stdout, done.stderr


@pytest.mark.parametrize(
    "name, content, expected",
    [
        ("cut.stl", binary_stl(POINTS, TRIANGLES)[:2084], "is truncated"),
        ("scan.obj", binary_ply(POINTS, TRIANGLES), "but PLY data"),
    ],
)
def test_subprocess_bad_file(tmp_path, name, content, expected):
    path = tmp_path / name
    path.write_bytes(content)
    before = _fingerprint(path)
    code, _, err = _run("inspect", path, "-o", tmp_path / "out.ply")
    assert code == 2 and expected in _one_sentence(err, name)
    assert _fingerprint(path) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]


# ------------------------------------------------------------------- material parameters (Python API)


@pytest.mark.parametrize(
    "make, error, expected",
    [
        (lambda: Medium(-0.01, 1.0, 0.0, 1.3), InvalidParameterError, "sigma_a must be >= 0"),
        (lambda: Medium(0.01, -1.0, 0.0, 1.3), InvalidParameterError, "sigma_s must be >= 0"),
        (lambda: Medium(0.01, 1.0, 0.0, 0.9), InvalidParameterError, "eta = n_inside / n_outside must be >= 1"),
        (lambda: Medium(0.01, [1.0, np.nan, 1.0], 0.0, 1.3), InvalidParameterError, "sigma_s must be finite"),
        (lambda: Medium(0.01, 1.0, 0.0, np.nan), InvalidParameterError, "eta must be finite"),
        (lambda: Medium(0.01, 1.0, 1.0, 1.3), InvalidParameterError, r"g must lie in \(-1, 1\)"),
        (lambda: Medium(0.01, 0.0, 0.0, 1.3), InvalidParameterError, "must scatter"),
        (lambda: material("unobtainium"), UnknownMaterialError, "unknown material 'unobtainium'"),
        (lambda: material("coke").medium(), TranslucencyError, "does not scatter"),
        (lambda: material("marble").medium().scaled(-1.0), InvalidParameterError, "positive number"),
    ],
    ids=[
        "negative-sigma_a",
        "negative-sigma_s",
        "eta-below-1",
        "nan-sigma_s",
        "nan-eta",
        "g-1",
        "no-scattering",
        "unknown-name",
        "non-scattering-preset",
        "negative-scale",
    ],
)
def test_bad_material_parameters(make, error, expected):
    with pytest.raises(error, match=expected) as info:
        make()
    text = str(info.value)
    assert text.endswith(".") and "\n" not in text and len(text) < 300


@pytest.mark.parametrize("material_name", ["unobtainium", "coke"])
def test_shade_refuses_a_bad_material_before_any_work(material_name):
    mesh = TriangleMesh(POINTS, TRIANGLES)
    with pytest.raises(TranslucencyError, match=material_name):
        shade(mesh, material_name)
