"""First run: wall time of the commands with an empty numba cache (cold) and with a filled one (warm).

Each command runs in its own process, in a temporary folder, with ``NUMBA_CACHE_DIR`` pointing at a
fresh empty folder (cold) and then at the same folder again (warm). A small driver around the command
line records the split of the time: numba compilation (the top-level ``numba:compile`` events),
the imports of the heavy libraries (numba, SciPy, PyVista/VTK, pymeshlab, Embree, Matplotlib) and
the rest (the work itself). Also measured: ``python -m translucency.app.warmup`` (what
``scripts/setup.sh`` runs) on an empty cache, and the main job after it. The warm-up compiles relighting's
kernels in a second process meanwhile, which the driver does not see: its compile column is the first process's.
Every row records the load average before it ran; the table shows medians over ``--repeats``.

    .venv/bin/python bench/first_run.py               # 3 repeats, into results/first_run.{json,md}
    .venv/bin/python bench/first_run.py --quick       # 1 repeat, main job only, into results/tmp/
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from report import load_average, machine_info, output_dir, write_results  # noqa: E402

JOBS = {
    "main job (`translucency`)": [],
    "`translucency bake`": ["bake", "-o", "baked"],
    "`translucency view --screenshot x.png`": ["view", "--screenshot", "x.png"],
    "`translucency compare --materials marble,skim_milk -o d`": [
        "compare",
        "--materials",
        "marble,skim_milk",
        "-o",
        "d",
    ],
}
WARMUP = "`python -m translucency.app.warmup` (set-up)"
AFTER_WARMUP = "main job after the set-up's warm-up"

# Runs one command line in-process and writes its split of the time to the JSON file in argv[1].
DRIVER = r"""
import json, sys, time
start = time.perf_counter()
import numba, scipy.integrate, pyvista, pymeshlab, embreex.rtcore, matplotlib.pyplot
imports = time.perf_counter() - start
from numba.core import event
compile_seconds = [0.0]
depth = [0]
class Timer(event.Listener):
    def on_start(self, ev):
        depth[0] += 1
        if depth[0] == 1:
            self.t = time.perf_counter()
    def on_end(self, ev):
        depth[0] -= 1
        if depth[0] == 0:
            compile_seconds[0] += time.perf_counter() - self.t
event.register("numba:compile", Timer())
code = 0
if sys.argv[2:] == ["warmup"]:
    from translucency.app.warmup import main
    code = main([])
else:
    from translucency.app.cli import main
    code = main(sys.argv[2:])
json.dump({"imports": imports, "compile": compile_seconds[0], "in_process": time.perf_counter() - start,
           "exit_code": code}, open(sys.argv[1], "w"))
"""


def run(args, cache: Path, folder: Path) -> dict:
    """One command in a child process; wall time, its split, the load before it and the notice lines."""
    split = folder / "split.json"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    load = load_average()
    start = time.perf_counter()
    command = [sys.executable, "-c", DRIVER, str(split)] + (["warmup"] if args == "warmup" else list(args))
    done = subprocess.run(command, cwd=folder, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    row = {
        "seconds": wall,
        "load_average": load,
        "returncode": done.returncode,
        "notice_lines": sum(
            "compiling the solver's kernels" in line for line in (done.stdout + done.stderr).splitlines()
        ),
    }
    if split.exists():
        row.update(json.loads(split.read_text()))
        split.unlink()
    if done.returncode:
        row["stderr"] = done.stderr[-2000:]
    return row


def measure(repeats: int, jobs: dict) -> dict:
    """Cold and warm rows of every job, and the warm-up pair, ``repeats`` times each."""
    rows: dict[str, dict[str, list]] = {name: {"cold": [], "warm": []} for name in [*jobs, WARMUP]}
    for _ in range(repeats):
        for name, args in jobs.items():
            with tempfile.TemporaryDirectory(prefix="first-run-") as tmp:
                cache, folder = Path(tmp) / "numba-cache", Path(tmp) / "work"
                cache.mkdir()
                folder.mkdir()
                rows[name]["cold"].append(run(args, cache, folder))
                rows[name]["warm"].append(run(args, cache, folder))
        with tempfile.TemporaryDirectory(prefix="first-run-") as tmp:
            cache, folder = Path(tmp) / "numba-cache", Path(tmp) / "work"
            cache.mkdir()
            folder.mkdir()
            rows[WARMUP]["cold"].append(run("warmup", cache, folder))
            rows[WARMUP]["warm"].append(run([], cache, folder))  # the main job on the warmed cache
    return rows


def _median(rows, key):
    values = [r.get(key) for r in rows if r.get(key) is not None]
    return statistics.median(values) if values else float("nan")


def table(rows: dict) -> str:
    """The Markdown table: medians of cold and warm wall times and the split of the cold time."""
    lines = [
        "| command | cold (s) | warm (s) | cold − warm (s) | cold: numba compile (s) | cold: imports (s) | "
        "cold: the rest (s) | notice lines cold / warm | load average (1 min) |",
        "|---|---:|---:|---:|---:|---:|---:|---|---|",
    ]
    for name, pair in rows.items():
        cold, warm = pair["cold"], pair["warm"]
        if name == WARMUP:
            label = f"{WARMUP}, then the main job"
        else:
            label = name
        c, w = _median(cold, "seconds"), _median(warm, "seconds")
        compile_s, imports = _median(cold, "compile"), _median(cold, "imports")
        rest = c - compile_s - imports
        notices = f"{max(r['notice_lines'] for r in cold)} / {max(r['notice_lines'] for r in warm)}"
        loads = [r["load_average"][0] for r in cold + warm]
        lines.append(
            f"| {label} | {c:.1f} | {w:.1f} | {c - w:.1f} | {compile_s:.1f} | {imports:.1f} | {rest:.1f} | "
            f"{notices} | {min(loads):.1f}–{max(loads):.1f} |"
        )
    n = len(next(iter(rows.values()))["cold"])
    lines += [
        "",
        f"Medians of {n} runs each (cold: a fresh empty `NUMBA_CACHE_DIR`; warm: the same cache again). "
        "*Imports*: numba, SciPy, PyVista/VTK, pymeshlab, Embree and Matplotlib; *the rest*: the work itself "
        "(and translucency's own imports). The warm-up row's warm column is the main job on the cache the "
        "set-up filled.",
    ]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="cold/warm pairs per command (median reported)")
    parser.add_argument("--quick", action="store_true", help="one repeat of the main job, into results/tmp/")
    args = parser.parse_args(argv)
    jobs = {k: v for k, v in JOBS.items() if not args.quick or not v}
    repeats = 1 if args.quick else args.repeats
    info = machine_info()
    rows = measure(repeats, jobs)
    failed = [name for name, pair in rows.items() for r in pair["cold"] + pair["warm"] if r["returncode"]]
    write_results(output_dir(args.quick), "first_run", {"info": info, "rows": rows}, table(rows))
    print(table(rows))
    if failed:
        print(f"failed: {', '.join(sorted(set(failed)))}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
