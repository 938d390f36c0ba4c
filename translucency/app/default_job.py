"""The main job on the embedded default scan: clean, light, solve, bake a PLY and draw its picture.

Until the full ``bake``/``view`` commands exist this is what ``./run.sh`` and ``translucency`` with no
subcommand do: a real end-to-end computation on the Stanford bunny shipped inside pymeshlab, in marble,
under one directional light from behind (:data:`MAIN_JOB_LIGHT`) with shadows, written to
``translucency-output/``. The PNG is the labelled
two-view picture of :mod:`translucency.app.figure` (sRGB and false-colour luminance in physical units,
scale bar, colour bar, light arrow).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ..io.atomic import prepare_output_folder
from ..io.clean import clean_mesh
from ..io.upright import to_scan_frame
from ..scatter.lights import DirectionalLight
from .figure import write_figure
from .progress import StageProgress
from .shading.result import write_result
from .shading.scan import default_scan_path, load_default_scan
from .shading.scene import scene_for
from .shading.settings import DEFAULT_MATERIAL, ShadeSettings

OUTPUT_FOLDER = Path("translucency-output")
#: Toward the main job's light, in the display frame (right, up, front; :func:`translucency.io.upright.
#: display_frame`): from behind the scan, to the left and above, so that its picture shows what translucency
#: does -- light coming through the ears and glowing along the rim -- rather than a lit, plaster-like front.
MAIN_JOB_LIGHT = (-0.5, 0.45, -0.8)


def run_default_job(output: Path = OUTPUT_FOLDER, material: str = DEFAULT_MATERIAL, *, quiet: bool = False) -> int:
    """Bake the embedded default scan; prints what it does and returns the exit code.

    The solve's progress goes to stderr (:mod:`translucency.app.progress`: a bar on a terminal, one
    line per stage elsewhere, nothing with ``quiet``); every other line to stdout.
    """
    total = time.perf_counter()
    prepare_output_folder(output)
    print(f"embedded default scan: {default_scan_path().name} (the Stanford bunny shipped inside pymeshlab)")
    mesh = load_default_scan()
    print(f"  {mesh.n_points} vertices, {mesh.n_triangles} triangles, {mesh.extent:.1f} mm across")
    mesh, report = clean_mesh(mesh)
    print("  repair: " + ("nothing to change" if not report.changed else report.summary().replace("\n", "\n  ")))
    settings = ShadeSettings(material=material)
    print(
        f"shading with {material} ({settings.model} dipole, {settings.method} method, tol {settings.tol:g}, "
        f"{settings.bounces} bounce{'s' if settings.bounces != 1 else ''}, Embree shadows) ..."
    )
    scene = scene_for(mesh, settings)
    light = DirectionalLight(to_scan_frame(MAIN_JOB_LIGHT, scene.up), 1.0)
    print(f"  light from behind the bunny, to the left and above: toward the light {np.round(light.direction, 2)}")
    with StageProgress(default_scan_path().stem, quiet=quiet) as progress:
        result = scene.shade_with(settings, light, progress=progress)
    lit = result.incident_flux.max(axis=1) > 0  # incident flux > 0: front-facing and not shadowed
    solver = result.stats["solver"]
    print(f"  vertices lit (incident flux > 0): {int(lit.sum())} of {mesh.n_points}")
    print(
        f"  source-receiver pairs evaluated {solver['pairs_evaluated']:,}, skipped {solver['pairs_skipped']:,}; "
        f"near-field triangles {solver['near_triangles']:,}"
    )
    bounced = result.stats["bounces"]
    if bounced["bounces"]:
        share = ", ".join(f"{name} {100 * part:.1f} %" for name, part in zip("RGB", bounced["share_of_B"]))
        print(
            f"  light that left the surface and entered again ({bounced['bounces']} bounce"
            f"{'s' if bounced['bounces'] > 1 else ''}): {share} of B"
        )
    steps = [f"{k} {v:.2f} s" for k, v in result.timings.items()]
    print("  wall time per step:")
    for first in range(0, len(steps), 3):
        print("    " + ", ".join(steps[first : first + 3]) + ("," if first + 3 < len(steps) else ""))
    print("  mean radiance toward the normal, W/(m^2 sr) per W/m^2 of irradiance:")
    for label, mask in ((f"the {int(lit.sum())} lit vertices", lit), (f"all {mesh.n_points} vertices", slice(None))):
        mean = result.radiance[mask].mean(axis=0)
        print(f"    over {label}: R {mean[0]:.4f}, G {mean[1]:.4f}, B {mean[2]:.4f}")
    output.mkdir(parents=True, exist_ok=True)
    ply = write_result(result, output / f"bunny_{material}.ply")
    png = output / f"bunny_{material}.png"
    write_figure(png, mesh, result, name="bunny")
    print(f"wrote {ply} and {png} in {time.perf_counter() - total:.1f} s")
    return 0
