"""A baked ``.glb`` opens in Blender every time, with its values under their own names.

Blender's glTF importer gathers a primitive's custom attributes in the order of a set of their names, which changes
with Python's hash seed; with attributes of different widths it stopped in most runs. Every custom attribute is now
three floats wide (:mod:`translucency.io.baked_gltf`). The test runs Blender's Python module (``bpy`` from PyPI,
about 350 MB, which needs numpy below 2 and so lives in a virtual environment of its own, made once in
``~/.cache/translucency/bpy-venv`` or where ``TRANSLUCENCY_BPY_VENV`` says) under 20 hash seeds, and is skipped
with pip's reason where it cannot be installed.
"""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import translucency as tl
from translucency.geometry.synthetic import icosphere

pytestmark = pytest.mark.slow

IMPORT = textwrap.dedent("""
    import json, sys
    import bpy
    import numpy as np

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=sys.argv[-1])
    (obj,) = [o for o in bpy.data.objects if o.type == "MESH"]
    values = {}
    for name in ("_RADIANCE", "_B", "_LUMINANCE"):
        data = obj.data.attributes[name].data
        flat = np.empty(3 * len(data), dtype=np.float32)
        data.foreach_get("vector", flat)
        values[name] = flat.reshape(-1, 3).mean(axis=0).tolist()
    print(json.dumps({"vertices": len(obj.data.vertices), "height_m": obj.dimensions.z, **values}))
""")


def blender_python() -> Path:
    """The Python of a virtual environment with ``bpy`` (made and installed once); skips the test when it cannot be."""
    venv = Path(os.environ.get("TRANSLUCENCY_BPY_VENV", Path.home() / ".cache" / "translucency" / "bpy-venv"))
    python = venv / "bin" / "python"
    if python.exists() and subprocess.run([python, "-c", "import bpy"], capture_output=True).returncode == 0:
        return python
    made = subprocess.run([sys.executable, "-m", "venv", str(venv)], capture_output=True, text=True)
    if made.returncode == 0:
        made = subprocess.run(
            [python, "-m", "pip", "install", "-q", "bpy"], capture_output=True, text=True, timeout=900
        )
    if made.returncode != 0:
        pytest.skip(f"Blender's Python module (bpy) could not be installed: {made.stderr.strip()[-300:]}")
    return python


def test_blender_imports_the_baked_glb_under_twenty_hash_seeds(tmp_path):
    python = blender_python()
    points, triangles = icosphere(2, radius=20.0)
    result = tl.shade(tl.TriangleMesh(points, triangles), "marble", bounces=0)
    path = tl.write_result(result, tmp_path / "ball.glb")
    radiance = result.radiance.astype(np.float32).mean(axis=0)
    for seed in range(20):
        done = subprocess.run(
            [python, "-c", IMPORT, str(path)],
            env={**os.environ, "PYTHONHASHSEED": str(seed)},
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert done.returncode == 0, f"hash seed {seed}: {done.stderr[-2000:]}"
        read = json.loads(done.stdout.strip().splitlines()[-1])
        assert read["vertices"] == len(points)
        np.testing.assert_allclose(read["_RADIANCE"], radiance, rtol=1e-5)  # each name holds its own values
        np.testing.assert_allclose(read["_B"], result.B.astype(np.float32).mean(axis=0), rtol=1e-5)
        luminance = float((result.radiance @ np.array([0.2126, 0.7152, 0.0722])).astype(np.float32).mean())
        np.testing.assert_allclose(read["_LUMINANCE"], [luminance] * 3, rtol=1e-5)
        assert read["height_m"] == pytest.approx(0.04, rel=1e-3)  # 40 mm across, in metres
