"""Defect counts on generated meshes and on the shared scans (against the README)."""

import numpy as np
import pytest

from translucency.io import find_defects

from .conftest import grid, icosphere, load_scan


def test_clean_closed_sphere_has_no_defects():
    defects = find_defects(*icosphere(2))
    counts = defects.as_dict()
    assert counts.pop("vertices") == 162 and counts.pop("triangles") == 320 and counts.pop("components") == 1
    assert not any(counts.values())


def test_each_defect_is_counted():
    points, triangles = grid(4, 4.0)
    n = len(points)
    points = np.concatenate(
        [points, points[:2], [[50, 50, 50]], [[10, 0, 0], [20, 0, 0]]]
    )  # 2 duplicates, 1 unreferenced, 2 for a cap
    extra = [
        [0, 0, 1],  # null face
        triangles[3][::-1],  # duplicate face (other orientation)
        [n + 3, n + 4, 20],  # zero-area: (10,0,0) (20,0,0) (4,0,0) are collinear
    ]
    defects = find_defects(points, np.concatenate([triangles, extra]))
    assert defects.duplicate_vertices == 2
    assert defects.unreferenced_vertices == 3  # the two copies and the far vertex
    assert defects.null_faces == 1
    assert defects.duplicate_faces == 1
    assert defects.zero_area_faces == 1


def test_non_manifold_edge_and_vertex():
    # three triangles on one edge (a fin), and two fans touching at one vertex (a bowtie)
    points = np.array(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [5, 5, 0], [6, 5, 0], [5, 6, 0], [4, 5, 0], [5, 4, 0]],
        float,
    )
    triangles = [[0, 1, 2], [1, 0, 3], [0, 1, 4], [5, 6, 7], [5, 8, 9]]
    defects = find_defects(points, triangles)
    assert defects.non_manifold_edges == 1
    # the ends of the fin's edge and the bowtie centre
    assert defects.non_manifold_vertices == 3
    assert defects.components == 5  # triangles around a non-manifold edge or a bowtie are separate


def test_holes_loops_and_inconsistent_orientation():
    points, triangles = icosphere(2)
    holed = triangles[3:]  # removing 3 adjacent triangles opens holes
    defects = find_defects(points, holed)
    assert defects.boundary_loops >= 1 and defects.boundary_edges > 0
    flipped = triangles.copy()
    flipped[0] = flipped[0, ::-1]
    assert find_defects(points, flipped).inconsistent_edges == 3


@pytest.mark.parametrize(
    "name, expected",
    [
        (
            "stanford_bunny_zipper.ply",
            dict(
                unreferenced_vertices=1113,
                boundary_loops=5,
                boundary_edges=223,
                largest_boundary_loop=80,
                components=1,
                non_manifold_edges=0,
            ),
        ),
        ("cyberware_horse.ply", dict(boundary_edges=0, components=1, non_manifold_edges=0, inconsistent_edges=0)),
        (
            "ggg_angel_sfm.ply",
            dict(
                non_manifold_edges=41,
                non_manifold_vertices=109,
                boundary_loops=199,
                boundary_edges=1413,
                components=49,
                null_faces=0,
                duplicate_faces=0,
            ),
        ),
        (
            "ggg_birdbath_sfm.ply",
            dict(
                duplicate_vertices=3,
                zero_area_faces=7,
                non_manifold_edges=2,
                non_manifold_vertices=206,
                boundary_loops=328,
                boundary_edges=3333,
                components=97,
            ),
        ),
    ],
)
def test_shared_scans_match_the_readme(name, expected):
    mesh = load_scan(name)
    counts = find_defects(mesh.points, mesh.triangles).as_dict()
    assert {key: counts[key] for key in expected} == expected


def test_the_components_found_with_the_defects_are_those_of_the_faces():
    """Two spheres and a stray triangle: the labels given with the defects are face_components' own (a repair
    that keeps the faces reuses them), and none are given when a face is null (labels would not line up)."""
    from translucency.geometry.topology import face_components
    from translucency.io.defects import defects_and_components

    points, triangles = icosphere(2)
    points = np.concatenate([points, points + 5.0, [[9.0, 9.0, 9.0], [9.5, 9.0, 9.0], [9.0, 9.5, 9.0]]])
    n = len(points) - 3
    triangles = np.concatenate([triangles, triangles + n // 2, [[n, n + 1, n + 2]]])
    defects, (count, labels) = defects_and_components(points, triangles)
    expected_count, expected = face_components(triangles)
    assert count == defects.components == expected_count == 3
    assert np.array_equal(labels, expected)
    _, none = defects_and_components(points, np.concatenate([triangles, [[0, 0, 1]]]))
    assert none is None
