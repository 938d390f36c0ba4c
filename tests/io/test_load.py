"""Loading every supported format, with per-vertex properties and units; the shared scans."""

import hashlib
import warnings

import numpy as np
import plyfile
import pytest

from translucency.errors import MeshError
from translucency.io import TriangleMesh, load_mesh, read_mesh_arrays, to_pyvista
from translucency.io.units import ImplausibleSizeWarning

from .conftest import icosphere, load_scan, shared_scan


def write_ply(path, points, faces, *, text=False, byte_order="<", colors=None, extra=None, strips=None):
    """Write a PLY with plyfile: faces as index lists (any length), optional colours and scalar props."""
    fields = [("x", "f4"), ("y", "f4"), ("z", "f4")]
    if colors is not None:
        fields += [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    for name, values in (extra or {}).items():
        fields.append((name, values.dtype.str))
    vertex = np.empty(len(points), dtype=fields)
    for i, axis in enumerate("xyz"):
        vertex[axis] = points[:, i]
    if colors is not None:
        for i, name in enumerate(("red", "green", "blue")):
            vertex[name] = colors[:, i]
    for name, values in (extra or {}).items():
        vertex[name] = values
    elements = [plyfile.PlyElement.describe(vertex, "vertex")]
    if faces is not None:
        face = np.empty(len(faces), dtype=[("vertex_indices", object)])
        face["vertex_indices"] = [np.asarray(f, dtype=np.int32) for f in faces]
        elements.append(plyfile.PlyElement.describe(face, "face", val_types={"vertex_indices": "i4"}))
    if strips is not None:
        strip = np.empty(1, dtype=[("vertex_indices", object)])
        strip["vertex_indices"] = [np.asarray(strips, dtype=np.int32)]
        elements.append(
            plyfile.PlyElement.describe(
                strip, "tristrips", len_types={"vertex_indices": "i4"}, val_types={"vertex_indices": "i4"}
            )
        )
    plyfile.PlyData(elements, text=text, byte_order=byte_order).write(str(path))
    return path


@pytest.fixture
def sphere_arrays():
    points, triangles = icosphere(2, 20.0)
    colors = np.clip((points / 20 + 1) * 127.5, 0, 255).astype(np.uint8)
    return points, triangles, colors


@pytest.mark.parametrize("text, byte_order", [(True, "="), (False, "<"), (False, ">")])
def test_ply_ascii_and_binary_keep_colours_and_properties(tmp_path, sphere_arrays, text, byte_order):
    points, triangles, colors = sphere_arrays
    confidence = np.linspace(0, 1, len(points)).astype(np.float32)
    path = write_ply(
        tmp_path / "s.ply",
        points,
        triangles,
        text=text,
        byte_order=byte_order,
        colors=colors,
        extra={"confidence": confidence},
    )
    mesh = load_mesh(path, unit="mm")
    np.testing.assert_allclose(mesh.points, points.astype(np.float32), rtol=0, atol=0)
    np.testing.assert_array_equal(mesh.triangles, triangles)
    np.testing.assert_array_equal(mesh.point_data["colors"], colors)
    np.testing.assert_array_equal(mesh.point_data["confidence"], confidence)
    assert mesh.point_data["confidence"].dtype.isnative
    assert mesh.source == path and mesh.mm_per_unit == 1.0


@pytest.mark.parametrize("text", [True, False])
def test_ply_polygons_are_triangulated(tmp_path, text):
    points = np.array([[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0], [5, 15, 0]], dtype=float)
    path = write_ply(tmp_path / "q.ply", points, [[0, 1, 2, 3], [3, 2, 4]], text=text)
    mesh = load_mesh(path, unit="mm")
    np.testing.assert_array_equal(mesh.triangles, [[0, 1, 2], [0, 2, 3], [3, 2, 4]])
    assert mesh.surface_area == pytest.approx(125.0)


@pytest.mark.parametrize("text", [True, False])
def test_ply_all_quads(tmp_path, text):
    points = np.array([[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0], [20, 0, 0], [20, 10, 0]], dtype=float)
    path = write_ply(tmp_path / "quads.ply", points, [[0, 1, 2, 3], [1, 4, 5, 2]], text=text)
    mesh = load_mesh(path, unit="mm")
    np.testing.assert_array_equal(mesh.triangles, [[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]])


def test_ply_triangle_strips(tmp_path):
    points = np.array([[x, y, 0.0] for x in range(0, 50, 10) for y in (0, 10)])
    path = write_ply(tmp_path / "strip.ply", points, None, strips=[0, 1, 2, 3, 4, 5, -1, 6, 7, 8, 9])
    mesh = load_mesh(path, unit="mm")
    assert mesh.n_triangles == 6
    assert mesh.surface_area == pytest.approx(300.0)
    normals = mesh.vertex_normals()
    assert np.all(np.abs(np.abs(normals[:, 2]) - 1) < 1e-12)
    assert np.all(np.sign(normals[:, 2]) == np.sign(normals[0, 2]))  # one winding


def test_obj_with_vertex_colours_and_quads(tmp_path):
    path = tmp_path / "q.obj"
    path.write_text(
        "# quad\nv 0 0 0 1 0 0\nv 10 0 0 0 1 0\nv 10 10 0 0 0 1\nv 0 10 0 1 1 1\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\n"
    )
    mesh = load_mesh(path, unit="mm")
    assert mesh.n_triangles == 2 and mesh.surface_area == pytest.approx(100.0)
    np.testing.assert_array_equal(
        mesh.point_data["colors"][:, :3], [[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]]
    )


def test_obj_texture_corners_do_not_split_vertices_and_negative_indices(tmp_path):
    path = tmp_path / "t.obj"
    path.write_text(
        "mtllib t.mtl\no scan\nv 0 0 0\nv 10 0 0\nv 10 10 0\nv 0 10 0\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\nvn 0 0 1\n"
        "usemtl skin\nf 1/1/1 2/2/1 3/3/1\nf -4/5/1 -2/4/1 -1/4/1\n"
    )
    mesh = load_mesh(path, unit="mm")
    assert mesh.n_points == 4  # VTK's reader would make 6 points, one per face corner
    np.testing.assert_array_equal(mesh.triangles, [[0, 1, 2], [0, 2, 3]])


def test_obj_index_zero_is_out_of_range(tmp_path):
    path = tmp_path / "zero.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n")
    with pytest.raises(MeshError, match="refers to vertex"):
        load_mesh(path)


def test_off_and_coff(tmp_path):
    path = tmp_path / "c.off"
    path.write_text(
        "COFF\n# comment\n4 2 0\n0 0 0 255 0 0 255\n10 0 0 0 255 0 255\n10 10 0 0 0 255 255\n0 10 0 9 9 9 "
        "255\n4 0 1 2 3\n3 0 2 1 1 0 0\n"
    )
    mesh = load_mesh(path, unit="mm")
    np.testing.assert_array_equal(mesh.triangles, [[0, 1, 2], [0, 2, 3], [0, 2, 1]])
    np.testing.assert_array_equal(mesh.point_data["colors"][:, :3], [[255, 0, 0], [0, 255, 0], [0, 0, 255], [9, 9, 9]])
    plain = tmp_path / "p.off"
    plain.write_text("OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    assert load_mesh(plain, "cm").extent == pytest.approx(10.0)


@pytest.mark.parametrize("suffix", [".vtp", ".vtk", ".stl", ".obj"])
def test_vtk_formats(tmp_path, sphere_arrays, suffix):
    points, triangles, _ = sphere_arrays
    mesh = TriangleMesh(points, triangles, {"confidence": np.arange(len(points), dtype=float)})
    path = tmp_path / f"s{suffix}"
    to_pyvista(mesh).save(str(path))
    loaded = load_mesh(path, unit="mm")
    assert loaded.n_triangles == len(triangles)
    assert loaded.surface_area == pytest.approx(mesh.surface_area, rel=1e-6)
    if suffix in (".vtp", ".vtk"):
        np.testing.assert_array_equal(loaded.points, points)
        np.testing.assert_array_equal(loaded.point_data["confidence"], mesh.point_data["confidence"])


def test_vtu_surface_is_extracted(tmp_path):
    import pyvista

    grid = pyvista.ImageData(dimensions=(3, 3, 3), spacing=(5, 5, 5)).cast_to_unstructured_grid()
    grid.save(str(tmp_path / "g.vtu"))
    mesh = load_mesh(tmp_path / "g.vtu", unit="mm")
    assert mesh.surface_area == pytest.approx(6 * 100.0)


@pytest.mark.parametrize("suffix", [".wrl", ".x3d", ".dae", ".3ds", ".ctm"])
def test_pymeshlab_formats(tmp_path, suffix):
    from translucency.io.meshlab import import_pymeshlab

    mesh_set = import_pymeshlab().MeshSet()
    mesh_set.create_sphere(subdiv=2)
    mesh_set.current_mesh()
    path = tmp_path / f"s{suffix}"
    mesh_set.save_current_mesh(str(path))
    with pytest.warns(ImplausibleSizeWarning):  # a unit sphere, 2 "mm" across
        mesh = load_mesh(path, unit="mm")
    assert (mesh.n_points, mesh.n_triangles) == (162, 320)


def test_format_override(tmp_path, sphere_arrays):
    points, triangles, _ = sphere_arrays
    path = write_ply(tmp_path / "mesh.data", points, triangles)
    assert load_mesh(path, unit="mm", format="ply").n_triangles == len(triangles)


def test_unit_converts_to_mm_and_warns_when_implausible(tmp_path):
    points, triangles = icosphere(1, 0.05)  # 0.1 units across
    path = write_ply(tmp_path / "small.ply", points, triangles)
    with pytest.warns(ImplausibleSizeWarning, match="unit='m'"):
        load_mesh(path, unit="mm")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mesh = load_mesh(path, unit="m")
    assert mesh.extent == pytest.approx(100.0, rel=1e-6)
    assert mesh.mm_per_unit == 1000.0


def test_loading_does_not_modify_the_file(tmp_path, sphere_arrays):
    points, triangles, colors = sphere_arrays
    path = write_ply(tmp_path / "s.ply", points, triangles, colors=colors)
    before = hashlib.sha256(path.read_bytes()).hexdigest(), path.stat().st_mtime_ns
    mesh = load_mesh(path, unit="mm")
    mesh.replace(points=mesh.points * 2)
    assert (hashlib.sha256(path.read_bytes()).hexdigest(), path.stat().st_mtime_ns) == before


def test_read_mesh_arrays_stays_in_file_units(tmp_path, sphere_arrays):
    points, triangles, _ = sphere_arrays
    path = write_ply(tmp_path / "s.ply", points, triangles)
    p, t, data = read_mesh_arrays(path)
    np.testing.assert_array_equal(p, points.astype(np.float32))
    assert data == {}


# ---- the shared scans (README counts) ---------------------------------------------------------------
@pytest.mark.parametrize(
    "name, unit, vertices, triangles, keys",
    [
        ("stanford_bunny_zipper.ply", "m", 35947, 69451, {"confidence", "intensity"}),
        ("cyberware_horse.ply", "m", 48485, 96966, {"colors", "confidence"}),
        ("ggg_angel_sfm.ply", "mm", 18412, 35804, set()),
        ("ggg_angel_sfm.vtp", "mm", 18412, 35804, set()),
        ("ggg_birdbath_sfm.ply", "mm", 18796, 35079, set()),
        ("ggg_birdbath_sfm.vtp", "mm", 18796, 35079, set()),
    ],
)
def test_shared_scans_load_with_their_counts(name, unit, vertices, triangles, keys):
    path = shared_scan(name)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # plausible in the right unit: no warning
        mesh = load_mesh(path, unit)
    assert (mesh.n_points, mesh.n_triangles) == (vertices, triangles)
    assert set(mesh.point_data) == keys


def test_shared_bunny_in_mm_warns_with_the_likely_unit():
    with pytest.warns(ImplausibleSizeWarning, match=r"stanford_bunny_zipper.ply is 0.16 mm across.*unit='m'"):
        load_mesh(shared_scan("stanford_bunny_zipper.ply"), unit="mm")


def test_shared_vtp_and_ply_copies_are_identical():
    ply, vtp = load_scan("ggg_birdbath_sfm.ply"), load_scan("ggg_birdbath_sfm.vtp")
    np.testing.assert_array_equal(ply.points, vtp.points)
    np.testing.assert_array_equal(ply.triangles, vtp.triangles)


def test_shared_igea_tristrips_equal_the_converted_triangle_list():
    strips = load_scan("cyberware_igea_tristrips.ply", "m")
    triangles = load_scan("cyberware_igea.ply", "m")
    assert (strips.n_points, strips.n_triangles) == (134345, 268686)
    np.testing.assert_array_equal(strips.points, triangles.points)
    np.testing.assert_array_equal(strips.triangles, triangles.triangles)
    assert strips.extent == pytest.approx(99.3, abs=0.1)
