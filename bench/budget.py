"""The solve's memory and time estimate (translucency.scatter.budget) against measured peak memory and time.

Each case runs in its own process: the scan is loaded, cleaned and lit, the peak-RSS mark is reset
(``/proc/self/clear_refs``), one solve runs through ``Scene.shade`` (tree, tol 0.01, with the budget),
and the peak RSS above what the process held before the solve (``VmHWM`` less ``VmRSS`` before) is
compared with the estimate's ``peak_bytes``, the solve's wall time with its ``seconds``.

With ``--relight`` the cases are relighting's preparations (``method="relight"``, no bounce; the embedded default
bunny in three materials at three tolerances, the horse and the Igea in marble): the estimate of the operators'
memory (``relight.operator_bytes``) against what they hold, the estimated peak against the measured one (``VmHWM``
less ``VmRSS`` before, over the whole shade: the preparation, the light and its check against ``tree``), its time
against the preparation's.

    .venv/bin/python bench/budget.py            # every case, into results/budget.json and results/budget.md
    .venv/bin/python bench/budget.py --quick    # bunny in marble only, into results/tmp/
    .venv/bin/python bench/budget.py --relight  # into results/budget_relight.json and .md (about 6 min)
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
MESHES = HERE.parent.parent / "shared" / "meshes"
SCANS = {"bunny": "stanford_bunny_zipper.ply", "horse": "cyberware_horse.ply", "igea": "cyberware_igea.ply"}
MATERIALS = ("marble", "skim_milk", "ketchup")
#: Relighting's cases: (scan, material, tol); "default" is the embedded default bunny.
RELIGHT_CASES = [("default", material, tol) for material in MATERIALS for tol in (0.1, 0.03, 0.01)] + [
    ("horse", "marble", 0.03),
    ("igea", "marble", 0.1),
]


def _status(field: str) -> float:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return float(line.split()[1]) * 1024
    return float("nan")


def run_case(scan: str, unit: str, material: str, memory_limit: float | None) -> dict:
    """One case in this process: load, light, reset the peak mark, shade; the numbers as a dict."""
    import numba

    from translucency.app.shading.scan import load_scan
    from translucency.app.shading.scene import Scene
    from translucency.geometry.measure import mean_edge_length

    mesh, _, _ = load_scan(str(MESHES / SCANS[scan]), unit)
    scene = Scene(mesh)
    warm = 10 * mean_edge_length(mesh.points, mesh.triangles)
    scene.shade(material, resolution=warm, time_limit=None)  # warm: the compiled kernels loaded, on a small proxy
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")
    before = _status("VmRSS")
    lines = []
    start = time.perf_counter()
    result = scene.shade(material, memory_limit=memory_limit, warn=lines.append)
    seconds = time.perf_counter() - start
    peak = _status("VmHWM") - before
    plan = result.stats["solver"]["budget"]
    return {
        "scan": scan,
        "unit": unit,
        "material": material,
        "memory_limit_gb": memory_limit,
        "vertices": mesh.n_points,
        "solver_vertices": result.stats["solver_vertices"],
        "coarser": lines,
        "keep_lists": plan["keep_lists"],
        "block_receivers": plan["block_receivers"],
        "estimated_peak_mb": plan["peak_bytes"] / 2**20,
        "measured_peak_mb": peak / 2**20,
        "estimated_s": plan["seconds"],
        "measured_s": seconds,
        "solve_s": sum(v for k, v in result.timings.items() if k.startswith("solve_")),
        "threads": numba.get_num_threads(),
        "load": os.getloadavg()[0],
    }


def run_relight_case(scan: str, material: str, tol: float) -> dict:
    """One preparation of relighting's operators in this process: the estimate against what was made."""
    import numba

    from translucency.app.shading.scan import load_default_scan, load_scan
    from translucency.app.shading.scene import Scene
    from translucency.scatter.lights import DirectionalLight

    mesh = load_default_scan() if scan == "default" else load_scan(str(MESHES / SCANS[scan]), "m")[0]
    scene = Scene(mesh)
    light = DirectionalLight((0.35, 1.0, 0.45), 1.0)
    scene.shade(material, light, bounces=0, time_limit=None)  # the Embree scene and the compiled kernels loaded
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")
    before = _status("VmRSS")
    result = scene.shade(material, light, method="relight", tol=tol, bounces=0, time_limit=None)
    peak = _status("VmHWM") - before
    solver = result.stats["solver"]
    plan = solver["budget"]
    return {
        "scan": scan,
        "material": material,
        "tol": tol,
        "vertices": mesh.n_points,
        "estimated_mb": plan["far_bytes"] / 2**20,
        "operators_mb": solver["bytes"] / 2**20,
        "estimated_peak_mb": plan["peak_bytes"] / 2**20,
        "measured_peak_mb": peak / 2**20,
        "estimated_s": plan["seconds"],
        "measured_s": result.timings["solve_prepare"],
        "far_fits": plan["counts"]["far_fits"],
        "near_entries": plan["counts"]["near_entries"],
        "threads": numba.get_num_threads(),
        "load": os.getloadavg()[0],
    }


def relight_table(rows) -> str:
    """The Markdown table of relighting's estimates."""
    lines = [
        "| scan | material | tol | operators estimated (MB) | held (MB) | off | peak estimated (MB) "
        "| peak above before (MB) | estimated (s) | measured (s) | load |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        off = r["estimated_mb"] / r["operators_mb"] - 1.0
        lines.append(
            f"| {r['scan']} | {r['material']} | {r['tol']:g} | {r['estimated_mb']:.0f} | {r['operators_mb']:.0f} | "
            f"{100 * off:+.0f} % | {r.get('estimated_peak_mb', r['estimated_mb']):.0f} | {r['measured_peak_mb']:.0f} | "
            f"{r['estimated_s']:.1f} | {r['measured_s']:.1f} | "
            f"{r['load']:.1f} |"
        )
    return "\n".join(lines) + "\n"


def table(rows) -> str:
    """The Markdown table of bench/README.md."""
    head = (
        "| scan | unit | material | limit | vertices solved | lists | estimated peak (MB) | measured peak (MB) "
        "| estimated (s) | measured (s) | load |\n|---|---|---|---:|---:|---|---:|---:|---:|---:|---:|"
    )
    lines = [head]
    for r in rows:
        lists = "kept" if r["keep_lists"] else f"blocks of {r['block_receivers']}"
        limit = "" if r["memory_limit_gb"] is None else f"{r['memory_limit_gb']:g} GB"
        solved = f"{r['solver_vertices']:,}" + (
            "" if r["solver_vertices"] == r["vertices"] else f" of {r['vertices']:,}"
        )
        lines.append(
            f"| {r['scan']} | {r['unit']} | {r['material']} | {limit} | {solved} | {lists} | "
            f"{r['estimated_peak_mb']:.0f} | {r['measured_peak_mb']:.0f} | {r['estimated_s']:.1f} | "
            f"{r['solve_s']:.1f} | {r['load']:.1f} |"
        )
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="bunny in marble only, into results/tmp/")
    parser.add_argument("--relight", action="store_true", help="relighting's preparations instead")
    parser.add_argument("--case", nargs=4, metavar=("SCAN", "UNIT", "MATERIAL", "LIMIT"), help=argparse.SUPPRESS)
    parser.add_argument("--relight-case", nargs=3, metavar=("SCAN", "MATERIAL", "TOL"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.relight_case:
        scan, material, tol = args.relight_case
        print(json.dumps(run_relight_case(scan, material, float(tol))))
        return 0
    if args.relight:
        return relight_main()
    if args.case:
        scan, unit, material, limit = args.case
        print(json.dumps(run_case(scan, unit, material, None if limit == "none" else float(limit))))
        return 0
    cases = (
        [("bunny", "m", "marble", "none")]
        if args.quick
        else (
            [(scan, "m", material, "none") for scan in SCANS for material in MATERIALS]
            + [("bunny", "mm", "marble", "4")]
        )
    )
    return run_cases("--case", cases, table, HERE / "results" / ("tmp" if args.quick else ""), "budget")


def relight_main() -> int:
    """Every relighting case whose scan is here, each in its own process."""
    cases = [
        [scan, material, str(tol)]
        for scan, material, tol in RELIGHT_CASES
        if scan == "default" or (MESHES / SCANS[scan]).exists()
    ]
    return run_cases("--relight-case", cases, relight_table, HERE / "results", "budget_relight")


def run_cases(flag: str, cases, make_table, out: Path, name: str) -> int:
    """Each case in a process of its own (``flag`` and the case's arguments), a line of the table as it ends; the
    rows into ``out/name.json`` and the table into ``out/name.md``."""
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for case in cases:
        done = subprocess.run([sys.executable, __file__, flag, *case], capture_output=True, text=True)
        if done.returncode != 0:
            print(f"{case}: failed\n{done.stderr[-2000:]}", file=sys.stderr)
            continue
        rows.append(json.loads(done.stdout.strip().splitlines()[-1]))
        print(make_table(rows[-1:]).splitlines()[-1], flush=True)
    (out / f"{name}.json").write_text(json.dumps({"cpus": os.cpu_count(), "rows": rows}, indent=1))
    (out / f"{name}.md").write_text(make_table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
