"""Bounces: what light that re-enters adds per bin of the light's cosine, and what it costs.

For a scan (default: the embedded bunny) in marble under the default light, solved with ``bounces``
0, 1 and 2 in one process: per bin of ``n . w_L`` (the far side [-0.3, 0), [-0.6, -0.3), [-1, -0.6)
and the lit side > 0.2), the ratio of the mean ``B`` with one bounce to none and with two to one, per
channel; the seconds of the gather and of the extra solves against the first solve's.

    python bench/bounces.py [MESH] [--unit m]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

BINS = (("[-0.3, 0)", -0.3, 0.0), ("[-0.6, -0.3)", -0.6, -0.3), ("[-1, -0.6)", -1.01, -0.6), ("lit > 0.2", 0.2, 1.01))


def main() -> None:
    """Print the table."""
    from translucency.app.shading.scan import load_scan
    from translucency.app.shading.scene import Scene
    from translucency.app.shading.settings import default_light_direction

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mesh", nargs="?")
    parser.add_argument("--unit", default=None)
    args = parser.parse_args()
    mesh, _, name = load_scan(args.mesh, args.unit)
    scene = Scene(mesh)
    scene.shade(bounces=0)  # compiles, builds the scene and the geometry caches
    results, seconds = {}, {}
    for bounces in (0, 1, 2):
        start = time.perf_counter()
        results[bounces] = scene.shade(bounces=bounces)
        seconds[bounces] = time.perf_counter() - start
    light = default_light_direction(scene.up)
    cos = results[0].normals @ (light / np.linalg.norm(light))
    print(f"{name}: {mesh.n_points} vertices, marble, default light; load {os.getloadavg()[0]:.2f}")
    for label, low, high in BINS:
        inside = (cos >= low) & (cos < high)
        mean = {k: r.B[inside].mean(axis=0) for k, r in results.items()}
        one, two = mean[1] / mean[0], mean[2] / mean[1]
        print(f"  {label:13s} {inside.sum():6d} vertices  B1/B0 {np.round(one, 3)}  B2/B1 {np.round(two, 3)}")
    first = sum(v for k, v in results[0].timings.items() if k.startswith("solve_"))
    stats = results[1].stats["bounces"]
    lit_flux = float((results[0].incident_flux[:, 0] * mesh.vertex_areas()).sum())
    mirror = stats["mirror"]
    print(
        f"  entering flux (red, W mm²/m²): lights {lit_flux:.4g}; first bounce {stats['entered_flux'][0][0]:.4g}, "
        f"of it the mirror reflection {mirror['deposited_flux'][0]:.4g} (reflected: {mirror['reflected_flux'][0]:.4g})"
    )
    for k in (1, 2):
        t = results[k].timings
        print(
            f"  bounces={k}: gather {t['bounce_gather']:.2f} s, extra solves {t['bounce_solve']:.2f} s, "
            f"together {t['bounce_gather'] + t['bounce_solve']:.2f} s against the first solve's {first:.2f} s; "
            f"share of B {np.round(results[k].stats['bounces']['share_of_B'], 3)}; wall {seconds[k]:.2f} s "
            f"(bounces=0: {seconds[0]:.2f} s)"
        )


if __name__ == "__main__":
    main()
