"""Time and memory against vertex count (10k to 10M vertices), and the largest bake end to end.

The meshes are all the shared Igea (cleaned, in mm) at other densities, so that only the vertex count
changes:

========= ================================================================================
label     how it is made
========= ================================================================================
10k, 30k  decimated (:func:`translucency.io.decimate.simplify_arrays`, quadric edge collapse)
134k      the scan itself
537k      midpoint-subdivided once (every triangle into four; the surface is unchanged)
1M        midpoint-subdivided once, then the longest edges (29 %) split at their midpoints once more
2.1M      midpoint-subdivided twice, every vertex moved along its normal by scan-like noise
10M       midpoint-subdivided three times, the longest edges split to 10M vertices, the same noise
========= ================================================================================

The noise (Gaussian, 5 % of the mesh's mean edge along each vertex normal) makes the subdivided meshes
as rough at their own scale as a scan is, instead of flat within each triangle of the Igea.

Each mesh is written to a temporary PLY and baked in a child process, as a user would bake it:
load -> clean -> ``Scene.shade()`` with the default settings (marble, one directional light with
Embree shadows, ``tree`` at tolerance 1 %, every vertex) -> :func:`translucency.io.baked.write_baked_ply`,
with the wall time of every stage; the solver's own stages (incident light and visibility, far
field, near lists, near field) come from the shade's timings. That first shade builds every cache
(Embree scene, source tree, near-triangle lists); a viewer's later solves reuse them, so warm shades
of the same scene are timed too (median of ``--repeats`` at up to 200k vertices, one above).
Then ``exact`` at a fixed number of random receivers (2000) gives the error of the bake (its first-order
``B``: the bounce's re-entered light taken off): relative RMS, worst lit-vertex error and the per-vertex
99th percentile, as in ``bench/solver.py``. Numba's kernels are compiled into its cache in a process of
their own before the first size (a bake on a small sphere), and each child loads them on that sphere again
before anything is timed: every bake runs as every run after a user's first does. The process that compiles
holds more (LLVM's memory stays with it), so its own time and peak are recorded too (``info["compile"]``).

Peak memory, three ways: the resident sets of the bake's process and its children (the decimation's
parts) summed, sampled every 0.2 s during the bake: what the machine must hold, and what the goal is
about; ``VmHWM`` of the bake's own process, read from ``/proc/self/status`` right after the bake is
written; and ``ru_maxrss`` of the finished child (its largest process, ``exact`` included unless it runs
apart). The parent stops a child whose bake runs past ``--time-limit`` seconds or whose processes' resident
sets grow past ``--memory-limit`` GB together, and records why.

Writes ``scaling.json``, ``scaling.md``, ``bake.md`` and ``scaling.png`` into ``bench/results``
(``bench/results/tmp`` with ``--quick``: 10k and 30k only).

    .venv/bin/python bench/scaling.py            # every size (about 3 min on 2 cores, most of it at 1M)
    .venv/bin/python bench/scaling.py --quick    # 10k and 30k, in a minute or two
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
from report import load_average, machine_info, output_dir, write_results  # noqa: E402
from solver import MESHES, SCANS, TOL_FLOOR, errors, prepare  # noqa: E402

from translucency import __version__  # noqa: E402,F401  (first: it selects numba's threading layer)
from translucency.errors import BudgetError  # noqa: E402
from translucency.processes import descendants  # noqa: E402

SIZES = ("10k", "30k", "134k", "537k", "1M", "2.1M", "10M")
#: Standard deviation of the scan-like noise of the 2.1M and 10M meshes, in mean edges (along the normals).
NOISE_EDGES = 0.05
QUICK_SIZES = ("10k", "30k")
RECEIVERS = 2000
#: Warm shades are repeated (median) on meshes up to this many vertices, run once above.
REPEAT_MAX_VERTICES = 200_000
#: What the solver's stages are called in ``ShadeResult.timings``, and in the tables.
SOLVER_STAGES = {
    "incident_light": "incident light + visibility",
    "solve_far_field": "far field",
    "solve_near_lists": "near lists",
    "solve_near_field": "near field",
}
#: Goals of the issue: seconds per solve at <= 1 % error.
GOALS = {"bunny": 0.5, "igea": 2.0, "bake_1M": 60.0, "bake_10M": 300.0, "memory_10M_gb": 8.0}
GOAL_ERROR = 0.01


def build_mesh(label, igea):
    """``(points, triangles, how)``: the cleaned Igea ``igea`` at the density ``label`` (module table)."""
    from translucency.geometry.synthetic import subdivide
    from translucency.io.decimate import simplify_arrays

    points, triangles = igea.points, igea.triangles
    if label in ("10k", "30k"):
        vertices = int(label[:-1]) * 1000
        points, triangles = simplify_arrays(points, triangles, 2 * vertices)
        return points, triangles, f"decimated to {2 * vertices} triangles"
    if label == "134k":
        return points, triangles, "the scan"
    points, triangles = subdivide(points, triangles)
    if label == "537k":
        return points, triangles, "midpoint-subdivided once"
    if label == "1M":
        points, triangles, share = split_longest_edges(points, triangles, 1_000_000)
        return (
            points,
            triangles,
            f"midpoint-subdivided once, then its longest {100 * share:.0f} % of edges split at their midpoints",
        )
    points, triangles = subdivide(points, triangles)
    how = "midpoint-subdivided twice"
    if label == "10M":
        points, triangles = subdivide(points, triangles)
        points, triangles, share = split_longest_edges(points, triangles, 10_000_000)
        how = f"midpoint-subdivided three times, its longest {100 * share:.0f} % of edges split"
    return (*with_noise(points, triangles), f"{how}, with noise of {NOISE_EDGES:g} mean edges along the normals")


def with_noise(points, triangles):
    """Every vertex moved along its normal by Gaussian noise of :data:`NOISE_EDGES` mean edges (seeded)."""
    from translucency.geometry.measure import mean_edge_length, vertex_normals

    sigma = NOISE_EDGES * mean_edge_length(points, triangles)
    offset = np.random.default_rng(17).normal(0.0, sigma, size=len(points))
    return points + offset[:, None] * vertex_normals(points, triangles), triangles


def split_longest_edges(points, triangles, vertices):
    """Split the longest edges at their midpoints until the mesh has about ``vertices`` vertices.

    pymeshlab's midpoint subdivision with an edge-length threshold: every edge longer than the
    threshold gets a new vertex at its midpoint (the surface does not change) and the triangles
    around it are split. The threshold is the edge length that as many edges exceed as vertices are
    missing. Returns ``(points, triangles, share of the edges split)``.
    """
    from translucency.io.meshlab import import_pymeshlab

    pymeshlab = import_pymeshlab()
    from translucency.geometry.topology import unique_edges

    edges, _ = unique_edges(triangles)
    lengths = np.sort(np.linalg.norm(points[edges[:, 0]] - points[edges[:, 1]], axis=1))
    missing = min(max(vertices - len(points), 1), len(lengths))
    mesh_set = pymeshlab.MeshSet()
    mesh_set.add_mesh(
        pymeshlab.Mesh(vertex_matrix=np.asarray(points, np.float64), face_matrix=np.asarray(triangles, np.int32))
    )
    mesh_set.meshing_surface_subdivision_midpoint(
        iterations=1, threshold=pymeshlab.PureValue(float(lengths[len(lengths) - missing]))
    )
    mesh = mesh_set.current_mesh()
    return (
        np.asarray(mesh.vertex_matrix(), np.float64),
        np.asarray(mesh.face_matrix(), np.int64),
        missing / len(lengths),
    )


def write_mesh(path, points, triangles):
    """Write a plain triangle mesh (mm) as a PLY with :func:`translucency.io.save.save_mesh`
    (as ``inspect -o`` does)."""
    from translucency.geometry.mesh import TriangleMesh
    from translucency.io.save import save_mesh

    save_mesh(path, TriangleMesh(points, triangles))


def peak_rss_mb() -> float:
    """This process's peak resident set size so far (``VmHWM``), MB."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024.0
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


class TreePeak:
    """The largest summed resident set of this process and its descendants (the decimation's children), MB,
    sampled every ``interval_s`` seconds on a thread while the ``with`` block runs."""

    def __init__(self, interval_s=0.2):
        import threading

        self.interval_s, self.peak_mb = interval_s, 0.0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._sample, daemon=True)

    def _sample(self):
        while True:
            self.peak_mb = max(self.peak_mb, tree_rss_mb(os.getpid()))
            if self._stop.wait(self.interval_s):
                return

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()


def tree_rss_mb(pid) -> float:
    """Resident sets of process ``pid`` and of its descendants now, summed, MB."""
    return sum(current_rss_mb(member) for member in [pid] + descendants(pid))


def current_rss_mb(pid) -> float:
    """Resident set size (``VmRSS``) of process ``pid`` now, MB (0 when it is gone)."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return 0.0


def bake(path, out_ply, stage=None):
    """Load -> clean -> shade (default settings) -> write the baked PLY; ``stage(name)`` is told each stage
    as it starts (the solver's too), so that a bake stopped over its limits says where.

    Returns ``(scene, result, mesh, seconds per stage)``.
    """
    stage = stage or (lambda name: None)
    current = [None]

    def progress(name, fraction):
        if name != current[0]:
            current[0] = name
            stage(f"shade: {name}")

    from translucency.app.shading.scene import Scene
    from translucency.io.baked import write_baked_ply
    from translucency.io.clean import clean_mesh
    from translucency.io.load import load_mesh

    stages = {}
    stage("load")
    start = time.perf_counter()
    mesh = load_mesh(path, unit="mm")
    stages["load"] = time.perf_counter() - start
    stage("clean")
    start = time.perf_counter()
    mesh, _ = clean_mesh(mesh)
    stages["clean"] = time.perf_counter() - start
    stage("shade")
    start = time.perf_counter()
    scene = Scene(mesh)
    result = scene.shade(progress=progress)
    stages["shade"] = time.perf_counter() - start
    stage("write")
    start = time.perf_counter()
    write_baked_ply(out_ply, mesh, result.radiance, result.B, result.colors, result.metadata)
    stages["write"] = time.perf_counter() - start
    return scene, result, mesh, stages


def exact_at(scene, receivers):
    """``exact`` (the default material and light, as the shade used them) at ``receivers``; ``(B, seconds)``."""
    from translucency.app.shading.settings import DEFAULT_MATERIAL, default_light_direction, resolve_medium
    from translucency.scatter.lights import DirectionalLight
    from translucency.scatter.solve import solve

    medium = resolve_medium(DEFAULT_MATERIAL)
    solver_mesh, _, _, geometry, _ = scene.solver_mesh(medium, "full")
    incident, _ = scene.light_cache.incident(
        geometry, solver_mesh.triangles, [DirectionalLight(default_light_direction(scene.up), 1.0)], medium.eta
    )
    start = time.perf_counter()
    exact = solve(geometry, incident.phi_rgb, incident.w12, medium, method="exact", receivers=receivers)
    return exact.B, time.perf_counter() - start


def warm_up(folder):
    """Load numba's compiled code and the libraries: the whole bake and ``exact`` on a small sphere."""
    from translucency.geometry.synthetic import icosphere

    points, triangles = icosphere(3, radius=20.0)
    write_mesh(folder / "warm_up.ply", points, triangles)
    scene, _, _, _ = bake(folder / "warm_up.ply", folder / "warm_up_baked.ply")
    exact_at(scene, np.arange(10))


def child(path, out_json, repeats):
    """Child process: the timed bake, warm shades and ``exact``, written to ``out_json`` after each phase."""
    folder = Path(path).parent
    record = {"phase": "warm-up"}

    def save(**values):
        """Add ``values`` to the record and rewrite the JSON file."""
        record.update(values)
        Path(f"{out_json}.part").write_text(json.dumps(record, indent=1))
        os.replace(f"{out_json}.part", out_json)  # the parent never reads a half-written file

    save()
    warm_up(folder)
    save(phase="bake", load_average_start=load_average())
    with TreePeak() as tree:
        scene, result, mesh, stages = bake(
            path, folder / (Path(path).stem + "_baked.ply"), stage=lambda name: save(phase=f"bake: {name}")
        )
    stages.update({SOLVER_STAGES[k]: result.timings.get(k, 0.0) for k in SOLVER_STAGES})
    save(
        phase="warm shades",
        vertices=mesh.n_points,
        triangles=mesh.n_triangles,
        stages=stages,
        bake_seconds=stages["load"] + stages["clean"] + stages["shade"] + stages["write"],
        peak_rss_bake_mb=peak_rss_mb(),
        peak_rss_tree_bake_mb=tree.peak_mb,
        load_average_bake=load_average(),
        solver_stats=result.stats["solver"],
        solver_vertices=result.stats["solver_vertices"],
        shade_timings=result.timings,
    )
    runs = repeats if mesh.n_points <= REPEAT_MAX_VERTICES else 1
    warm = []
    for _ in range(runs):
        start = time.perf_counter()
        again = scene.shade()
        warm.append((time.perf_counter() - start, again.timings))
    seconds, timings = sorted(warm, key=lambda item: item[0])[len(warm) // 2]
    save(
        phase="exact",
        warm_seconds=seconds,
        warm_runs=runs,
        warm_stages={SOLVER_STAGES[k]: timings.get(k, 0.0) for k in SOLVER_STAGES},
        peak_rss_warm_mb=peak_rss_mb(),
    )
    receivers = np.sort(np.random.default_rng(0).choice(mesh.n_points, min(RECEIVERS, mesh.n_points), replace=False))
    # exact solves the light that enters from the lights; the bake's bounce (light that re-enters) comes off
    first = result.B if result.reentered is None else result.B - result.reentered
    try:
        exact, exact_seconds = exact_at(scene, receivers)
    except BudgetError as exc:  # over what is left beside the bake: exact runs in a process of its own
        np.savez(f"{out_json}.bake.npz", receivers=receivers, first=first[receivers])
        save(phase="done", exact_refused=str(exc), peak_rss_mb=peak_rss_mb(), load_average_end=load_average())
        return
    save(
        phase="done",
        peak_rss_mb=peak_rss_mb(),
        load_average_end=load_average(),
        **error_record(first, receivers, exact, mesh.vertex_normals(), scene.up),
    )
    save(exact_seconds=exact_seconds)


def error_record(first, receivers, exact, normals, up):
    """The record's error fields: the bake's first-order ``B`` (at every vertex) at ``receivers`` against ``exact``,
    and where the error is (:func:`error_bands`; ``normals`` the mesh's unit vertex normals, ``up`` the Scene's up
    axis, which turns the default light into the scan's frame)."""
    rms, worst, p99 = errors(first[receivers], exact)
    record = {"receivers": int(receivers.size), "error_rms": rms, "error_worst": worst, "error_p99": p99}
    return {**record, **error_bands(first[receivers], exact, normals[receivers], up)}


#: Where a receiver sits against the default light, by the cosine of its normal with it.
LIGHT_BANDS = {
    "facing the light (cos > 0.2)": (0.2, 1.0),
    "at the terminator (cos -0.3 to 0.2)": (-0.3, 0.2),
    "facing away (cos < -0.3)": (-1.0, -0.3),
}


def error_bands(B, exact, normals, up):
    """The share of (receiver, channel) pairs off by more than 1 % and 5 %, and the median and 99th percentile of the
    per-vertex error per :data:`LIGHT_BANDS` band (pairs with ``exact`` at least 1e-4 of its channel's largest, as
    :func:`solver.per_vertex_error`)."""
    from translucency.app.shading.settings import default_light_direction

    keep = exact >= TOL_FLOOR * exact.max(axis=0)
    relative = np.abs(B - exact) / np.where(keep, exact, 1.0)
    light = np.asarray(default_light_direction(up), dtype=float)
    light /= np.linalg.norm(light)
    cosine = normals @ light
    bands = {}
    for name, (low, high) in LIGHT_BANDS.items():
        inside = keep & ((cosine >= low) & (cosine <= high))[:, None]
        values = relative[inside]
        if values.size:
            bands[name] = {
                "receivers": int(inside.any(axis=1).sum()),
                "median": float(np.median(values)),
                "p99": float(np.percentile(values, 99)),
            }
    values = relative[keep]
    return {
        "error_over_1pct": float(np.mean(values > 0.01)),
        "error_over_5pct": float(np.mean(values > 0.05)),
        "error_bands": bands,
    }


def reference_child(path, out_json):
    """Child process: ``exact`` at the receivers the bake child saved, on the mesh loaded and cleaned as the bake
    did it, with nothing else held; the error fields added to the bake's record."""
    from translucency.app.shading.scene import Scene
    from translucency.io.clean import clean_mesh
    from translucency.io.load import load_mesh

    saved = np.load(f"{out_json}.bake.npz")
    mesh, _ = clean_mesh(load_mesh(path, unit="mm"))
    scene = Scene(mesh)
    exact, exact_seconds = exact_at(scene, saved["receivers"])
    record = json.loads(Path(out_json).read_text())
    first = np.zeros((mesh.n_points, exact.shape[1]))
    first[saved["receivers"]] = saved["first"]
    record.update(
        error_record(first, saved["receivers"], exact, mesh.vertex_normals(), scene.up),
        exact_seconds=exact_seconds,
        exact_apart_peak_rss_mb=peak_rss_mb(),
    )
    Path(f"{out_json}.part").write_text(json.dumps(record, indent=1))
    os.replace(f"{out_json}.part", out_json)


def run_child(path, out_json, repeats, time_limit, memory_limit_gb):
    """Run :func:`child` on ``path`` in a new process, watching its time and memory, then, when ``exact`` did not
    fit beside the bake, :func:`reference_child`; the record, with ``status``."""
    command = [sys.executable, __file__, "--child", str(path), str(out_json), "--repeats", str(repeats)]
    record = _watched(command, out_json, time_limit, memory_limit_gb)
    if record["status"] == "finished" and record.get("exact_refused"):
        apart = _watched(
            [sys.executable, __file__, "--reference", str(path), str(out_json)], out_json, time_limit, memory_limit_gb
        )
        record.update({k: v for k, v in apart.items() if k.startswith(("error_", "exact_", "receivers"))})
        if apart["status"] == "finished" and "error_p99" in apart:
            record["status"] = "finished; exact at the receivers in a process of its own (over the bake's budget)"
            record["exact_apart_ru_maxrss_mb"] = apart["ru_maxrss_mb"]
        else:
            record["status"] = f"finished; exact at the receivers {apart['status']}, error not measured"
    return record


def _watched(command, out_json, time_limit, memory_limit_gb):
    """Run ``command`` (a child writing ``out_json``), stopping it past ``time_limit`` seconds (twice that after the
    bake) or ``memory_limit_gb`` of resident memory; its record with ``status``, ``child_seconds`` and peaks."""
    process = subprocess.Popen(command, cwd=ROOT)
    start = time.perf_counter()
    status, peak_seen, usage = "finished", 0.0, None
    while usage is None:
        pid, code, ru = os.wait4(process.pid, os.WNOHANG)
        if pid:
            usage = ru
            status = (
                "finished"
                if os.waitstatus_to_exitcode(code) == 0
                else f"failed (exit {os.waitstatus_to_exitcode(code)})"
            )
            break
        rss = tree_rss_mb(process.pid)
        peak_seen = max(peak_seen, rss)
        record = json.loads(Path(out_json).read_text()) if Path(out_json).exists() else {}
        in_bake = record.get("phase") in (None, "warm-up") or str(record.get("phase")).startswith("bake")
        if rss > memory_limit_gb * 1024:
            status = (
                f"stopped: resident set {rss / 1024:.1f} GB above the {memory_limit_gb:g} GB limit "
                f"(phase {record.get('phase')})"
            )
        elif time.perf_counter() - start > (time_limit if in_bake else 2 * time_limit):
            status = f"stopped: over the {time_limit:g} s limit (phase {record.get('phase')})"
        else:
            time.sleep(0.5)
            continue
        process.kill()
        _, _, usage = os.wait4(process.pid, 0)
    record = json.loads(Path(out_json).read_text()) if Path(out_json).exists() else {}
    record.update(
        status=status,
        child_seconds=time.perf_counter() - start,
        peak_rss_polled_mb=peak_seen,
        ru_maxrss_mb=usage.ru_maxrss / 1024.0,
    )
    return record


def fit_exponent(n, seconds):
    """Slope of log(seconds) against log(n) (least squares), or None with fewer than two points."""
    n, seconds = np.asarray(n, float), np.asarray(seconds, float)
    ok = np.isfinite(seconds) & (seconds > 0)
    if ok.sum() < 2:
        return None
    return float(np.polyfit(np.log(n[ok]), np.log(seconds[ok]), 1)[0])


def curves(rows):
    """The timed series per row: ``{name: [seconds or nan per row]}`` (exact at all vertices extrapolated)."""
    get = lambda key: [r.get(key, float("nan")) for r in rows]  # noqa: E731
    exact = np.array(get("exact_seconds"), float)
    scale = np.array([r.get("vertices", np.nan) / r.get("receivers", np.nan) for r in rows], float)
    return {
        "bake (load to write)": get("bake_seconds"),
        "tree 1e-2, first shade": [r.get("stages", {}).get("shade", float("nan")) for r in rows],
        "tree 1e-2, warm shade": get("warm_seconds"),
        f"exact at {RECEIVERS} receivers": list(exact),
        "exact at every vertex (extrapolated)": list(exact * scale),
    }


def plot(rows, exponents, path):
    """Three panels: time against vertices (log-log, fitted exponents), the first shade's stages, peak memory."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    done = [r for r in rows if "vertices" in r]
    n = np.array([r["vertices"] for r in done], float)
    fig, axes = plt.subplots(1, 3, figsize=(17, 4.8))
    ax = axes[0]
    for (name, seconds), style in zip(curves(done).items(), ("k-o", "C0-o", "C1-s", "C3-^", "C3:^")):
        ax.plot(
            n,
            seconds,
            style,
            label=f"{name}: n^{exponents[name]:.2f}" if exponents.get(name) else name,
            mfc="none" if "extrapolated" in name else None,
        )
    ax.axhline(GOALS["bake_1M"], color="grey", ls="--", lw=0.8)
    ax.text(n.min(), GOALS["bake_1M"] * 1.1, "goal: 1M bake in 60 s", fontsize=7, color="grey")
    ax.set(xscale="log", yscale="log", xlabel="vertices", ylabel="wall time (s)", title="time against vertex count")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    ax = axes[1]
    bottom = np.zeros(len(done))
    labels = [r["label"] for r in done]
    totals = np.array([r["bake_seconds"] for r in done])
    for name in ["load", "clean", *SOLVER_STAGES.values(), "other (shade)", "write"]:
        values = np.array([stage_seconds(r, name) for r in done]) / totals
        ax.bar(labels, values, bottom=bottom, label=name)
        bottom += values
    for x, total in enumerate(totals):
        ax.text(x, 1.01, f"{total:.0f} s" if total >= 10 else f"{total:.1f} s", ha="center", fontsize=8)
    ax.set(
        ylabel="share of the bake's wall time",
        ylim=(0, 1.45),
        yticks=np.linspace(0, 1, 6),
        title="the bake's stages (first shade, caches cold)",
    )
    ax.legend(fontsize=7, loc="upper center", ncol=3)
    ax = axes[2]
    memory = fit_exponent(n, [r.get("peak_rss_bake_mb", np.nan) for r in done])
    ax.plot(
        n,
        [r.get("peak_rss_bake_mb", np.nan) for r in done],
        "k-o",
        label=f"peak RSS of the bake: n^{memory:.2f}" if memory else "peak RSS of the bake",
    )
    ax.plot(
        n,
        [r.get("peak_rss_tree_bake_mb", np.nan) for r in done],
        "C0--^",
        label="peak RSS of the bake's processes, summed",
    )
    ax.plot(
        n,
        [r.get("ru_maxrss_mb", np.nan) for r in done],
        "C3:s",
        label="peak RSS of the child's largest process (exact included, unless run apart)",
    )
    ax.set(xscale="log", yscale="log", xlabel="vertices", ylabel="MB", title="memory against vertex count")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.suptitle(
        "translucency: the Igea from 10k to 10M vertices, marble, one directional light, tree 1e-2 "
        "(other: the bounce, geometry, set-up)"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def stage_seconds(row, name):
    """Seconds of one bake stage of ``row``; ``other (shade)`` is the shade's time outside the solver stages."""
    stages = row.get("stages", {})
    if name == "other (shade)":
        return max(stages.get("shade", 0.0) - sum(stages.get(s, 0.0) for s in SOLVER_STAGES.values()), 0.0)
    return stages.get(name, 0.0)


def markdown(rows, exponents):
    """The scaling table (one row per size) and the fitted exponents."""
    lines = [
        "| mesh | vertices | how | bake (s) | first shade (s) | incident light (s) | far field (s) | near lists (s) "
        "| near field (s) | warm shade (s) | exact at 2000 (s) | rel. RMS error | worst lit-vertex error | "
        "p99 per-vertex error | solved on (vertices) | "
        "peak RSS of the bake's processes, summed / of its own process / of the child's largest process, exact "
        "included unless apart (MB) | load | status |",
        "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    fmt = lambda value, spec: "" if value is None or value != value else format(value, spec)  # noqa: E731
    for r in rows:
        stages = r.get("stages", {})
        lines.append(
            f"| {r['label']} | {r.get('vertices', '')} | {r['how']} | {fmt(r.get('bake_seconds'), '.1f')} | "
            f"{fmt(stages.get('shade'), '.1f')} | "
            + " | ".join(fmt(stages.get(s), ".2f") for s in SOLVER_STAGES.values())
            + f" | {fmt(r.get('warm_seconds'), '.1f')} | {fmt(r.get('exact_seconds'), '.1f')} | "
            f"{fmt(r.get('error_rms'), '.1e')} | {fmt(r.get('error_worst'), '.1e')} | "
            f"{fmt(r.get('error_p99'), '.1e')} | {r.get('solver_vertices', '')} | "
            f"{fmt(r.get('peak_rss_tree_bake_mb'), '.0f')} / {fmt(r.get('peak_rss_bake_mb'), '.0f')} / "
            f"{fmt(r.get('ru_maxrss_mb'), '.0f')} | "
            f"{fmt((r.get('load_average_bake') or [None])[0], '.1f')} | {r['status']} |"
        )
    lines.append("")
    fitted = "; ".join(f"{name}: k = {k:.2f}" for name, k in exponents.items() if k is not None)
    lines.append(
        "Fitted exponents (time or memory ∝ vertices^k, least squares over the sizes measured): "
        + (fitted or "none (fewer than two sizes)")
        + "."
    )
    return "\n".join(lines)


def bake_markdown(row):
    """The table of the largest bake: seconds per stage, error against ``exact``, peak memory, goal."""
    if row is None or "stages" not in row:
        return f"(the bake did not finish: {row['status'] if row else 'not run'})"
    s = row["stages"]
    lines = [
        f"Mesh: {row['label']} ({row['vertices']:,} vertices, {row['triangles']:,} triangles; {row['how']}).",
        "",
        "| stage | wall time (s) |",
        "|---|---:|",
        f"| load (PLY) | {s['load']:.1f} |",
        f"| clean | {s['clean']:.1f} |",
    ]
    lines += [f"| shade: {name} | {s[name]:.1f} |" for name in SOLVER_STAGES.values()]
    lines += [
        f"| shade: other (geometry, set-up, colours) | {stage_seconds(row, 'other (shade)'):.1f} |",
        f"| write (baked PLY) | {s['write']:.1f} |",
        f"| **bake, load to write** | **{row['bake_seconds']:.1f}** |",
        "",
        "| measure | value | goal |",
        "|---|---:|---|",
    ]
    met = lambda ok: "met" if ok else "missed"  # noqa: E731
    goal = {"1M": GOALS["bake_1M"], "10M": GOALS["bake_10M"]}.get(row["label"])
    lines.append(
        f"| bake time | {row['bake_seconds']:.0f} s | "
        + (f"≤ {goal:.0f} s at {row['label']} vertices: {met(row['bake_seconds'] <= goal)} |" if goal else " |")
    )
    if "solver_vertices" in row:
        lines.append(f"| vertices solved (a proxy when fewer than the mesh's) | {row['solver_vertices']:,} | |")
    if "error_rms" in row:
        lines.append(
            f"| error against `exact` at {row['receivers']} random vertices: rel. RMS "
            f"| {100 * row['error_rms']:.2f} % | |"
        )
        lines.append(f"| worst lit-vertex error | {100 * row['error_worst']:.1f} % | |")
        if "error_p99" in row:
            lines.append(
                f"| per-vertex error, 99th percentile (B ≥ 1e-4 of the largest) | {100 * row['error_p99']:.2f} % | "
                f"≤ 1 %: {met(row['error_p99'] <= GOAL_ERROR)} |"
            )
    if "error_bands" in row:
        lines.append(
            f"| (vertex, channel) pairs off by more than 1 % / 5 % | {100 * row['error_over_1pct']:.0f} % / "
            f"{100 * row['error_over_5pct']:.0f} % | |"
        )
        for name, band in row["error_bands"].items():
            lines.append(
                f"| per-vertex error of the vertices {name}: median / 99th percentile ({band['receivers']} "
                f"receivers) | {100 * band['median']:.1f} % / {100 * band['p99']:.1f} % | |"
            )
    memory_goal = lambda mb: (  # noqa: E731
        f"≤ {GOALS['memory_10M_gb']:g} GB: {met(mb <= GOALS['memory_10M_gb'] * 1024)}" if row["label"] == "10M" else ""
    )
    if "peak_rss_tree_bake_mb" in row:  # the goal is the machine's: every process of the bake
        lines.append(
            "| peak RSS of the bake's processes (the bake and the decimation's children, summed, sampled every "
            f"0.2 s) | {row['peak_rss_tree_bake_mb'] / 1024:.2f} GB | {memory_goal(row['peak_rss_tree_bake_mb'])} |"
        )
    lines.append(
        f"| peak RSS of the bake's own process (VmHWM after writing) | {row['peak_rss_bake_mb'] / 1024:.2f} GB | "
        + ("|" if "peak_rss_tree_bake_mb" in row else f"{memory_goal(row['peak_rss_bake_mb'])} |")
    )
    if "exact_apart_ru_maxrss_mb" in row:
        lines.append(
            "| peak RSS of the child's largest process over its run (the bake, a decimation child, the later shade, "
            "or `exact` planned beside them before it ran apart; ru_maxrss) | "
            f"{row['ru_maxrss_mb'] / 1024:.2f} GB | |"
        )
        lines.append(
            f"| peak RSS of `exact` at the receivers, in a process of its own | "
            f"{row['exact_apart_ru_maxrss_mb'] / 1024:.2f} GB | |"
        )
    else:
        lines.append(f"| peak RSS of the child (exact included, ru_maxrss) | {row['ru_maxrss_mb'] / 1024:.2f} GB | |")
    if "warm_seconds" in row:
        lines.append(f"| a later shade of the same scene (caches warm) | {row['warm_seconds']:.0f} s | |")
    if "peak_rss_warm_mb" in row:
        lines.append(
            "| peak RSS of the bake's own process after that shade (VmHWM) | "
            f"{row['peak_rss_warm_mb'] / 1024:.2f} GB | |"
        )
    lines.append(
        f"| load average (1 min) at the start / end of the bake | {row['load_average_start'][0]:.1f} / "
        f"{row['load_average_bake'][0]:.1f} | |"
    )
    return "\n".join(lines)


def run(labels, repeats, time_limit, memory_limit_gb):
    """Fill numba's cache in a process of its own, then build the meshes and bake each in a child process:
    ``(rows, one per size; the cache fill's seconds and peak, compiling or loading what is there already)``."""
    folder = Path(tempfile.mkdtemp(prefix="translucency-scaling-"))
    rows = []
    try:
        igea, _ = prepare("igea")
        start = time.perf_counter()
        subprocess.run([sys.executable, __file__, "--fill-cache", str(folder)], cwd=ROOT, check=True)
        compile_run = {
            "seconds": time.perf_counter() - start,
            "ru_maxrss_mb": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024,
        }
        print(f"numba's cache filled in {compile_run['seconds']:.1f} s, {compile_run['ru_maxrss_mb']:.0f} MB")
        for label in labels:
            start = time.perf_counter()
            points, triangles, how = build_mesh(label, igea)
            path = folder / f"igea_{label}.ply"
            write_mesh(path, points, triangles)
            built = len(points)
            del points, triangles  # the child reads the file: the parent holds nothing while it runs
            print(f"{label}: {built} vertices ({how}) built in {time.perf_counter() - start:.1f} s; baking")
            record = run_child(path, folder / f"igea_{label}.json", repeats, time_limit, memory_limit_gb)
            record.update(label=label, how=how, built_vertices=built)
            rows.append(record)
            print(
                f"{label}: {record['status']}; bake {record.get('bake_seconds', float('nan')):.1f} s, "
                f"error {record.get('error_rms', float('nan')):.2e}, peak RSS {record['ru_maxrss_mb']:.0f} MB"
            )
            for stale in folder.glob(f"igea_{label}*.ply"):
                stale.unlink()
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return rows, compile_run


def write_meshes(folder, labels):
    """Write the meshes of ``labels`` (module table) as ``folder/igea_<label>.ply``, one at a time."""
    folder.mkdir(parents=True, exist_ok=True)
    igea, _ = prepare("igea")
    for label in labels:
        points, triangles, how = build_mesh(label, igea)
        write_mesh(folder / f"igea_{label}.ply", points, triangles)
        print(f"{folder / f'igea_{label}.ply'}: {len(points):,} vertices ({how})")


def main(argv=None):
    """Command line: the scaling run (or, with ``--child``, one bake in this process)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="10k and 30k only, into results/tmp")
    parser.add_argument("--sizes", nargs="+", choices=SIZES, help="sizes to run (default: all)")
    parser.add_argument("--repeats", type=int, default=3, help="warm shades per size up to 200k vertices (median)")
    parser.add_argument("--time-limit", type=float, default=900.0, help="seconds a bake may take before it is stopped")
    parser.add_argument("--memory-limit", type=float, default=16.0, help="GB of resident memory a bake may use")
    parser.add_argument(
        "--write-meshes",
        metavar="FOLDER",
        help="only write the meshes of --sizes as igea_<size>.ply into FOLDER (to bake them by hand)",
    )
    parser.add_argument("--child", nargs=2, metavar=("MESH", "JSON"), help=argparse.SUPPRESS)
    parser.add_argument("--reference", nargs=2, metavar=("MESH", "JSON"), help=argparse.SUPPRESS)
    parser.add_argument("--fill-cache", metavar="FOLDER", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.fill_cache:
        warm_up(Path(args.fill_cache))
        return 0
    if args.child:
        child(args.child[0], args.child[1], args.repeats)
        return 0
    if args.reference:
        reference_child(*args.reference)
        return 0
    if not (MESHES / SCANS["igea"][0]).exists():
        print(f"the shared Igea ({SCANS['igea'][0]} in ../shared/meshes) is not present; nothing to benchmark")
        return 0
    labels = args.sizes or (QUICK_SIZES if args.quick else SIZES)
    if args.write_meshes:
        write_meshes(Path(args.write_meshes), labels)
        return 0
    info = machine_info()
    start = time.perf_counter()
    rows, info["compile"] = run(labels, args.repeats, args.time_limit, args.memory_limit)
    info["seconds_total"] = time.perf_counter() - start
    done = [r for r in rows if "vertices" in r]
    exponents = {name: fit_exponent([r["vertices"] for r in done], seconds) for name, seconds in curves(done).items()}
    exponents["peak RSS of the bake"] = fit_exponent(
        [r["vertices"] for r in done], [r.get("peak_rss_bake_mb", np.nan) for r in done]
    )
    out = output_dir(args.quick)
    largest = rows[-1] if rows else None
    write_results(
        out,
        "scaling",
        {"info": info, "receivers": RECEIVERS, "goals": GOALS, "exponents": exponents, "rows": rows},
        markdown(rows, exponents),
    )
    (out / "bake.md").write_text(bake_markdown(largest) + "\n")
    if done:
        plot(rows, exponents, out / "scaling.png")
    print(markdown(rows, exponents))
    print(bake_markdown(largest))
    return 0


if __name__ == "__main__":
    sys.exit(main())
