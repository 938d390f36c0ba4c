"""The main job on the embedded default scan: clean, light, solve, bake a PLY and draw its picture.

Until the full ``bake``/``view`` commands exist this is what ``./run.sh`` and ``translucency`` with no
subcommand do: a real end-to-end computation on the Stanford bunny shipped inside pymeshlab, in marble,
under one directional light with shadows, written to ``translucency-output/``. The PNG is the labelled
two-view picture of :mod:`translucency.app.figure` (sRGB and false-colour luminance in physical units,
scale bar, colour bar, light arrow).
"""

from __future__ import annotations

import time
from pathlib import Path

from ..io.atomic import prepare_output_folder
from ..io.clean import clean_mesh
from .figure import write_figure
from .pipeline import default_scan_path, load_default_scan, shade_scan, write_result
from .settings import DEFAULT_MATERIAL, ShadeSettings

OUTPUT_FOLDER = Path("translucency-output")


def run_default_job(output: Path = OUTPUT_FOLDER, material: str = DEFAULT_MATERIAL) -> int:
    """Bake the embedded default scan; prints what it does and returns the exit code."""
    total = time.perf_counter()
    prepare_output_folder(output)
    print(f"embedded default scan: {default_scan_path().name} (the Stanford bunny shipped inside pymeshlab)")
    mesh = load_default_scan()
    print(f"  {mesh.n_points} vertices, {mesh.n_triangles} triangles, {mesh.extent:.1f} mm across")
    mesh, report = clean_mesh(mesh)
    print("  repair: " + ("nothing to change" if not report.changed else report.summary().replace("\n", "\n  ")))
    settings = ShadeSettings(material)
    print(
        f"shading with {material} ({settings.model} dipole, {settings.method} method, tol {settings.tol:g}, "
        "Embree shadows) ..."
    )
    result = shade_scan(mesh, settings)
    solver = result.stats["solver"]
    print(
        f"  sources lit: {solver['sources']} of {mesh.n_points}; pairs evaluated {solver['pairs_evaluated']:,}, "
        f"skipped {solver['pairs_skipped']:,}; near-field triangles {solver['near_triangles']:,}"
    )
    print("  time: " + ", ".join(f"{k} {v:.2f} s" for k, v in result.timings.items()))
    lit = result.radiance.max(axis=1) > 0
    mean = result.radiance[lit].mean(axis=0)
    print(
        f"  mean radiance toward the normal over lit vertices (W/(m^2 sr) per W/m^2): "
        f"R {mean[0]:.4f}, G {mean[1]:.4f}, B {mean[2]:.4f}"
    )
    output.mkdir(parents=True, exist_ok=True)
    ply = write_result(result, output / f"bunny_{material}.ply")
    png = output / f"bunny_{material}.png"
    write_figure(png, mesh, result, name="bunny")
    print(f"wrote {ply} and {png} in {time.perf_counter() - total:.1f} s")
    return 0
