"""The viewer at two tolerances: its first picture, the relighting operators, and a frame while the light moves.

What a user of ``translucency view`` waits for, measured without a window on
:class:`~translucency.app.viewer.state.ViewerState` (the state the window drives), marble, the viewer's own
settings but ``tol``:

* *first picture*: :meth:`ViewerState.solve_preview` (``tree`` on the interactive proxy), what the window shows
  within seconds of opening a scan;
* *operators and first light*: :meth:`ViewerState.solve`, the relighting operators prepared on every vertex
  (docs/physics.md §8.7) and the first light with its bounce;
* *a frame while dragged*: the median of ``set_lights(..., moving=True)`` over the azimuths (no bounce, as a
  window asks while the light moves), and *a frame let go*: of ``set_light`` (the default bounce);
* the process's peak resident memory, whether every vertex was solved (or a proxy, when the operators would not
  fit the memory budget), and the warnings the user saw.

Each (scan, tol) runs in a process of its own. Writes ``viewer_tol.json`` and ``viewer_tol.md`` into
``bench/results`` (``bench/results/tmp`` with ``--quick``).

    .venv/bin/python bench/viewer_tol.py                 # the default bunny and the horse at 0.1 and 0.01 (~5 min)
    .venv/bin/python bench/viewer_tol.py --scans igea    # the Igea (~8 min, about 10 GB at its peak)
    .venv/bin/python bench/viewer_tol.py --quick         # the default bunny at 0.1
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from relight import MESHES, SCANS, load  # noqa: E402  (the relighting benchmark's scans, loaded its way)
from report import load_average, machine_info, output_dir, write_results  # noqa: E402

TOLS = (0.1, 0.01)
#: Azimuths of the frames (degrees around the scan's up), at an elevation of 30 degrees.
AZIMUTHS = tuple(range(0, 360, 30))


def row(scan: str, tol: float) -> dict:
    """One (scan, tol): the viewer's waits, measured in this process."""
    from translucency.app.viewer.state import ViewerState
    from translucency.errors import TranslucencyWarning

    mesh = load(scan)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", TranslucencyWarning)
        start = time.perf_counter()
        state = ViewerState(mesh, "marble", solve=False, tol=tol)
        state.solve_preview()
        preview = time.perf_counter() - start
        start = time.perf_counter()
        state.solve()
        prepared = time.perf_counter() - start
        moving, let_go = [], []
        for azimuth in AZIMUTHS:
            lights = state.rig.steered(float(azimuth), 30.0, state.up).lights
            start = time.perf_counter()
            state.set_lights(lights, moving=True)
            moving.append(time.perf_counter() - start)
            start = time.perf_counter()
            state.set_light(float(azimuth) + 15.0, 30.0)
            let_go.append(time.perf_counter() - start)
    stats = state.result.stats
    return {
        "scan": scan,
        "vertices": int(stats["vertices"]),
        "solved_vertices": int(stats["solver_vertices"]),
        "tol": tol,
        "preview_s": preview,
        "prepare_s": prepared,
        "frame_moving_s": statistics.median(moving),
        "frame_let_go_s": statistics.median(let_go),
        "peak_rss_gb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20,
        "warnings": [str(w.message) for w in caught if issubclass(w.category, TranslucencyWarning)],
        "load": load_average(),
    }


def table(rows) -> str:
    """The rows as a markdown table."""
    lines = [
        "| scan | vertices | tol | first picture | operators and first light | a frame while dragged | a frame let go "
        "| peak RSS | every vertex | warnings | load (1 min) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---|---:|---|",
    ]
    for r in rows:
        every = "yes" if r["solved_vertices"] == r["vertices"] else f"proxy of {r['solved_vertices']:,}"
        lines.append(
            f"| {r['scan']} | {r['vertices']:,} | {r['tol']:g} | {r['preview_s']:.1f} s | {r['prepare_s']:.0f} s "
            f"| {1000 * r['frame_moving_s']:.0f} ms | {1000 * r['frame_let_go_s']:.0f} ms | {r['peak_rss_gb']:.1f} GB "
            f"| {every} | {len(r['warnings'])} | {r['load'][0]:.1f} |"
        )
    return "\n".join(lines) + "\n"


def main(argv=None):
    """Command line: every (scan, tol) of the plan, each in a process of its own, written after every row."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the default bunny at tol 0.1")
    parser.add_argument("--scans", nargs="+", choices=list(SCANS), help="scans (default: the bunny and the horse)")
    parser.add_argument("--tols", nargs="+", type=float, default=list(TOLS), help="tolerances (default 0.1 0.01)")
    parser.add_argument("--row", nargs=2, metavar=("SCAN", "TOL"), help=argparse.SUPPRESS)  # one row, as JSON
    args = parser.parse_args(argv)
    if args.row:
        print(json.dumps(row(args.row[0], float(args.row[1]))))
        return
    out = output_dir(args.quick)
    scans = ["bunny (default)"] if args.quick else args.scans or ["bunny (default)", "horse"]
    tols = [0.1] if args.quick else args.tols
    rows = []
    for scan in scans:
        if SCANS[scan] is not None and not (MESHES / SCANS[scan]).exists():
            print(f"skipping {scan}: {SCANS[scan]} not in ../shared/meshes")
            continue
        for tol in tols:
            done = subprocess.run(
                [sys.executable, __file__, "--row", scan, str(tol)], capture_output=True, text=True, check=False
            )
            if done.returncode != 0:
                print(f"{scan} at tol {tol:g} failed:\n{done.stderr[-2000:]}")
                continue
            rows.append(json.loads(done.stdout.strip().splitlines()[-1]))
            write_results(out, "viewer_tol", {"info": machine_info(), "rows": rows}, table(rows))
    print(table(rows))


if __name__ == "__main__":
    main()
