"""A corpus of broken files, generated here: each gives a MeshError with one clear sentence."""

import os
import struct

import numpy as np
import pytest

from translucency.errors import MeshError
from translucency.io import load_mesh

from .conftest import icosphere, shared_scan
from .test_load import write_ply


def binary_ply(points, triangles, *, vertex_count=None, face_count=None, index_type="i4"):
    """Bytes of a little-endian binary PLY (counts in the header can lie)."""
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(points) if vertex_count is None else vertex_count}\n"
        "property float x\nproperty float y\nproperty float z\n"
        f"element face {len(triangles) if face_count is None else face_count}\n"
        f"property list uchar {'int' if index_type == 'i4' else 'uint'} vertex_indices\nend_header\n"
    ).encode()
    faces = np.empty(len(triangles), dtype=[("n", "u1"), ("i", "<" + index_type, (3,))])
    faces["n"], faces["i"] = 3, triangles
    return header + np.asarray(points, "<f4").tobytes() + faces.tobytes()


def binary_stl(points, triangles, *, count=None):
    """Bytes of a binary STL (80-byte header, triangle count, 50 bytes per facet; the count can lie)."""
    facets = np.zeros(len(triangles), dtype=[("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])
    facets["corners"] = np.asarray(points)[triangles]
    return b"binary stl".ljust(80) + struct.pack("<I", len(triangles) if count is None else count) + facets.tobytes()


def ascii_stl(points, triangles):
    """Bytes of an ASCII STL."""
    corners = np.asarray(points)[triangles]
    facets = "".join(
        "facet normal 0 0 0\nouter loop\n" + "".join(f"vertex {x} {y} {z}\n" for x, y, z in c) + "endloop\nendfacet\n"
        for c in corners
    )
    return f"solid s\n{facets}endsolid s\n".encode()


def obj_text(points, triangles):
    """Bytes of a Wavefront OBJ (1-based indices)."""
    return (
        "".join(f"v {x} {y} {z}\n" for x, y, z in points)
        + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in triangles)
    ).encode()


POINTS, TRIANGLES = icosphere(1, 20.0)
NAN_POINTS = np.where(np.arange(len(POINTS))[:, None] == 5, np.nan, POINTS)


def check_sentence(info, name):
    """The message names the file and is one sentence (one final period, no line break)."""
    text = str(info.value)
    assert name in text, text
    assert text.endswith("."), text
    assert "\n" not in text and "Traceback" not in text, text
    assert len(text) < 400, text


# (file name, content bytes, expected words in the message)
CORPUS = [
    ("empty.ply", b"", "is empty"),
    ("empty.obj", b"", "is empty"),
    ("truncated.ply", binary_ply(POINTS, TRIANGLES)[:-100], "truncated"),
    ("truncated_vertices.ply", binary_ply(POINTS, TRIANGLES)[:300], "truncated"),
    ("huge_count.ply", binary_ply(POINTS, TRIANGLES, vertex_count=10**12), "truncated"),
    ("no_end_header.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n", "header"),
    (
        "bad_type.ply",
        b"ply\nformat ascii 1.0\nelement vertex 3\nproperty flaot x\nend_header\n0\n0\n0\n",
        "corrupt PLY header",
    ),
    ("bad_format.ply", b"ply\nformat binary_middle_endian 1.0\nelement vertex 0\nend_header\n", "corrupt PLY header"),
    ("no_xyz.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float u\nend_header\n0\n", "x, y, z"),
    (
        "points_only.ply",
        b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float "
        b"z\nend_header\n0 0 0\n10 0 0\n0 10 0\n",
        "point cloud",
    ),
    ("zero_faces.ply", binary_ply(POINTS, TRIANGLES[:0]), "point cloud"),
    (
        "nan.ply",
        binary_ply(np.where(np.arange(len(POINTS))[:, None] == 5, np.nan, POINTS), TRIANGLES),
        "NaN or infinite",
    ),
    ("inf.obj", b"v 0 0 0\nv 10 0 0\nv inf 10 0\nf 1 2 3\n", "NaN or infinite"),
    ("out_of_range.ply", binary_ply(POINTS, np.where(TRIANGLES == 7, 999, TRIANGLES)), "refers to vertex 999"),
    ("negative.ply", binary_ply(POINTS, np.where(TRIANGLES == 7, -5, TRIANGLES)), "refers to vertex -5"),
    ("out_of_range.off", b"OFF\n3 1 0\n0 0 0\n10 0 0\n0 10 0\n3 0 1 3\n", "refers to vertex 3"),
    (
        "ascii_garbage.ply",
        b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float "
        b"z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 zero 0\n",
        "corrupt",
    ),
    ("absurd.ply", binary_ply(POINTS * 1e14, TRIANGLES), "larger than any scanned object"),
    ("one_point.ply", binary_ply(np.zeros_like(POINTS), TRIANGLES), "one position"),
    ("truncated.off", b"OFF\n4 2 0\n0 0 0\n1 0 0\n", "truncated"),
    ("not_off.off", b"FFO\n3 1 0\n", "not an OFF file"),
    ("binary.off", b"OFF BINARY\n" + b"\x00" * 40, "binary OFF"),
    ("truncated.stl", b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0\n", "STL"),
    ("plyfile.stl", binary_ply(POINTS, TRIANGLES), "but PLY data; rename it to plyfile.ply"),
    ("objfile.ply", b"v 0 0 0\nv 10 0 0\nv 0 10 0\nf 1 2 3\n", "but OBJ data"),
    ("garbage.vtp", b"\x00\x01\x02garbage" * 10, "VTK XML PolyData"),
    ("mesh.abc", b"v 0 0 0\n", "unknown mesh format '.abc'"),
    ("noextension", b"ply\nformat ascii 1.0\n", "unknown mesh format"),
    # a list length beyond its count type (plyfile raises OverflowError; found by tests/io/test_fuzz_ply.py)
    (
        "list_overflow.ply",
        (
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            b"element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n300 0 1 2\n"
        ),
        "corrupt",
    ),
    (
        "ply_index_overflow.ply",
        binary_ply(POINTS, np.where(TRIANGLES == 7, 2**31 - 1, TRIANGLES)),
        "refers to vertex 2147483647",
    ),
    (
        "ascii_nan.ply",
        b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        b"element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n",
        "NaN or infinite",
    ),
    # cut at a record boundary: VTK alone would read the 40 whole triangles and say nothing
    ("truncated_half.stl", binary_stl(POINTS, TRIANGLES)[: 84 + 25 * len(TRIANGLES)], "announces 80 triangles"),
    ("count_too_large.stl", binary_stl(POINTS, TRIANGLES, count=10**6), "truncated"),
    ("truncated_header.stl", binary_stl(POINTS, TRIANGLES)[:50], "not a readable STL"),
    ("truncated_ascii_half.stl", ascii_stl(POINTS, TRIANGLES)[:1000], "not a readable STL"),
    ("nan_binary.stl", binary_stl(NAN_POINTS, TRIANGLES), "STL"),
    ("nan_ascii.stl", ascii_stl(NAN_POINTS, TRIANGLES), "NaN or infinite"),
    ("empty.stl", b"", "is empty"),
    ("truncated.obj", obj_text(POINTS, TRIANGLES)[:700], "fewer than 3 coordinates"),  # cut in a vertex line
    ("out_of_range.obj", b"v 0 0 0\nv 10 0 0\nv 0 10 0\nf 1 2 99\n", "refers to vertex 98"),
    ("nan.obj", obj_text(NAN_POINTS, TRIANGLES), "NaN or infinite"),
    ("points_only.obj", b"v 0 0 0\nv 10 0 0\nv 0 10 0\n", "point cloud"),
    ("words.obj", b"v 0 0 0\nv 10 0 zero\nv 0 10 0\nf 1 2 3\n", "not numbers"),
    ("random_bytes.obj", bytes(np.random.default_rng(0).integers(128, 256, 300, dtype=np.uint8)), "no vertex"),
    ("plybytes.obj", binary_ply(POINTS, TRIANGLES), "but PLY data; rename it to plybytes.ply"),
    ("plybytes.xyz", binary_ply(POINTS, TRIANGLES), "but PLY data; rename it to plybytes.ply"),
    ("points.xyz", b"0 0 0\n10 0 0\n0 10 0\n", "point cloud"),
]


@pytest.mark.parametrize("name, content, expected", CORPUS, ids=[c[0] for c in CORPUS])
def test_broken_file_gives_one_sentence(tmp_path, name, content, expected):
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(MeshError, match=expected) as info:
        load_mesh(path)
    check_sentence(info, name)


def test_truncated_shared_scan_vtp(tmp_path):
    source = shared_scan("ggg_angel_sfm.vtp")
    path = tmp_path / "angel_truncated.vtp"
    path.write_bytes(source.read_bytes()[:20000])
    with pytest.raises(MeshError, match="not a readable") as info:
        load_mesh(path)
    check_sentence(info, path.name)


def test_truncated_binary_stl(tmp_path):
    header = b"x" * 80 + struct.pack("<I", 10)
    path = tmp_path / "short.stl"
    path.write_bytes(header + b"\x00" * 120)
    with pytest.raises(MeshError) as info:
        load_mesh(path)
    check_sentence(info, path.name)


def test_missing_file(tmp_path):
    with pytest.raises(MeshError, match="does not exist") as info:
        load_mesh(tmp_path / "nothing.ply")
    check_sentence(info, "nothing.ply")


def test_dangling_symlink(tmp_path):
    link = tmp_path / "scan.ply"
    link.symlink_to(tmp_path / "moved_away.ply")
    with pytest.raises(MeshError, match="does not exist") as info:
        load_mesh(link)
    check_sentence(info, "scan.ply")


def test_directory_instead_of_file(tmp_path):
    folder = tmp_path / "scan.ply"
    folder.mkdir()
    with pytest.raises(MeshError, match="is a directory") as info:
        load_mesh(folder)
    check_sentence(info, "scan.ply")


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0, reason="root can read files with mode 000")
def test_unreadable_file(tmp_path):
    path = tmp_path / "locked.ply"
    path.write_bytes(binary_ply(POINTS, TRIANGLES))
    path.chmod(0)
    try:
        with pytest.raises(MeshError, match="permission denied") as info:
            load_mesh(path)
        check_sentence(info, "locked.ply")
    finally:
        path.chmod(0o644)


def test_unknown_format_override(tmp_path):
    path = write_ply(tmp_path / "s.ply", POINTS, TRIANGLES)
    with pytest.raises(MeshError, match="unknown mesh format 'xyzw'"):
        load_mesh(path, format="xyzw")
