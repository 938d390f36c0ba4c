"""The README's PyVista session runs as written: a PolyData in, the result as a PolyData out, plotted
with a colour bar (off-screen, on a sphere written to a PLY in metres in place of the user's scan)."""

import re
from pathlib import Path

import numpy as np
import pytest

pyvista = pytest.importorskip("pyvista")

README = Path(__file__).resolve().parents[2] / "README.md"


def readme_session() -> str:
    """The Python block under the README's "### With PyVista" heading."""
    text = README.read_text()
    section = text[text.index("### With PyVista") :]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_the_readme_pyvista_session_runs_and_plots_with_a_colour_bar(tmp_path, monkeypatch):
    code = readme_session()
    assert len([line for line in code.splitlines() if line.strip()]) <= 5
    scan = tmp_path / "scan.ply"
    pyvista.Sphere(radius=0.01, theta_resolution=32, phi_resolution=32).save(scan)  # 20 mm across, in metres
    shown = {}
    original_show = pyvista.Plotter.show

    def show(self, *args, **kwargs):  # off-screen, keeping what was drawn
        shown["bars"] = list(self.scalar_bars.keys())
        kwargs["screenshot"] = str(tmp_path / "plot.png")
        shown["image"] = original_show(self, *args, **kwargs)
        return shown["image"]

    monkeypatch.setattr(pyvista, "OFF_SCREEN", True)
    monkeypatch.setattr(pyvista.Plotter, "show", show)
    monkeypatch.chdir(tmp_path)
    namespace = {}
    exec(compile(code, "README.md", "exec"), namespace)

    out, result = namespace["out"], namespace["result"]
    assert isinstance(out, pyvista.PolyData) and out.n_points == result.mesh.n_points
    assert out.bounds[5] - out.bounds[4] == pytest.approx(20.0, rel=1e-6)  # pole to pole, converted to mm
    for name in ("radiance", "B", "colors", "luminance", "incident_flux", "normals"):
        assert name in out.point_data
    np.testing.assert_allclose(out.point_data["radiance"], result.radiance)
    assert shown["bars"] == ["luminance"]
    # the view: the scan's up axis (+y for this sphere's inferred up, or the one recorded) is the view-up
    up = {"+x": (1, 0, 0), "+y": (0, 1, 0), "+z": (0, 0, 1), "-x": (-1, 0, 0), "-y": (0, -1, 0), "-z": (0, 0, -1)}
    assert tuple(result.camera_position()[2]) == pytest.approx(up[result.metadata["up"]])
    assert (tmp_path / "plot.png").is_file()
