"""Write a :class:`~translucency.io.mesh.TriangleMesh` to a mesh file, atomically, never over its source.

The file is written by PyVista (VTK's writers, chosen by the suffix) into a scratch folder and then
moved into place with the atomic write of :mod:`translucency.io.ply`: an existing file is replaced
only by a complete one, a failed write leaves nothing behind, and the scan a mesh was read from is
never overwritten. Coordinates are written in mm (the mesh's unit).

========== ===================================================== =====
name       meaning                                               unit
========== ===================================================== =====
path       the output file (.ply, .vtp, .vtk, .stl or .obj)      --
points     vertex positions written                              mm
========== ===================================================== =====
"""

from __future__ import annotations

import tempfile
import warnings
from pathlib import Path

from ..errors import InvalidParameterError, TranslucencyError
from .ply import _atomic_write, _same_file

__all__ = ["WRITABLE_FORMATS", "check_output_path", "save_mesh"]

#: Suffixes :func:`save_mesh` writes.
WRITABLE_FORMATS = (".ply", ".vtp", ".vtk", ".stl", ".obj")


def check_output_path(path, source=None) -> Path:
    """Check where a mesh will be written, before any work is done; return it as a Path.

    Parameters
    ----------
    path : str or path-like
        The output file.
    source : str or path-like, optional
        The input file; the output may not be the same file (inputs are never modified).

    Raises
    ------
    InvalidParameterError
        An unsupported suffix, a missing folder, a folder in place of the file, or the input file itself.
    """
    path = Path(path)
    if path.suffix.lower() not in WRITABLE_FORMATS:
        raise InvalidParameterError(f"cannot write {path}: use a {', '.join(WRITABLE_FORMATS[:-1])} or .obj name.")
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise InvalidParameterError(f"the folder {parent} does not exist; create it or choose another output path.")
    if path.is_dir():
        raise InvalidParameterError(f"{path} is a folder; pass a file name such as {path / ('mesh' + path.suffix)}.")
    if source is not None and path.exists() and _same_file(path, Path(source)):
        raise InvalidParameterError(
            f"{path} is the input file; write the result to another file (inputs are never modified)."
        )
    return path


def save_mesh(path, mesh) -> Path:
    """Write ``mesh`` (points in mm, triangles, per-vertex data) to ``path``, atomically.

    Parameters
    ----------
    path : str or path-like
        Output file; its suffix (:data:`WRITABLE_FORMATS`) selects the format.
    mesh : TriangleMesh
        The mesh; never written over ``mesh.source``.

    Returns
    -------
    Path
        ``path``, once the complete file is in place.

    Raises
    ------
    InvalidParameterError
        See :func:`check_output_path`.
    TranslucencyError
        When the writer fails or the disk refuses the file; nothing is left behind.
    """
    import pyvista

    path = check_output_path(path, mesh.source)
    with tempfile.TemporaryDirectory(prefix="translucency-") as scratch:
        temporary = Path(scratch) / ("mesh" + path.suffix.lower())
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                with pyvista.vtk_verbosity("off"), pyvista.VtkErrorCatcher(send_to_logging=False) as catcher:
                    mesh.to_pyvista().save(temporary)
        except (OSError, ValueError, RuntimeError) as exc:
            raise TranslucencyError(f"writing {path.name} failed ({exc}); check the disk space and the file name.") from exc
        errors = [event.alert.strip() for event in catcher.error_events]
        if errors or not temporary.is_file():
            detail = errors[0].splitlines()[0][:120] if errors and errors[0] else "no file was written"
            raise TranslucencyError(f"writing {path.name} failed ({detail}); check the disk space and the file name.")
        data = temporary.read_bytes()
    _atomic_write(path, [data])
    return path
