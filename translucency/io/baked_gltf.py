"""Baked glTF files (``.glb``, ``.gltf``): the bake's colours for Blender and web viewers, with the settings.

glTF 2.0 is what Blender, three.js, Babylon.js, the Khronos sample viewer and most web viewers open.
A bake is one triangle mesh whose primitive holds

============== ============ ================================================================
attribute      type         meaning, unit
============== ============ ================================================================
POSITION       float VEC3   position, **metres** (glTF's unit), in glTF's frame (below)
NORMAL         float VEC3   unit vertex normal, same frame
COLOR_0        float VEC3   the display colours decoded to linear RGB (glTF's colours are
                            linear): a viewer that encodes to sRGB shows the bake's 8-bit
                            display colours exactly (see :func:`write_baked_gltf`)
_RADIANCE      float VEC3   linear radiance toward the normal, W/(m^2 sr) per W/m^2 of
                            irradiance of the light (custom attribute; trimesh reads it)
_B             float VEC3   the view-independent factor B(x_o), same unit
_LUMINANCE     float VEC3   Rec. 709 luminance of the radiance, same unit, the same value in its
                            three components
============== ============ ================================================================

Every custom attribute is three floats wide: Blender's glTF importer gathers a primitive's custom attributes in
an order that changes from run to run (a set of their names) and stops when their widths differ, so a scalar is
written as three copies of itself.

and one material, white and unlit (``KHR_materials_unlit``; for viewers without that extension
a rough dielectric, metallic 0, roughness 1), so the vertex colours are shown as they are: the
light is in the bake already. The settings are the scene's ``extras`` (Blender shows them as
custom properties of the scene; trimesh reads them into ``Scene.metadata``), with
``length_unit = "m"`` and ``frame`` saying how the scan's axes were turned.

glTF is +Y up, +Z front, in metres. The scan is turned into that frame with the bake's up axis
(:func:`translucency.io.upright.display_frame`, which is the identity for a +y-up scan) and scaled
from mm to m, so it stands upright at its real size in Blender.

The file is built by trimesh's exporter (a ``.gltf`` embeds its buffer as a data URI, so a bake is
one file) and written by the atomic writer (:mod:`translucency.io.atomic`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError, WriteError
from ..geometry.mesh import TriangleMesh
from .atomic import write_bytes
from .baked import check_bake_path, complete_metadata, json_metadata
from .upright import display_frame

__all__ = ["GLTF_BAKE_SUFFIXES", "MM_PER_METRE", "write_baked_gltf"]

#: The width of every custom attribute (module docstring: Blender's importer needs them all of one width).
CUSTOM_WIDTH = 3

#: Suffixes :func:`write_baked_gltf` writes: binary glTF and text glTF with an embedded buffer.
GLTF_BAKE_SUFFIXES = (".glb", ".gltf")

#: glTF's lengths are metres; the bake's are mm.
MM_PER_METRE = 1000.0

#: Placeholder name of the colour attribute while trimesh builds the file (renamed to COLOR_0).
_COLOR_PLACEHOLDER = "_TRANSLUCENCY_LINEAR_COLOR"


def write_baked_gltf(
    path, mesh: TriangleMesh, colors_linear, metadata: dict, *, normals=None, attributes=None, up=None
) -> Path:
    """Write a bake as binary (``.glb``) or text (``.gltf``) glTF 2.0, atomically.

    Parameters
    ----------
    path : str or path-like
        Destination ending in ``.glb`` or ``.gltf``; its folder must exist.
    mesh : TriangleMesh
        The mesh (points in mm; written in metres).
    colors_linear : array_like, shape (n, 3)
        Linear RGB in [0, 1] per vertex, the vertex colours ``COLOR_0`` (stored as float32, so no
        8-bit rounding in linear light darkens the shadows).
    metadata : dict
        Every setting of the run (see :func:`translucency.io.baked.complete_metadata`); written as
        the scene's ``extras``.
    normals : array_like, shape (n, 3), optional
        Vertex normals; default ``mesh.point_data["normals"]`` or the area-weighted normals.
    attributes : dict of str to array_like, optional
        More per-vertex float arrays, ``(n,)`` or ``(n, 3)``, written as custom attributes named ``_<NAME>``
        (upper case), three floats wide (a scalar three times: module docstring): the pipeline gives
        ``radiance``, ``B`` and ``luminance``.
    up : str, optional
        The scan's up axis (``"+x"`` ... ``"-z"``) turned to glTF's +Y; default ``metadata["up"]``,
        else +y.

    Returns
    -------
    Path

    Raises
    ------
    InvalidParameterError
        Another suffix, wrong shapes, values that are not finite, colours outside [0, 1], missing
        settings, a missing folder, or the scan itself as the destination.
    WriteError
        When the file cannot be encoded or the disk refuses it; nothing is left behind.
    """
    import trimesh

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in GLTF_BAKE_SUFFIXES:
        raise InvalidParameterError(f"cannot write {path.name} as glTF; give it a .glb or .gltf name.")
    if not isinstance(mesh, TriangleMesh):
        raise InvalidParameterError(f"write_baked_gltf needs a TriangleMesh, not {type(mesh).__name__}.")
    check_bake_path(path, mesh.source)
    n = mesh.n_points
    colors = _float_rows("colors_linear", colors_linear, n, 3)
    if colors.size and (colors.min() < 0 or colors.max() > 1):
        raise InvalidParameterError(
            "colors_linear must be linear RGB in [0, 1]; decode the display colours (or clip the exposed radiance)."
        )
    if normals is None:
        normals = mesh.point_data["normals"] if "normals" in mesh.point_data else mesh.vertex_normals()
    normals = _float_rows("normals", normals, n, 3)
    settings = complete_metadata(metadata, mesh)
    up = up or settings.get("up") or "+y"
    frame = display_frame(up)  # rows: right, up, front in the scan's coordinates = glTF's x, y, z
    vertex_attributes = {_COLOR_PLACEHOLDER: colors}
    for name, values in (attributes or {}).items():
        array = np.asarray(values)
        width = 1 if array.ndim == 1 else (array.shape[1] if array.ndim == 2 else 0)
        if width not in (1, CUSTOM_WIDTH):
            raise InvalidParameterError(
                f"the attribute {name!r} has shape {array.shape}; pass one value or a row of {CUSTOM_WIDTH} per vertex."
            )
        rows = _float_rows(name, array.reshape(len(array), width), n, width)
        vertex_attributes["_" + name.upper()] = np.repeat(rows, CUSTOM_WIDTH // width, axis=1)
    extras = {
        **json_metadata(settings),
        "length_unit": "m",
        "frame": f"glTF's +Y up, +Z front: the scan's up axis {up} turned to +Y",
        "scan_axes_in_gltf": frame.T.tolist(),  # row i: the scan's axis i in glTF coordinates
    }
    scene_mesh = trimesh.Trimesh(
        vertices=(mesh.points @ frame.T) / MM_PER_METRE,
        faces=mesh.triangles,
        vertex_normals=normals @ frame.T,
        vertex_attributes=vertex_attributes,
        process=False,
        validate=False,
    )

    def finish(tree):
        _finish_tree(tree, extras)

    try:
        if suffix == ".glb":
            data = trimesh.exchange.gltf.export_glb(scene_mesh, include_normals=True, tree_postprocessor=finish)
        else:
            files = trimesh.exchange.gltf.export_gltf(
                scene_mesh, include_normals=True, merge_buffers=True, embed_buffers=True, tree_postprocessor=finish
            )
            data = files["model.gltf"]
    except (ValueError, TypeError, KeyError) as exc:
        raise WriteError(f"encoding {path.name} failed ({exc}); write the result as .ply instead.") from None
    return write_bytes(path, data)


def _float_rows(name: str, values, n: int, width: int) -> np.ndarray:
    """``values`` as finite float32 of shape ``(n, width)``, or a sentence."""
    array = np.asarray(values, dtype=np.float64)
    if array.shape != (n, width):
        raise InvalidParameterError(
            f"{name} has shape {array.shape}; pass one row of {width} per vertex, ({n}, {width})."
        )
    with np.errstate(over="ignore", invalid="ignore"):
        stored = array.astype(np.float32)
    if not np.all(np.isfinite(stored)):
        raise InvalidParameterError(f"{name} has NaN, infinite or float32-overflowing values; fix them before baking.")
    return stored


def _finish_tree(tree: dict, extras: dict) -> None:
    """The placeholder colour attribute becomes ``COLOR_0``; the unlit white material; the settings as extras."""
    material = {
        "name": "translucency bake (vertex colours, unlit)",
        "pbrMetallicRoughness": {
            "baseColorFactor": [1.0, 1.0, 1.0, 1.0],
            "metallicFactor": 0.0,
            "roughnessFactor": 1.0,
        },
        "extensions": {"KHR_materials_unlit": {}},
    }
    tree["materials"] = tree.get("materials", []) + [material]
    for gltf_mesh in tree.get("meshes", []):
        for primitive in gltf_mesh["primitives"]:
            attributes = primitive["attributes"]
            if _COLOR_PLACEHOLDER in attributes:
                attributes["COLOR_0"] = attributes.pop(_COLOR_PLACEHOLDER)
            primitive["material"] = len(tree["materials"]) - 1
    tree["extensionsUsed"] = sorted(set(tree.get("extensionsUsed", [])) | {"KHR_materials_unlit"})
    for scene in tree.get("scenes", []):
        scene["extras"] = extras
    tree.setdefault("asset", {})["generator"] = f"translucency {extras.get('version', '')} (trimesh exporter)".strip()
