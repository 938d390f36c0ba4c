"""Polygons and triangle strips to triangle lists."""

import numpy as np

from translucency.io.triangulate import (
    drop_repeated_index_triangles,
    triangulate_polygon_lists,
    triangulate_polygons,
    triangulate_strips,
)


def test_fan_triangulation_of_mixed_polygons():
    offsets = [0, 3, 7, 9, 14]  # a triangle, a quad, a 2-gon (dropped), a pentagon
    connectivity = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13]
    triangles = triangulate_polygons(offsets, connectivity)
    np.testing.assert_array_equal(triangles, [[0, 1, 2], [3, 4, 5], [3, 5, 6], [9, 10, 11], [9, 11, 12], [9, 12, 13]])
    lists = [np.array(connectivity[a:b]) for a, b in zip(offsets[:-1], offsets[1:])]
    np.testing.assert_array_equal(triangulate_polygon_lists(lists), triangles)


def test_strip_winding_alternates_and_restarts():
    # strip 0 1 2 3 4 | restart | 5 6 7
    triangles = triangulate_strips([0, 1, 2, 3, 4, -1, 5, 6, 7])
    np.testing.assert_array_equal(triangles, [[0, 1, 2], [2, 1, 3], [2, 3, 4], [5, 6, 7]])


def test_strip_winding_is_consistent_on_a_grid():
    # a strip over a row of quads: every triangle must have the same orientation (normal +z)
    points = np.array([[x, y, 0.0] for x in range(5) for y in (0, 1)])
    strip = np.arange(10)  # (0,0) (0,1) (1,0) (1,1) ...
    triangles = triangulate_strips(strip)
    p = points[triangles]
    normals = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert len(triangles) == 8
    assert np.all(np.sign(normals[:, 2]) == np.sign(normals[0, 2]))


def test_strip_offsets_separate_strips_and_degenerates_are_dropped():
    # two strips given by offsets; a repeated index turns a corner and makes degenerate triangles
    triangles = triangulate_strips([0, 1, 2, 2, 3, 4, 5, 6], offsets=[0, 5, 8])
    np.testing.assert_array_equal(triangles, [[0, 1, 2], [4, 5, 6]])


def test_other_negative_indices_are_kept_for_the_range_check():
    assert (triangulate_strips([0, 1, -2]) == -2).any()


def test_drop_repeated():
    np.testing.assert_array_equal(drop_repeated_index_triangles([[0, 1, 2], [1, 1, 2], [3, 4, 3]]), [[0, 1, 2]])
