"""A TriangleMesh to and from a pyvista.PolyData: round trip, polygons and strips."""

import numpy as np
import pytest

from translucency.io.polydata import from_pyvista, to_pyvista


def test_pyvista_round_trip(sphere_mesh):
    poly = to_pyvista(sphere_mesh)
    assert poly.n_points == sphere_mesh.n_points and poly.n_cells == sphere_mesh.n_triangles
    back = from_pyvista(poly)
    np.testing.assert_array_equal(back.points, sphere_mesh.points)
    np.testing.assert_array_equal(back.triangles, sphere_mesh.triangles)
    np.testing.assert_array_equal(back.point_data["colors"], sphere_mesh.point_data["colors"])
    np.testing.assert_array_equal(back.point_data["confidence"], sphere_mesh.point_data["confidence"])


def test_from_pyvista_triangulates_polygons_and_strips():
    import pyvista

    quads = pyvista.Plane(i_resolution=3, j_resolution=2)  # 6 quads
    mesh = from_pyvista(quads)
    assert mesh.n_triangles == 12
    assert mesh.surface_area == pytest.approx(1.0)
    strips = quads.triangulate().strip()
    assert strips.n_strips > 0
    assert from_pyvista(strips).surface_area == pytest.approx(1.0)
