"""Colour from the scan: run time against error of the reflectance levels (docs/physics.md §6.5).

The embedded bunny in marble under the default light, ``tree`` at tol 0.01, with a colour that has sharp
stripes in red, a ramp in green and a wave in blue (reflectance 0.15-0.85). For each level step, the
time of :func:`translucency.scatter.varying.solve_varying` against the solve with the material's own
albedo (side by side in one process, after a warm-up) and its error against a step of 0.0125 (per vertex
and channel, over ``B`` >= 1e-4 of the largest): the 99th percentile, the largest and the RMS. Written to
``bench/results/colour_levels.json`` and ``.md``.

    python bench/colour_levels.py
"""

from __future__ import annotations

import json
import os
import time
import warnings
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).parent / "results"
STEPS = (0.2, 0.1, 0.05, 0.025)
REFERENCE_STEP = 0.0125


def main() -> None:
    """Run, print and write the table."""
    from translucency.app.shading.scan import load_default_scan
    from translucency.app.shading.scene import Scene
    from translucency.app.shading.settings import default_light_direction, resolve_medium
    from translucency.errors import TranslucencyWarning
    from translucency.scatter import varying
    from translucency.scatter.lights import DirectionalLight
    from translucency.scatter.solve import solve

    warnings.simplefilter("ignore", TranslucencyWarning)
    medium = resolve_medium("marble")
    scene = Scene(load_default_scan())
    mesh, _, _, geometry, _ = scene.solver_mesh(medium, "full")
    incident, _ = scene.light_cache.incident(
        geometry, mesh.triangles, [DirectionalLight(default_light_direction(scene.up), 1.0)], medium.eta
    )
    p = geometry.points
    u = (p - p.min(0)) / np.ptp(p, 0)
    reflectance = np.stack(
        [0.15 + 0.7 * (np.sin(12 * u[:, 0]) > 0), 0.2 + 0.6 * u[:, 1], 0.5 + 0.3 * np.cos(9 * u[:, 2])], axis=1
    )
    args = (geometry, incident.phi_rgb, incident.w12, medium)
    options = {"method": "tree", "tol": 0.01}
    solve(*args, **options)  # warm-up: compiles and builds the geometry's caches

    def timed(step=None):
        start = time.perf_counter()
        if step is None:
            solution = solve(*args, **options)
        else:
            varying.REFLECTANCE_STEP = step
            solution = varying.solve_varying(*args, reflectance=reflectance, **options)
        return solution, time.perf_counter() - start

    reference, _ = timed(REFERENCE_STEP)
    lit = reference.B > 1e-4 * reference.B.max(axis=0)
    rows = []
    for step in STEPS:
        _, plain = timed()
        solution, seconds = timed(step)
        error = np.abs(solution.B - reference.B)[lit] / reference.B[lit]
        rows.append(
            {
                "step": step,
                "levels": len(solution.stats["levels"]),
                "levels_per_receiver": solution.stats["receiver_solves"] / geometry.n_vertices,
                "seconds": seconds,
                "one_albedo_seconds": plain,
                "time_ratio": seconds / plain,
                "p99": float(np.percentile(error, 99)),
                "max": float(error.max()),
                "rms": float(np.sqrt(np.mean(error**2))),
            }
        )
    load = os.getloadavg()[0]
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "colour_levels.json").write_text(
        json.dumps(
            {"vertices": geometry.n_vertices, "reference_step": REFERENCE_STEP, "load": load, "rows": rows}, indent=1
        )
    )
    lines = [
        f"Embedded bunny ({geometry.n_vertices:,} vertices), marble, default light, tree at tol 0.01; load {load:.1f}; "
        f"error against a step of {REFERENCE_STEP}:",
        "",
        "| step | levels | levels per receiver | time | x one albedo | p99 | max | RMS |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['step']:g} | {r['levels']} | {r['levels_per_receiver']:.1f} | {r['seconds']:.1f} s | "
            f"{r['time_ratio']:.1f} | {r['p99']:.2%} | {r['max']:.1%} | {r['rms']:.2%} |"
        )
    (RESULTS / "colour_levels.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
