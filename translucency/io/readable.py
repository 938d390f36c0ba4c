"""Is a path a file that can be read? One check for every file a user names (scans, materials, references,
environment maps), so that a FIFO, a device or a directory is refused in one sentence before anything opens it
(opening a FIFO waits for a writer forever, a device reads forever).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

__all__ = ["regular_file", "special_kind"]


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
