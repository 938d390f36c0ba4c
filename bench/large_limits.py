"""Budgets that must hold on large scans: the memory limit is a limit, and a valid scan bakes to the end.

Each case is ``translucency bake`` in a child process, as a user runs it, with the resident sets of its process
group summed every 0.2 s (:func:`scaling.tree_rss_mb`):

========================= =========================================================================
case                      what is checked
========================= =========================================================================
sphere 1M, limit 1 GB     a 998,002-vertex sphere (PyVista, 50 mm radius) with ``--memory-limit 1``:
                          peak at most the limit and 10 %
sphere 3M, limit 2 GB     a 2,995,002-vertex sphere with ``--memory-limit 2``: the same
Igea x2, defaults         the shared Igea midpoint-subdivided twice (2,149,490 vertices, PyVista's
                          ``subdivide(2, "linear")``), ``--unit m`` and the defaults: baked to the end
========================= =========================================================================

The parent stops a case past ``--time-limit`` seconds (default 900) or past 8 GB of resident memory, and
records why. Writes ``large_limits.json`` and ``large_limits.md`` into ``bench/results``.

    .venv/bin/python bench/large_limits.py                 # every case, about 20 min on 2 cores
    .venv/bin/python bench/large_limits.py --only sphere1m
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from report import load_average, machine_info, output_dir, write_results  # noqa: E402
from scaling import tree_rss_mb  # noqa: E402

MESHES = ROOT.parent / "shared" / "meshes"
STOP_GB = 8.0
CASES = {  # name -> (how the mesh is made, bake options, memory limit in GB or None)
    "sphere1m": ("sphere", 1000, ["--unit", "mm", "--memory-limit", "1"], 1.0),
    "sphere3m": ("sphere", 1732, ["--unit", "mm", "--memory-limit", "2"], 2.0),
    "igea2": ("igea", 2, ["--unit", "m"], None),
}


def make_mesh(kind: str, size: int, path: Path) -> int | None:
    """Write the case's mesh to ``path``; its vertex count, or None when the shared scan is missing."""
    import pyvista as pv

    if kind == "sphere":
        mesh = pv.Sphere(radius=50.0, theta_resolution=size, phi_resolution=size)
    else:
        if not (MESHES / "cyberware_igea.ply").exists():
            return None
        mesh = pv.read(MESHES / "cyberware_igea.ply").triangulate().subdivide(size, "linear")
    mesh.save(path)
    return int(mesh.n_points)


def run_case(name: str, folder: Path, time_limit: float) -> dict:
    """Bake one case in a child process; its status, wall time, peak of the process group and last lines."""
    kind, size, options, limit = CASES[name]
    mesh = folder / f"{name}.ply"
    vertices = make_mesh(kind, size, mesh)
    if vertices is None:
        return {"case": name, "status": "skipped: the shared Igea is missing"}
    log = folder / f"{name}.log"
    command = [sys.executable, "-m", "translucency", "bake", str(mesh), *options, "-o", str(folder / f"{name}_out.ply")]
    with open(log, "w") as stream:
        process = subprocess.Popen(command, stdout=stream, stderr=subprocess.STDOUT, cwd=folder)
        start, peak, status = time.perf_counter(), 0.0, None
        while process.poll() is None:
            peak = max(peak, tree_rss_mb(process.pid))
            if peak > STOP_GB * 1024:
                status = f"stopped: resident sets above {STOP_GB:g} GB"
            elif time.perf_counter() - start > time_limit:
                status = f"stopped: over {time_limit:g} s"
            if status:
                process.kill()
                process.wait()
                break
            time.sleep(0.2)
    seconds = time.perf_counter() - start
    text = log.read_text(errors="replace").replace("\r", "\n").replace(f"{folder}{os.sep}", "")  # names only
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    status = status or ("baked" if process.returncode == 0 else f"failed (exit {process.returncode})")
    return {
        "case": name,
        "vertices": vertices,
        "options": " ".join(options),
        "memory_limit_gb": limit,
        "status": status,
        "seconds": round(seconds, 1),
        "peak_mb": round(peak),
        "within_limit": None if limit is None else peak <= 1.1 * limit * 1024,
        "said": [line for line in lines if line.startswith("translucency:")],
        "last_lines": lines[-4:],
    }


def table(rows) -> str:
    """The cases as a Markdown table."""
    lines = [
        "| case | vertices | options | status | time (s) | peak (MB) | within limit + 10 % | said |",
        "|---|---:|---|---|---:|---:|---|---|",
    ]
    for r in rows:
        if "vertices" not in r:
            lines.append(f"| {r['case']} |  |  | {r['status']} |  |  |  |  |")
            continue
        within = "" if r["within_limit"] is None else ("yes" if r["within_limit"] else "**no**")
        said = "<br>".join(line.replace("|", "/") for line in r["said"]) or "nothing"
        lines.append(
            f"| {r['case']} | {r['vertices']:,} | `{r['options']}` | {r['status']} | {r['seconds']} "
            f"| {r['peak_mb']:,} | {within} | {said} |"
        )
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", choices=sorted(CASES), action="append", help="run this case (repeatable)")
    parser.add_argument("--time-limit", type=float, default=900.0, help="seconds a case may run (default 900)")
    args = parser.parse_args()
    payload = {"info": {**machine_info(), "load_average_start": load_average()}, "rows": []}
    with tempfile.TemporaryDirectory() as folder:
        for name in args.only or list(CASES):
            payload["rows"].append(run_case(name, Path(folder), args.time_limit))
            print(payload["rows"][-1], flush=True)
    write_results(output_dir(False), "large_limits", *merged(payload))


def merged(payload) -> tuple[str, dict, str]:
    """``(name, payload, table)`` with the rows of an earlier run kept for the cases this run did not make (a run
    with ``--only`` replaces its own rows)."""
    earlier = output_dir(False) / "large_limits.json"
    if earlier.exists():
        made = {row["case"] for row in payload["rows"]}
        kept = [row for row in json.loads(earlier.read_text()).get("rows", []) if row["case"] not in made]
        payload["rows"] = sorted(kept + payload["rows"], key=lambda row: list(CASES).index(row["case"]))
    return "large_limits", payload, table(payload["rows"])


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    main()
