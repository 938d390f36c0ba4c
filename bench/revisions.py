"""The warm solve of the same scans at several git revisions, side by side in one run.

A table of timings is only comparable with another measured on the same machine at the same load;
this script makes that comparison directly. Each revision is extracted (``git archive``) into a
temporary folder and imported from there by a small driver in its own process, with this
interpreter and its packages. The driver loads a scan, cleans it, keeps one ``Scene`` and times
``--solves`` warm ``Scene.shade`` calls (marble, the default light and settings, method ``tree``) after one untimed
solve (numba's compilation, the geometry caches). The revisions take turns, ``--rounds`` times, so
that a change of the machine's load falls on all of them alike. Every row records the load average;
the table gives the median and the range of each revision's warm solves, its ratio to the first
revision's median, and the largest difference of its ``B`` from the first revision's, relative to
the largest ``B``.

    .venv/bin/python bench/revisions.py 9601509 HEAD                  # bunny, 3 rounds of 4 solves
    .venv/bin/python bench/revisions.py 9601509 b8df834 HEAD --scans bunny igea
    .venv/bin/python bench/revisions.py 766c866 HEAD --relight 0.01 --rounds 2 --solves 12

With ``--relight TOL`` each driver prepares relighting's operators (``method="relight"`` at ``TOL``,
``bounces=0``) with the default light, then times ``--solves`` new lights, each its own direction (the same
directions in every revision) with its own shadow rays; the table gives the new lights and the preparation.

Results: ``results/revisions.json`` and ``results/revisions.md``, with ``--relight`` ``results/revisions_relight.*``
(``--quick``: into ``results/tmp``).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from report import ROOT, load_average, machine_info, output_dir, write_results  # noqa: E402

MESHES = ROOT.parent / "shared" / "meshes"
#: Scan name -> (file in the shared scans, its unit).
SCANS = {
    "bunny": ("stanford_bunny_zipper.ply", "m"),
    "horse": ("cyberware_horse.ply", "m"),
    "igea": ("cyberware_igea.ply", "m"),
}

# Runs in the extracted revision: times warm solves and saves the last B. argv: mesh, unit, solves, out.
DRIVER = r"""
import json, sys, time, warnings
import numpy as np
warnings.simplefilter("ignore")
import translucency as tl
try:  # the shading room's Scene; before it, the pipeline's
    from translucency.app.shading import Scene
except ImportError:
    from translucency.app.pipeline import Scene
path, unit, solves, out, relight = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4], sys.argv[5]
mesh, _ = tl.clean_mesh(tl.load_mesh(path, unit=unit))
scene = Scene(mesh)
if relight:  # prepare the operators once, then time new lights
    options = {"method": "relight", "tol": float(relight), "bounces": 0, "time_limit": None}
    start = time.perf_counter()
    result = scene.shade("marble", **options)
    prepare = time.perf_counter() - start
    rng = np.random.default_rng(5)
    times = []
    for _ in range(solves):
        d = rng.normal(size=3)
        d[1] = abs(d[1]) + 0.3  # from above, where the scans face
        light = tl.DirectionalLight(tuple(d / np.linalg.norm(d)), 1.0)
        start = time.perf_counter()
        result = scene.shade("marble", light, **options)
        times.append(time.perf_counter() - start)
    np.save(out + ".npy", result.B)
    with open(out + ".json", "w") as f:
        json.dump({"seconds": times, "prepare": prepare, "vertices": int(mesh.n_points)}, f)
    sys.exit(0)
# one solve per call in every revision: revisions with bounces run without them
import inspect
parameters = inspect.signature(Scene.shade).parameters
keywords = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters.values())  # settings by keyword
single = {"bounces": 0} if "bounces" in parameters or keywords else {}
if "method" in parameters or keywords:  # tree, the default before auto, which would relight once lights had paid
    single["method"] = "tree"
result = scene.shade("marble", **single)
times, stages = [], []
for _ in range(solves):
    start = time.perf_counter()
    result = scene.shade("marble", **single)
    times.append(time.perf_counter() - start)
    stages.append({k: v for k, v in result.timings.items() if k.startswith("solve_")})
np.save(out + ".npy", result.B)
with open(out + ".json", "w") as f:
    json.dump({"seconds": times, "stages": stages, "vertices": int(mesh.n_points)}, f)
"""


def extract(revision: str, into: Path) -> str:
    """Extract ``revision`` of this repository into ``into``; returns its short commit hash."""
    commit = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--short", revision], check=True, capture_output=True, text=True
    ).stdout.strip()
    into.mkdir(parents=True)
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", commit], check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive, check=True)
    return commit


def run_driver(tree: Path, mesh: Path, unit: str, solves: int, out: Path, relight: float | None = None) -> dict:
    """One driver process in an extracted revision: its timings, with the load average before it ran (``relight``:
    the tolerance of the relighting operators it prepares, then new lights)."""
    load = load_average()
    env = {**os.environ, "PYTHONPATH": str(tree)}
    mode = "" if relight is None else repr(float(relight))
    subprocess.run(
        [sys.executable, "-c", DRIVER, str(mesh), unit, str(solves), str(out), mode], cwd=tree, env=env, check=True
    )
    record = json.loads(Path(str(out) + ".json").read_text())
    record["load_before"] = load
    return record


def table(rows: list[dict]) -> str:
    """The Markdown table of the comparison (with the preparations where the rows relight)."""
    relit = any("prepare" in row for row in rows)
    what = "new light" if relit else "warm solve"
    lines = [
        f"| scan | vertices | revision | {what}, median (s) | range (s) | solves | ratio to first | "
        + ("preparation (s) | " if relit else "")
        + "max abs B difference / max B | load (1 min) |",
        "|---|---:|---|---:|---|---:|---:|" + ("---|" if relit else "") + "---:|---|",
    ]
    for row in rows:
        prepare = f"{min(row['prepare']):.1f}–{max(row['prepare']):.1f} | " if relit else ""
        lines.append(
            f"| {row['scan']} | {row['vertices']:,} | {row['revision']} | {row['median']:.3f} | "
            f"{min(row['seconds']):.3f}–{max(row['seconds']):.3f} | {len(row['seconds'])} | {row['ratio']:.2f} | "
            f"{prepare}{row['b_difference']:.1e} | {min(row['loads']):.1f}–{max(row['loads']):.1f} |"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("revisions", nargs="+", help="git revisions to compare (the first is the reference)")
    parser.add_argument("--scans", nargs="+", default=["bunny"], choices=sorted(SCANS))
    parser.add_argument("--rounds", type=int, default=3, help="turns each revision takes (default 3)")
    parser.add_argument("--solves", type=int, default=4, help="timed warm solves per turn (default 4)")
    parser.add_argument("--quick", action="store_true", help="one round of two solves, into results/tmp")
    parser.add_argument(
        "--relight", type=float, metavar="TOL", help="time new lights on relighting operators prepared at TOL"
    )
    args = parser.parse_args(argv)
    rounds, solves = (1, 2) if args.quick else (args.rounds, args.solves)
    info = machine_info()
    rows = []
    with tempfile.TemporaryDirectory(prefix="translucency-revisions-") as folder:
        folder = Path(folder)
        trees = {}
        for k, revision in enumerate(args.revisions):
            commit = extract(revision, folder / f"rev{k}")
            trees[f"{revision} ({commit})" if commit != revision else commit] = folder / f"rev{k}"
        for scan in args.scans:
            name, unit = SCANS[scan]
            mesh = MESHES / name
            if not mesh.is_file():
                print(f"{scan}: {mesh.name} is not in the shared scans; skipped")
                continue
            runs = {label: [] for label in trees}
            for turn in range(rounds):
                for label, tree in trees.items():
                    record = run_driver(tree, mesh, unit, solves, folder / f"{scan}-{tree.name}", args.relight)
                    runs[label].append(record)
                    print(
                        f"{scan} round {turn + 1} {label}: "
                        + " ".join(f"{s:.2f}" for s in record["seconds"])
                        + f" s (load {record['load_before'][0]:.1f})",
                        flush=True,
                    )
            first_label = next(iter(trees))
            first_B = np.load(folder / f"{scan}-{trees[first_label].name}.npy")
            first_median = statistics.median(s for r in runs[first_label] for s in r["seconds"])
            for label, tree in trees.items():
                seconds = [s for r in runs[label] for s in r["seconds"]]
                B = np.load(folder / f"{scan}-{tree.name}.npy")
                difference = (
                    float(np.abs(B - first_B).max() / np.abs(first_B).max()) if B.shape == first_B.shape else np.nan
                )
                rows.append(
                    {
                        "scan": scan,
                        "vertices": runs[label][0]["vertices"],
                        "revision": label,
                        "seconds": seconds,
                        "median": statistics.median(seconds),
                        "ratio": statistics.median(seconds) / first_median,
                        "b_difference": difference,
                        "loads": [r["load_before"][0] for r in runs[label]],
                        **(
                            {"prepare": [r["prepare"] for r in runs[label]], "tol": args.relight}
                            if args.relight is not None
                            else {"stages": [r["stages"] for r in runs[label]]}
                        ),
                    }
                )
    text = table(rows)
    print(text)
    name = "revisions" if args.relight is None else "revisions_relight"
    write_results(output_dir(args.quick), name, {"info": info, "rows": rows}, text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
