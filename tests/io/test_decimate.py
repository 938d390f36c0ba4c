"""Decimation keeps the shape; the proxy mapping interpolates back exactly at shared vertices."""

import numpy as np
import pytest

from translucency.errors import InvalidParameterError
from translucency.geometry.proximity import vertex_hausdorff_distance
from translucency.io import clean_mesh, decimate_mesh, map_to_proxy, simplify_arrays, target_face_count

from .conftest import icosphere, load_scan


def test_target_face_count_from_edge_length():
    # a 1 mm² equilateral triangle has side sqrt(4 / sqrt(3))
    side = np.sqrt(4 / np.sqrt(3))
    assert target_face_count(1000.0, side) == 1000
    with pytest.raises(InvalidParameterError, match="target_edge_length"):
        target_face_count(1.0, 0.0)


@pytest.mark.parametrize("method", ["fast-simplification", "pymeshlab"])
def test_sphere_decimation_keeps_the_shape(sphere_mesh, method):
    decimation = decimate_mesh(sphere_mesh, target_faces=500, method=method)
    proxy = decimation.proxy
    assert 400 <= proxy.n_triangles <= 520
    radius = np.linalg.norm(proxy.points, axis=1)
    assert np.allclose(radius, 25.0, rtol=0.01)  # proxy vertices stay on the 25 mm sphere
    hausdorff = vertex_hausdorff_distance(sphere_mesh.points, sphere_mesh.triangles, proxy.points, proxy.triangles)
    assert hausdorff < 0.02 * 50  # below 2 % of the diameter
    assert decimation.mapping.distance.max() <= hausdorff + 1e-12
    assert set(proxy.point_data) == {"colors", "confidence"}


def test_interpolation_is_exact_at_shared_vertices(sphere_mesh):
    # a proxy whose vertices are a subset of the full mesh's (the level-2 icosphere inside level 3)
    coarse_points, coarse_triangles = icosphere(2, 25.0)
    mapping = map_to_proxy(sphere_mesh.points, coarse_points, coarse_triangles)
    values = np.random.default_rng(0).random((len(coarse_points), 3)) * 1e3
    full = mapping.interpolate(values)
    shared = np.arange(len(coarse_points))  # icosphere subdivision keeps the coarse vertices first
    np.testing.assert_array_equal(sphere_mesh.points[shared], coarse_points)
    np.testing.assert_array_equal(full[shared], values)  # bit for bit
    # linear fields are reproduced everywhere inside the proxy triangles
    linear = coarse_points @ [1.0, -2.0, 0.5] + 7.0
    closest = np.einsum("qi,qij->qj", mapping.weights, coarse_points[mapping.vertex_index])
    np.testing.assert_allclose(mapping.interpolate(linear), closest @ [1.0, -2.0, 0.5] + 7.0, rtol=1e-12)


def test_interpolation_shapes_and_constant_fields(sphere_mesh):
    decimation = decimate_mesh(sphere_mesh, target_faces=300)
    n_proxy = decimation.proxy.n_points
    assert decimation.interpolate(np.ones(n_proxy)).shape == (sphere_mesh.n_points,)
    np.testing.assert_allclose(decimation.interpolate(np.full((n_proxy, 3), 2.5)), 2.5, rtol=1e-15)
    assert decimation.interpolate(np.arange(n_proxy)).dtype == np.float64
    assert decimation.interpolate(np.ones(n_proxy, np.float32)).dtype == np.float32
    with pytest.raises(InvalidParameterError, match="one value per proxy vertex"):
        decimation.interpolate(np.ones(n_proxy + 1))


def test_gather_is_the_adjoint_of_interpolate_and_keeps_sums(sphere_mesh):
    """<gather(f), p> = <f, interpolate(p)> for any full values f and proxy values p: what a proxy vertex receives is
    what it would hand back; the sum over the full mesh is the sum over the proxy."""
    decimation = decimate_mesh(sphere_mesh, target_faces=300)
    rng = np.random.default_rng(4)
    full = rng.random((sphere_mesh.n_points, 3))
    proxy = rng.random((decimation.proxy.n_points, 3))
    gathered = decimation.gather(full)
    assert gathered.shape == proxy.shape
    np.testing.assert_allclose(np.sum(gathered * proxy), np.sum(full * decimation.interpolate(proxy)), rtol=1e-12)
    np.testing.assert_allclose(gathered.sum(axis=0), full.sum(axis=0), rtol=1e-12)
    np.testing.assert_allclose(decimation.gather(full[:, 0]), gathered[:, 0], rtol=1e-15)
    with pytest.raises(InvalidParameterError, match="one value or row per full-mesh vertex"):
        decimation.gather(np.ones(sphere_mesh.n_points + 1))


def test_no_decimation_needed_is_the_identity(sphere_mesh):
    decimation = decimate_mesh(sphere_mesh, target_faces=10**6)
    assert decimation.method == "none" and decimation.proxy is sphere_mesh
    values = np.random.default_rng(1).random(sphere_mesh.n_points)
    np.testing.assert_array_equal(decimation.interpolate(values), values)


def test_edge_length_target(sphere_mesh):
    decimation = decimate_mesh(sphere_mesh, target_edge_length=5.0)
    expected = target_face_count(sphere_mesh.surface_area, 5.0)
    assert abs(decimation.proxy.n_triangles - expected) <= 0.1 * expected + 4
    with pytest.raises(InvalidParameterError, match="would leave"):
        decimate_mesh(sphere_mesh, target_edge_length=100.0)


@pytest.mark.parametrize(
    "options, message",
    [
        (dict(), "exactly one"),
        (dict(target_faces=100, target_edge_length=1.0), "exactly one"),
        (dict(target_faces=5), "at least 20"),
        (dict(target_faces=100, method="vtk"), "unknown decimation method"),
    ],
)
def test_bad_arguments(sphere_mesh, options, message):
    with pytest.raises(InvalidParameterError, match=message):
        decimate_mesh(sphere_mesh, **options)


def test_simplify_arrays_drops_unreferenced_vertices():
    points, triangles = icosphere(3)
    points = np.concatenate([points, [[99.0, 99.0, 99.0]]])
    new_points, new_triangles = simplify_arrays(points, triangles, 200)
    assert new_triangles.max() == len(new_points) - 1
    assert not np.any(np.all(new_points == 99.0, axis=1))


def test_shared_bunny_decimation_hausdorff_bound():
    mesh, _ = clean_mesh(load_scan("stanford_bunny_zipper.ply", "m"))
    diagonal = np.linalg.norm(np.ptp(mesh.points, axis=0))
    decimation = decimate_mesh(mesh, target_faces=mesh.n_triangles // 10)
    proxy = decimation.proxy
    assert proxy.n_triangles == pytest.approx(mesh.n_triangles // 10, rel=0.05)
    hausdorff = vertex_hausdorff_distance(mesh.points, mesh.triangles, proxy.points, proxy.triangles)
    assert hausdorff < 0.005 * diagonal  # 10x fewer triangles, within 0.5 % of the size (about 1 mm)
    assert np.mean(decimation.mapping.distance) < 0.0005 * diagonal
    # the solver's proxy interpolates back smoothly: a smooth field on the proxy stays within its range
    field = proxy.points[:, 2]
    back = decimation.interpolate(field)
    assert field.min() - 1e-9 <= back.min() and back.max() <= field.max() + 1e-9


def test_shared_igea_full_pipeline_timing():
    # the large scan, once: clean + decimate to the solver's resolution + map back
    mesh = load_scan("cyberware_igea.ply", "m")
    cleaned, report = clean_mesh(mesh)
    assert not report.changed
    decimation = decimate_mesh(cleaned, target_edge_length=1.5)
    assert decimation.mapping.weights.shape == (cleaned.n_points, 3)
    assert decimation.mapping.distance.max() < 0.5  # mm, on a 99 mm head
    assert decimation.seconds < 30


def test_a_large_decimation_in_its_own_process_gives_the_same_proxy(monkeypatch):
    """From ISOLATED_TRIANGLES on, fast-simplification runs in a child process (its module-level mesh stays
    there); the proxy is the one the call in this process makes."""
    from translucency import processes
    from translucency.io import decimate

    points, triangles = icosphere(3)
    here = simplify_arrays(points, triangles, 200)
    monkeypatch.setattr(decimate, "ISOLATED_TRIANGLES", 0)
    children = []
    run = processes.run_in_child
    monkeypatch.setattr(
        processes, "run_in_child", lambda function, *args: children.append(function) or run(function, *args)
    )
    apart = simplify_arrays(points, triangles, 200)
    assert children == [decimate.fast_simplify]
    assert all(np.array_equal(a, b) for a, b in zip(here, apart))


def _edge_uses(triangles):
    """How many triangles hold each undirected edge."""
    from translucency.geometry.topology import unique_edges

    _, edge_of_corner = unique_edges(triangles)
    return np.bincount(edge_of_corner.ravel())


@pytest.mark.parametrize("parts", [2, 3])
def test_a_mesh_decimated_in_parts_is_one_closed_surface_as_close_as_the_whole(monkeypatch, parts):
    """Parts side by side (each in a child of its own, cuts kept), welded and decimated once more: a closed
    sphere stays one closed 2-manifold of genus 0 with the triangles asked for, no doubled vertex along the
    cuts, and as close to the sphere as the proxy decimated whole."""
    from translucency import processes
    from translucency.io import decimate

    points, triangles = icosphere(5, radius=25.0)  # 20,480 triangles
    whole_points, whole_triangles = simplify_arrays(points, triangles, 1000)
    monkeypatch.setattr(decimate, "decimation_parts", lambda n_triangles: parts)
    calls = []
    run = processes.run_in_child
    monkeypatch.setattr(
        processes,
        "run_in_child",
        lambda function, *args, **kwargs: calls.append(args[4:]) or run(function, *args, **kwargs),
    )
    new_points, new_triangles = simplify_arrays(points, triangles, 1000)
    assert calls == [(True,)] * parts  # each part kept its cut; the last pass (small: here) did not
    assert len(new_triangles) == pytest.approx(1000, rel=0.02)
    assert np.all(_edge_uses(new_triangles) == 2)  # closed, and every edge between two triangles
    assert len(new_points) - len(new_triangles) // 2 == 2  # V - E + F = V - F/2 = 2: one sphere, no handle
    assert len(np.unique(new_points, axis=0)) == len(new_points)  # the cuts' vertices were welded
    error = np.abs(np.linalg.norm(new_points, axis=1) - 25.0).max()
    whole_error = np.abs(np.linalg.norm(whole_points, axis=1) - 25.0).max()
    assert error <= 2 * whole_error + 1e-3  # mm


def test_welding_joins_the_cut_vertices_only():
    """Two parts that share the cut (0,0,0)-(1,0,0), each with its own copy, and each with a vertex at
    (5,5,5) that is not on the cut: the cut's copies become one vertex, the other two stay two."""
    from translucency.io.decimate import _weld

    cut = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    part_a = (
        np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [5.0, 5.0, 5.0]]),
        np.array([[1, 0, 2], [2, 0, 3]]),
    )
    part_b = (
        np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [5.0, 5.0, 5.0]]),
        np.array([[1, 0, 2], [0, 1, 3]]),
    )
    points, triangles = _weld(cut, np.array([2, 2]), [part_a, part_b])
    assert len(points) == 6  # 2 on the cut, (0,1,0), (0,-1,0) and (5,5,5) twice
    assert np.array_equal(points[triangles[0]], part_a[0][part_a[1][0]])
    assert np.array_equal(points[triangles[2]], part_b[0][part_b[1][0]])
    shared = set(triangles[0]) & set(triangles[2])
    assert sorted(map(tuple, points[sorted(shared)])) == [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0)]
    assert triangles[1][2] != triangles[3][2]  # the two (5,5,5) vertices stay apart


@pytest.mark.parametrize(
    ("cores", "n_triangles", "parts"),
    [
        (2, 1_000_000, 1),  # too small to be worth a second child
        (2, 4_200_000, 2),  # the Igea subdivided twice: one part per core
        (2, 20_000_000, 4),  # 10M vertices: parts of at most 5M triangles, two at a time
        (1, 4_200_000, 1),
        (1, 20_000_000, 4),  # one core: the parts one after the other, for the memory
        (8, 20_000_000, 8),
    ],
)
def test_decimation_parts_one_per_thread_and_none_too_large(monkeypatch, cores, n_triangles, parts):
    from translucency import threads
    from translucency.io import decimate

    monkeypatch.setattr(threads, "thread_count", lambda: cores)
    assert decimate.PART_TRIANGLES == 2_000_000 and decimate.PART_MAX_TRIANGLES == 5_000_000
    assert decimate.decimation_parts(n_triangles) == parts


def test_a_cut_position_with_more_vertices_than_parts_is_not_welded():
    """Two vertices of one part at a position of the cut (a mesh with duplicate vertices there): which one
    belongs to the other part's is not known, so the weld gives up (None) and the caller decimates whole."""
    from translucency.io.decimate import _weld

    cut = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    part_a = (np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), np.array([[1, 0, 2]]))
    doubled = (
        np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]),
        np.array([[1, 0, 2], [3, 0, 2]]),
    )
    assert _weld(cut, np.array([2, 2]), [part_a, doubled]) is None


def test_parts_that_cannot_be_welded_leave_the_mesh_to_one_pass(monkeypatch):
    from translucency.io import decimate

    points, triangles = icosphere(4, radius=25.0)
    whole = simplify_arrays(points, triangles, 500)
    monkeypatch.setattr(decimate, "decimation_parts", lambda n_triangles: 2)
    monkeypatch.setattr(decimate, "_weld", lambda *args: None)
    assert all(np.array_equal(a, b) for a, b in zip(whole, simplify_arrays(points, triangles, 500)))


def test_under_a_memory_limit_the_parts_are_smaller_and_go_fewer_at_a_time(monkeypatch):
    """The decimating children's memory (``CHILD_BYTES_PER_TRIANGLE`` per triangle of a part) is held within the
    room a memory limit leaves beside what the process holds: a 6M-triangle mesh with 1 GB of room goes in three
    parts of 2M triangles (700 MB each), one at a time; without a limit, one part per thread side by side."""
    from translucency import memory
    from translucency.io import decimate

    monkeypatch.setattr(memory, "resident_memory", lambda: 1e9)
    monkeypatch.setattr("translucency.threads.thread_count", lambda: 2)
    assert decimate.decimation_plan(6_000_000) == (2, 2)
    parts, at_once = decimate.decimation_plan(6_000_000, memory_limit_bytes=2e9)
    assert (parts, at_once) == (3, 1)
    assert -(-6_000_000 // parts) * decimate.CHILD_BYTES_PER_TRIANGLE <= 1e9
    parts, at_once = decimate.decimation_plan(6_000_000, memory_limit_bytes=1.5e9)  # 0.5 GB of room
    assert parts == 5 and at_once == 1
    assert decimate.decimation_plan(1_000_000, memory_limit_bytes=2e9) == (1, 2)  # fits whole: as without a limit
