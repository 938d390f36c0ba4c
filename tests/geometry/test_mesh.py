"""The triangle-mesh record: validation, immutability."""

import numpy as np
import pytest

from translucency.errors import MeshError
from translucency.geometry.mesh import TriangleMesh, validate_mesh_arrays

from ..io.conftest import icosphere


def test_arrays_are_converted_copied_and_read_only():
    points, triangles = icosphere(1)
    source_points = points.astype(np.float32)
    mesh = TriangleMesh(source_points, triangles.astype(np.int32), {"q": np.arange(len(points))})
    assert mesh.points.dtype == np.float64 and mesh.triangles.dtype == np.int64
    with pytest.raises(ValueError):
        mesh.points[0, 0] = 1.0
    with pytest.raises(TypeError):
        mesh.point_data["new"] = np.zeros(len(points))
    source_points[0, 0] = 1e6  # the caller's array is not shared
    assert mesh.points[0, 0] != 1e6
    assert mesh.n_points == len(points) and mesh.n_triangles == len(triangles)


def test_sizes_area_and_replace():
    points, triangles = icosphere(3, 10.0)
    mesh = TriangleMesh(points, triangles)
    assert mesh.extent == pytest.approx(20.0, rel=1e-9)
    assert mesh.surface_area == pytest.approx(4 * np.pi * 100, rel=5e-3)
    assert mesh.vertex_areas().sum() == pytest.approx(mesh.surface_area)
    assert mesh.vertex_normals().shape == (len(points), 3)
    moved = mesh.replace(points=mesh.points + 1)
    assert np.allclose(moved.points, mesh.points + 1) and moved.triangles is not None
    assert "TriangleMesh(642 points" in repr(mesh)


@pytest.mark.parametrize(
    "points, triangles, message",
    [
        (np.zeros((3, 2)), [[0, 1, 2]], "shape"),
        (np.zeros((0, 3)), np.zeros((0, 3), int), "no vertices"),
        (np.eye(3), np.zeros((0, 3), int), "point cloud"),
        (np.array([[0, 0, 0], [1, 0, 0], [np.nan, 0, 1]]), [[0, 1, 2]], "NaN or infinite"),
        (np.array([[0, 0, 0], [1, 0, 0], [np.inf, 0, 1]]), [[0, 1, 2]], "NaN or infinite"),
        (np.eye(3), [[0, 1, 3]], "refers to vertex 3"),
        (np.eye(3), [[0, -1, 2]], "refers to vertex -1"),
        (np.eye(3), [[0, 1]], "shape"),
        (np.eye(3), [[0, 1.5, 2]], "not integers"),
        ([["a", "b", "c"]], [[0, 0, 0]], "not numbers"),
    ],
)
def test_invalid_arrays_raise_one_sentence(points, triangles, message):
    with pytest.raises(MeshError, match=message) as info:
        validate_mesh_arrays(points, triangles)
    text = str(info.value)
    assert text.count(". ") == 0 and text.endswith(".") and "\n" not in text


def test_point_data_must_match_vertices():
    with pytest.raises(MeshError, match="one row per vertex"):
        TriangleMesh(np.eye(3), [[0, 1, 2]], {"colors": np.zeros((2, 3))})


def test_bad_unit_factor():
    with pytest.raises(MeshError, match="mm_per_unit"):
        TriangleMesh(np.eye(3), [[0, 1, 2]], mm_per_unit=0)


def test_a_mesh_pickles_with_its_point_data():
    import pickle

    from translucency.geometry.synthetic import icosphere

    points, triangles = icosphere(1, 5.0)
    colours = np.arange(len(points) * 3, dtype=np.uint8).reshape(-1, 3)
    mesh = TriangleMesh(points, triangles, {"colors": colours}, source="scan.ply", mm_per_unit=10.0, unit_inferred=True)
    back = pickle.loads(pickle.dumps(mesh))
    np.testing.assert_array_equal(back.points, mesh.points)
    np.testing.assert_array_equal(back.point_data["colors"], colours)
    assert (back.source.name, back.mm_per_unit, back.unit_inferred) == ("scan.ply", 10.0, True)
