"""Relighting: preparation time and memory, time per light, and the per-vertex error of relit ``B``.

For each scan (the embedded default bunny; the shared horse and Igea, cleaned, in mm), material (marble,
skim milk, ketchup) and tolerance, the operators of ``method="relight"`` (docs/physics.md §8.7) are
prepared once on every vertex, then several directional lights with Embree shadows are relit. Reported:

* preparation: wall time (far field, near field), the operators' memory (bytes they hold) and the
  process's peak resident memory after it;
* per light: the median wall time of :meth:`Scene.shade <translucency.app.shading.scene.Scene.shade>` with
  ``bounces=0`` (incident light with shadow rays, the product, colours), and, side by side in the same
  run, the same call with ``method="tree"`` at tolerance 0.01 (the ratio is the speed-up);
* error: the figure ``tol`` bounds (docs/physics.md §8.5), the 99th percentile of ``|B - B_ref| / B_ref``
  over the (vertex, channel) pairs with ``B_ref`` at least 1e-4 of the channel's largest, and the median,
  against ``tree`` at 1e-3 (every light) and against ``exact`` (the first light, bunny only, whose time is shown
  beside: a new light's speed-up over ``exact``).

Where the operators would not fit the memory budget (the machine's available memory) the row says so.
Writes ``relight.json`` and ``relight.md`` into ``bench/results`` (``bench/results/tmp`` with ``--quick``).

    .venv/bin/python bench/relight.py            # everything (about 30 min on 2 cores)
    .venv/bin/python bench/relight.py --quick    # bunny in marble at tol 0.1 only
"""

from __future__ import annotations

import argparse
import gc
import json
import resource
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
from report import load_average, machine_info, output_dir, write_results  # noqa: E402

from translucency import __version__  # noqa: E402,F401  (first: it selects numba's threading layer)
from translucency.app.shading.scan import load_default_scan  # noqa: E402
from translucency.app.shading.scene import Scene  # noqa: E402
from translucency.errors import BudgetError  # noqa: E402
from translucency.io.clean import clean_mesh  # noqa: E402
from translucency.io.load import load_mesh  # noqa: E402
from translucency.scatter.lights import DirectionalLight  # noqa: E402
from translucency.scatter.materials import material  # noqa: E402
from translucency.scatter.solve import TOL_FLOOR  # noqa: E402

MESHES = ROOT.parent / "shared" / "meshes"
SCANS = {"bunny (default)": None, "horse": "cyberware_horse.ply", "igea": "cyberware_igea.ply"}
MATERIALS = ("marble", "skim_milk", "ketchup")
#: Light directions (scan frame), one per relit frame.
LIGHTS = [(0.35, 1.0, 0.45), (-0.8, 0.5, 0.3), (0.2, 0.3, -1.0), (1.0, -0.2, 0.4)]
PLAN = {  # scan -> (materials, tolerances)
    "bunny (default)": (MATERIALS, (0.1, 0.03, 0.01)),
    "horse": (("marble",), (0.1, 0.03)),
    "igea": (("marble",), (0.1, 0.01)),
}


def load(scan):
    """The scan as the pipeline shades it (mm), or None when its file is not in ../shared/meshes."""
    if SCANS[scan] is None:
        return load_default_scan()
    path = MESHES / SCANS[scan]
    if not path.exists():
        return None
    mesh, _ = clean_mesh(load_mesh(path, unit="m"))
    return mesh


def per_vertex(B, reference, percentile):
    """The ``percentile`` of ``|B - B_ref| / B_ref`` over the pairs with ``B_ref >= TOL_FLOOR`` x its channel's max."""
    keep = reference >= TOL_FLOOR * reference.max(axis=0)
    return float(np.percentile(np.abs(B - reference)[keep] / reference[keep], percentile))


def peak_rss_gb() -> float:
    """The process's peak resident memory so far, GB."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20


def run(scan, mesh, name, tol, lights, with_exact):
    """One (scan, material, tol) row: prepare, relight every light, compare."""
    scene = Scene(mesh)
    shade = dict(bounces=0, time_limit=None)
    first = DirectionalLight(lights[0], 1.0)
    start = time.perf_counter()
    try:
        prepared = scene.shade(name, first, method="relight", tol=tol, **shade)
    except BudgetError as exc:
        return {"scan": scan, "material": name, "tol": tol, "refused": str(exc)}
    prepare_seconds = time.perf_counter() - start
    stats = prepared.stats["solver"]
    row = {
        "scan": scan,
        "vertices": int(mesh.n_points),
        "material": name,
        "tol": tol,
        "prepare_s": prepare_seconds,
        "prepare_far_s": stats["seconds"]["far"],
        "prepare_near_s": stats["seconds"]["near"],
        "operator_gb": stats["bytes"] / 2**30,
        "peak_rss_gb": peak_rss_gb(),
        "entries_per_vertex": (stats["far_entries"] + stats["near_entries"]) / mesh.n_points,
        "coarser": prepared.stats["coarser"],
    }
    relight_s, tree_s, p99, p50 = [], [], [], []
    for k, direction in enumerate(lights):
        light = DirectionalLight(direction, 1.0)
        t = time.perf_counter()
        relit = scene.shade(name, light, method="relight", tol=tol, **shade)
        relight_s.append(time.perf_counter() - t)
        t = time.perf_counter()
        scene.shade(name, light, method="tree", tol=0.01, **shade)
        tree_s.append(time.perf_counter() - t)
        reference = scene.shade(name, light, method="tree", tol=1e-3, **shade).B
        p99.append(per_vertex(relit.B, reference, 99))
        p50.append(per_vertex(relit.B, reference, 50))
        if k == 0 and with_exact:
            t = time.perf_counter()
            exact = scene.shade(name, light, method="exact", **shade).B
            row["exact_s"] = time.perf_counter() - t
            row["p99_vs_exact"] = per_vertex(relit.B, exact, 99)
            row["p99_tree_1e-3_vs_exact"] = per_vertex(reference, exact, 99)
    row.update(
        {
            "relight_s": statistics.median(relight_s),
            "relight_s_all": relight_s,
            "tree_0.01_s": statistics.median(tree_s),
            "speedup": statistics.median(tree_s) / statistics.median(relight_s),
            "p99_vs_tree_1e-3": max(p99),
            "p50_vs_tree_1e-3": max(p50),
            "lights": len(lights),
            "load": load_average(),
        }
    )
    print(row, flush=True)
    return row


def table(rows) -> str:
    """The Markdown table of the rows."""
    lines = [
        "| scan | vertices | material | tol | prepare (far + near) | operators | peak RSS | per light (relight) "
        "| per light (tree 0.01) | speed-up | p99 vs tree 1e-3 (worst light) | median | p99 vs exact "
        "| exact (first light) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        if "refused" in r:
            lines.append(f"| {r['scan']} | | {r['material']} | {r['tol']:g} | refused: {r['refused']} ||||||||||")
            continue
        exact = f"{100 * r['p99_vs_exact']:.2f} %" if "p99_vs_exact" in r else ""
        exact_time = f"{r['exact_s']:.1f} s ({r['exact_s'] / r['relight_s']:.0f}x)" if "exact_s" in r else ""
        lines.append(
            f"| {r['scan']} | {r['vertices']:,} | {r['material']} | {r['tol']:g} | {r['prepare_s']:.0f} s "
            f"({r['prepare_far_s']:.0f} + {r['prepare_near_s']:.0f}) | {r['operator_gb']:.2f} GB | "
            f"{r['peak_rss_gb']:.1f} GB | {1000 * r['relight_s']:.0f} ms | {1000 * r['tree_0.01_s']:.0f} ms | "
            f"{r['speedup']:.1f} | {100 * r['p99_vs_tree_1e-3']:.2f} % | {100 * r['p50_vs_tree_1e-3']:.3f} % "
            f"| {exact} | {exact_time} |"
        )
    return "\n".join(lines)


def main(argv=None):
    """Command line: the rows of :data:`PLAN` (``--quick``: bunny in marble at 0.1), written to results."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="bunny in marble at tol 0.1, two lights")
    parser.add_argument("--scans", nargs="+", choices=list(SCANS), help="scans to run (default: all)")
    parser.add_argument("--materials", nargs="+", choices=MATERIALS, help="materials to run (default: the plan's)")
    parser.add_argument("--tols", nargs="+", type=float, help="tolerances to run (default: the plan's)")
    parser.add_argument("--append", action="store_true", help="add the rows to those of relight.json already there")
    args = parser.parse_args(argv)
    out = output_dir(args.quick)
    info = machine_info()
    plan = {"bunny (default)": (("marble",), (0.1,))} if args.quick else PLAN
    previous = out / "relight.json"
    rows = json.loads(previous.read_text())["rows"] if args.append and previous.exists() else []
    materials_described = {m: material(m).medium().describe() for m in MATERIALS}
    for scan, (materials, tolerances) in plan.items():
        if args.scans and scan not in args.scans:
            continue
        mesh = load(scan)
        if mesh is None:
            print(f"skipping {scan}: {SCANS[scan]} not in ../shared/meshes")
            continue
        for name in [m for m in materials if not args.materials or m in args.materials]:
            for tol in [t for t in tolerances if not args.tols or t in args.tols]:
                lights = LIGHTS[:2] if args.quick or scan != "bunny (default)" else LIGHTS
                rows.append(run(scan, mesh, name, tol, lights, with_exact=scan == "bunny (default)"))
                gc.collect()  # the Scene's caches hold a cycle: free its operators before the next row
                # written after every row: a long run that stops keeps what it measured
                write_results(
                    out, "relight", {"info": info, "rows": rows, "materials": materials_described}, table(rows)
                )
    print(table(rows))


if __name__ == "__main__":
    main()
