"""The scan's colours as its albedo: sRGB decoding, the option on the command line and in Python, the
sentence for a scan without colours."""

import numpy as np
import plyfile
import pytest

from translucency.app import cli
from translucency.app.shading.scan import scan_reflectance
from translucency.app.shading.scene import Scene
from translucency.app.shading.settings import ShadeSettings
from translucency.errors import InvalidParameterError
from translucency.geometry.mesh import TriangleMesh
from translucency.geometry.synthetic import icosphere


def _sphere(colors=None):
    points, triangles = icosphere(3)
    point_data = {} if colors is None else {"colors": colors(points)}
    return TriangleMesh(points * 20.0, triangles, point_data=point_data)


def _halves(points):
    """Red where x < 0, blue elsewhere (8-bit sRGB)."""
    return np.where(points[:, :1] < 0, [[230, 40, 40]], [[40, 40, 230]]).astype(np.uint8)


def test_colours_are_decoded_from_srgb():
    mesh = _sphere(lambda p: np.tile(np.array([[0, 188, 255]], dtype=np.uint8), (len(p), 1)))
    reflectance = scan_reflectance(mesh)
    # sRGB 188/255 is linear 0.503 (IEC 61966-2-1)
    assert np.allclose(reflectance[0], [0.0, 0.5029, 1.0], atol=2e-4)


def test_colours_change_the_light_where_they_change():
    """Red half and blue half: the red channel is brighter on the red half than on the blue half, and the
    other way round, where the homogeneous material is symmetric."""
    mesh = _sphere(_halves)
    light = [0.0, 0.0, 1.0]  # along z: both halves lit alike
    from translucency.scatter.lights import DirectionalLight

    scene = Scene(mesh, shadows=False, up="+z")
    plain = scene.shade_with(ShadeSettings(material="marble", method="exact", up="+z"), DirectionalLight(light, 1.0))
    coloured = scene.shade_with(
        ShadeSettings(material="marble", method="exact", up="+z", albedo="vertex_colors"), DirectionalLight(light, 1.0)
    )
    red = mesh.points[:, 0] < -5.0
    blue = mesh.points[:, 0] > 5.0
    top = mesh.points[:, 2] > 10.0
    B = coloured.B
    assert B[red & top, 0].mean() > 3 * B[blue & top, 0].mean()
    assert B[blue & top, 2].mean() > 3 * B[red & top, 2].mean()
    assert np.allclose(plain.B[red & top].mean(axis=0), plain.B[blue & top].mean(axis=0), rtol=0.05)
    assert coloured.metadata["albedo"] != plain.metadata["albedo"]


def test_a_scan_without_colours_is_one_sentence():
    with pytest.raises(InvalidParameterError, match="no vertex colours or texture"):
        Scene(_sphere()).shade_with(ShadeSettings(albedo="vertex_colors"))


def test_the_command_line_option(tmp_path, capsys):
    mesh = _sphere(_halves)
    vertex = np.empty(
        mesh.n_points, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("red", "u1"), ("green", "u1"), ("blue", "u1")]
    )
    for i, axis in enumerate("xyz"):
        vertex[axis] = mesh.points[:, i]
    colors = _halves(mesh.points)
    for i, name in enumerate(("red", "green", "blue")):
        vertex[name] = colors[:, i]
    face = np.empty(mesh.n_triangles, dtype=[("vertex_indices", "i4", (3,))])
    face["vertex_indices"] = mesh.triangles
    coloured = tmp_path / "coloured.ply"
    plyfile.PlyData([plyfile.PlyElement.describe(vertex, "vertex"), plyfile.PlyElement.describe(face, "face")]).write(
        coloured
    )
    out = tmp_path / "out"
    assert cli.main(["bake", str(coloured), "--unit", "mm", "--albedo-from-colors", "-o", str(out), "--quiet"]) == 0
    header = (out / "coloured_marble.ply").read_bytes()[:4000]
    assert b"colours as its diffuse reflectance" in header
    plain = tmp_path / "plain.ply"
    vertex_plain = np.empty(mesh.n_points, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])  # no colours
    for axis in "xyz":
        vertex_plain[axis] = vertex[axis]
    plyfile.PlyData(
        [plyfile.PlyElement.describe(vertex_plain, "vertex"), plyfile.PlyElement.describe(face, "face")]
    ).write(plain)
    capsys.readouterr()
    assert cli.main(["bake", str(plain), "--unit", "mm", "--albedo-from-colors", "-o", str(out), "--quiet"]) != 0
    err = capsys.readouterr().err
    assert "plain.ply has no vertex colours or texture" in err and "--albedo-from-colors" in err
    assert "Traceback" not in err


def test_the_viewer_and_compare_take_the_colours_too():
    from translucency.app.compare import compare
    from translucency.app.viewer.state import ViewerState

    mesh = _sphere(_halves)
    state = ViewerState(mesh, "marble", albedo="vertex_colors", resolution="full", up="+z")
    red = mesh.points[:, 0] < -5.0
    assert state.result.B[red, 0].mean() > 2 * state.result.B[red, 2].mean()
    comparison = compare(mesh, "marble", albedo="vertex_colors", up="+z")
    assert comparison.results["marble", "directional"].metadata["albedo"] != "material"
