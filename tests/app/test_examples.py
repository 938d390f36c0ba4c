"""The scripts in examples/ run (on a decimated default scan) and write what they say."""

import runpy
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def run_example(name, *args, monkeypatch):
    monkeypatch.setattr(sys, "argv", [str(EXAMPLES / name), *map(str, args)])
    runpy.run_path(str(EXAMPLES / name), run_name="__main__")


@pytest.mark.slow
def test_compare_materials(tmp_path, monkeypatch, capsys):
    import imageio.v3 as iio

    run_example("compare_materials.py", tmp_path / "out", "--quick", monkeypatch=monkeypatch)
    assert iio.imread(tmp_path / "out" / "grid.png").shape[:2] == (240, 3 * 240)
    out = capsys.readouterr().out
    assert all(name in out for name in ("marble", "skim_milk", "ketchup"))


def test_bake_and_render(tmp_path, monkeypatch, capsys):
    from translucency.io.baked import read_baked_ply

    run_example("bake_and_render.py", tmp_path, "--material", "marble", "--quick", monkeypatch=monkeypatch)
    baked = read_baked_ply(tmp_path / "marble.ply")
    assert baked.metadata["material"] == "marble" and (baked.radiance > 0).any()
    assert (tmp_path / "marble.png").stat().st_size > 1000


# models compared: test_compare.py; an example script running: the two tests above
@pytest.mark.slow
def test_model_differences(tmp_path, monkeypatch, capsys):
    run_example("model_differences.py", tmp_path, "--quick", monkeypatch=monkeypatch)
    assert (tmp_path / "differences.png").exists() and (tmp_path / "statistics.json").exists()
    out = capsys.readouterr().out
    assert "standard  vs directional" in out and "better    vs directional" in out


@pytest.mark.parametrize("name", ["compare_materials.py", "bake_and_render.py", "model_differences.py"])
def test_every_example_documents_its_command_line(name):
    text = (EXAMPLES / name).read_text()
    assert f"python examples/{name} OUT" in text
