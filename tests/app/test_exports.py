"""A result for other programs: ShadeResult.to_pyvista and write_result's formats (PLY, VTP/VTK, glTF), read
back with the tools people use (pyvista, trimesh, pymeshlab, plyfile; open3d when installed)."""

import base64
import json
import struct

import numpy as np
import plyfile
import pytest

from translucency.app.shading.result import write_result
from translucency.app.shading.scene import Scene, shade
from translucency.errors import InvalidParameterError
from translucency.geometry.mesh import TriangleMesh
from translucency.geometry.synthetic import icosphere
from translucency.scatter.lights import DirectionalLight

#: Rec. 709 luminance weights of linear R, G, B (ITU-R BT.709-6, item 3.3), written out here as the reference.
REC709 = np.array([0.2126, 0.7152, 0.0722])
RADIANCE_UNIT = "W/(m^2 sr) per W/m^2 of irradiance of the light"


def srgb_to_linear(encoded):
    """IEC 61966-2-1 decoding, written out here as the reference."""
    c = np.asarray(encoded, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(linear):
    c = np.clip(np.asarray(linear, dtype=np.float64), 0, 1)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)


@pytest.fixture(scope="module")
def result():
    """A real solve on a small sphere (642 vertices, 20 mm radius) read from a file in metres."""
    points, triangles = icosphere(3, 20.0)
    mesh = TriangleMesh(points, triangles, mm_per_unit=1000.0, unit_inferred=True)
    return shade(mesh, "marble", DirectionalLight((0.3, 1.0, 0.5), 1.0), method="exact")


f32 = lambda values: np.asarray(values, dtype=np.float32)  # noqa: E731


# --------------------------------------------------------------------------------------------------
# ShadeResult.to_pyvista
# --------------------------------------------------------------------------------------------------
def test_to_pyvista_holds_every_array_and_the_settings(result):
    mesh = result.to_pyvista()
    n = result.mesh.n_points
    np.testing.assert_array_equal(mesh.points, result.mesh.points)
    np.testing.assert_array_equal(mesh.regular_faces, result.mesh.triangles)
    np.testing.assert_array_equal(mesh.point_data["radiance"], result.radiance)
    np.testing.assert_array_equal(mesh.point_data["B"], result.B)
    assert mesh.point_data["colors"].dtype == np.uint8 and mesh.point_data["colors"].shape == (n, 3)
    np.testing.assert_array_equal(mesh.point_data["colors"], result.colors)
    np.testing.assert_allclose(mesh.point_data["luminance"], result.radiance @ REC709, rtol=1e-12)
    np.testing.assert_array_equal(mesh.point_data["normals"], result.normals)
    assert mesh.point_data["incident_flux"].shape == (n, 3)
    fields = mesh.field_data
    assert fields["length_unit"][0] == "mm" and fields["radiance_unit"][0] == RADIANCE_UNIT
    assert fields["incident_flux_unit"][0] == "W/m^2"
    assert fields["material"][0] == "marble" and fields["method"][0] == "exact"
    assert fields["source_unit"][0] == "m" and fields["source_mm_per_unit"][0] == 1000.0
    assert fields["source_unit_inferred"][0] == "true"
    np.testing.assert_allclose(fields["lights.0.direction"], np.array([0.3, 1.0, 0.5]) / np.linalg.norm([0.3, 1, 0.5]))
    np.testing.assert_array_equal(
        fields["coefficients.sigma_a_per_mm"], result.metadata["coefficients"]["sigma_a_per_mm"]
    )


def test_the_incident_flux_is_t12_e_cos_on_a_convex_sphere(result):
    from translucency.scatter.fresnel import fresnel_transmittance

    light = np.array([0.3, 1.0, 0.5]) / np.linalg.norm([0.3, 1.0, 0.5])
    cosine = result.normals @ light
    phi = result.to_pyvista().point_data["incident_flux"]
    assert np.all(phi[cosine <= 0] == 0) and np.all(phi[cosine > 0.2] > 0)
    lit = cosine > 0.2  # nearer the terminator a vertex's own neighbours may shadow it
    expected = fresnel_transmittance(cosine[lit], 1.5) * cosine[lit]  # E = 1 W/m^2, white, no shadow on a sphere
    for channel in range(3):
        np.testing.assert_allclose(phi[lit, channel], expected, rtol=0.02)


def test_to_pyvista_plots_with_no_more_code(result, tmp_path):
    mesh = result.to_pyvista()
    colours = mesh.plot(scalars="colors", rgb=True, off_screen=True, screenshot=True, window_size=(120, 100))
    radiance = mesh.plot(scalars="radiance", rgb=True, off_screen=True, screenshot=True, window_size=(120, 100))
    luminance = mesh.plot(scalars="luminance", off_screen=True, screenshot=True, window_size=(120, 100))
    for image in (colours, radiance, luminance):
        assert image.shape == (100, 120, 3) and image.std() > 1  # something was drawn


def test_a_proxy_result_carries_the_incident_flux_on_every_vertex():
    points, triangles = icosphere(5, 20.0)  # 0.6 mm edges
    mesh = TriangleMesh(points, triangles)
    light = DirectionalLight((0, 0, 1), 1.0)
    proxy = Scene(mesh).shade("skim_milk", light, method="exact", resolution=2.0)
    assert proxy.stats["solver_vertices"] < mesh.n_points / 4
    phi = proxy.incident_flux
    assert phi.shape == (mesh.n_points, 3) and np.all(phi >= 0)
    full = Scene(mesh).shade("skim_milk", light, method="exact").incident_flux
    away = np.abs(mesh.vertex_normals()[:, 2]) > 0.2  # away from the terminator the interpolation is close
    np.testing.assert_allclose(phi[away], full[away], atol=0.05)
    assert np.linalg.norm(phi[away] - full[away]) / np.linalg.norm(full[away]) < 0.01


# --------------------------------------------------------------------------------------------------
# PLY
# --------------------------------------------------------------------------------------------------
def test_ply_read_back_with_plyfile_pymeshlab_trimesh_and_pyvista(result, tmp_path):
    import pyvista
    import trimesh

    from translucency.io.meshlab import import_pymeshlab

    path = write_result(result, tmp_path / "bake.ply")
    ply = plyfile.PlyData.read(str(path))
    vertex = ply["vertex"]
    radiance = np.stack([vertex[f"radiance_{c}"] for c in "rgb"], axis=1)
    np.testing.assert_array_equal(radiance, f32(result.radiance))
    np.testing.assert_array_equal(np.stack([vertex[f"b_{c}"] for c in "rgb"], axis=1), f32(result.B))
    np.testing.assert_array_equal(vertex["quality"], f32(result.radiance @ REC709))
    header = {c.split(" = ")[0]: json.loads(c.split(" = ", 1)[1]) for c in ply.comments if " = " in c}
    assert header["translucency length_unit"] == "mm" and header["translucency radiance_unit"] == RADIANCE_UNIT
    assert header["translucency source_unit"] == "m" and header["translucency source_mm_per_unit"] == 1000.0
    assert "translucency unit" not in header and "translucency mm_per_unit" not in header
    # MeshLab's per-vertex quality is the luminance
    mesh_set = import_pymeshlab().MeshSet()
    mesh_set.load_new_mesh(str(path))
    np.testing.assert_array_equal(f32(mesh_set.current_mesh().vertex_scalar_array()), f32(result.radiance @ REC709))
    colours = np.round(mesh_set.current_mesh().vertex_color_matrix()[:, :3] * 255).astype(np.uint8)
    np.testing.assert_array_equal(colours, result.colors)
    loaded = trimesh.load(str(path), process=False)
    np.testing.assert_array_equal(loaded.visual.vertex_colors[:, :3], result.colors)
    np.testing.assert_array_equal(loaded.metadata["_ply_raw"]["vertex"]["data"]["quality"], vertex["quality"])
    np.testing.assert_array_equal(pyvista.read(str(path)).point_data["RGB"], result.colors)


def test_ply_colours_in_open3d(result, tmp_path):
    open3d = pytest.importorskip("open3d")
    path = write_result(result, tmp_path / "bake.ply")
    loaded = open3d.io.read_triangle_mesh(str(path))
    np.testing.assert_array_equal(np.round(np.asarray(loaded.vertex_colors) * 255).astype(np.uint8), result.colors)


# --------------------------------------------------------------------------------------------------
# VTP / VTK
# --------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("suffix", [".vtp", ".vtk"])
def test_vtk_files_read_back_with_pyvista_keep_every_array_and_setting(result, tmp_path, suffix):
    import pyvista

    path = write_result(result, tmp_path / f"bake{suffix}")
    mesh = pyvista.read(str(path))
    np.testing.assert_array_equal(mesh.points, result.mesh.points)  # float64 mm, unrounded
    np.testing.assert_array_equal(mesh.regular_faces, result.mesh.triangles)
    np.testing.assert_array_equal(mesh.point_data["radiance"], result.radiance)
    np.testing.assert_array_equal(mesh.point_data["B"], result.B)
    np.testing.assert_array_equal(mesh.point_data["colors"], result.colors)
    np.testing.assert_allclose(mesh.point_data["luminance"], result.radiance @ REC709, rtol=1e-12)
    np.testing.assert_array_equal(mesh.point_data["incident_flux"], result.incident_flux)
    np.testing.assert_array_equal(mesh.point_data["normals"], result.normals)
    assert mesh.field_data["length_unit"][0] == "mm" and mesh.field_data["material"][0] == "marble"
    assert mesh.field_data["radiance_unit"][0] == RADIANCE_UNIT and mesh.field_data["exposure"][0] == result.exposure
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"bake{suffix}"]  # no temporary left behind


# --------------------------------------------------------------------------------------------------
# glTF
# --------------------------------------------------------------------------------------------------
def gltf_document(path):
    """The JSON and the binary buffer of a .glb or .gltf (embedded data URI), read by the glTF 2.0 layout."""
    data = path.read_bytes()
    if path.suffix == ".glb":
        magic, version, _ = struct.unpack_from("<4sII", data, 0)
        assert magic == b"glTF" and version == 2
        json_length, json_type = struct.unpack_from("<I4s", data, 12)
        assert json_type == b"JSON"
        document = json.loads(data[20 : 20 + json_length])
        bin_length, bin_type = struct.unpack_from("<I4s", data, 20 + json_length)
        assert bin_type == b"BIN\x00"
        buffer = data[28 + json_length : 28 + json_length + bin_length]
    else:
        document = json.loads(data)
        uri = document["buffers"][0]["uri"]
        buffer = base64.b64decode(uri.split(",", 1)[1])
    return document, buffer


def accessor(document, buffer, index):
    """An accessor's values (float32 or uint32; tightly packed views, as the exporter writes them)."""
    acc = document["accessors"][index]
    view = document["bufferViews"][acc["bufferView"]]
    dtype = {5126: np.float32, 5125: np.uint32}[acc["componentType"]]
    width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[acc["type"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    values = np.frombuffer(buffer, dtype=dtype, count=acc["count"] * width, offset=start)
    return values.reshape(acc["count"], width) if width > 1 else values


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_gltf_holds_linear_colours_metres_and_the_settings(result, tmp_path, suffix):
    path = write_result(result, tmp_path / f"bake{suffix}")
    document, buffer = gltf_document(path)
    primitive = document["meshes"][0]["primitives"][0]
    attributes = primitive["attributes"]
    # +y up already: positions are the mm points in metres
    np.testing.assert_array_equal(accessor(document, buffer, attributes["POSITION"]), f32(result.mesh.points / 1000))
    np.testing.assert_array_equal(
        accessor(document, buffer, primitive["indices"]).reshape(-1, 3), result.mesh.triangles
    )
    colour = accessor(document, buffer, attributes["COLOR_0"])
    assert document["accessors"][attributes["COLOR_0"]]["componentType"] == 5126  # float: linear, not 8-bit
    np.testing.assert_allclose(colour, srgb_to_linear(result.colors / 255.0), rtol=1e-6, atol=1e-7)
    # a viewer that encodes linear to sRGB shows the bake's 8-bit colours exactly
    np.testing.assert_array_equal(np.round(linear_to_srgb(colour) * 255).astype(np.uint8), result.colors)
    np.testing.assert_array_equal(accessor(document, buffer, attributes["_RADIANCE"]), f32(result.radiance))
    np.testing.assert_array_equal(accessor(document, buffer, attributes["_B"]), f32(result.B))
    luminance = accessor(document, buffer, attributes["_LUMINANCE"])  # three copies: Blender needs one width
    np.testing.assert_array_equal(luminance, np.repeat(f32(result.radiance @ REC709)[:, None], 3, axis=1))
    material = document["materials"][primitive["material"]]
    assert "KHR_materials_unlit" in material["extensions"] and "KHR_materials_unlit" in document["extensionsUsed"]
    extras = document["scenes"][0]["extras"]
    assert extras["material"] == "marble" and extras["length_unit"] == "m" and extras["radiance_unit"] == RADIANCE_UNIT
    assert extras["source_unit"] == "m" and extras["lights"] == result.metadata["lights"]


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_gltf_read_back_with_trimesh_and_pyvista(result, tmp_path, suffix):
    import pyvista
    import trimesh

    path = write_result(result, tmp_path / f"bake{suffix}")
    scene = trimesh.load(str(path), process=False)
    assert scene.metadata["material"] == "marble" and scene.metadata["length_unit"] == "m"
    (loaded,) = scene.geometry.values()
    np.testing.assert_array_equal(loaded.vertices, f32(result.mesh.points / 1000))
    np.testing.assert_array_equal(loaded.faces, result.mesh.triangles)
    np.testing.assert_array_equal(loaded.vertex_attributes["_RADIANCE"], f32(result.radiance))
    np.testing.assert_array_equal(loaded.vertex_attributes["_B"], f32(result.B))
    linear = srgb_to_linear(result.colors / 255.0)
    # with a material, trimesh keeps COLOR_0 as the float vertex attribute "color"
    np.testing.assert_allclose(loaded.visual.vertex_attributes["color"], linear, rtol=1e-6, atol=1e-7)
    read = pyvista.read(str(path))
    block = read.combine() if isinstance(read, pyvista.MultiBlock) else read
    np.testing.assert_allclose(block.points, result.mesh.points / 1000, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(block.point_data["COLOR_0"][:, :3], linear, rtol=1e-6, atol=1e-7)
    np.testing.assert_array_equal(block.point_data["_RADIANCE"], f32(result.radiance))
    np.testing.assert_array_equal(block.point_data["_LUMINANCE"][:, 0], f32(result.radiance @ REC709))


def test_gltf_turns_a_z_up_scan_to_y_up(result, tmp_path):
    import dataclasses

    turned = dataclasses.replace(result, metadata={**result.metadata, "up": "+z"})
    document, buffer = gltf_document(write_result(turned, tmp_path / "z.glb"))
    positions = accessor(document, buffer, document["meshes"][0]["primitives"][0]["attributes"]["POSITION"])
    top = np.argmax(result.mesh.points[:, 2])  # the highest vertex along the scan's z ...
    assert np.argmax(positions[:, 1]) == top  # ... is the highest along glTF's y
    np.testing.assert_allclose(np.linalg.norm(positions, axis=1), np.linalg.norm(result.mesh.points, axis=1) / 1000)


# --------------------------------------------------------------------------------------------------
# the suffix
# --------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["bake.obj", "bake.stl", "bake"])
def test_an_unknown_suffix_is_one_sentence_listing_the_supported_ones(result, tmp_path, name):
    with pytest.raises(InvalidParameterError) as info:
        write_result(result, tmp_path / name)
    message = str(info.value)
    assert all(s in message for s in (".ply", ".vtp", ".vtk", ".glb", ".gltf")) and message.count(". ") == 0
    assert list(tmp_path.iterdir()) == []
