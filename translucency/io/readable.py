"""Is a path a file that can be read? One check for every file a user names (scans, materials, references,
environment maps), so that a FIFO, a device or a directory is refused in one sentence before anything opens it
(opening a FIFO waits for a writer forever, a device reads forever).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from ..memory import available_memory

__all__ = ["MAX_PIXELS", "check_pixels", "image_size", "regular_file", "special_kind"]

#: The most pixels an image may have whatever the memory: 2**28 (16384 x 16384), beyond any map or texture in use.
MAX_PIXELS = 2**28


def special_kind(mode: int) -> str:
    """What a file that is not a regular file is, in words ("a FIFO (named pipe)", ...)."""
    for test, words in (
        (stat.S_ISFIFO, "a FIFO (named pipe)"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return words
    return "a special file"


def regular_file(path, error: type[Exception], what: str = "", kind: str = "file") -> Path:
    """``path`` as a :class:`~pathlib.Path` when it names a regular file (links followed); otherwise ``error``
    with one sentence: it does not exist, cannot be looked at, is a directory, or is a FIFO, device or socket.

    ``what`` starts the sentence ("material file", or empty: the path alone); ``kind`` names what was expected
    ("mesh file", "image file").
    """
    path = Path(path)
    name = f"{what} {path}".strip()
    article = "an" if kind[:1] in "aeiou" else "a"
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise error(f"{name} does not exist; check the path and the file name.") from None
    except OSError as exc:
        raise error(f"{name} cannot be read ({exc.strerror or 'refused'}); check the file and the disk.") from None
    if stat.S_ISDIR(mode):
        raise error(f"{name} is a directory, not {article} {kind}; pass the path of {article} {kind} inside it.")
    if not stat.S_ISREG(mode):
        raise error(f"{name} is {special_kind(mode)}, not a regular file; pass {article} {kind} stored on disk.")
    return path


def image_size(path) -> tuple[int, int] | None:
    """``(height, width)`` an image file's header declares, read without decoding it (imageio's properties), or
    None when no installed reader can tell (reading it then says so)."""
    import warnings

    import imageio.v3 as iio

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # imageio's plugins warn while they try an unknown file
            shape = iio.improps(path).shape
    except Exception as exc:  # noqa: BLE001 - imageio raises many types for a file it cannot read
        return _pillow_size(path) if type(exc).__name__ == "DecompressionBombError" else None
    return (int(shape[0]), int(shape[1])) if len(shape) >= 2 else None


def _pillow_size(path) -> tuple[int, int] | None:
    """``(height, width)`` from the header of an image Pillow refused as too large to open."""
    from PIL import Image

    limit, Image.MAX_IMAGE_PIXELS = Image.MAX_IMAGE_PIXELS, None
    try:
        with Image.open(path) as image:
            width, height = image.size
    except Exception:  # noqa: BLE001 - unreadable after all: reading it says so
        return None
    finally:
        Image.MAX_IMAGE_PIXELS = limit
    return int(height), int(width)


def check_pixels(name: str, height: int, width: int, bytes_per_pixel: int, error: type[Exception], advice: str):
    """Refuse an image whose header claims more than :data:`MAX_PIXELS` pixels or more than the free memory can
    decode (``bytes_per_pixel`` each while it is read), before anything is decoded: a header costs nothing to
    write, and a decoder that believes it aborts the process. ``advice`` ends the sentence."""
    need = height * width * bytes_per_pixel
    free = available_memory()
    if height * width > MAX_PIXELS or (free is not None and need > free):
        room = "" if free is None else f", and this machine has {free / 1e9:.1f} GB free"
        raise error(f"{name} claims {width} x {height} pixels, {need / 1e9:.1f} GB to decode{room}; {advice}.")
