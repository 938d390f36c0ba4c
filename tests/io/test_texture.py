"""An OBJ's diffuse texture sampled at its vertices (the per-vertex colour of textured scans)."""

import imageio.v3 as iio
import numpy as np
import pytest

from translucency.errors import MeshError
from translucency.io import read_mesh_arrays
from translucency.io.texture import read_texture, sample_at_vertices

TEXELS = np.array([[[255, 0, 0], [0, 255, 0]], [[0, 0, 255], [40, 80, 120]]], dtype=np.uint8)  # rows top to bottom


def _textured_obj(tmp_path, negative=False):
    """A quad of two triangles whose four corners sit at the centres of the 2 x 2 texture's texels."""
    iio.imwrite(tmp_path / "skin.png", TEXELS)
    (tmp_path / "quad.mtl").write_text("newmtl skin\nKd 1 1 1\nmap_Kd skin.png\n")
    uv = ["vt 0.25 0.75", "vt 0.75 0.75", "vt 0.25 0.25", "vt 0.75 0.25"]  # texel (row, col): 00, 01, 10, 11
    faces = ["f -4/-4 -3/-3 -1/-1", "f -4/-4 -1/-1 -2/-2"] if negative else ["f 1/1 2/2 4/4", "f 1/1 4/4 3/3"]
    lines = ["mtllib quad.mtl", "v 0 0 0", "v 1 0 0", "v 0 1 0", "v 1 1 0", *uv, "usemtl skin", *faces]
    path = tmp_path / "quad.obj"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("negative", [False, True])
def test_vertices_take_the_texel_under_their_coordinates(tmp_path, negative):
    _, _, point_data = read_mesh_arrays(_textured_obj(tmp_path, negative))
    expected = TEXELS.reshape(4, 3)  # vertex i sits on texel i
    assert np.array_equal(point_data["colors"], expected)


def test_a_vertex_on_a_seam_averages_its_corners():
    image = TEXELS.astype(float)
    uv = np.array([[0.25, 0.75], [0.75, 0.75]])  # one vertex, two corners: red and green texels
    colors, has = sample_at_vertices(image, uv, np.array([0, 0]), 2)
    assert colors[0].tolist() == [128, 128, 0] and has.tolist() == [True, False]


def test_without_its_texture_an_obj_has_no_colours(tmp_path):
    path = _textured_obj(tmp_path)
    (tmp_path / "skin.png").unlink()
    _, _, point_data = read_mesh_arrays(path)
    assert "colors" not in point_data


def test_an_unreadable_texture_is_one_sentence(tmp_path):
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"not a picture")
    with pytest.raises(MeshError, match="bad.png could not be read"):
        read_texture(bad)


def test_a_texture_whose_header_claims_too_many_pixels_is_refused_before_decoding(tmp_path):
    """A decompression bomb: a PNG of a few bytes whose header claims 100000 x 100000 pixels."""
    import struct
    import zlib

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", 100_000, 100_000, 8, 2, 0, 0, 0)  # 8-bit RGB
    idat = zlib.compress(b"\0" * 64)
    (tmp_path / "bomb.png").write_bytes(
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")
    )
    with pytest.raises(MeshError, match=r"the texture bomb.png claims 100000 x 100000 pixels.*resample it"):
        read_texture(tmp_path / "bomb.png")


def test_an_unreadable_texture_names_no_library_text(tmp_path):
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"not a picture")
    with pytest.raises(MeshError) as caught:
        read_texture(bad)
    assert str(caught.value) == (
        "the texture bad.png could not be read as an image (damaged, or in a format no installed reader handles); "
        "check the file or save it as PNG."
    )
