"""STL (ascii and binary): a binary file's length is checked against its triangle count, then VTK reads it."""

from __future__ import annotations

import os
from pathlib import Path

from ...errors import MeshError
from .vtk import read_with_vtk

__all__ = ["check_binary_stl", "read_stl"]


def check_binary_stl(path: Path) -> None:
    """Refuse a binary STL shorter than its header's triangle count says.

    VTK's reader reads whatever whole 50-byte records follow the header, so a file cut at a record
    boundary would silently lose triangles. ASCII STL (text starting with ``solid``) is left to VTK.
    """
    with open(path, "rb") as stream:
        head = stream.read(512)
        stream.seek(0, os.SEEK_END)
        size = stream.tell()
    text = head.lstrip()
    if size < 84 or (text.startswith(b"solid") and all(32 <= c < 127 or c in b"\t\r\n" for c in text)):
        return
    count = int.from_bytes(head[80:84], "little")
    needed = 84 + 50 * count
    if size < needed:
        raise MeshError(
            f"{path.name} is truncated: its header announces {count} triangles, which need {needed} bytes, "
            f"but the file has {size}; download or export the file again."
        )


def read_stl(path: Path):
    check_binary_stl(path)
    return read_with_vtk(path, ".stl")
