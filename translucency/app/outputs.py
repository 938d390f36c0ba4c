"""Output files written atomically: a reader sees the old file or the complete new one, never a part.

* :func:`staged_folder` -- write a set of files into a temporary folder beside the destination; only
  when everything succeeded does each replace its namesake in the destination (``os.replace``, atomic
  per file). On failure the destination is left as it was and the temporary folder is removed.
* :func:`write_png` -- one image, through a temporary file in the same folder.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
import uuid
from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError, TranslucencyError


@contextlib.contextmanager
def staged_folder(folder):
    """Context manager yielding a temporary folder whose files replace those in ``folder`` on success.

    ``folder`` (and its parents) are created at the end, when the files are moved in.
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise InvalidParameterError(f"{folder} exists and is not a folder; pass a folder name for the output.")
    try:
        folder.parent.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", suffix=".partial", dir=folder.parent))
    except OSError as exc:
        raise TranslucencyError(f"cannot write into {folder.parent}: {exc.strerror or exc}; choose another output folder.") from None
    try:
        yield staging
        folder.mkdir(exist_ok=True)
        for path in sorted(staging.iterdir()):
            os.replace(path, folder / path.name)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def write_png(path, image) -> Path:
    """Write an (h, w, 3) uint8 image as a PNG atomically; the folder must exist. Returns the path."""
    import imageio.v3 as iio

    path = Path(path)
    if path.suffix.lower() != ".png":
        raise InvalidParameterError(f"{path} is not a .png file name; images are written as PNG.")
    if not path.parent.is_dir():
        raise InvalidParameterError(f"the folder {path.parent} does not exist; create it or choose another path.")
    temporary = path.with_name(f".{path.name}.{uuid.uuid4().hex}.partial")  # open() gives the usual permissions
    try:
        iio.imwrite(temporary, np.asarray(image, dtype=np.uint8), extension=".png")
        os.replace(temporary, path)
    except OSError as exc:
        raise TranslucencyError(f"cannot write {path}: {exc.strerror or exc}.") from None
    finally:
        if os.path.exists(temporary):
            os.unlink(temporary)
    return path
