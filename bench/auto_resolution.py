"""Resolution "auto" against the tolerance it is given: does it keep its promise, and what does it save?

``resolution="auto"`` (the default of bake, compare and :func:`translucency.shade`) solves on a proxy of
:func:`translucency.app.shading.resolution.auto_proxy_edge` only where the scan is much finer than that edge, so that
the
proxy's expected error stays within ``tol`` (docs/physics.md §8.6). For each shared scan (bunny, horse, Igea),
material (marble, skim milk, ketchup, and two whose light diffuses little: soy milk, whose mean free path is 12 mm,
and marble at a diffuse reflectance of 0.99) and tolerance (0.01 -- the default -- 0.1, 0.3, 0.45, 0.6), one
directional light with Embree shadows and no bounce, ``Scene.shade`` with the defaults but ``tol``: the edge ``auto``
chose, the vertices it solved, the wall time of one warm call, and the per-vertex figure ``tol`` bounds (§8.5:
the 99th percentile of ``|B - B_exact| / B_exact`` over the (vertex, channel) pairs with ``B_exact`` at least 1e-4
of the channel's largest) against ``exact`` on the full mesh at 4000 random vertices (its light traced there, the
same for every row), and, where ``auto`` took a proxy, the same figure against the full solve at the default
tolerance (1 %, what the proxy's far field is held to; where ``auto`` solved every vertex: "--").
"met" is the figure against ``exact`` at or below ``tol``. Times are side by side in one run, with the load; the
proxy's decimation is counted apart (it is made once per scan, material and edge).

Written to ``bench/results/auto_resolution.json`` and ``.md`` (with ``--quick``: the bunny in marble at 0.01 and
0.6, into ``bench/results/tmp``).

    .venv/bin/python bench/auto_resolution.py           # about 20 min on 2 cores
    .venv/bin/python bench/auto_resolution.py --quick
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
from report import load_average, machine_info, output_dir, write_results  # noqa: E402
from solver import LIGHT, MATERIALS, SCANS, per_vertex_error, prepare, present_scans, timed  # noqa: E402

from translucency import __version__  # noqa: E402,F401  (first: it selects numba's threading layer)
from translucency.app.shading.scene import Scene  # noqa: E402
from translucency.scatter.definition import varied  # noqa: E402
from translucency.scatter.materials import material  # noqa: E402
from translucency.scatter.names import DEFAULT_TOL  # noqa: E402
from translucency.scatter.solve import solve  # noqa: E402

TOLS = (0.01, 0.1, 0.3, 0.45, 0.6)
#: Besides the catalogue's: media whose light diffuses little over a mean free path or over the object.
AUTO_MATERIALS = (*MATERIALS, "regular_soy_milk", "marble_reflectance_0.99")
RECEIVERS = 4000
SEED = 0


def medium_of(name: str):
    """The catalogue's medium ``name``, or ``"<name>_reflectance_<value>"``: that medium at another diffuse
    reflectance, its mean free path kept (``compare --sweep reflectance=...``)."""
    base, _, value = name.partition("_reflectance_")
    medium = material(base).medium()
    return varied(medium, "reflectance", float(value)) if value else medium


def measure(scan: str, name: str, tols) -> list[dict]:
    """Rows of one scan and material: ``auto`` at each tolerance against ``exact`` on the full mesh."""
    mesh, _ = prepare(scan)
    medium = medium_of(name)
    scene = Scene(mesh)
    receivers = np.sort(np.random.default_rng(SEED).choice(mesh.n_points, min(RECEIVERS, mesh.n_points), replace=False))
    _, _, _, geometry, _ = scene.solver_mesh(medium, "full")
    light, _ = scene.light_cache.incident_on_mesh(medium, [LIGHT])
    start = time.perf_counter()
    exact = solve(geometry, light.phi_rgb, light.w12, medium, method="exact", receivers=receivers).B
    exact_seconds = time.perf_counter() - start
    reference = None  # the full solve at the default tolerance, where a proxy is to be compared with it
    rows = []
    for tol in tols:
        _, decimation, edge, _, _ = scene.solver_mesh(medium, "auto", tol)
        result, seconds = timed(lambda tol=tol: scene.shade(medium, LIGHT, tol=tol, bounces=0), 1)
        p99 = per_vertex_error(result.B[receivers], exact)
        full_seconds = against_full = full_over_budget = None
        if decimation is not None:
            full, full_seconds = timed(
                lambda tol=tol: scene.shade(medium, LIGHT, tol=tol, resolution="full", bounces=0), 1
            )
            full_over_budget = full.stats.get("coarser") is not None
            if reference is None:
                reference = scene.shade(medium, LIGHT, tol=DEFAULT_TOL, resolution="full", bounces=0)
            # a full solve over the time budget went to a proxy itself: no reference then
            against_full = None if reference.stats.get("coarser") else per_vertex_error(result.B, reference.B)
        row = {
            "scan": scan,
            "material": name,
            "tol": tol,
            "vertices": mesh.n_points,
            "mean_edge_mm": geometry.mean_edge_length,
            "sigma_tr_max_per_mm": float(np.max(medium.sigma_tr)),
            "proxy_edge_mm": edge,
            "sigma_tr_times_edge": None if edge is None else float(np.max(medium.sigma_tr) * edge),
            "vertices_solved": int(result.stats["solver_vertices"]),
            "over_budget": result.stats.get("coarser") is not None,
            "full_over_budget": full_over_budget,
            "seconds": seconds,
            "decimation_seconds": None if decimation is None else decimation.seconds,
            "exact_seconds": exact_seconds,
            "receivers": int(receivers.size),
            "p99": p99,
            "p99_against_full": against_full,
            "full_seconds": full_seconds,
            "met": p99 <= tol,
            "coarser": result.stats.get("coarser"),
            "load": load_average()[0],
        }
        rows.append(row)
        print(
            f"{scan:6s} {name:10s} tol {tol:<5g} solved {row['vertices_solved']:7d} of {mesh.n_points:7d}  "
            f"{seconds:6.2f} s  p99 {p99:.4f}  {'met' if row['met'] else 'MISSED'}",
            flush=True,
        )
    return rows


def markdown(rows) -> str:
    """The table of bench/README.md's "Automatic resolution"."""
    lines = [
        "| scan, material | vertices (mean edge) | tol | auto's edge (σ_tr h) | vertices solved | time (every vertex) "
        "| p99 against exact | p99 against every vertex at 1 % | met |",
        "|---|---|---:|---|---:|---:|---:|---:|---|",
    ]
    for r in rows:
        full = (
            "" if r["full_seconds"] is None else f" ({r['full_seconds']:.2f} s{' *' if r['full_over_budget'] else ''})"
        )
        solved = f"{r['vertices_solved']:,}" + (" *" if r["over_budget"] else "")
        edge = (
            "every vertex"
            if r["proxy_edge_mm"] is None
            else f"{r['proxy_edge_mm']:.2f} mm ({r['sigma_tr_times_edge']:.2f})"
        )
        lines.append(
            f"| {r['scan']}, {r['material'].replace('_', ' ')} | {r['vertices']:,} ({r['mean_edge_mm']:.2f} mm) | "
            f"{r['tol']:g} | {edge} | {solved} | {r['seconds']:.2f} s{full} | {r['p99']:.2%} | "
            f"{'--' if r['p99_against_full'] is None else format(r['p99_against_full'], '.2%')} | "
            f"{'yes' if r['met'] else '**no**'} |"
        )
    lines.append(
        "\n\\* over the solve's time budget (5 min by its estimate): solved on the coarser proxy the budget allows, "
        "with a warning; no full solve to compare with."
    )
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    """Measure every scan, material and tolerance asked for; write the JSON and the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scans", nargs="+", choices=list(SCANS), default=list(SCANS))
    parser.add_argument("--materials", nargs="+", default=list(AUTO_MATERIALS))
    parser.add_argument("--tols", nargs="+", type=float, default=list(TOLS))
    parser.add_argument("--quick", action="store_true", help="the bunny in marble at 0.01 and 0.6")
    args = parser.parse_args(argv)
    if args.quick:
        args.scans, args.materials, args.tols = ["bunny"], ["marble"], [0.01, 0.6]
    info = machine_info()
    start = time.perf_counter()
    rows = []
    for scan in present_scans(args.scans):
        for name in args.materials:
            rows.extend(measure(scan, name, args.tols))
    info["seconds_total"] = time.perf_counter() - start
    table = markdown(rows)
    write_results(output_dir(args.quick), "auto_resolution", {"info": info, "rows": rows}, table)
    print(table)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
