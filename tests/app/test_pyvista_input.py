"""shade, Scene, shade_scan, compare and the viewer's state take a pyvista.PolyData (in its unit) as well
as a TriangleMesh, and give the same answer as for the mesh it converts to."""

import numpy as np
import pytest

pyvista = pytest.importorskip("pyvista")


def _sphere_m():
    return pyvista.Sphere(radius=0.01, theta_resolution=24, phi_resolution=24)  # 20 mm across, in metres


def test_shade_of_a_polydata_equals_shade_of_its_cleaned_mesh():
    import translucency as tl
    from translucency.io.polydata import from_pyvista

    poly = _sphere_m()
    result = tl.shade(poly, "marble", unit="m")
    in_mm = np.asarray(poly.points, dtype=np.float64) * 1000.0  # the conversion, done by hand
    mesh, _ = tl.clean_mesh(from_pyvista(poly, mm_per_unit=1000.0).replace(points=in_mm))
    reference = tl.shade(mesh, "marble")
    np.testing.assert_array_equal(result.mesh.points, mesh.points)
    np.testing.assert_allclose(result.B, reference.B, rtol=1e-12, atol=0)
    assert result.metadata["source_mm_per_unit"] == 1000.0 and result.B.max() > 0


def test_scene_shade_scan_compare_and_viewer_state_take_a_polydata():
    import translucency as tl
    from translucency.app.viewer.state import ViewerState

    poly = _sphere_m()
    scene = tl.Scene(poly, unit="m")
    assert scene.mesh.extent == pytest.approx(20.0, rel=1e-3)
    scanned = tl.shade_scan(poly, tl.ShadeSettings(material="marble"), unit="m")
    np.testing.assert_allclose(scanned.B, scene.shade("marble").B, rtol=1e-12)
    comparison = tl.compare(poly, ["marble", "ketchup"], unit="m")
    assert comparison.mean("ketchup", "directional").shape == (3,)
    state = ViewerState(poly, "marble", unit="m", resolution="full")
    assert state.base_mesh.extent == pytest.approx(20.0, rel=1e-3)
    assert state.result is not None and state.result.B.shape == (state.base_mesh.n_points, 3)
