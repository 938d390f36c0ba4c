"""The scan a shade starts from: the embedded default, a file loaded and cleaned, or a PyVista mesh converted.

Every mesh that reaches :class:`~translucency.app.shading.scene.Scene` is a cleaned
:class:`~translucency.geometry.mesh.TriangleMesh` in mm with outward orientation; this module makes one from what
a user hands in, and reads the scan's own colours as a reflectance (docs/physics.md §6.5).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np

from ...errors import TranslucencyError

__all__ = [
    "DEFAULT_SCAN_WIDTH_MM",
    "default_scan_path",
    "load_default_scan",
    "load_scan",
    "mesh_for_shading",
    "scan_reflectance",
]

#: The embedded default scan: the watertight Stanford bunny inside the pymeshlab wheel, stored
#: normalised to a unit diagonal; it is scaled to this width (mm), the size of the original figurine.
DEFAULT_SCAN_WIDTH_MM = 155.0


def default_scan_path() -> Path:
    """Path of the embedded default scan (``pymeshlab/tests/sample_meshes/bunny.obj``)."""
    path = resources.files("pymeshlab") / "tests" / "sample_meshes" / "bunny.obj"
    if not path.is_file():
        raise TranslucencyError(
            "the embedded default scan (pymeshlab/tests/sample_meshes/bunny.obj) is missing from the "
            "installed pymeshlab; reinstall it (pip install --force-reinstall 'pymeshlab==2025.7.*') or pass "
            "a mesh file."
        )
    return Path(str(path))


def load_default_scan():
    """The embedded default scan as a :class:`~translucency.geometry.mesh.TriangleMesh`, 155 mm across."""
    from ...io.load import load_mesh, read_mesh_arrays

    path = default_scan_path()
    points, _, _ = read_mesh_arrays(path)
    width = float(np.max(points.max(axis=0) - points.min(axis=0)))
    return load_mesh(path, unit=DEFAULT_SCAN_WIDTH_MM / width)


def load_scan(path, unit=None, *, warn=None, note=None):
    """A mesh file (or the embedded default scan when ``path`` is None), loaded in ``unit`` and cleaned.

    ``unit`` None: inferred from the size (:func:`translucency.io.units.infer_unit`). Returns
    ``(mesh in mm, CleanReport or None, name)``. Warnings from loading (the unit inferred, an
    implausible size for the unit given) go to ``warn(message)`` when given; the line that says
    which unit was inferred goes to ``note(message)`` instead when that is given.
    """
    import warnings

    from ...io.clean import clean_mesh
    from ...io.load import load_mesh
    from ...io.units import UnitInferredWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if path is None:
            mesh, name = load_default_scan(), default_scan_path().stem
        else:
            mesh, name = load_mesh(path, unit=unit), str(path)
    for warning in caught:
        say = note if note is not None and issubclass(warning.category, UnitInferredWarning) else warn
        if say is not None:
            say(str(warning.message))
    mesh, report = clean_mesh(mesh)
    return mesh, report, name


def mesh_for_shading(mesh, unit=None, *, entry: str):
    """The mesh an entry point shades: a :class:`~translucency.geometry.mesh.TriangleMesh` as it is (already
    cleaned, in mm), a ``pyvista.PolyData`` (or other PyVista dataset) converted in ``unit``
    (:func:`~translucency.io.polydata.as_triangle_mesh`: None reads its ``field_data["length_unit"]`` or
    infers the unit from the size) and repaired with :func:`~translucency.io.clean.clean_mesh`, as a scan
    file would be."""
    from ...geometry.mesh import TriangleMesh
    from ...io.clean import clean_mesh
    from ...io.polydata import as_triangle_mesh

    if isinstance(mesh, TriangleMesh):
        return as_triangle_mesh(mesh, unit, entry=entry)
    mesh = as_triangle_mesh(mesh, unit, entry=entry)
    return clean_mesh(mesh)[0]


def scan_reflectance(mesh) -> np.ndarray:
    """The scan's colour per vertex as its diffuse reflectance: ``(n, 3)`` linear values in [0, 1], the 8-bit
    sRGB colours decoded (docs/physics.md §6.5); a sentence when the scan has none."""
    from ...errors import InvalidParameterError, command_line_active
    from ..display import srgb_decode

    colors = mesh.point_data.get("colors")
    if colors is None:
        name = Path(mesh.source).name if mesh.source is not None else "this mesh"
        flag = "--albedo-from-colors" if command_line_active() else 'albedo="vertex_colors"'
        raise InvalidParameterError(
            f"{name} has no vertex colours or texture to take the albedo from; drop {flag} or give a scan with "
            "colours (PLY red/green/blue, OBJ with a map_Kd texture, VTK 'colors')."
        )
    return srgb_decode(np.asarray(colors, dtype=np.float64)[:, :3] / 255.0)


def load_scan_quietly(path, unit=None):
    """:func:`load_scan` with what it would say collected: ``(mesh in mm, name, notes)``, ``notes`` a list of
    sentences (the unit inferred, warnings). Picklable arguments and result, for a call in a child process
    (:func:`translucency.processes.run_in_child`): the desktop viewer loads scans there, because the mesh
    library's own Qt must not share a process with the viewer's."""
    notes = []
    mesh, _, name = load_scan(path, unit, warn=notes.append, note=notes.append)
    return mesh, name, notes
