"""Colour from the scan: which coefficients a pair of vertices with two albedos should use, against a
two-media random walk (docs/physics.md §6.5).

Two half-spaces side by side (``x < 0``: reflectance 0.7, ``x >= 0``: 0.2; mean free path 1 mm, g = 0,
eta = 1.3), simulated with Woodcock tracking (:func:`translucency.scatter.montecarlo.simulate_two_media`).
Each choice is built from the walk's own homogeneous profiles (the line-spread function of each side),
so what differs is the choice alone, not the diffusion model's own error:

* the receiver's coefficients (pbrt's and Cycles' shading point), what ``--albedo-from-colors`` uses;
* the source's;
* the mean of the two.

Two lightings: a uniform beam over ``[-40, 40]`` mm (the edge of a colour under even light) and a pencil
beam 2 mm from the boundary on either side (light carried across). Written to
``bench/results/albedo_choice.json`` and ``.md``.

    python bench/albedo_choice.py [--photons 2000000]
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).parent / "results"
REFLECTANCES = (0.7, 0.2)
HALF_WIDTH, STRIP, CELLS, PENCIL = 40.0, 8.0, 32, 2.0


def main() -> None:
    """Run the walks, print and write the table."""
    from translucency.scatter.appearance import reduced_albedo
    from translucency.scatter.montecarlo import simulate_two_media

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photons", type=int, default=2_000_000)
    args = parser.parse_args()
    eta = 1.3
    albedos = [float(reduced_albedo(r, eta)[0]) for r in REFLECTANCES]
    bright, dark = ((1.0 - a, a) for a in albedos)  # sigma_t = 1/mm, g = 0
    runs = {
        "uniform": (bright, dark, (-HALF_WIDTH, HALF_WIDTH), 4),
        "bright": (bright, bright, (0.0, 0.0), 1),
        "dark": (dark, dark, (0.0, 0.0), 1),
        "pencil_bright_side": (bright, dark, (-PENCIL, -PENCIL), 1),
        "pencil_dark_side": (bright, dark, (PENCIL, PENCIL), 1),
    }
    tallies, start = {}, time.perf_counter()
    for name, (left, right, launch, factor) in runs.items():
        tallies[name] = simulate_two_media(
            left,
            right,
            0.0,
            eta,
            launch_x_mm=launch,
            n_photons=factor * args.photons,
            seed=1,
            strip_extent_mm=STRIP,
            strip_cells=CELLS,
        )
    seconds = time.perf_counter() - start
    x = tallies["uniform"].strip_centres_mm
    dx = float(np.diff(tallies["uniform"].strip_edges_mm)[0])
    lsf = {k: tallies[k].strip_exitance for k in ("bright", "dark")}
    total = {k: tallies[k].total_reflectance for k in ("bright", "dark")}

    def beyond(side, j):  # the line-spread function's mass at u > x_j (tails past the strips split evenly)
        tail = (total[side] - lsf[side].sum() * dx) / 2.0
        return lsf[side][j + 1 :].sum() * dx + 0.5 * lsf[side][j] * dx + tail

    truth, truth_se = tallies["uniform"].uniform_exitance
    receiver = np.where(x < 0, total["bright"], total["dark"])
    source = np.array([beyond("bright", j) + total["dark"] - beyond("dark", j) for j in range(x.size)])
    uniform = {"receiver": receiver, "source": source, "mean": 0.5 * (receiver + source)}

    shift = int(round(PENCIL / dx))

    def shifted(profile, by):
        out = np.full_like(profile, np.nan)
        if by > 0:
            out[by:] = profile[:-by]
        else:
            out[:by] = profile[-by:]
        return out

    pencils = {}
    for case, by, own in (("pencil_bright_side", -shift, "bright"), ("pencil_dark_side", shift, "dark")):
        at = {side: shifted(lsf[side], by) for side in ("bright", "dark")}
        rcv = np.where(x < 0, at["bright"], at["dark"])
        pencils[case] = {"receiver": rcv, "source": at[own], "mean": 0.5 * (rcv + at[own])}

    def errors(prediction, reference, where):
        relative = prediction[where] / reference[where] - 1.0
        weights = reference[where]
        return {
            "rms": float(np.sqrt(np.mean(relative**2))),
            "max": float(np.max(np.abs(relative))),
            "flux_weighted_mean": float(np.sum(np.abs(relative) * weights) / np.sum(weights)),
        }

    report = {
        "reflectances": REFLECTANCES,
        "reduced_albedos": albedos,
        "photons": args.photons,
        "monte_carlo_seconds": seconds,
        "load": os.getloadavg()[0],
        "strip_centres_mm": x.tolist(),
        "uniform": {
            "monte_carlo": truth.tolist(),
            "monte_carlo_se": truth_se.tolist(),
            **{k: v.tolist() for k, v in uniform.items()},
            "errors": {k: errors(v, truth, np.isfinite(v)) for k, v in uniform.items()},
        },
    }
    for case, predictions in pencils.items():
        truth_p = tallies[case].strip_exitance
        report[case] = {
            "monte_carlo": truth_p.tolist(),
            **{k: v.tolist() for k, v in predictions.items()},
            "errors": {k: errors(v, truth_p, np.isfinite(v)) for k, v in predictions.items()},
        }
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "albedo_choice.json").write_text(json.dumps(report, indent=1))
    lines = [
        f"Reflectance {REFLECTANCES[0]} (x < 0) beside {REFLECTANCES[1]} (x >= 0), mean free path 1 mm, eta 1.3; "
        f"{args.photons:,} photons per walk (4x for the uniform beam), {seconds:.0f} s of Monte Carlo at load "
        f"{report['load']:.1f}. Relative error of each choice against the two-media walk, over x in "
        f"[-{STRIP:g}, {STRIP:g}] mm:",
        "",
        "| lighting | choice | rms | max | flux-weighted mean |",
        "|---|---|---|---|---|",
    ]
    for case in ("uniform", *pencils):
        for choice, e in report[case]["errors"].items():
            row = f"{e['rms']:.1%} | {e['max']:.0%} | {e['flux_weighted_mean']:.1%}"
            lines.append(f"| {case.replace('_', ' ')} | {choice} | {row} |")
    (RESULTS / "albedo_choice.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
