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


# ---- every mesh-level entry point takes a PolyData (as_triangle_mesh) ------------------------------


def test_a_polydata_in_metres_is_converted_to_mm():
    import pyvista

    from translucency.io.polydata import as_triangle_mesh

    poly = pyvista.Sphere(radius=0.01)  # 20 mm across, in metres
    mesh = as_triangle_mesh(poly, "m")
    np.testing.assert_allclose(mesh.points, np.asarray(poly.points, dtype=np.float64) * 1000.0)
    assert mesh.mm_per_unit == 1000.0 and not mesh.unit_inferred
    assert mesh.n_triangles == poly.n_cells


def test_a_polydata_without_a_unit_is_inferred_and_said_as_for_a_file():
    import pyvista

    from translucency.io.polydata import as_triangle_mesh
    from translucency.io.units import UnitInferredWarning

    with pytest.warns(UnitInferredWarning, match=r"0\.02 units across, read as metres"):
        mesh = as_triangle_mesh(pyvista.Sphere(radius=0.01))
    assert mesh.mm_per_unit == 1000.0 and mesh.unit_inferred
    assert mesh.extent == pytest.approx(20.0, rel=1e-3)


def test_a_polydata_that_says_its_unit_is_not_inferred(recwarn):
    import pyvista

    from translucency.io.polydata import LENGTH_UNIT_FIELD, as_triangle_mesh

    poly = pyvista.Sphere(radius=0.01)
    poly.field_data[LENGTH_UNIT_FIELD] = ["cm"]
    mesh = as_triangle_mesh(poly)
    assert mesh.mm_per_unit == 10.0 and not mesh.unit_inferred
    assert not [w for w in recwarn if "units across" in str(w.message)]


def test_a_volume_dataset_gives_its_outer_surface():
    import pyvista

    from translucency.io.polydata import as_triangle_mesh

    grid = pyvista.ImageData(dimensions=(3, 3, 3), spacing=(5.0, 5.0, 5.0)).cast_to_unstructured_grid()
    mesh = as_triangle_mesh(grid, "mm")
    # a 10 mm cube: 6 faces of 2 x 2 quads, 2 triangles each
    assert mesh.n_triangles == 48 and mesh.surface_area == pytest.approx(600.0)


def test_what_is_not_a_mesh_is_one_sentence_naming_what_to_pass():
    import pyvista

    from translucency.errors import InvalidParameterError, MeshError
    from translucency.io.clean import clean_mesh
    from translucency.io.decimate import decimate_mesh

    with pytest.raises(
        InvalidParameterError, match=r"^clean_mesh needs a TriangleMesh or a pyvista\.PolyData, not list"
    ):
        clean_mesh([[0, 0, 0]])
    with pytest.raises(InvalidParameterError, match=r"^decimate_mesh got unit='m' with a TriangleMesh"):
        decimate_mesh(from_pyvista(pyvista.Sphere(radius=10)), unit="m", target_faces=100)
    lines = pyvista.Line((0, 0, 0), (10, 0, 0))
    with pytest.raises(MeshError, match="no triangles|triangles"):
        clean_mesh(lines, unit="mm")


def test_clean_and_decimate_take_a_polydata_like_its_triangle_mesh():
    import pyvista

    from translucency.io.clean import clean_mesh
    from translucency.io.decimate import decimate_mesh

    poly = pyvista.Sphere(radius=10.0, theta_resolution=24, phi_resolution=24)
    from_poly, report = clean_mesh(poly, unit="mm")
    from_mesh, _ = clean_mesh(from_pyvista(poly))
    np.testing.assert_array_equal(from_poly.points, from_mesh.points)
    np.testing.assert_array_equal(from_poly.triangles, from_mesh.triangles)
    proxy = decimate_mesh(poly, unit="mm", target_faces=200).proxy
    assert 150 <= proxy.n_triangles <= 200
