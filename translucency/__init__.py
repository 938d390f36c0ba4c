"""translucency: translucent shading of 3D scans with the directional dipole BSSRDF.

The public API is re-exported here and imported lazily, so ``import translucency`` stays cheap:
heavy libraries (numba, PyVista, pymeshlab, Embree) load only when a function that needs them is
first used.
"""

import importlib
import os

# numba: the TBB layer shipped in some environments is too old and only produces a warning; OpenMP
# (libgomp) is what the set-up installs. A user's own choice wins.
os.environ.setdefault("NUMBA_THREADING_LAYER", "omp")

__version__ = "0.1.0"

# numba's cached kernels, removed where they were compiled from other sources than these (an update in place)
from .kernel_cache import refresh as _refresh_kernel_cache  # noqa: E402

_refresh_kernel_cache()

_LAZY = {
    # scattering physics
    "Medium": "translucency.scatter.medium",
    "Material": "translucency.scatter.materials",
    "material": "translucency.scatter.materials",
    "material_names": "translucency.scatter.materials",
    "catalogue": "translucency.scatter.materials",
    "medium_from_appearance": "translucency.scatter.appearance",
    "appearance_of": "translucency.scatter.appearance",
    "directional_dipole": "translucency.scatter.dipoles",
    "standard_dipole_profile": "translucency.scatter.dipoles",
    "better_dipole_profile": "translucency.scatter.dipoles",
    # meshes
    "TriangleMesh": "translucency.geometry.mesh",
    "load_mesh": "translucency.io.load",
    "clean_mesh": "translucency.io.clean",
    "decimate_mesh": "translucency.io.decimate",
    "write_baked_ply": "translucency.io.baked",
    "read_baked_ply": "translucency.io.baked",
    # lights and the solver
    "DirectionalLight": "translucency.scatter.lights",
    "PointLight": "translucency.scatter.lights",
    "EnvironmentLight": "translucency.scatter.lights",
    "incident_flux": "translucency.scatter.irradiance",
    "SurfaceGeometry": "translucency.scatter.surface",
    "solve": "translucency.scatter.solve",
    # the whole chain on one mesh
    "shade": "translucency.app.shading",
    "Scene": "translucency.app.shading",
    "ShadeResult": "translucency.app.shading",
    "load_default_scan": "translucency.app.shading",
    "ShadeSettings": "translucency.app.shading",
    "shade_scan": "translucency.app.shading",
    "write_result": "translucency.app.shading",
    # many scans to baked PLY files
    "bake": "translucency.app.bake",
    "display_colors": "translucency.app.display",
    "luminance": "translucency.app.display",
    # showing and comparing
    "Viewer": "translucency.app.viewer",
    "compare": "translucency.app.compare",
    "Comparison": "translucency.app.compare",
    "render_colors": "translucency.app.render",
    # the path-traced ground truth
    "trace_reference": "translucency.app.ground_truth",
    "write_reference": "translucency.app.ground_truth",
    "read_reference_file": "translucency.io.reference_file",
    # errors
    "TranslucencyError": "translucency.errors",
    "InvalidParameterError": "translucency.errors",
    "UnknownMaterialError": "translucency.errors",
    "MeshError": "translucency.errors",
}

__all__ = sorted(_LAZY) + ["__version__"]


def __getattr__(name):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'translucency' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__():
    return __all__
