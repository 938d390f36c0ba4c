"""Shadow rays: analytic shadows of a box, no self-hits, segments, threads, validation, the cache."""

import numpy as np
import pytest
import trimesh

from translucency.errors import InvalidParameterError, MeshError
from translucency.scatter.visibility import RELATIVE_OFFSET, Occluder, VisibilityCache, array_digest

BOX_CENTRE = np.array([1.0, -2.0, 30.0])
BOX_EXTENTS = np.array([12.0, 9.0, 4.0])


def sphere(radius=10.0, subdivisions=3):
    """Icosphere (points mm, triangles, unit vertex normals)."""
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return np.asarray(mesh.vertices), np.asarray(mesh.faces), np.asarray(mesh.vertex_normals)


def sphere_and_box():
    """An icosphere at the origin and an axis-aligned box above it, as one mesh."""
    p, t, n = sphere()
    box = trimesh.creation.box(extents=BOX_EXTENTS)
    box.apply_translation(BOX_CENTRE)
    points = np.vstack([p, box.vertices])
    triangles = np.vstack([t, np.asarray(box.faces) + len(p)])
    return points, triangles, p, n


def ray_hits_box(origins, direction, lo, hi):
    """Slab test: does the ray origin + t direction (t > 0) meet the box [lo, hi]? Also the margin."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (lo - origins) / direction
        t2 = (hi - origins) / direction
    t_near = np.max(np.minimum(t1, t2), axis=1)
    t_far = np.min(np.maximum(t1, t2), axis=1)
    return (t_near <= t_far) & (t_far > 0), t_far - t_near


@pytest.mark.parametrize("direction", [(0.0, 0.0, 1.0), (0.25, -0.15, 1.0), (-0.3, 0.1, 1.0)])
def test_sphere_behind_box_is_dark_exactly_where_the_box_shadows_it(direction):
    points, triangles, p, n = sphere_and_box()
    w = np.asarray(direction) / np.linalg.norm(direction)
    occluder = Occluder(points, triangles)
    front = n @ w > 0
    visible = occluder.visible(p[front], n[front], w)
    lo, hi = BOX_CENTRE - BOX_EXTENTS / 2, BOX_CENTRE + BOX_EXTENTS / 2
    shadowed, margin = ray_hits_box(p[front], w, lo, hi)
    # Rays that only graze a box edge (within 1e-3 mm) may go either way; there are hardly any.
    clear = np.abs(margin) > 1e-3
    assert clear.mean() > 0.98
    assert 20 < shadowed.sum() < front.sum()  # the box does shadow part of the lit side
    assert np.array_equal(visible[clear], ~shadowed[clear])


def test_rays_from_a_convex_mesh_never_hit_it():
    p, t, n = sphere(radius=25.0, subdivisions=4)
    occluder = Occluder(p, t)
    rng = np.random.default_rng(0)
    directions = rng.normal(size=(40, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    for w in directions:
        front = n @ w > 0
        assert occluder.visible(p[front], n[front], w).all()


def test_without_offset_rays_hit_their_own_faces():
    # The reason for the offset: from the vertex itself, rays hit the adjacent faces.
    p, t, n = sphere()
    occluder = Occluder(p, t)
    w = np.array([0.0, 0.6, 0.8])
    front = n @ w > 0
    assert occluder.visible(p[front], 0.0 * n[front], w).mean() < 0.9
    assert occluder.visible(p[front], n[front], w).all()


def test_offset_scales_with_the_mesh():
    p, t, _ = sphere()
    small, large = Occluder(p, t), Occluder(p * 1000.0, t)
    assert large.epsilon == pytest.approx(1000.0 * small.epsilon)
    assert small.epsilon == pytest.approx(RELATIVE_OFFSET * 20.0 * np.sqrt(3), rel=0.05)  # box diagonal 2 r sqrt(3)
    # Far from the origin the float32 spacing sets the floor.
    far = Occluder(p + 1e7, t)
    assert far.epsilon >= 64 * np.finfo(np.float32).eps * 1e7


def test_point_light_segments_stop_at_the_light():
    points, triangles, p, n = sphere_and_box()
    occluder = Occluder(points, triangles)
    for light, expect_shadow in (((0.0, 0.0, 20.0), False), ((1.0, -2.0, 60.0), True)):
        to_light = np.asarray(light) - p
        distance = np.linalg.norm(to_light, axis=1)
        w = to_light / distance[:, None]
        front = np.einsum("ij,ij->i", n, w) > 0
        visible = occluder.visible(p[front], n[front], w[front], distance[front])
        assert (not visible.all()) == expect_shadow


def test_threads_give_the_same_answer_as_one():
    points, triangles, _, _ = sphere_and_box()
    rng = np.random.default_rng(1)
    origins = rng.uniform(-40, 40, size=(70000, 3))
    directions = rng.normal(size=(70000, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    serial = Occluder(points, triangles, workers=1)
    threaded = Occluder(points, triangles, workers=2)
    a = serial.visible(origins, directions, directions)
    b = threaded.visible(origins, directions, directions)
    assert np.array_equal(a, b) and 0 < a.mean() < 1
    assert threaded.rays_cast == 70000


def test_no_triangles_occlude_nothing():
    occluder = Occluder(np.zeros((3, 3)), np.zeros((0, 3), dtype=np.int64))
    assert occluder.visible(np.zeros((4, 3)), np.ones((4, 3)), (0, 0, 1)).all()


def test_cache_keeps_the_most_recent_scenes_and_visibility():
    cache = VisibilityCache(max_entries=2, max_scenes=1)
    points, triangles, _ = sphere(subdivisions=1)
    first, reused = cache.occluder(points, triangles)
    assert not reused and cache.occluder(points, triangles) == (first, True)
    other, reused = cache.occluder(points + 1.0, triangles)
    assert not reused and other is not first
    assert cache.occluder(points, triangles)[1] is False  # one scene kept: the first was dropped
    cache.put("a", [True, False])
    cache.put("b", [True])
    assert cache.get("a").tolist() == [True, False]  # "a" is now the most recent
    cache.put("c", [False])
    assert cache.get("b") is None and len(cache) == 2 and not cache.get("c").flags.writeable
    assert (cache.hits, cache.misses) == (2, 1)


@pytest.mark.parametrize(
    "points, triangles, words",
    [
        (np.zeros((3, 2)), [[0, 1, 2]], r"shape \(n, 3\)"),
        (np.full((3, 3), np.nan), [[0, 1, 2]], "NaN"),
        (np.eye(3), [[0, 1, 3]], "indices must lie in"),
        (np.eye(3), [[0.0, 1.0, 2.0]], "integer array"),
    ],
)
def test_occluder_rejects_bad_meshes_with_a_sentence(points, triangles, words):
    with pytest.raises(MeshError, match=words):
        Occluder(points, triangles)


def test_digests_follow_the_bytes_whether_remembered_or_not():
    rng = np.random.default_rng(3)
    frozen = rng.normal(size=(50, 3))
    frozen.setflags(write=False)
    fresh = frozen.copy()  # writeable: hashed every time
    assert array_digest(frozen) == array_digest(frozen) == array_digest(fresh)
    assert array_digest(frozen, fresh) != array_digest(fresh, fresh[::-1].copy())
    fresh[7, 1] += 1e-9  # changed in place: a new digest
    assert array_digest(fresh) != array_digest(frozen)
    assert array_digest(frozen.astype(np.float32)) != array_digest(frozen)  # the dtype counts
    del frozen  # its remembered digest goes with it: a new array at the same address is hashed anew
    again = np.zeros((50, 3))
    again.setflags(write=False)
    assert array_digest(again) == array_digest(np.zeros((50, 3)))


def test_occluder_rejects_bad_options():
    with pytest.raises(InvalidParameterError, match="relative_offset"):
        Occluder(np.eye(3), [[0, 1, 2]], relative_offset=0.0)
    with pytest.raises(InvalidParameterError, match="workers"):
        Occluder(np.eye(3), [[0, 1, 2]], workers=0)


def test_no_self_hits_on_a_real_scan(shared_meshes):
    """On the bunny, no offset ray hits a face of its own vertex's one-ring that faces the light.

    Hits on one-ring faces that face away from the light are real geometry (the vertex sits at the
    shadow terminator or in a crease) and are allowed.
    """
    plyfile = pytest.importorskip("plyfile")
    from embreex.mesh_construction import TriangleMesh
    from embreex.rtcore_scene import EmbreeScene

    ply = plyfile.PlyData.read(shared_meshes / "stanford_bunny_zipper.ply")
    v = ply["vertex"]
    points = np.column_stack([v["x"], v["y"], v["z"]]).astype(np.float64) * 1000.0  # file is in metres
    triangles = np.vstack(ply["face"]["vertex_indices"]).astype(np.int64)
    mesh = trimesh.Trimesh(points, triangles, process=False)
    normals = np.asarray(mesh.vertex_normals)
    occluder = Occluder(points, triangles)
    scene = EmbreeScene()
    TriangleMesh(scene, points.astype(np.float32), triangles.astype(np.int32))
    for w in np.array([[0.3, 0.8, 0.5], [-0.7, 0.1, 0.2], [0.0, -1.0, 0.1]]):
        w = w / np.linalg.norm(w)
        front = np.flatnonzero(normals @ w > 0)
        origins = points[front] + occluder.epsilon * normals[front]
        hit = scene.run(origins.astype(np.float32), np.tile(w, (len(front), 1)).astype(np.float32), query="INTERSECT")
        # The Occluder agrees with the first-hit query.
        assert np.array_equal(occluder.visible(points[front], normals[front], w), hit < 0)
        struck = hit >= 0
        own = (triangles[hit[struck]] == front[struck, None]).any(axis=1)  # hit a face of its own vertex
        toward_light = np.asarray(mesh.face_normals)[hit[struck]] @ w > 0
        assert not np.any(own & toward_light)
        assert 0.02 < struck.mean() < 0.4  # a real shadow, not noise


def test_intersect_gives_the_triangle_the_barycentrics_and_the_distance_of_the_hit():
    corners = np.array([[-50.0, -50.0, 10.0], [80.0, -40.0, 10.0], [-30.0, 90.0, 10.0], [0.0, 0.0, 30.0]])
    triangles = np.array([[0, 1, 2], [0, 1, 3]])
    rng = np.random.default_rng(3)
    origins = np.column_stack([rng.uniform(-10, 10, (40000, 2)), np.zeros(40000)])
    up = np.tile([0.0, 0.0, 1.0], (40000, 1))
    directions = np.column_stack([rng.uniform(-0.3, 0.3, (40000, 2)), np.ones(40000)])
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    directions[:5] = (0.0, 0.0, -1.0)  # these escape
    threaded = Occluder(corners, triangles, workers=2).intersect(origins, up, directions)
    single = Occluder(corners, triangles, workers=1)
    hits = single.intersect(origins, up, directions)
    for a, b in zip(threaded, hits):
        np.testing.assert_array_equal(a, b)  # the chunks on threads come back in order
    assert np.all(hits.triangle[:5] == -1) and np.all(np.isinf(hits.distance[:5])) and single.rays_cast == 40000
    met = hits.triangle[5:]
    assert np.all(met == 0)  # the plane z = 10 is the first thing every upward ray meets here
    start = origins[5:] + single.epsilon * up[5:]
    expected = start + directions[5:] * ((10.0 - start[:, 2]) / directions[5:, 2])[:, None]
    u, v = hits.u[5:, None], hits.v[5:, None]
    at = (1 - u - v) * corners[0] + u * corners[1] + v * corners[2]
    np.testing.assert_allclose(at, expected, atol=1e-4)
    np.testing.assert_allclose(hits.distance[5:], np.linalg.norm(expected - start, axis=1), rtol=1e-5)
