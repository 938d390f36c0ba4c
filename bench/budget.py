"""The solve's memory and time estimate (translucency.scatter.budget) against measured peak memory and time.

Each case runs in its own process: the scan is loaded, cleaned and lit, the peak-RSS mark is reset
(``/proc/self/clear_refs``), one solve runs through ``Scene.shade`` (tree, tol 0.01, with the budget),
and the peak RSS above what the process held before the solve (``VmHWM`` less ``VmRSS`` before) is
compared with the estimate's ``peak_bytes``, the solve's wall time with its ``seconds``.

    .venv/bin/python bench/budget.py            # every case, into results/budget.json and results/budget.md
    .venv/bin/python bench/budget.py --quick    # bunny in marble only, into results/tmp/
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
    parser.add_argument("--case", nargs=4, metavar=("SCAN", "UNIT", "MATERIAL", "LIMIT"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
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
    out = HERE / "results" / ("tmp" if args.quick else "")
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for case in cases:
        done = subprocess.run([sys.executable, __file__, "--case", *case], capture_output=True, text=True)
        if done.returncode != 0:
            print(f"{case}: failed\n{done.stderr[-2000:]}", file=sys.stderr)
            continue
        rows.append(json.loads(done.stdout.strip().splitlines()[-1]))
        print(table(rows[-1:]).splitlines()[-1], flush=True)
    (out / "budget.json").write_text(json.dumps({"cpus": os.cpu_count(), "rows": rows}, indent=1))
    (out / "budget.md").write_text(table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
