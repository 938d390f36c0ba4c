"""Run time against error of the per-vertex solver on real scans.

For each scan (shared Stanford bunny, Cyberware horse and Igea, cleaned, in mm), material (marble,
skim milk, ketchup: three very different diffusion lengths) and setting, one directional light with
Embree shadows: the median wall time of warm solves and the error against ``exact`` on the full mesh:

* relative RMS ``||B - B_exact|| / ||B_exact||`` over all channels and the evaluated vertices,
* the per-vertex figure that ``tol`` bounds (docs/physics.md §8.5): the 99th percentile of
  ``|B - B_exact| / B_exact`` over the (vertex, channel) pairs whose ``B_exact`` is at least 1e-4 of the
  channel's largest,
* the worst relative error over "lit-enough" vertices (``B`` above 1 % of its 99th percentile).

The settings are the far-field methods at several tolerances on every vertex (``tree``,
``cutoff``), and the pipeline's proxy resolution (:meth:`translucency.app.shading.scene.Scene.shade` with
the light's detail, :func:`~translucency.app.shading.resolution.proxy_edge_length`, which ``resolution="auto"`` takes
only
at a loose tolerance, and explicit proxy edge lengths, ``tree`` at 1 %): ``B`` is solved on a
decimated mesh and interpolated back to every vertex, and its error is measured on the full mesh.

``exact`` on every vertex of a large scan costs ``n^2`` pair evaluations; the error is therefore
measured at a fixed random subset of receivers (all vertices of the bunny, 4000 elsewhere), where
``exact`` is computed in full. Also measured: the throughput of the ``exact`` kernel in pairs per
second and, to give it meaning, the throughput of a minimal reference loop (one ``exp`` and one
``sqrt`` per pair, vectorised the same way) and the FLOP rate of a loop of fused multiply-adds, the
machine's peak as numba's code reaches it.

Writes ``solver.json``, ``solver.md``, ``kernel.md`` and ``solver_pareto.png`` into
``bench/results`` (``bench/results/tmp`` with ``--quick``); ``bench/run_all.py`` puts the tables
into ``bench/README.md``.

    .venv/bin/python bench/solver.py            # everything (about 30 min on 2 cores; --repeats 2: 20 min)
    .venv/bin/python bench/solver.py --quick    # bunny in marble only, fewer settings, one repeat
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numba  # noqa: E402
import numpy as np  # noqa: E402
from report import load_average, machine_info, output_dir, write_results  # noqa: E402

from translucency import __version__  # noqa: E402,F401  (first: it selects numba's threading layer)
from translucency.app.shading.resolution import fine_enough_for, proxy_edge_length  # noqa: E402
from translucency.app.shading.scene import Scene  # noqa: E402
from translucency.geometry.measure import mean_edge_length  # noqa: E402
from translucency.io.clean import clean_mesh  # noqa: E402
from translucency.io.load import load_mesh  # noqa: E402
from translucency.scatter import kernels  # noqa: E402
from translucency.scatter.irradiance import incident_flux  # noqa: E402
from translucency.scatter.lights import DirectionalLight  # noqa: E402
from translucency.scatter.materials import material  # noqa: E402
from translucency.scatter.solve import TOL_FLOOR, SurfaceGeometry, solve  # noqa: E402

MESHES = ROOT.parent / "shared" / "meshes"
RESULTS = ROOT / "bench" / "results"
SCANS = {  # file, unit
    "bunny": ("stanford_bunny_zipper.ply", "m"),
    "horse": ("cyberware_horse.ply", "m"),
    "igea": ("cyberware_igea.ply", "m"),
}
MATERIALS = ("marble", "skim_milk", "ketchup")
SETTINGS = [
    ("tree", 0.1),
    ("tree", 0.03),
    ("tree", 0.01),
    ("tree", 0.003),
    ("cutoff", 0.01),
    ("relight", 0.1),
    ("relight", 0.01),
]
#: Proxy resolutions of the pipeline (``Scene.shade(resolution=...)``): "detail" (the medium's
#: :func:`~translucency.app.shading.resolution.proxy_edge_length`, the proxy "auto" takes at a tolerance of 0.53 and
#: above in
#: marble) and edge lengths in mm.
PROXY_RESOLUTIONS = ("detail", 2.0, 3.0)
PROXY_METHOD, PROXY_TOL = "tree", 0.01
LIGHT = DirectionalLight((0.35, 0.45, 1.0), 1.0)
LIGHTS_LABEL = "1 directional, shadows"
#: Floating-point operations per pair of the reference loop (an FMA counts two, sqrt one): 3
#: differences, 5 for the squared distance, sqrt, negation, clamp and scaling in ``exp_nonpositive``,
#: its degree-10 Horner polynomial (10 FMA) and 12 squarings, and the accumulation.
REFERENCE_FLOP_PER_PAIR = 44
#: FMA loop: a degree-32 Horner polynomial per element of an array that stays in the L1 cache.
FMA_DEGREE = 32


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


@numba.njit(parallel=True, fastmath=True, cache=True)
def _fma_loop(xs, rows):
    """FLOP-rate probe: per row, the sum over ``xs`` of a degree-``FMA_DEGREE`` Horner polynomial (FMAs only)."""
    out = np.zeros(rows)
    for o in numba.prange(rows):
        acc = 0.0
        c = 1.0 + o * 1e-9
        for j in range(xs.shape[0]):
            x = xs[j]
            p = c
            for _ in range(FMA_DEGREE):
                p = p * x + 0.5
            acc += p
        out[o] = acc
    return out


def present_scans(scans):
    """The scans of ``scans`` whose file is in ../shared/meshes, in order; each missing one said skipped."""
    for scan in scans:
        if (MESHES / SCANS[scan][0]).exists():
            yield scan
        else:
            print(f"skipping {scan}: {SCANS[scan][0]} not in ../shared/meshes")


def detail_resolution(scene, medium):
    """The proxy of the light's detail as a resolution: :func:`~translucency.app.shading.resolution.proxy_edge_length`,
    or
    ``"full"`` where the mesh is not fine enough for it
    (:func:`~translucency.app.shading.resolution.fine_enough_for`)."""
    edge = proxy_edge_length(medium)
    return edge if fine_enough_for(edge, mean_edge_length(scene.mesh.points, scene.mesh.triangles)) else "full"


def prepare(name):
    """The cleaned scan ``name`` (mm) and its :class:`SurfaceGeometry`."""
    file, unit = SCANS[name]
    mesh, _ = clean_mesh(load_mesh(MESHES / file, unit=unit))
    normals = mesh.vertex_normals()
    geometry = SurfaceGeometry(mesh.points, mesh.triangles, normals)
    return mesh, geometry


def timed(fn, repeats, warm=True):
    """``(last result, median wall time)`` of ``repeats`` calls of ``fn``, after one untimed call if ``warm``."""
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
    """Relative RMS error, worst relative error over lit-enough vertices and the per-vertex figure of
    ``tol`` (:func:`per_vertex_error`) of ``B`` against ``exact``."""
    rms = float(np.linalg.norm(B - exact) / np.linalg.norm(exact))
    level = np.percentile(exact, 99)
    lit = exact > 0.01 * level
    worst = float(np.max(np.abs(B[lit] - exact[lit]) / exact[lit])) if lit.any() else 0.0
    return rms, worst, per_vertex_error(B, exact)


def per_vertex_error(B, exact, floor=TOL_FLOOR, percentile=99.0):
    """What ``tol`` bounds: the ``percentile`` of ``|B - exact| / exact`` over the (vertex, channel) pairs
    whose ``exact`` is at least ``floor`` of the largest of its channel."""
    relative = []
    for c in range(exact.shape[1]):
        keep = exact[:, c] >= floor * exact[:, c].max() if exact[:, c].max() > 0 else np.zeros(exact.shape[0], bool)
        relative.append(np.abs(B[keep, c] - exact[keep, c]) / exact[keep, c])
    relative = np.concatenate(relative)
    return float(np.percentile(relative, percentile)) if relative.size else 0.0


def throughput(geometry, incident, medium):
    """Pairs per second of the exact kernel and of the reference loop (lit sources), and the FMA loop's FLOP/s."""
    lit = np.flatnonzero(incident.phi_rgb.max(axis=1) > 0)
    receivers = np.arange(min(6000, geometry.n_vertices))
    rows = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta)
    flux = incident.phi_rgb * geometry.vertex_areas[:, None]
    cols = [
        np.ascontiguousarray(a[lit, i]) for a in (geometry.points, geometry.normals, incident.w12) for i in range(3)
    ]

    def run():
        return kernels.vertex_sum(
            0,
            geometry.points[lit],
            geometry.normals[lit],
            incident.w12[lit],
            flux[lit],
            geometry.points[receivers],
            geometry.normals[receivers],
            rows,
            np.arange(3),
        )

    _, seconds = timed(run, 3)
    pairs = lit.size * receivers.size

    def ref():
        return _reference_loop(
            cols[0], cols[1], cols[2], *[np.ascontiguousarray(geometry.points[receivers, i]) for i in range(3)]
        )

    _, ref_seconds = timed(ref, 3)
    xs = np.linspace(0.05, 0.45, 4096)
    fma_rows = 20000
    _, fma_seconds = timed(lambda: _fma_loop(xs, fma_rows), 3)
    fma_flops = 2.0 * FMA_DEGREE * xs.size * fma_rows / fma_seconds
    reference_flops = REFERENCE_FLOP_PER_PAIR * pairs / ref_seconds
    return {
        "pairs": pairs,
        "seconds": seconds,
        "pairs_per_second": pairs / seconds,
        "reference_loop_pairs_per_second": pairs / ref_seconds,
        "fraction_of_reference": (pairs / seconds) / (pairs / ref_seconds),
        "reference_flop_per_pair": REFERENCE_FLOP_PER_PAIR,
        "reference_loop_flops": reference_flops,
        "fma_loop_flops": fma_flops,
        "reference_fraction_of_fma_peak": reference_flops / fma_flops,
        "load_average": load_average(),
    }


def make_row(
    scan, n, name, method, tol, resolution, seconds, repeats, rms, worst, receivers, stats, timings, p99=0.0, **extra
):
    """One result row (every benchmark row has the same keys; ``extra`` adds what a setting has beyond them)."""
    return dict(
        scan=scan,
        vertices=n,
        material=name,
        lights=LIGHTS_LABEL,
        method=method,
        tol=tol,
        resolution=resolution,
        seconds=seconds,
        repeats=repeats,
        error_rms=rms,
        error_worst=worst,
        error_p99=p99,
        receivers=int(receivers),
        pairs_evaluated=int(stats.get("pairs_evaluated", 0)),
        pairs_skipped=int(stats.get("pairs_skipped", 0)),
        sources_skipped=int(stats.get("sources_skipped_no_flux", 0)),
        vertices_solved=int(extra.pop("vertices_solved", n)),
        timings=timings,
        load_average=load_average(),
        **extra,
    )


def method_rows(scan, name, geometry, incident, medium, receivers, exact, settings, repeats):
    """Rows of the far-field methods on every vertex: median of ``repeats`` warm solves each."""
    rows = []
    n = geometry.n_vertices
    for method in sorted({m for m, _ in settings} - {"relight"}):
        solve(geometry, incident.phi_rgb, incident.w12, medium, method=method, tol=0.5)  # compile, fill caches
    for method, tol in settings:
        # time the solve at every vertex (warm); measure the error at the exact's receivers
        extra = {}
        if method == "relight":  # the first light prepares the operators: its time apart, then a light's
            start = time.perf_counter()
            first = solve(geometry, incident.phi_rgb, incident.w12, medium, method=method, tol=tol)
            extra = {
                "prepare_seconds": first.timings["prepare"],
                "first_light_seconds": time.perf_counter() - start,
                "operator_bytes": first.stats["bytes"],
            }
        full, seconds = timed(
            lambda: solve(geometry, incident.phi_rgb, incident.w12, medium, method=method, tol=tol), repeats, warm=False
        )
        rms, worst, p99 = errors(full.B[receivers], exact.B)
        rows.append(
            make_row(
                scan,
                n,
                name,
                method,
                tol,
                "full",
                seconds,
                repeats,
                rms,
                worst,
                receivers.size,
                full.stats,
                full.timings,
                p99=p99,
                **extra,
            )
        )
        stages = (
            f"prepared in {extra['prepare_seconds']:.1f} s, {extra['operator_bytes'] / 1e9:.2f} GB"
            if extra
            else f"far {full.timings['far_field']:.2f} s  near {full.timings['near_field']:.2f} s"
        )
        print(
            f"{scan:6s} {n:7d} {name:10s} {method:6s} tol {tol:<6g} {seconds:7.2f} s  "
            f"rms {rms:.2e}  p99 {p99:.2e}  worst {worst:.2e}  {stages}"
        )
    return rows


def proxy_rows(scan, name, scene, medium, receivers, exact, resolutions, repeats):
    """Rows of the pipeline's proxy resolutions: median of ``repeats`` warm ``Scene.shade`` calls each.

    The first (untimed) call decimates and maps the full mesh onto the proxy; its cost is reported
    as ``proxy_seconds``. ``B`` comes back on every vertex of the full mesh, where the error is measured.
    """
    rows = []
    n = scene.mesh.n_points
    for resolution in resolutions:
        setting = detail_resolution(scene, medium) if resolution == "detail" else resolution
        result, seconds = timed(
            # no bounce: the error is against a single exact solve
            lambda: scene.shade(medium, LIGHT, method=PROXY_METHOD, tol=PROXY_TOL, resolution=setting, bounces=0),
            repeats,
        )
        solver_mesh, decimation, edge, _, _ = scene.solver_mesh(medium, setting)
        rms, worst, p99 = errors(result.B[receivers], exact.B)
        label = f"{resolution:g} mm" if isinstance(resolution, float) else resolution
        label += f": {solver_mesh.n_points} vertices" if decimation is not None else ": full (no proxy)"
        rows.append(
            make_row(
                scan,
                n,
                name,
                PROXY_METHOD,
                PROXY_TOL,
                label,
                seconds,
                repeats,
                rms,
                worst,
                receivers.size,
                result.stats["solver"],
                result.timings,
                p99=p99,
                vertices_solved=solver_mesh.n_points,
                proxy_edge_mm=edge,
                proxy_seconds=None if decimation is None else decimation.seconds,
                resolution_setting=resolution,
            )
        )
        print(
            f"{scan:6s} {n:7d} {name:10s} proxy {label:28s} {seconds:7.2f} s  "
            f"rms {rms:.2e}  p99 {p99:.2e}  worst {worst:.2e}"
        )
    return rows


def run(scans, materials, settings, repeats, resolutions=PROXY_RESOLUTIONS, subset=4000):
    """Every row of the benchmark, and the kernel throughput (measured once, on the first scan).

    The error is measured at every vertex of scans up to 40000 vertices and at ``subset`` random
    vertices of larger scans (at ``subset`` vertices always when ``subset`` is below 4000).
    """
    rows = []
    kernel_speed = None
    for scan in present_scans(scans):
        mesh, geometry = prepare(scan)
        scene = Scene(mesh)
        n = geometry.n_vertices
        rng = np.random.default_rng(0)
        everywhere = n <= 40000 and subset >= 4000
        receivers = np.arange(n) if everywhere else np.sort(rng.choice(n, min(subset, n), replace=False))
        for name in materials:
            medium = material(name).medium()
            incident = incident_flux(
                mesh.points, geometry.normals, geometry.vertex_areas, LIGHT, medium.eta, triangles=mesh.triangles
            )
            if kernel_speed is None:
                kernel_speed = throughput(geometry, incident, medium)
                print(
                    f"exact kernel: {kernel_speed['pairs_per_second'] / 1e6:.1f} M pairs/s "
                    f"({kernel_speed['fraction_of_reference']:.2f} of the reference loop's "
                    f"{kernel_speed['reference_loop_pairs_per_second'] / 1e6:.1f} M/s); "
                    f"FMA loop {kernel_speed['fma_loop_flops'] / 1e9:.1f} GFLOP/s"
                )
            start = time.perf_counter()
            exact = solve(geometry, incident.phi_rgb, incident.w12, medium, method="exact", receivers=receivers)
            exact_seconds = time.perf_counter() - start
            rows.append(
                make_row(
                    scan,
                    n,
                    name,
                    "exact",
                    None,
                    "full",
                    exact_seconds,
                    1,
                    0.0,
                    0.0,
                    receivers.size,
                    exact.stats,
                    exact.timings,
                )
            )
            print(f"{scan:6s} {n:7d} {name:10s} exact            {exact_seconds:7.2f} s (receivers {receivers.size})")
            rows += method_rows(scan, name, geometry, incident, medium, receivers, exact, settings, repeats)
            rows += proxy_rows(scan, name, scene, medium, receivers, exact, resolutions, repeats)
    return rows, kernel_speed


def series(row):
    """The plot series a row belongs to: the method, or the method at a proxy resolution."""
    if row["resolution"] == "full":
        return row["method"]
    setting = row["resolution_setting"]
    return f"proxy {setting:g} mm" if isinstance(setting, float) else f"proxy {setting}"


def plot(rows, path):
    """Time against error, one panel per scan: colour per material, marker per method or proxy resolution."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.ticker import NullFormatter

    scans = list(dict.fromkeys(r["scan"] for r in rows))
    fig, axes = plt.subplots(1, len(scans), figsize=(5 * len(scans), 4.4), squeeze=False)
    colours = {"marble": "tab:grey", "skim_milk": "tab:blue", "ketchup": "tab:red"}
    names = list(dict.fromkeys(series(r) for r in rows if r["method"] != "exact"))
    markers = dict(zip(names, "os^vDPX*"))
    for ax, scan in zip(axes[0], scans):
        for name in colours:
            for key in names:
                sel = [
                    r
                    for r in rows
                    if r["scan"] == scan and r["material"] == name and r["method"] != "exact" and series(r) == key
                ]
                if sel:
                    ax.plot(
                        [max(r["error_rms"], 1e-7) for r in sel],
                        [r["seconds"] for r in sel],
                        marker=markers[key],
                        color=colours[name],
                        ls="-" if len(sel) > 1 else "none",
                    )
            ex = [r for r in rows if r["scan"] == scan and r["material"] == name and r["method"] == "exact"]
            if ex and ex[0]["receivers"] == ex[0]["vertices"]:
                ax.axhline(ex[0]["seconds"], color=colours[name], lw=0.8, ls=":")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.axvline(0.01, color="k", lw=0.6, ls="--")
        ax.set_xlabel("relative RMS error against exact (full mesh)")
        ax.set_ylabel("wall time per solve (s)")
        vertices = next(r["vertices"] for r in rows if r["scan"] == scan)
        ax.set_title(f"{scan} ({vertices} vertices)")
        ax.grid(True, which="both", alpha=0.3)
        ax.xaxis.set_minor_formatter(NullFormatter())
    present = {r["material"] for r in rows}
    handles = [Line2D([], [], color=c, label=m) for m, c in colours.items() if m in present]
    handles += [Line2D([], [], color="k", marker=markers[k], ls="none", label=k) for k in names]
    axes[0][0].legend(handles=handles, fontsize=7)
    fig.suptitle(
        "translucency solver: time against error\n(one directional light, Embree shadows; dotted: exact)", fontsize=10
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def markdown(rows):
    """The Markdown table of the rows."""
    lines = [
        "| scan | vertices | material | lights | method | tol | resolution | time (s) | runs | rel. RMS error "
        "| per-vertex error (99th pct.) | worst lit-vertex error | pairs evaluated | pairs skipped "
        "| sources skipped (no flux) | vertices "
        "skipped (proxy) | load |",
        "|---|---:|---|---|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        tol = "" if r["tol"] is None else f"{r['tol']:g}"
        note = "" if r["method"] != "exact" or r["receivers"] == r["vertices"] else f" ({r['receivers']} receivers)"
        if "prepare_seconds" in r:  # relighting: a light's time; its operators' preparation and size once
            note = f" (prepared in {r['prepare_seconds']:.0f} s, {r['operator_bytes'] / 1e9:.2f} GB)"
        lines.append(
            f"| {r['scan']} | {r['vertices']} | {r['material']} | {r['lights']} | {r['method']}{note} | {tol} | "
            f"{r['resolution']} | {r['seconds']:.2f} | {r['repeats']} | {r['error_rms']:.1e} | "
            f"{r.get('error_p99', 0.0):.1e} | {r['error_worst']:.1e} | "
            f"{r['pairs_evaluated']:,} | {r['pairs_skipped']:,} | {r['sources_skipped']:,} | "
            f"{r['vertices'] - r['vertices_solved']:,} | {r['load_average'][0]:.1f} |"
        )
    return "\n".join(lines)


def kernel_markdown(speed):
    """The Markdown table of the kernel throughput against the reference loop and the FMA loop."""
    if not speed:
        return "(not measured: no scan available)"
    fma = speed["fma_loop_flops"]
    return "\n".join(
        [
            "| loop | pairs/s | GFLOP/s | fraction |",
            "|---|---:|---:|---|",
            f"| `exact` kernel (directional dipole, 3 channels) | {speed['pairs_per_second'] / 1e6:.1f} M | | "
            f"{speed['fraction_of_reference']:.3f} of the reference loop |",
            f"| reference loop (one sqrt + one exp per pair, ≈ {speed['reference_flop_per_pair']} FLOP) | "
            f"{speed['reference_loop_pairs_per_second'] / 1e6:.1f} M | {speed['reference_loop_flops'] / 1e9:.1f} | "
            f"{speed['reference_fraction_of_fma_peak']:.2f} of the FMA loop |",
            f"| FMA loop (degree-{FMA_DEGREE} Horner polynomial, L1-resident) | | {fma / 1e9:.1f} | the "
            "machine's measured peak |",
            "",
            f"Load average during the measurement: {speed['load_average'][0]:.1f} (1 min).",
        ]
    )


def main(argv=None):
    """Command line: run the benchmark, write the JSON, the tables and the plot."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quick",
        action="store_true",
        help="bunny in marble only, fewer settings, error at 1000 vertices, one repeat, into results/tmp",
    )
    parser.add_argument("--repeats", type=int, default=3, help="timed warm solves per setting (median reported)")
    parser.add_argument("--scans", nargs="+", choices=list(SCANS), help="scans to run (default: all; --quick: bunny)")
    args = parser.parse_args(argv)
    if not MESHES.is_dir():
        print("the shared scans (../shared/meshes) are not present; nothing to benchmark")
        return 0
    scans = args.scans or (["bunny"] if args.quick else list(SCANS))
    settings = [s for s in SETTINGS[::2] if s[0] == "tree"] if args.quick else SETTINGS
    resolutions = PROXY_RESOLUTIONS[:2] if args.quick else PROXY_RESOLUTIONS
    info = {**machine_info(), "light": LIGHT.to_dict()}
    start = time.perf_counter()
    materials = MATERIALS[:1] if args.quick else MATERIALS
    rows, kernel_speed = run(
        scans, materials, settings, 1 if args.quick else args.repeats, resolutions, subset=1000 if args.quick else 4000
    )
    info["seconds_total"] = time.perf_counter() - start
    out = output_dir(args.quick)
    table = markdown(rows)
    write_results(out, "solver", {"info": info, "kernel": kernel_speed, "rows": rows}, table)
    (out / "kernel.md").write_text(kernel_markdown(kernel_speed) + "\n")
    plot(rows, out / "solver_pareto.png")
    print(table)
    print(kernel_markdown(kernel_speed))
    return 0


if __name__ == "__main__":
    sys.exit(main())
