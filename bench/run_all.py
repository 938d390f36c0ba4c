"""Run the benchmark suite with one command and put its tables into ``bench/README.md``.

The suite, in this order, each script in its own process:

=================== ========================================================= ==================
script              what it measures                                          when
=================== ========================================================= ==================
solver.py           time against error per scan, material, method, tolerance  always
                    and proxy resolution; the ``exact`` kernel's throughput
scaling.py          time and memory from 10k to 1M vertices; the 1M bake      always
decimation.py       the 10M proxy's decimation, whole and in parts            always
stability.py        the solver's stability at extreme inputs                  when the file exists
first_run.py        cold (empty numba cache) and warm times of the commands   always (last)
validate_models.py  the diffusion models against Monte Carlo (slow)           with ``--validate``
relight.py          relighting: preparation, time per light, error (slow)     with ``--validate``
=================== ========================================================= ==================

Each script writes its JSON, Markdown tables and PNG plots into ``bench/results`` (with ``--quick``:
small sizes, into ``bench/results/tmp``; :data:`SUITE` holds each script's quick arguments).
Afterwards the suite writes ``suite.json`` (what ran, how
long, the load average) and ``goals.md`` (the issue's speed goals against the measurements), and
replaces every generated block of ``bench/README.md`` -- the text between
``<!-- NAME-table:start -->`` and ``<!-- NAME-table:end -->`` -- with ``bench/results/NAME.md``.
Nothing else of the README changes, and a ``--quick`` run leaves it alone.

    .venv/bin/python bench/run_all.py              # the suite (about 40 min on 2 cores)
    .venv/bin/python bench/run_all.py --validate   # and the Monte Carlo validation (+ about 10 min)
    .venv/bin/python bench/run_all.py --quick      # a smoke run of every script (a few minutes)
    .venv/bin/python bench/run_all.py --tables-only  # only rewrite the README's tables from bench/results
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time

from report import RESULTS, ROOT, load_average, machine_info, output_dir, update_readme

BENCH = ROOT / "bench"
#: (name, script, arguments of a quick run, takes --repeats, optional): the suite in the order it runs.
SUITE = [
    ("solver", "solver.py", ["--quick"], True, False),
    ("scaling", "scaling.py", ["--quick"], True, False),
    ("decimation", "decimation.py", ["--quick"], False, False),
    ("stability", "stability.py", ["--blocks", "256", "--out", "bench/results/tmp"], False, False),
    ("validate_models", "validate_models.py", ["--quick"], False, True),
    ("first_run", "first_run.py", ["--quick"], True, False),
    ("relight", "relight.py", ["--quick"], False, True),
]


def run_script(script, quick_arguments, repeats):
    """Run one benchmark script in a child process; ``{"returncode", "seconds", "load_average_*"}``.

    ``quick_arguments`` (a list, or None for a full run) are what makes the script a smoke run.
    """
    command = [sys.executable, str(BENCH / script)] + (quick_arguments or [])
    if repeats is not None:
        command += ["--repeats", str(repeats)]
    print(f"== bench/{script} {' '.join(command[2:])}", flush=True)
    before = load_average()
    start = time.perf_counter()
    returncode = subprocess.run(command, cwd=ROOT).returncode
    return {
        "returncode": returncode,
        "seconds": time.perf_counter() - start,
        "load_average_start": before,
        "load_average_end": load_average(),
    }


def fastest_within(rows, scan, error):
    """Per material of ``scan``: the fastest solve (not ``exact``, and not ``relight``, whose rows time a light after
    a preparation: the relighting goal's own row) with relative RMS error at most ``error``."""
    best = {}
    for r in rows:
        if r["scan"] == scan and r["method"] not in ("exact", "relight") and r["error_rms"] <= error:
            if r["material"] not in best or r["seconds"] < best[r["material"]]["seconds"]:
                best[r["material"]] = r
    return best


def relight_goal(results) -> str:
    """The relighting goal's row: on the default bunny, a new light in <= 33 ms at <= 1 % (99th percentile
    against ``tree`` at 1e-3), after a preparation of <= 5 s and <= 1 GB (``relight.json``)."""
    goal = "default bunny: a new light ≤ 33 ms at ≤ 1 % (p99), prepared in ≤ 5 s, ≤ 1 GB"
    path = results / "relight.json"
    rows = json.loads(path.read_text())["rows"] if path.exists() else []
    within = [
        r for r in rows if r["scan"] == "bunny (default)" and "refused" not in r and r["p99_vs_tree_1e-3"] <= 0.01
    ]
    if not within:
        return f"| {goal} | not measured | |"
    parts = [
        f"{r['material']} tol {r['tol']:g}: {1000 * r['relight_s']:.0f} ms, {100 * r['p99_vs_tree_1e-3']:.2f} %, "
        f"prepared in {r['prepare_s']:.0f} s, {r['operator_gb']:.1f} GB"
        for r in within
    ]
    ok = all(r["relight_s"] <= 0.033 and r["prepare_s"] <= 5 and r["operator_gb"] <= 1 for r in within)
    return f"| {goal} | {'; '.join(parts)} | {'met' if ok else 'missed'} |"


def default_method_goal(results) -> str:
    """The far-field issue's first goal's row: on the default bunny (marble, tol 0.01, no bounce), a new light at
    least 30 times faster than ``exact`` in the same run at <= 1 % (p99 against it), with the default method
    (``default_method.json``: ``auto``, which relights from the light it prepared at)."""
    goal = "default bunny, default method: a new light ≥ 30× faster than `exact` at ≤ 1 % (p99)"
    path = results / "default_method.json"
    if not path.exists():
        return f"| {goal} | not measured | |"
    data = json.loads(path.read_text())
    runs, at = data["runs"], data["auto_prepared_at_light"]
    exact = sum(data["exact_seconds"]) / len(data["exact_seconds"])
    last = sum(runs["auto"]["seconds"][-2:]) / 2
    tree = sorted(runs["tree"]["seconds"])[len(runs["tree"]["seconds"]) // 2]
    error = max(data["p99_against_exact"]["auto"])
    relit = f"from light {at} on relit: {1000 * last:.0f} ms against `exact`'s {exact:.1f} s ({exact / last:.0f}×)"
    measured = f"{relit}, {100 * error:.2f} %; the lights before by `tree`: {tree:.2f} s ({exact / tree:.1f}×)"
    ok = at is not None and exact / last >= 30 and error <= 0.01
    return f"| {goal} | {measured} | {'met from light ' + str(at) if ok else 'missed'} |"


def goals_markdown(results):
    """The issue's goals against the latest results in ``results`` (a table; missing results are said so)."""
    from scaling import GOAL_ERROR, GOALS

    lines = ["| goal | measured | verdict |", "|---|---|---|"]
    solver = results / "solver.json"
    rows = json.loads(solver.read_text())["rows"] if solver.exists() else []
    for scan in ("bunny", "igea"):
        best = fastest_within(rows, scan, GOAL_ERROR)
        if not best:
            lines.append(f"| {scan}: ≤ {GOALS[scan]:g} s per solve at ≤ 1 % | not measured | |")
            continue
        parts = [
            f"{m} {r['seconds']:.1f} s ({r['method']} {r['tol']:g}, {r.get('resolution', 'full')}, "
            f"{100 * r['error_rms']:.2f} %)"
            for m, r in best.items()
        ]
        ok = all(r["seconds"] <= GOALS[scan] for r in best.values())
        lines.append(
            f"| {scan}: ≤ {GOALS[scan]:g} s per solve at ≤ 1 % | fastest setting within 1 %: {'; '.join(parts)} "
            f"| {'met' if ok else 'missed'} |"
        )
    scaling = results / "scaling.json"
    bakes = [r for r in json.loads(scaling.read_text())["rows"] if r["label"] == "1M"] if scaling.exists() else []
    if bakes and "bake_seconds" in bakes[0] and "error_rms" in bakes[0]:
        r = bakes[0]
        ok = r["bake_seconds"] <= GOALS["bake_1M"] and r["error_rms"] <= GOAL_ERROR
        lines.append(
            f"| 1M-vertex bake ≤ {GOALS['bake_1M']:g} s at ≤ 1 % | {r['bake_seconds']:.0f} s, "
            f"{100 * r['error_rms']:.2f} %, peak RSS {r['ru_maxrss_mb'] / 1024:.1f} GB | {'met' if ok else 'missed'} |"
        )
    else:
        status = bakes[0]["status"] if bakes else "not measured"
        lines.append(f"| 1M-vertex bake ≤ {GOALS['bake_1M']:g} s at ≤ 1 % | {status} | {'missed' if bakes else ''} |")
    lines.append(default_method_goal(results))
    lines.append(relight_goal(results))
    lines.append("")
    lines.append(
        "Times are wall times on the machine of the run; the load average in each table shows how much "
        "other work shared it."
    )
    return "\n".join(lines)


def main(argv=None):
    """Command line: run the suite, write ``suite.json`` and ``goals.md``, update the README's tables."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quick", action="store_true", help="a smoke run: small sizes, into results/tmp, README untouched"
    )
    parser.add_argument("--validate", action="store_true", help="also run validate_models.py and relight.py (slow)")
    parser.add_argument("--only", nargs="+", choices=[name for name, *_ in SUITE], help="run only these scripts")
    parser.add_argument("--repeats", type=int, help="timed warm runs per setting for solver.py and scaling.py")
    parser.add_argument("--no-readme", action="store_true", help="leave bench/README.md as it is")
    parser.add_argument(
        "--tables-only",
        action="store_true",
        help="run nothing: rewrite goals.md and the README's tables from the results there are",
    )
    args = parser.parse_args(argv)
    out = output_dir(args.quick)
    info = machine_info()
    ran = {}
    for name, script, quick_arguments, takes_repeats, optional in SUITE:
        if args.tables_only or (args.only and name not in args.only):
            continue
        if optional and not args.validate and not (args.only and name in args.only):
            print(f"== {script}: skipped (slow; run it with --validate or --only {name})")
            continue
        if not (BENCH / script).exists():
            print(f"== {script}: skipped (bench/{script} does not exist in this checkout)")
            ran[name] = {"skipped": "script not present"}
            continue
        ran[name] = run_script(script, quick_arguments if args.quick else None, args.repeats if takes_repeats else None)
        if ran[name]["returncode"]:
            print(f"== {script} failed with exit code {ran[name]['returncode']}")
    info["load_average_end"] = load_average()
    if not args.tables_only:
        (out / "suite.json").write_text(json.dumps({"info": info, "scripts": ran}, indent=1))
    (out / "goals.md").write_text(goals_markdown(out) + "\n")
    print((out / "goals.md").read_text())
    if args.quick or args.no_readme:
        print(f"results in {out.relative_to(ROOT)}; bench/README.md left as it is")
    else:
        tables = {f"{path.stem}-table": path.read_text() for path in sorted(RESULTS.glob("*.md"))}
        done = update_readme(tables)
        print(f"bench/README.md: updated {', '.join(done) or 'nothing'}")
    return 1 if any(r.get("returncode") for r in ran.values()) else 0


if __name__ == "__main__":
    sys.exit(main())
