"""Run time against error of the per-vertex solver on real scans.

For each scan (shared Stanford bunny, Cyberware horse and Igea, cleaned, in mm), material (marble,
skim milk, ketchup: three very different diffusion lengths) and method/tolerance, one directional
light with Embree shadows: the median wall time of warm solves and the error against ``exact``:

* relative RMS ``||B - B_exact|| / ||B_exact||`` over all channels and the evaluated vertices,
* the worst relative error over "lit-enough" vertices (``B`` above 1 % of its 99th percentile).

``exact`` on every vertex of a large scan costs ``n^2`` pair evaluations; the error is therefore
measured at a fixed random subset of receivers (all vertices of the bunny, 4000 elsewhere), where
``exact`` is computed in full. Also measured: the throughput of the ``exact`` kernel in pairs per
second and, to give it meaning, the throughput of a minimal reference loop (one ``exp`` and one
``sqrt`` per pair, vectorised the same way) on the same machine.

Writes ``bench/results/solver.json`` and ``bench/results/solver_pareto.png`` and prints a Markdown
table (pasted into ``bench/README.md``).

    .venv/bin/python bench/solver.py            # everything (about 30 min on 2 cores; --repeats 1: 15 min)
    .venv/bin/python bench/solver.py --quick    # bunny only, fewer settings
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from translucency import __version__  # noqa: E402  (first: it selects numba's threading layer)

import numba  # noqa: E402
import numpy as np  # noqa: E402
from translucency.io.clean import clean_mesh  # noqa: E402
from translucency.io.load import load_mesh  # noqa: E402
from translucency.scatter import kernels  # noqa: E402
from translucency.scatter.irradiance import incident_flux  # noqa: E402
from translucency.scatter.lights import DirectionalLight  # noqa: E402
from translucency.scatter.materials import material  # noqa: E402
from translucency.scatter.solve import SurfaceGeometry, solve  # noqa: E402

MESHES = ROOT.parent / "shared" / "meshes"
RESULTS = ROOT / "bench" / "results"
SCANS = {  # file, unit
    "bunny": ("stanford_bunny_zipper.ply", "m"),
    "horse": ("cyberware_horse.ply", "m"),
    "igea": ("cyberware_igea.ply", "m"),
}
MATERIALS = ("marble", "skim_milk", "ketchup")
SETTINGS = [("tree", 0.1), ("tree", 0.03), ("tree", 0.01), ("tree", 0.003), ("cutoff", 0.01)]
LIGHT = DirectionalLight((0.35, 0.45, 1.0), 1.0)


@numba.njit(parallel=True, fastmath=True, cache=True)
def _reference_loop(xs, ys, zs, rx, ry, rz):
    """Peak reference: sum of exp(-|x_o - x_i|) over all pairs (one sqrt and one exp per pair)."""
    out = np.zeros(rx.shape[0])
    for o in numba.prange(rx.shape[0]):
        acc = 0.0
        for j in range(xs.shape[0]):
            dx = rx[o] - xs[j]
            dy = ry[o] - ys[j]
            dz = rz[o] - zs[j]
            acc += kernels.exp_nonpositive(-math.sqrt(dx * dx + dy * dy + dz * dz))
        out[o] = acc
    return out


def prepare(name):
    file, unit = SCANS[name]
    mesh, _ = clean_mesh(load_mesh(MESHES / file, unit=unit))
    normals = mesh.vertex_normals()
    geometry = SurfaceGeometry(mesh.points, mesh.triangles, normals)
    return mesh, geometry


def timed(fn, repeats, warm=True):
    if warm:
        fn()  # compilation, caches of the geometry
    times = []
    result = None
    for _ in range(repeats):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return result, statistics.median(times)


def errors(B, exact):
    rms = float(np.linalg.norm(B - exact) / np.linalg.norm(exact))
    level = np.percentile(exact, 99)
    lit = exact > 0.01 * level
    worst = float(np.max(np.abs(B[lit] - exact[lit]) / exact[lit])) if lit.any() else 0.0
    return rms, worst


def throughput(geometry, incident, medium):
    """Pairs per second of the exact kernel and of the reference loop, on the lit sources."""
    lit = np.flatnonzero(incident.phi_rgb.max(axis=1) > 0)
    receivers = np.arange(min(6000, geometry.n_vertices))
    rows = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta)
    flux = incident.phi_rgb * geometry.vertex_areas[:, None]
    cols = [np.ascontiguousarray(a[lit, i]) for a in (geometry.points, geometry.normals, incident.w12) for i in range(3)]
    run = lambda: kernels.directional_vertex_sum(*cols, np.ascontiguousarray(flux[lit].T), geometry.points[receivers],  # noqa: E731
                                                  geometry.normals[receivers], rows, np.arange(3))
    _, seconds = timed(run, 3)
    pairs = lit.size * receivers.size
    ref = lambda: _reference_loop(cols[0], cols[1], cols[2], *[np.ascontiguousarray(geometry.points[receivers, i]) for i in range(3)])  # noqa: E731
    _, ref_seconds = timed(ref, 3)
    return {"pairs": pairs, "seconds": seconds, "pairs_per_second": pairs / seconds,
            "reference_loop_pairs_per_second": pairs / ref_seconds,
            "fraction_of_reference": (pairs / seconds) / (pairs / ref_seconds)}


def run(scans, materials, settings, repeats):
    rows = []
    kernel_speed = None
    for scan in scans:
        if not (MESHES / SCANS[scan][0]).exists():
            print(f"skipping {scan}: {SCANS[scan][0]} not in ../shared/meshes")
            continue
        mesh, geometry = prepare(scan)
        n = geometry.n_vertices
        rng = np.random.default_rng(0)
        receivers = np.arange(n) if n <= 40000 else np.sort(rng.choice(n, 4000, replace=False))
        for name in materials:
            medium = material(name).medium()
            incident = incident_flux(mesh.points, geometry.normals, geometry.vertex_areas, LIGHT, medium.eta,
                                     triangles=mesh.triangles)
            if kernel_speed is None:
                kernel_speed = throughput(geometry, incident, medium)
                print(f"exact kernel: {kernel_speed['pairs_per_second'] / 1e6:.1f} M pairs/s "
                      f"({kernel_speed['fraction_of_reference']:.2f} of the reference loop's "
                      f"{kernel_speed['reference_loop_pairs_per_second'] / 1e6:.1f} M/s)")
            start = time.perf_counter()
            exact = solve(geometry, incident.phi_rgb, incident.w12, medium, method="exact", receivers=receivers)
            exact_seconds = time.perf_counter() - start
            rows.append(dict(scan=scan, vertices=n, material=name, method="exact", tol=None, seconds=exact_seconds,
                             error_rms=0.0, error_worst=0.0, receivers=int(receivers.size),
                             pairs_evaluated=exact.stats["pairs_evaluated"], pairs_skipped=0,
                             sources_skipped=exact.stats["sources_skipped_no_flux"], timings=exact.timings))
            print(f"{scan:6s} {n:7d} {name:10s} exact            {exact_seconds:7.2f} s (receivers {receivers.size})")
            for method in sorted({m for m, _ in settings}):
                solve(geometry, incident.phi_rgb, incident.w12, medium, method=method, tol=0.5)  # compile, fill caches
            for method, tol in settings:
                # time the solve at every vertex (warm); measure the error at the exact's receivers
                full, seconds = timed(lambda: solve(geometry, incident.phi_rgb, incident.w12, medium, method=method,
                                                    tol=tol), repeats, warm=False)
                rms, worst = errors(full.B[receivers], exact.B)
                rows.append(dict(scan=scan, vertices=n, material=name, method=method, tol=tol, seconds=seconds,
                                 error_rms=rms, error_worst=worst, receivers=int(receivers.size),
                                 pairs_evaluated=full.stats["pairs_evaluated"], pairs_skipped=full.stats["pairs_skipped"],
                                 sources_skipped=full.stats["sources_skipped_no_flux"], timings=full.timings))
                print(f"{scan:6s} {n:7d} {name:10s} {method:6s} tol {tol:<6g} {seconds:7.2f} s  "
                      f"rms {rms:.2e}  worst {worst:.2e}  far {full.timings['far_field']:.2f} s  "
                      f"near {full.timings['near_field']:.2f} s")
    return rows, kernel_speed


def plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scans = sorted({r["scan"] for r in rows})
    fig, axes = plt.subplots(1, len(scans), figsize=(5 * len(scans), 4.2), squeeze=False)
    colours = {"marble": "tab:grey", "skim_milk": "tab:blue", "ketchup": "tab:red"}
    markers = {"tree": "o", "cutoff": "s"}
    for ax, scan in zip(axes[0], scans):
        for name in colours:
            for method in markers:
                sel = [r for r in rows if r["scan"] == scan and r["material"] == name and r["method"] == method]
                if sel:
                    ax.plot([max(r["error_rms"], 1e-7) for r in sel], [r["seconds"] for r in sel], marker=markers[method],
                            color=colours[name], label=f"{name} {method}")
            ex = [r for r in rows if r["scan"] == scan and r["material"] == name and r["method"] == "exact"]
            if ex and ex[0]["receivers"] == ex[0]["vertices"]:
                ax.axhline(ex[0]["seconds"], color=colours[name], lw=0.8, ls=":")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.axvline(0.01, color="k", lw=0.6, ls="--")
        ax.set_xlabel("relative RMS error against exact")
        ax.set_ylabel("wall time per solve (s)")
        ax.set_title(f"{scan} ({sel[0]['vertices'] if sel else ''} vertices)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=7)
    fig.suptitle("translucency solver: time against error (one directional light, Embree shadows; dotted: exact)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def markdown(rows, kernel_speed):
    lines = ["| scan | vertices | material | method | tol | time (s) | rel. RMS error | worst lit-vertex error | pairs evaluated | pairs skipped | sources skipped (no flux) |",
             "|---|---:|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        tol = "" if r["tol"] is None else f"{r['tol']:g}"
        note = "" if r["method"] != "exact" or r["receivers"] == r["vertices"] else f" ({r['receivers']} receivers)"
        lines.append(f"| {r['scan']} | {r['vertices']} | {r['material']} | {r['method']}{note} | {tol} | {r['seconds']:.2f} | "
                     f"{r['error_rms']:.1e} | {r['error_worst']:.1e} | {r['pairs_evaluated']:,} | {r['pairs_skipped']:,} | {r['sources_skipped']:,} |")
    if kernel_speed:
        lines.append("")
        lines.append(f"`exact` kernel throughput: {kernel_speed['pairs_per_second'] / 1e6:.1f} M pairs/s (all three channels); "
                     f"reference loop (one sqrt + one exp per pair): {kernel_speed['reference_loop_pairs_per_second'] / 1e6:.1f} M pairs/s; "
                     f"ratio {kernel_speed['fraction_of_reference']:.2f}.")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="bunny only, fewer settings, one repeat")
    parser.add_argument("--repeats", type=int, default=3, help="timed warm solves per setting (median reported)")
    args = parser.parse_args(argv)
    if not MESHES.is_dir():
        print("the shared scans (../shared/meshes) are not present; nothing to benchmark")
        return 0
    scans = ["bunny"] if args.quick else list(SCANS)
    settings = SETTINGS[::2] if args.quick else SETTINGS
    start = time.perf_counter()
    rows, kernel_speed = run(scans, MATERIALS, settings, 1 if args.quick else args.repeats)
    out = RESULTS / "tmp" if args.quick else RESULTS
    out.mkdir(parents=True, exist_ok=True)
    info = {"version": __version__, "python": platform.python_version(), "machine": platform.machine(),
            "threads": numba.get_num_threads(), "light": LIGHT.to_dict(), "seconds_total": time.perf_counter() - start}
    (out / "solver.json").write_text(json.dumps({"info": info, "kernel": kernel_speed, "rows": rows}, indent=1))
    plot(rows, out / "solver_pareto.png")
    table = markdown(rows, kernel_speed)
    (out / "solver.md").write_text(table + "\n")
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
