"""A result for other programs: a PyVista PolyData of every per-vertex array, and files chosen by suffix.

This module only builds arrays from a :class:`~translucency.app.shading.result.ShadeResult`; the files are
written by the io layer (:mod:`translucency.io.baked`, :mod:`translucency.io.baked_vtk`,
:mod:`translucency.io.baked_gltf`), each atomically and each with every setting of the run.

====== ==================================== ===================================================
suffix what it holds                        read by
====== ==================================== ===================================================
.ply   colours; radiance, B as float        colours: everything; floats: plyfile, trimesh
       properties; ``quality`` = luminance  (``metadata["_ply_raw"]``); quality: MeshLab,
       of the radiance; settings as header  pymeshlab
       comments
.vtp   :func:`result_polydata`: every array PyVista (``pv.read``), ParaView, VTK
.vtk   as point data, settings as field
       data
.glb   ``COLOR_0`` (the display colours     Blender, web viewers (three.js, Babylon.js), trimesh
.gltf  decoded to linear), custom radiance,
       B, luminance; settings in extras
====== ==================================== ===================================================

OBJ is not offered (yet): its vertex colours (``v x y z r g b``, an unofficial extension) do survive
in PyVista 0.49, trimesh and pymeshlab, but it has no place for the float values, and the settings
could only be comments no reader returns.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError, setting_name
from ..io.baked import BAKED_FORMATS, complete_metadata, flat_metadata
from ..io.units import INCIDENT_FLUX_UNIT, RADIANCE_UNIT, unit_metadata
from .display import luminance, srgb_decode

__all__ = [
    "DEFAULT_FORMAT",
    "FORMAT_HELP",
    "RESULT_SUFFIXES",
    "check_format",
    "check_result_suffix",
    "result_polydata",
    "write_result_file",
]

#: Suffixes a result is written with (:data:`translucency.io.baked.BAKED_FORMATS`, with the dot).
RESULT_SUFFIXES = tuple(f".{name}" for name in BAKED_FORMATS)

#: Format of the files a batch writes into a folder.
DEFAULT_FORMAT = "ply"

#: Help of ``--format``.
FORMAT_HELP = (
    f"format of the files written into an output folder (default {DEFAULT_FORMAT}): ply (colours, float radiance, "
    "quality), vtp/vtk (every array as point data), glb/gltf (vertex colours for Blender and web viewers); "
    "a file output's suffix names its own"
)


def check_format(format: str) -> str:
    """``format`` when it is one of :data:`~translucency.io.baked.BAKED_FORMATS`, else one sentence."""
    if format not in BAKED_FORMATS:
        raise InvalidParameterError(
            f"{setting_name('format')} must be one of {', '.join(BAKED_FORMATS)}, got {format!r}."
        )
    return format


def check_result_suffix(path) -> str:
    """The lower-case suffix of ``path`` when a result can be written with it, else one sentence.

    Raises
    ------
    InvalidParameterError
        A suffix that is not one of :data:`RESULT_SUFFIXES`.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in RESULT_SUFFIXES:
        raise InvalidParameterError(
            f"cannot write a result as {path.name}: name the file with one of the suffixes "
            f"{', '.join(RESULT_SUFFIXES)} (the format follows the suffix)."
        )
    return suffix


def _settings(result) -> dict:
    """The result's settings with the units every output states (added where absent)."""
    mesh = result.mesh
    settings = dict(result.metadata)
    for key, value in unit_metadata(mesh.mm_per_unit, mesh.unit_inferred).items():
        settings.setdefault(key, value)
    settings.setdefault("radiance_unit", RADIANCE_UNIT)
    if result.incident_flux is not None:
        settings.setdefault("incident_flux_unit", INCIDENT_FLUX_UNIT)
    return settings


def result_polydata(result):
    """A ``pyvista.PolyData`` of a result: points (mm), triangles, every per-vertex array, the settings.

    ``point_data``: ``radiance`` and ``B`` (n, 3) float64, ``colors`` (n, 3) uint8 (the active
    scalars), ``luminance`` (n,), ``incident_flux`` (n, 3), ``reentered`` (n, 3, the part of ``B`` that
    re-entered, when bounces were solved) and ``normals`` (n, 3, the active normals);
    ``field_data``: the settings flattened to strings and numbers
    (:func:`translucency.io.baked.flat_metadata`), among them ``length_unit`` ("mm"),
    ``radiance_unit`` and ``incident_flux_unit``. See :meth:`ShadeResult.to_pyvista
    <translucency.app.shading.result.ShadeResult.to_pyvista>`.
    """
    from ..geometry.mesh import TriangleMesh
    from ..io.polydata import to_pyvista

    mesh = result.mesh
    poly = to_pyvista(TriangleMesh(mesh.points, mesh.triangles))
    point_data = {
        "radiance": result.radiance,
        "B": result.B,
        "luminance": luminance(result.radiance),
        "incident_flux": result.incident_flux,
        "reentered": result.reentered,
        "normals": result.normals,
    }
    for name, values in point_data.items():
        if values is not None:
            poly.point_data[name] = np.array(values, dtype=np.float64)
    poly.point_data["colors"] = np.asarray(result.colors, dtype=np.uint8)
    poly.point_data.active_normals_name = "normals"
    poly.set_active_scalars("colors")
    for key, value in flat_metadata(_settings(result)).items():
        poly.field_data[key] = [value] if isinstance(value, str) else np.atleast_1d(value)
    return poly


def write_result_file(result, path) -> Path:
    """Write a result in the format its suffix names (:data:`RESULT_SUFFIXES`), atomically; returns the path.

    Every format carries the settings (checked by :func:`translucency.io.baked.complete_metadata`).
    ``.ply``: :func:`~translucency.io.baked.write_baked_ply` with ``quality`` the Rec. 709 luminance of
    the radiance; ``.vtp``/``.vtk``: :func:`result_polydata`, written by
    :func:`~translucency.io.baked_vtk.write_baked_polydata`; ``.glb``/``.gltf``:
    :func:`~translucency.io.baked_gltf.write_baked_gltf` with ``COLOR_0`` the display colours decoded
    to linear (so a viewer shows the same colours as the PLY), and radiance, ``B`` and luminance as
    custom attributes.
    """
    suffix = check_result_suffix(path)
    mesh = result.mesh
    if suffix == ".ply":
        from ..io.baked import write_baked_ply

        return write_baked_ply(
            path,
            mesh,
            result.radiance,
            result.B,
            result.colors,
            result.metadata,
            normals=result.normals,
            quality=luminance(result.radiance),
        )
    complete_metadata(result.metadata, mesh)  # every setting present, as the PLY requires
    if suffix in (".vtp", ".vtk"):
        from ..io.baked_vtk import write_baked_polydata

        return write_baked_polydata(path, result_polydata(result), source=mesh.source)
    from ..io.baked_gltf import write_baked_gltf

    return write_baked_gltf(
        path,
        mesh,
        srgb_decode(np.asarray(result.colors, dtype=np.float64) / 255.0),
        result.metadata,
        normals=result.normals,
        attributes={"radiance": result.radiance, "B": result.B, "luminance": luminance(result.radiance)},
    )
