"""Baked PLY: round trips through plyfile, trimesh, pymeshlab and PyVista; atomic writes; metadata."""

import io
import json
import os

import numpy as np
import plyfile
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from translucency.errors import InvalidParameterError, MeshError, TranslucencyError
from translucency.io import read_baked_ply, write_baked_ply
from translucency.io.baked import comments_to_metadata, metadata_to_comments

METADATA = {
    "material": "marble",
    "coefficients": {"sigma_a": [0.0021, 0.0041, 0.0071], "sigma_s_reduced": [2.19, 2.62, 3.0], "g": 0.0, "eta": 1.5},
    "lights": [{"type": "directional", "direction": [0.0, 0.0, -1.0], "irradiance": [1.0, 1.0, 1.0]}],
    "model": "directional dipole",
    "method": "tree",
    "tolerance": 1e-3,
}


@pytest.fixture
def bake(tmp_path, sphere_mesh):
    rng = np.random.default_rng(7)
    n = sphere_mesh.n_points
    values = dict(
        radiance=rng.random((n, 3)) * 3.0,
        b=rng.random((n, 3)) * 5.0,
        colors_rgb8=rng.integers(0, 256, (n, 3)).astype(np.uint8),
    )
    path = write_baked_ply(tmp_path / "bake.ply", sphere_mesh, metadata=METADATA, **values)
    return path, sphere_mesh, values


def test_layout_is_binary_little_endian_with_the_named_properties(bake):
    path, mesh, _ = bake
    data = plyfile.PlyData.read(str(path))
    assert data.byte_order == "<" and not data.text
    names = [p.name for p in data["vertex"].properties]
    assert names == ["x", "y", "z", "nx", "ny", "nz", "red", "green", "blue",
                     "radiance_r", "radiance_g", "radiance_b", "b_r", "b_g", "b_b"]  # fmt: skip
    assert data["vertex"]["radiance_r"].dtype == np.float32 and data["vertex"]["red"].dtype == np.uint8
    assert data["face"].count == mesh.n_triangles
    assert all(len(line) < 200 for line in data.comments)


def test_round_trip_with_read_baked_ply(bake):
    path, mesh, values = bake
    baked = read_baked_ply(path)
    np.testing.assert_array_equal(baked.points, mesh.points.astype(np.float32))
    np.testing.assert_array_equal(baked.triangles, mesh.triangles)
    np.testing.assert_array_equal(baked.radiance, values["radiance"].astype(np.float32))
    np.testing.assert_array_equal(baked.b, values["b"].astype(np.float32))
    np.testing.assert_array_equal(baked.colors_rgb8, values["colors_rgb8"])
    np.testing.assert_allclose(baked.normals, mesh.vertex_normals(), atol=1e-7)
    for key, value in METADATA.items():
        assert baked.metadata[key] == value
    assert baked.metadata["source_unit"] == "mm" and baked.metadata["length_unit"] == "mm"
    assert baked.metadata["radiance_unit"] == "W/(m^2 sr) per W/m^2 of irradiance of the light"
    assert baked.metadata["version"] and baked.metadata["format"] == "translucency-bake"


def test_header_records_the_mesh_unit_and_whether_it_was_inferred(tmp_path, sphere_mesh):
    n = sphere_mesh.n_points
    inferred = sphere_mesh.replace(points=sphere_mesh.points * 1000.0, mm_per_unit=1000.0, unit_inferred=True)
    path = write_baked_ply(
        tmp_path / "m.ply", inferred, np.ones((n, 3)), np.ones((n, 3)), np.zeros((n, 3), np.uint8), METADATA
    )
    metadata = read_baked_ply(path).metadata
    source = ("source_unit", "source_unit_name", "source_mm_per_unit", "source_unit_inferred")
    assert tuple(metadata[key] for key in source) == ("m", "metres", 1000.0, True)
    assert metadata["length_unit"] == "mm"  # the coordinates: mm whatever the file's unit
    assert "unit" not in metadata and "mm_per_unit" not in metadata
    given = write_baked_ply(
        tmp_path / "g.ply", sphere_mesh, np.ones((n, 3)), np.ones((n, 3)), np.zeros((n, 3), np.uint8), METADATA
    )
    assert read_baked_ply(given).metadata["source_unit_inferred"] is False


def test_round_trip_with_plyfile(bake):
    path, _, values = bake
    vertex = plyfile.PlyData.read(str(path))["vertex"]
    for i, channel in enumerate("rgb"):
        np.testing.assert_array_equal(vertex[f"radiance_{channel}"], values["radiance"][:, i].astype(np.float32))
        np.testing.assert_array_equal(vertex[f"b_{channel}"], values["b"][:, i].astype(np.float32))
        np.testing.assert_array_equal(vertex[("red", "green", "blue")[i]], values["colors_rgb8"][:, i])


def test_the_file_is_what_plyfile_writes(bake):
    path, _, _ = bake
    stream = io.BytesIO()
    plyfile.PlyData.read(str(path)).write(stream)
    assert stream.getvalue() == path.read_bytes()


def test_round_trip_with_trimesh(bake):
    trimesh = pytest.importorskip("trimesh")
    path, mesh, values = bake
    loaded = trimesh.load(str(path), process=False)
    np.testing.assert_array_equal(loaded.vertices, mesh.points.astype(np.float32))
    np.testing.assert_array_equal(loaded.faces, mesh.triangles)
    np.testing.assert_array_equal(loaded.visual.vertex_colors[:, :3], values["colors_rgb8"])
    raw = loaded.metadata["_ply_raw"]["vertex"]["data"]
    np.testing.assert_array_equal(raw["b_g"], values["b"][:, 1].astype(np.float32))


def test_round_trip_with_pymeshlab(bake):
    from translucency.io.meshlab import import_pymeshlab

    path, mesh, values = bake
    mesh_set = import_pymeshlab().MeshSet()
    mesh_set.load_new_mesh(str(path))
    loaded = mesh_set.current_mesh()
    np.testing.assert_array_equal(loaded.vertex_matrix(), mesh.points.astype(np.float32))
    np.testing.assert_array_equal(loaded.face_matrix(), mesh.triangles)
    colours = np.round(loaded.vertex_color_matrix()[:, :3] * 255).astype(np.uint8)
    np.testing.assert_array_equal(colours, values["colors_rgb8"])
    np.testing.assert_allclose(loaded.vertex_normal_matrix(), read_baked_ply(path).normals, atol=1e-6)


def test_round_trip_with_pyvista(bake):
    import pyvista

    path, mesh, values = bake
    loaded = pyvista.read(str(path))
    np.testing.assert_array_equal(loaded.points, mesh.points.astype(np.float32))
    np.testing.assert_array_equal(loaded.regular_faces, mesh.triangles)
    np.testing.assert_array_equal(loaded.point_data["RGB"], values["colors_rgb8"])


def test_existing_output_is_replaced_only_by_a_complete_file(bake, monkeypatch):
    path, mesh, values = bake
    before = path.read_bytes()
    # a failure in the middle of writing: the old bake stays, and no temporary file is left
    real_fsync = os.fsync

    def broken_fsync(fd):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", broken_fsync)
    with pytest.raises(TranslucencyError, match="No space left"):
        write_baked_ply(path, mesh, metadata=METADATA, **values)
    monkeypatch.setattr(os, "fsync", real_fsync)
    assert path.read_bytes() == before
    assert sorted(p.name for p in path.parent.iterdir()) == ["bake.ply"]
    # a successful rewrite replaces it
    write_baked_ply(path, mesh, metadata={**METADATA, "model": "standard dipole"}, **values)
    assert read_baked_ply(path).metadata["model"] == "standard dipole"
    assert sorted(p.name for p in path.parent.iterdir()) == ["bake.ply"]


def test_the_input_scan_is_never_overwritten(tmp_path, sphere_mesh):
    source = tmp_path / "scan.ply"
    write_baked_ply(source, sphere_mesh, np.zeros((sphere_mesh.n_points, 3)), np.zeros((sphere_mesh.n_points, 3)),
                    np.zeros((sphere_mesh.n_points, 3), np.uint8), METADATA)  # fmt: skip
    from translucency.io import load_mesh

    mesh = load_mesh(source, unit="mm")
    before = source.read_bytes()
    with pytest.raises(InvalidParameterError, match="never modified"):
        write_baked_ply(
            source,
            mesh,
            np.ones((mesh.n_points, 3)),
            np.ones((mesh.n_points, 3)),
            np.zeros((mesh.n_points, 3), np.uint8),
            METADATA,
        )
    assert source.read_bytes() == before


@pytest.mark.parametrize(
    "change, message",
    [
        (dict(radiance=np.zeros((3, 3))), "shape"),
        (dict(radiance=np.full((642, 3), np.nan)), "NaN"),
        (dict(b=np.full((642, 3), 1e39)), "beyond float32"),
        (dict(colors_rgb8=np.full((642, 3), 0.5)), "8-bit"),
        (dict(colors_rgb8=np.full((642, 3), 300)), "8-bit"),
        (dict(metadata={"material": "marble"}), "lacks coefficients"),
        (dict(metadata={**METADATA, "bad key": 1}), "not usable"),
        (dict(metadata={**METADATA, "x": object()}), "cannot be written"),
    ],
)
def test_invalid_bakes_are_refused(tmp_path, sphere_mesh, change, message):
    n = sphere_mesh.n_points
    arguments = dict(
        radiance=np.zeros((n, 3)), b=np.zeros((n, 3)), colors_rgb8=np.zeros((n, 3), np.uint8), metadata=METADATA
    )
    arguments.update(change)
    with pytest.raises(InvalidParameterError, match=message):
        write_baked_ply(tmp_path / "x.ply", sphere_mesh, **arguments)
    assert not (tmp_path / "x.ply").exists()


def test_missing_folder(tmp_path, sphere_mesh):
    n = sphere_mesh.n_points
    with pytest.raises(InvalidParameterError, match="does not exist"):
        write_baked_ply(
            tmp_path / "no" / "x.ply",
            sphere_mesh,
            np.zeros((n, 3)),
            np.zeros((n, 3)),
            np.zeros((n, 3), np.uint8),
            METADATA,
        )


def test_a_plain_ply_is_not_a_bake(tmp_path):
    path = tmp_path / "plain.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n10 0 0\n0 10 "
                    "0\n3 0 1 2\n")  # fmt: skip
    with pytest.raises(MeshError, match="not a translucency bake"):
        read_baked_ply(path)


json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-(10**12), 10**12) | st.floats(allow_nan=False) | st.text(max_size=300),
    lambda children: (
        st.lists(children, max_size=5)
        | st.dictionaries(st.from_regex(r"[a-z_][a-z0-9_]{0,8}", fullmatch=True), children, max_size=4)
    ),
    max_leaves=20,
)


@settings(max_examples=80, deadline=None)
@given(metadata=st.dictionaries(st.from_regex(r"[a-zA-Z][a-zA-Z0-9_-]{0,10}", fullmatch=True), json_values, max_size=6))
def test_metadata_round_trips_exactly_through_header_comments(metadata):
    comments = metadata_to_comments(metadata)
    assert all("\n" not in line and line.isascii() and len(line) <= 200 for line in comments)
    # readers strip the ends of header lines: the encoding must survive that
    decoded = comments_to_metadata([" " + line.strip() + "  " for line in comments])

    def normalise(value):  # empty dicts stay dicts; JSON round trip of floats is exact
        return json.loads(json.dumps(value))

    assert normalise(decoded) == normalise({k: v for k, v in metadata.items()})
