"""Files and meshes: load scans, repair them, decimate to the solver's resolution, write baked PLYs.

The public API is re-exported here lazily, so ``import translucency.io`` imports neither PyVista,
VTK nor pymeshlab; each loads when a function that needs it is first called.

==================== ==================================================================
module               concept
==================== ==================================================================
units                length units, conversion to mm, size plausibility
load                 every mesh file to a :class:`TriangleMesh`: dispatch, units, size
formats              one reader per file format (PLY, OFF, OBJ, STL, VTK, pymeshlab)
polydata             a :class:`TriangleMesh` to and from a ``pyvista.PolyData``
triangulate          polygons and triangle strips to triangle lists
defects              counts of mesh defects (what repair has to fix)
clean                scan repair with a report of what changed
decimate             proxy meshes and the mapping of proxy values back to the full mesh
meshlab              pymeshlab, imported once with its OpenGL-dependent filters checked
baked                baked PLY output and input, atomic, with every setting in the header
save                 any mesh to a mesh file, atomic, never over its source
==================== ==================================================================

The mesh record and the array geometry (areas, normals, edges, orientation, closest points) live in
:mod:`translucency.geometry`; the names below re-export them for convenience.
"""

import importlib

_LAZY = {
    # the mesh type and units
    "TriangleMesh": "translucency.geometry.mesh",
    "validate_mesh_arrays": "translucency.geometry.mesh",
    "parse_unit": "translucency.io.units",
    "unit_label": "translucency.io.units",
    "ImplausibleSizeWarning": "translucency.io.units",
    "UNITS": "translucency.io.units",
    # loading
    "load_mesh": "translucency.io.load",
    "read_mesh_arrays": "translucency.io.load",
    "to_pyvista": "translucency.io.polydata",
    "from_pyvista": "translucency.io.polydata",
    "detect_format": "translucency.io.load",
    "SUPPORTED_FORMATS": "translucency.io.load",
    "triangulate_polygons": "translucency.io.triangulate",
    "triangulate_strips": "translucency.io.triangulate",
    # per-vertex geometry for the solver
    "triangle_areas": "translucency.geometry.measure",
    "triangle_normals": "translucency.geometry.measure",
    "vertex_normals": "translucency.geometry.measure",
    "vertex_areas": "translucency.geometry.measure",
    "mean_edge_length": "translucency.geometry.measure",
    "signed_volume": "translucency.geometry.measure",
    # repair
    "MeshDefects": "translucency.io.defects",
    "find_defects": "translucency.io.defects",
    "CleanReport": "translucency.io.clean",
    "clean_mesh": "translucency.io.clean",
    "clean_arrays": "translucency.io.clean",
    "smooth_vertex_normals": "translucency.io.clean",
    "coherent_orientation": "translucency.geometry.orientation",
    "outward_flips": "translucency.geometry.orientation",
    # decimation and the proxy mapping
    "Decimation": "translucency.io.decimate",
    "ProxyMapping": "translucency.io.decimate",
    "decimate_mesh": "translucency.io.decimate",
    "simplify_arrays": "translucency.io.decimate",
    "map_to_proxy": "translucency.io.decimate",
    "target_face_count": "translucency.io.decimate",
    "closest_points_on_triangles": "translucency.geometry.proximity",
    "vertex_hausdorff_distance": "translucency.geometry.proximity",
    # baked PLY
    "BakedPly": "translucency.io.baked",
    "write_baked_ply": "translucency.io.baked",
    "read_baked_ply": "translucency.io.baked",
    "REQUIRED_METADATA": "translucency.io.baked",
    # any mesh file
    "save_mesh": "translucency.io.save",
    "check_output_path": "translucency.io.save",
    "WRITABLE_FORMATS": "translucency.io.save",
}

__all__ = sorted(_LAZY)


def __getattr__(name):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'translucency.io' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__():
    return __all__
