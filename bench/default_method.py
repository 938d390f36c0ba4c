"""The default method over a run of lights: ``auto`` against ``tree`` and ``relight``; a new light against ``exact``.

On the embedded default bunny in marble at tol 0.01 with ``bounces=0`` (the far-field issue's conditions), a fresh
``Scene`` per method shades the same lights one after another (random directions, seeded), each the wall time of
:meth:`Scene.shade <translucency.app.shading.scene.Scene.shade>` (incident light with Embree shadows, solve, colours).
``auto`` (docs/physics.md §8.10) solves the first lights by ``tree`` and prepares relighting's operators once those
lights have taken as long as preparing would; the table gives each method's time to the end of each light count and
which light ``auto`` prepared at. In the same run, two lights by ``exact``: a relit light's speed-up over it and the
per-vertex error of both methods against it (docs/physics.md §8.5: the 99th percentile of ``|B - B_ref| / B_ref``
over the (vertex, channel) pairs with ``B_ref`` at least 1e-4 of the channel's largest).

Writes ``default_method.json``, ``default_method.md`` and ``default_method.png`` (the cumulative time of the three
methods against the number of lights) into ``bench/results`` (``bench/results/tmp`` with ``--quick``).

    .venv/bin/python bench/default_method.py             # 100 lights (about 4 min on 2 cores)
    .venv/bin/python bench/default_method.py --quick     # 6 lights
"""

from __future__ import annotations

import argparse
import gc
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
from translucency.scatter.lights import DirectionalLight  # noqa: E402
from translucency.scatter.solve import TOL_FLOOR  # noqa: E402

METHODS = ("tree", "relight", "auto")
TOL = 0.01
SEED = 20261207
#: Light counts the table reports the time to.
COUNTS = (1, 3, 10, 20, 30, 40, 60, 100)


def _directions(n: int) -> list:
    """``n`` light directions drawn at random over the sphere (some light the bunny from behind)."""
    rng = np.random.default_rng(SEED)
    found = rng.normal(size=(n, 3))
    return [tuple(d / np.linalg.norm(d)) for d in found]


def _error(B, reference) -> float:
    """The 99th percentile of the per-vertex relative error, over the pairs above ``TOL_FLOOR`` of the largest."""
    keep = reference >= TOL_FLOOR * reference.max(axis=0)
    return float(np.percentile(np.abs(B - reference)[keep] / reference[keep], 99))


def _sweep(mesh, method: str, directions: list) -> dict:
    """Every light on a fresh ``Scene`` by ``method``: seconds per light, the method used, the last ``B``'s."""
    scene = Scene(mesh)
    seconds, used, kept = [], [], {}
    for k, direction in enumerate(directions):
        start = time.perf_counter()
        result = scene.shade("marble", DirectionalLight(direction, 1.0), method=method, tol=TOL, bounces=0)
        seconds.append(time.perf_counter() - start)
        used.append(result.metadata["method_used"])
        if k >= len(directions) - 2:
            kept[k] = result.B
        print(f"{method:8s} light {k + 1:3d}: {seconds[-1]:7.3f} s by {used[-1]}", flush=True)
    del scene
    gc.collect()
    return {"seconds": seconds, "used": used, "last_B": kept, "load": load_average()}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lights", type=int, default=100, help="lights per method (default 100)")
    parser.add_argument("--quick", action="store_true", help="6 lights, into bench/results/tmp")
    args = parser.parse_args(argv)
    n = 6 if args.quick else args.lights
    out = output_dir(args.quick)
    info = {**machine_info(), "load_average_start": load_average()}
    mesh = load_default_scan()
    directions = _directions(n)
    runs = {method: _sweep(mesh, method, directions) for method in METHODS}

    scene = Scene(mesh)
    exact = {}
    for k in range(n - 2, n):
        start = time.perf_counter()
        result = scene.shade("marble", DirectionalLight(directions[k], 1.0), method="exact", bounces=0)
        exact[k] = {"seconds": time.perf_counter() - start, "B": result.B}
        print(f"exact    light {k + 1:3d}: {exact[k]['seconds']:7.3f} s", flush=True)
    errors = {method: [_error(runs[method]["last_B"][k], exact[k]["B"]) for k in sorted(exact)] for method in METHODS}
    prepared_at = next((k + 1 for k, m in enumerate(runs["auto"]["used"]) if m == "relight"), None)
    payload = {
        "info": info,
        "scan": "bunny (default)",
        "vertices": int(mesh.n_points),
        "material": "marble",
        "tol": TOL,
        "lights": n,
        "runs": {m: {k: v for k, v in r.items() if k != "last_B"} for m, r in runs.items()},
        "exact_seconds": [exact[k]["seconds"] for k in sorted(exact)],
        "p99_against_exact": errors,
        "auto_prepared_at_light": prepared_at,
    }
    table = _table(runs, exact, errors, prepared_at, n)
    write_results(out, "default_method", payload, table)
    _figure(out / "default_method.png", runs, prepared_at, mesh.n_points)
    print(table)


def _table(runs, exact, errors, prepared_at, n) -> str:
    counts = [c for c in COUNTS if c <= n]
    lines = [
        "| method | "
        + " | ".join(f"{c} lights (s)" for c in counts)
        + " | last two lights (s) | p99 vs exact (last two) |",
        "|---|" + "---:|" * len(counts) + "---:|---|",
    ]
    for method in METHODS:
        total = np.cumsum(runs[method]["seconds"])
        last = ", ".join(f"{s:.3f}" for s in runs[method]["seconds"][-2:])
        error = ", ".join(f"{100 * e:.2f} %" for e in errors[method])
        lines.append(f"| {method} | " + " | ".join(f"{total[c - 1]:.1f}" for c in counts) + f" | {last} | {error} |")
    exact_s = ", ".join(f"{exact[k]['seconds']:.2f}" for k in sorted(exact))
    lines.append("| exact | " + " | ".join("" for _ in counts) + f" | {exact_s} | |")
    lines.append("")
    lines.append(f"`auto` prepared the operators at light {prepared_at}." if prepared_at else "`auto` did not prepare.")
    return "\n".join(lines)


def _figure(path: Path, runs, prepared_at, vertices: int) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.0, 4.2), dpi=120)
    colours = {"tree": "tab:blue", "relight": "tab:orange", "auto": "tab:green"}
    for method in METHODS:
        total = np.cumsum(runs[method]["seconds"])
        ax.plot(np.arange(1, total.size + 1), total, label=method, color=colours[method], lw=2)
    if prepared_at:
        ax.axvline(prepared_at, color="tab:green", ls=":", lw=1)
        ax.annotate(
            f" auto prepares the operators\n (light {prepared_at})", (prepared_at, ax.get_ylim()[1] * 0.05), fontsize=8
        )
    ax.set_xlabel("lights shaded on one Scene")
    ax.set_ylabel("time to the end of that light (s)")
    ax.set_title(f"Default bunny ({vertices:,} vertices), marble, tol {TOL:g}, no bounce", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


if __name__ == "__main__":
    main()
