"""Images written atomically, and tables as CSV.

* :func:`write_png` -- one image, through the atomic writer (:mod:`translucency.io.atomic`), which
  also provides :func:`~translucency.io.atomic.staged_folder` for sets of files: a reader sees the old
  file or the complete new one, never a part;
* :func:`write_csv` -- rows of dicts as a CSV table (written into such a staged folder).
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError
from ..io.atomic import write_bytes


def write_png(path, image) -> Path:
    """Write an (h, w, 3) uint8 image as a PNG atomically; the folder must exist. Returns the path.

    Raises
    ------
    InvalidParameterError
        A name that does not end in ``.png``, or a missing folder.
    WriteError
        When the disk refuses the file (full, quota, read-only); nothing is left behind.
    """
    import imageio.v3 as iio

    path = Path(path)
    if path.suffix.lower() != ".png":
        raise InvalidParameterError(f"{path} is not a .png file name; images are written as PNG.")
    if not path.parent.is_dir():
        raise InvalidParameterError(f"the folder {path.parent} does not exist; create it or choose another path.")
    # encoded in memory, so that a full disk is met by the atomic writer, not inside the image library
    write_bytes(path, iio.imwrite("<bytes>", np.asarray(image, dtype=np.uint8), extension=".png"))
    return path


def write_csv(path, rows, columns) -> None:
    """Write ``rows`` (dicts) as CSV with the header ``columns`` and those keys of each row; a None is an
    empty cell."""
    with open(path, "w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(columns))
        writer.writeheader()
        for row in rows:
            writer.writerow({k: ("" if row[k] is None else row[k]) for k in columns})
