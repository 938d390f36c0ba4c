"""Scan repair: every defect is repaired and counted, on generated meshes and on the shared scans."""

import numpy as np
import pytest

from translucency.errors import InvalidParameterError, MeshError
from translucency.io import TriangleMesh, clean_mesh, find_defects, signed_volume
from translucency.io.clean import clean_arrays, smooth_vertex_normals

from .conftest import icosphere, load_scan

REPAIRABLE = (
    "duplicate_vertices",
    "unreferenced_vertices",
    "null_faces",
    "duplicate_faces",
    "zero_area_faces",
    "non_manifold_edges",
    "non_manifold_vertices",
    "inconsistent_edges",
)


def assert_fully_repaired(report, *, closed=True):
    after = report.after.as_dict()
    assert {key: after[key] for key in REPAIRABLE} == dict.fromkeys(REPAIRABLE, 0)
    if closed:
        assert after["boundary_edges"] == 0 and after["components"] == 1


def test_clean_sphere_is_unchanged(sphere_mesh):
    cleaned, report = clean_mesh(sphere_mesh)
    assert not report.changed
    np.testing.assert_array_equal(cleaned.points, sphere_mesh.points)
    np.testing.assert_array_equal(cleaned.triangles, sphere_mesh.triangles)
    assert report.after == report.before


def test_every_generated_defect_is_repaired_and_counted(sphere_mesh):
    points, triangles = sphere_mesh.points, sphere_mesh.triangles
    n = len(points)
    colors = sphere_mesh.point_data["colors"]
    # a duplicate of vertex 0 used by the triangles of one side of it
    around = np.flatnonzero((triangles == 0).any(axis=1))[:2]
    triangles = triangles.copy()
    triangles[around] = np.where(triangles[around] == 0, n, triangles[around])
    points = np.concatenate([points, points[:1], [[500.0, 0, 0]]])  # + an unreferenced far vertex
    colors = np.concatenate([colors, colors[:1], [[1, 2, 3]]])
    extra = [
        [5, 5, 6],  # null face
        triangles[30][[1, 2, 0]],  # duplicate face
    ]
    island = icosphere(0, 0.5)  # a small closed island far away
    island_points = island[0] + [300.0, 0, 0]
    island_triangles = island[1] + len(points)
    points = np.concatenate([points, island_points])
    colors = np.concatenate([colors, np.zeros((len(island_points), 3), np.uint8)])
    all_triangles = np.concatenate([triangles[20:], extra, island_triangles])  # 20 triangles removed: holes
    all_triangles[:100] = all_triangles[:100, ::-1]  # incoherent orientation
    mesh = TriangleMesh(points, all_triangles, {"colors": colors})

    cleaned, report = clean_mesh(mesh, max_hole_edges=200)
    assert report.duplicate_vertices_merged == 1
    assert report.null_faces_removed == 1
    assert report.duplicate_faces_removed == 1
    assert report.islands_removed == 1 and report.island_faces_removed == 20
    assert report.holes_closed >= 1 and report.hole_faces_added >= report.holes_closed
    assert report.faces_flipped_coherent == 100
    assert report.unreferenced_vertices_removed >= 1 + len(island_points)
    assert_fully_repaired(report)
    assert signed_volume(cleaned.points, cleaned.triangles) > 0
    # colours followed their vertices
    sphere_points = sphere_mesh.points
    match = np.all(np.isclose(cleaned.points[:, None, :], sphere_points[None, :, :]), axis=2)
    rows, columns = np.nonzero(match)
    np.testing.assert_array_equal(cleaned.point_data["colors"][rows], sphere_mesh.point_data["colors"][columns])
    # the input is untouched
    np.testing.assert_array_equal(mesh.points, points)


def test_non_manifold_edge_and_vertex_are_repaired():
    a_points, a_triangles = icosphere(1, 10.0)
    b_points = a_points + (a_points[0] - (-a_points[0]))  # a second sphere touching the first at vertex 0
    points = np.concatenate([a_points, b_points])
    triangles = np.concatenate([a_triangles, a_triangles + len(a_points)])
    # glue: make the second sphere's antipode of vertex 0 the same vertex as the first's vertex 0
    antipode = int(np.argmin(np.linalg.norm(b_points - a_points[0], axis=1)))
    triangles[triangles == antipode + len(a_points)] = 0
    fin = np.array([[triangles[0, 0], triangles[0, 1], len(points)]])  # a third triangle on an edge
    points = np.concatenate([points, [[0.0, 0.0, 30.0]]])
    defects = find_defects(points, np.concatenate([triangles, fin]))
    assert defects.non_manifold_edges == 1 and defects.non_manifold_vertices >= 1
    cleaned, report = clean_mesh(TriangleMesh(points, np.concatenate([triangles, fin])), min_island_fraction=0.0)
    assert report.non_manifold_edges_repaired == 1 and report.non_manifold_edge_faces_removed >= 1
    assert report.non_manifold_vertices_repaired >= 1 and report.non_manifold_vertices_added >= 1
    assert report.after.non_manifold_edges == 0 and report.after.non_manifold_vertices == 0


def test_zero_area_needle_is_collapsed_not_opened():
    points, triangles = icosphere(2, 10.0)
    # move a vertex onto the middle of an opposite edge of one of its triangles: a zero-area cap
    t = triangles[0]
    points = points.copy()
    points[t[2]] = 0.5 * (points[t[0]] + points[t[1]])
    before = find_defects(points, triangles)
    assert before.zero_area_faces >= 1
    cleaned, report = clean_mesh(TriangleMesh(points, triangles))
    assert report.zero_area_faces_removed == before.zero_area_faces
    assert report.after.zero_area_faces == 0


def test_options_switch_steps_off(sphere_mesh):
    flipped = sphere_mesh.replace(triangles=sphere_mesh.triangles[:, ::-1])
    kept, report = clean_mesh(flipped, orient_outward=False)
    np.testing.assert_array_equal(kept.triangles, flipped.triangles)
    fixed, report = clean_mesh(flipped)
    assert report.components_flipped_outward == 1 and report.faces_flipped_outward == flipped.n_triangles


def test_normals_are_recomputed_and_optionally_smoothed(sphere_mesh):
    cleaned, _ = clean_mesh(sphere_mesh)
    np.testing.assert_allclose(cleaned.point_data["normals"], cleaned.vertex_normals())
    _, report = clean_mesh(sphere_mesh, smooth_normals=2)
    assert report.normal_smoothing_iterations == 2
    smoothed = smooth_vertex_normals(sphere_mesh.points, sphere_mesh.triangles, iterations=3)
    np.testing.assert_allclose(np.linalg.norm(smoothed, axis=1), 1.0)
    radial = sphere_mesh.points / np.linalg.norm(sphere_mesh.points, axis=1, keepdims=True)
    assert np.min(np.einsum("ij,ij->i", smoothed, radial)) > 0.99


@pytest.mark.parametrize(
    "options, message",
    [
        (dict(min_island_fraction=1.5), "min_island_fraction"),
        (dict(max_hole_edges=-1), "max_hole_edges"),
        (dict(max_hole_edges=2.5), "max_hole_edges"),
        (dict(smooth_normals=-2), "smooth_normals"),
    ],
)
def test_bad_options(sphere_mesh, options, message):
    with pytest.raises(InvalidParameterError, match=message):
        clean_mesh(sphere_mesh, **options)


def test_not_a_mesh():
    with pytest.raises(InvalidParameterError, match="TriangleMesh"):
        clean_mesh("bunny.ply")


def test_fully_degenerate_mesh_is_an_error():
    points = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], float)
    with pytest.raises(MeshError, match="no triangle is left"):
        clean_arrays(points, [[0, 1, 2], [0, 0, 1]])


def test_report_summary_is_a_table(sphere_mesh):
    _, report = clean_mesh(sphere_mesh.replace(triangles=sphere_mesh.triangles[5:]))
    text = str(report)
    assert "holes closed" in text and "before" in text and "after" in text
    assert text == report.summary()


# ---- the shared scans: every defect of the README repaired and counted ----------------------------
def test_shared_bunny_holes_and_unreferenced_vertices():
    mesh = load_scan("stanford_bunny_zipper.ply", "m")
    cleaned, report = clean_mesh(mesh)
    assert report.before.unreferenced_vertices == 1113 and report.unreferenced_vertices_removed == 1113
    assert report.before.boundary_loops == 5 and report.holes_closed >= 5
    assert_fully_repaired(report)
    assert set(cleaned.point_data) == {"confidence", "intensity", "normals"}
    assert signed_volume(cleaned.points, cleaned.triangles) > 0


def test_shared_horse_is_turned_outward():
    mesh = load_scan("cyberware_horse.ply", "m")
    assert signed_volume(mesh.points, mesh.triangles) < 0  # every face points inward
    cleaned, report = clean_mesh(mesh)
    assert report.components_flipped_outward == 1 and report.faces_flipped_outward == 96966
    assert signed_volume(cleaned.points, cleaned.triangles) > 0
    assert_fully_repaired(report)
    np.testing.assert_array_equal(cleaned.point_data["colors"], mesh.point_data["colors"])


def test_shared_angel_non_manifold_islands_and_holes():
    mesh = load_scan("ggg_angel_sfm.ply")
    mesh = mesh.replace(point_data={"index": np.arange(mesh.n_points)})
    cleaned, report = clean_mesh(mesh, max_hole_edges=2000)
    # per-vertex data followed the vertices through pymeshlab: same positions, except the copies of
    # split non-manifold vertices, which are moved by 1 % towards their fan
    origin = cleaned.point_data["index"]
    offset = np.linalg.norm(cleaned.points - mesh.points[origin], axis=1)
    assert np.count_nonzero(offset) <= report.non_manifold_vertices_added
    assert offset.max() < 0.05 * 3.67  # mean edge length of the angel: 3.67 mm
    assert report.non_manifold_edges_repaired == 41
    assert report.before.non_manifold_vertices == 109 and report.non_manifold_vertices_repaired >= 1
    assert report.before.components == 49 and report.islands_removed >= 1
    assert report.before.boundary_loops == 199 and report.holes_closed >= 150
    assert_fully_repaired(report)


def test_shared_birdbath_duplicates_and_zero_area_faces():
    mesh = load_scan("ggg_birdbath_sfm.ply")
    cleaned, report = clean_mesh(mesh, max_hole_edges=2000)
    assert report.duplicate_vertices_merged == 3
    # the 7 zero-area triangles: 6 lose a corner when the duplicates merge, 1 is collapsed
    assert report.null_faces_removed + report.zero_area_faces_removed == 7
    assert report.non_manifold_edges_repaired == 2
    assert report.before.non_manifold_vertices == 206
    assert report.before.components == 97 and report.islands_removed >= 90
    assert report.before.boundary_loops == 328 and report.holes_closed >= 300
    assert_fully_repaired(report)


def test_shared_open_scan_keeps_large_borders_open_by_default():
    mesh = load_scan("ggg_birdbath_sfm.ply")
    cleaned, report = clean_mesh(mesh)  # max_hole_edges=100: the 1000-edge border stays
    assert_fully_repaired(report, closed=False)
    assert report.after.largest_boundary_loop > 100
    assert report.after.boundary_loops < report.before.boundary_loops
