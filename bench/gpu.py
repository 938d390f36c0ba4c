"""GPU: the pair sums of ``exact`` on an NVIDIA GPU against the CPU's, time next to error (bench/README.md, "GPU").

Run it on a machine with an NVIDIA GPU and the gpu extra (numba-cuda); it needs numpy, SciPy and numba-cuda only
(no VTK, PyVista, pymeshlab or Embree), and builds its meshes in place: tori of the default bunny's, the Igea's,
1M and 10M vertices (80 mm across), lit by one directional light without shadows, marble, the directional
dipole. A scan can come as an ``.npz`` file of ``points`` (mm) and ``triangles`` (``--mesh``; ``--export FOLDER``
writes the default bunny's and the Igea's where the scans can be loaded).

Per mesh:

* the far field of one light on the GPU, every pair at every vertex (:class:`translucency.scatter.gpu.pairs.PairSums`,
  sources copied to the device and ``B`` back included), warm, the best of ``--repeats``; where the pairs would take
  more than ``--full-seconds`` by the rate already measured, only at the sampled receivers, and the whole light
  estimated from that rate;
* the CPU's ``exact`` (:func:`translucency.scatter.kernels.vertex_sum`, every thread) at ``--receivers`` random
  vertices, and the per-vertex relative error of the GPU's there (p99 and largest);
* pairs per second, and against the device's FP64 peak where the device is in :data:`FP64_PEAK`;
* a whole ``solve(method="tree", tol=0.01, device="gpu")`` at every vertex (the tree's walk and the near field's
  quadrature on the GPU, the near lists on the CPU): its seconds by stage, the evaluations per receiver, and its
  per-vertex error against ``exact`` at the sampled receivers (``exact`` on the GPU there, near field and all:
  :func:`tree_solve`); above 2M vertices (``--tree-whole-up-to``) at 10 patches of 20,000 neighbouring vertices,
  its seconds scaled to every vertex (a whole solve of 10M vertices might not fit a GPU machine's lease); on meshes
  up to 200,000 vertices also with 8, 16 and 32 receivers sharing a walk of the tree instead of the package's 4
  (:func:`tree_groups`);
* on the smallest mesh, a whole ``solve(method="exact")`` with ``device="gpu"`` and ``device="cpu"``, the near field
  on the CPU in both; and relighting with its far field on the GPU (:func:`relit_lights`): six lights, per light
  the product's seconds and the error against ``exact``, with every pair and with the tree's walk; on the second
  mesh, relighting with the tree's walk.

Writes ``bench/results/gpu.json`` and ``gpu.md`` (``bench/results/tmp`` with ``--quick``: a small torus in numba's
CUDA simulator, to check the script itself)::

    .venv/bin/python bench/gpu.py                 # on a GPU machine, a few minutes
    .venv/bin/python bench/gpu.py --quick         # anywhere: the simulator
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.report import machine_info, output_dir, write_results  # noqa: E402

#: FP64 peak (FLOP/s, without tensor cores; the kernels compute in float64) by device name: the vendors' data sheets
#: (SXM boards). Their FP32 peaks are twice these.
FP64_PEAK = {"H100": 34e12, "H200": 34e12, "A100": 9.7e12}
#: Tori: (label, vertices around the ring, around the tube), about the vertices of the scans they stand for.
TORI = (
    ("bunny-sized (28k)", 336, 84),
    ("Igea-sized (134k)", 672, 200),
    ("1M", 2000, 500),
    ("10M", 6400, 1600),
)
QUICK_TORI = (("quick (240)", 24, 10),)


def torus_mesh(n_major: int, n_minor: int):
    """A torus 80 mm across (ring radius 28 mm, tube 12 mm): points (mm), triangles."""
    from translucency.geometry.synthetic import torus

    return torus(28.0, 12.0, n_major, n_minor)


def lit_surface(points, triangles, medium, toward=(0.35, 1.0, 0.45)):
    """The surface record and one directional light without shadows (``toward`` the light): ``phi = T12 cos`` and
    ``w12`` per vertex."""
    from translucency.geometry.measure import vertex_normals
    from translucency.scatter import fresnel
    from translucency.scatter.solve import SurfaceGeometry

    normals = vertex_normals(points, triangles)
    light = np.asarray(toward, float) / np.linalg.norm(toward)
    cos = normals @ light
    phi = np.where(cos > 0, fresnel.fresnel_transmittance(np.clip(cos, 0, 1), medium.eta) * cos, 0.0)
    w12 = fresnel.refract(np.broadcast_to(light, normals.shape), normals, medium.eta)
    return SurfaceGeometry(points, triangles, normals), np.repeat(phi[:, None], 3, axis=1), w12


def sources_of(geometry, phi, w12):
    """The lit vertices as the pair sums take them: positions, normals, ``w12``, flux ``phi A``."""
    lit = np.flatnonzero(phi.max(axis=1) > 0)
    flux = phi[lit] * geometry.vertex_areas[lit, None]
    return (geometry.points[lit], geometry.normals[lit], w12[lit], flux), lit.size


def measure(label, points, triangles, args, rate_so_far):
    """One mesh's row (see the module docstring)."""
    from translucency.scatter import kernels
    from translucency.scatter.gpu.pairs import PairSums
    from translucency.scatter.materials import material

    medium = material("marble").medium()
    geometry, phi, w12 = lit_surface(points, triangles, medium)
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta)
    channel_of = np.arange(3)
    sources, n_lit = sources_of(geometry, phi, w12)
    n = geometry.n_vertices
    rng = np.random.default_rng(7)
    sample = np.sort(rng.choice(n, size=min(args.receivers, n), replace=False))
    row = {"mesh": label, "vertices": n, "lit": n_lit, "pairs": n * n_lit, "sampled_receivers": int(sample.size)}

    def light(receivers):
        start = time.perf_counter()
        B, _ = PairSums(0, *sources, params, channel_of)(geometry.points[receivers], geometry.normals[receivers])
        return B, time.perf_counter() - start

    light(sample[:64])  # compiles the kernel
    at_sample, seconds = min((light(sample) for _ in range(args.repeats)), key=lambda r: r[1])
    row["gpu_sample_seconds"] = seconds
    rate = sample.size * n_lit / seconds
    full = rate_so_far is None or n * n_lit / rate_so_far <= args.full_seconds
    if full:
        every = np.arange(n)
        B, seconds = min((light(every) for _ in range(args.repeats)), key=lambda r: r[1])
        row["gpu_light_seconds"], row["light_measured"] = seconds, True
        rate = n * n_lit / seconds
        at_sample = B[sample]
    else:
        row["gpu_light_seconds"], row["light_measured"] = n * n_lit / rate, False
    row["pairs_per_second"] = rate
    start = time.perf_counter()
    cpu, _ = kernels.vertex_sum(0, *sources, geometry.points[sample], geometry.normals[sample], params, channel_of)
    row["cpu_sample_seconds"] = time.perf_counter() - start
    row["cpu_pairs_per_second"] = sample.size * n_lit / row["cpu_sample_seconds"]
    counted = cpu >= 1e-4 * cpu.max(axis=0)  # the receivers tol is held over (docs/physics.md §8.5)
    error = np.abs(at_sample - cpu)[counted] / cpu[counted]
    row["error_p99"], row["error_max"] = float(np.percentile(error, 99)), float(error.max())
    patches = args.tree_patches if n > args.tree_whole_up_to else None
    row["tree"] = tree_solve(geometry, phi, w12, medium, sample, patches, args.reference)
    if n <= GROUPS_UP_TO:
        row["tree_groups"] = tree_groups(geometry, phi, w12, medium, sample, patches, args.groups, args.reference)
    return row, geometry, phi, w12, medium, rate


#: Above this many vertices a ``tree`` solve is made at :data:`TREE_PATCHES` patches of neighbouring vertices, its
#: seconds scaled to every vertex (``--tree-whole-up-to``).
TREE_WHOLE_UP_TO = 2_000_000
TREE_PATCHES = (10, 20_000)


def tree_solve(geometry, phi, w12, medium, sample, patches=None, reference="gpu"):
    """``solve(method="tree", tol=0.01, device="gpu")`` at every vertex (with ``patches``, ``(count, vertices)``,
    at that many patches of vertices neighbouring along the solver's order, with every stage's seconds scaled by the
    vertices over the patches' and ``"patches"`` set), timed by stage, and its per-vertex error (p99 and largest
    over the vertices of docs/physics.md §8.5) against ``exact`` on the device ``reference`` at ``sample`` (or at
    the patches' vertices)."""
    from translucency.scatter.solve import solve
    from translucency.scatter.surface import spatial_order

    n = geometry.n_vertices
    receivers, scale = None, 1.0
    if patches is not None:
        count, size = patches
        _, order, _ = spatial_order(geometry)
        first = np.linspace(0, n - size, count).astype(np.int64)
        receivers = np.sort(np.concatenate([order[k : k + size] for k in first]))
        scale = n / receivers.size
        sample = receivers[:: max(1, receivers.size // sample.size)]
    start = time.perf_counter()
    tree = solve(geometry, phi, w12, medium, method="tree", tol=0.01, device="gpu", receivers=receivers)
    seconds = (time.perf_counter() - start) * scale
    at = np.arange(n) if receivers is None else receivers
    exact = solve(geometry, phi, w12, medium, method="exact", receivers=sample, device=reference).B
    counted = exact >= 1e-4 * exact.max(axis=0)
    error = np.abs(tree.B[np.searchsorted(at, sample)] - exact)[counted] / exact[counted]
    return {
        "seconds": seconds,
        "timings": {stage: value * scale for stage, value in tree.timings.items()},
        "patches": receivers is not None,
        "evaluations_per_receiver": tree.stats["pairs_evaluated"] / at.size,
        "device": tree.stats["device"],
        "error_p99": float(np.percentile(error, 99)),
        "error_max": float(error.max()),
    }


#: The receivers that share a walk of the tree on the GPU, tried on meshes of at most GROUPS_UP_TO vertices beside the
#: package's (``gpu.tree.WalkedSums.group``).
GROUPS = (4, 16, 32)
GROUPS_UP_TO = 200_000


def tree_groups(geometry, phi, w12, medium, sample, patches=None, groups=GROUPS, reference="gpu"):
    """:func:`tree_solve` with each of ``groups`` receivers sharing a walk on the GPU, by group."""
    from translucency.scatter.gpu.tree import WalkedSums

    package = WalkedSums.group
    try:
        out = {}
        for group in groups:
            WalkedSums.group = group
            out[group] = tree_solve(geometry, phi, w12, medium, sample, patches, reference)
        return out
    finally:
        WalkedSums.group = package


def whole_solves(geometry, phi, w12, medium):
    """``solve(method="exact")`` on the GPU and on the CPU, seconds per stage and the largest relative difference."""
    from translucency.scatter.solve import solve

    out = {}
    for device in ("gpu", "cpu"):
        start = time.perf_counter()
        solution = solve(geometry, phi, w12, medium, method="exact", device=device)
        out[device] = {"seconds": time.perf_counter() - start, "timings": solution.timings, "B": solution.B}
    top = out["cpu"]["B"].max(axis=0)
    counted = out["cpu"]["B"] >= 1e-4 * top
    difference = np.abs(out["gpu"]["B"] - out["cpu"]["B"])[counted] / out["cpu"]["B"][counted]
    return {
        device: {"seconds": out[device]["seconds"], "timings": out[device]["timings"]} for device in ("gpu", "cpu")
    } | {"largest_relative_difference": float(difference.max())}


def relit_lights(points, triangles, lights: int = 5, all_pairs_up_to: float | None = None, reference="gpu"):
    """Relighting with its far field on the GPU (``solve(method="relight", device="gpu")``, tol 0.01): the
    preparation (the near field, on the CPU), then per light the seconds of its product and its per-vertex error
    against ``exact`` on the device ``reference`` (p99 over the vertices of docs/physics.md §8.5).
    ``all_pairs_up_to`` replaces ``gpu.pairs.ALL_PAIRS_UP_TO`` (every pair per light, or the tree's walk) for this
    run."""
    from translucency.scatter.gpu import pairs
    from translucency.scatter.materials import material
    from translucency.scatter.solve import solve

    if all_pairs_up_to is not None:
        pairs.ALL_PAIRS_UP_TO = all_pairs_up_to

    medium = material("marble").medium()
    rng = np.random.default_rng(3)
    rows = []
    geometry = None
    for k in range(lights + 1):
        toward = (0.35, 1.0, 0.45) if k == 0 else rng.normal(size=3)
        surface, phi, w12 = lit_surface(points, triangles, medium, toward)
        geometry = geometry or surface  # one surface: the operators are kept on it
        relit = solve(geometry, phi, w12, medium, method="relight", tol=0.01, device="gpu")
        exact = solve(geometry, phi, w12, medium, method="exact", device=reference).B
        counted = exact >= 1e-4 * exact.max(axis=0)
        error = np.abs(relit.B - exact)[counted] / exact[counted]
        rows.append(
            {
                "prepare_seconds": relit.timings.get("prepare", 0.0),
                "apply_seconds": relit.timings["apply"],
                "error_p99": float(np.percentile(error, 99)),
                "reused": relit.stats["operators_reused"],
                "near_on_gpu": bool(relit.stats.get("near_on_gpu")),
                "far_on_gpu": relit.stats.get("far_on_gpu", ""),
            }
        )
    return rows


def export_scans(folder: Path) -> int:
    """Write the default bunny and the Igea (cleaned, mm; ``bench/relight.py``'s loading) as ``.npz`` files of
    ``points`` and ``triangles`` into ``folder``, for ``--mesh`` on a machine that cannot load scans."""
    from relight import load

    folder.mkdir(parents=True, exist_ok=True)
    for scan, stem in (("bunny (default)", "default_bunny"), ("igea", "igea")):
        mesh = load(scan)
        if mesh is None:
            print(f"skipping {scan}: not in ../shared/meshes")
            continue
        np.savez(folder / f"{stem}.npz", points=np.asarray(mesh.points), triangles=np.asarray(mesh.triangles))
        print(f"wrote {folder / stem}.npz ({mesh.n_points:,} vertices)")
    return 0


def peak_of(name: str) -> float | None:
    """The FP64 peak of a device named ``name`` (:data:`FP64_PEAK`), or None."""
    return next((peak for key, peak in FP64_PEAK.items() if key in name), None)


def markdown(payload) -> str:
    """The results as bench/README.md's table."""
    device = payload["device"]
    lines = [
        f"Device: {device}; CPU: {payload['machine']['cpu']} ({payload['machine']['threads']} threads).",
        "",
        "| mesh | vertices | pairs | a light's far field on the GPU | GPU pairs/s | CPU pairs/s (every thread) "
        "| GPU/CPU | error p99 (max) vs CPU exact |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for row in payload["rows"]:
        light = f"{1e3 * row['gpu_light_seconds']:.1f} ms" + ("" if row["light_measured"] else " (from the rate)")
        lines.append(
            f"| {row['mesh']} | {row['vertices']:,} | {row['pairs']:.2e} | {light} | {row['pairs_per_second']:.2e} "
            f"| {row['cpu_pairs_per_second']:.2e} | {row['pairs_per_second'] / row['cpu_pairs_per_second']:.0f}× "
            f"| {row['error_p99']:.1e} ({row['error_max']:.1e}) |"
        )
    lines += [
        "",
        "`tree` at tol 0.01 on the GPU, every vertex (its near lists on the CPU):",
        "",
        "| mesh | vertices | whole solve | far field | near field | evaluations per receiver | p99 (max) vs exact |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for row in payload["rows"]:
        tree = row["tree"]
        for group, other in row.get("tree_groups", {}).items():
            lines.append(
                f"| {row['mesh']}, {group} receivers a walk | | {other['seconds']:.2f} s "
                f"| {other['timings'].get('far_field', 0.0):.2f} s | | {other['evaluations_per_receiver']:.0f} "
                f"| {other['error_p99']:.1e} ({other['error_max']:.1e}) |"
            )
        lines.append(
            f"| {row['mesh']} | {row['vertices']:,} | {tree['seconds']:.2f} s"
            f"{' (from patches)' if tree['patches'] else ''} "
            f"| {tree['timings'].get('far_field', 0.0):.2f} s | {tree['timings'].get('near_field', 0.0):.2f} s "
            f"| {tree['evaluations_per_receiver']:.0f} | {tree['error_p99']:.1e} ({tree['error_max']:.1e}) |"
        )
    peak = peak_of(device)
    if peak:
        best = max(row["pairs_per_second"] for row in payload["rows"])
        lines += [
            "",
            f"Best rate {best:.2e} pairs/s against an FP64 peak of {peak:.2e} FLOP/s (FP32: twice that): "
            f"{peak / best:.0f} FLOP of FP64 peak per pair.",
        ]
    solves = payload.get("whole_solves")
    if solves:
        lines += [
            "",
            f"Whole exact solve of the {payload['rows'][0]['mesh']} torus: GPU {solves['gpu']['seconds']:.2f} s "
            f"(far field {solves['gpu']['timings'].get('far_field', 0):.2f} s), CPU {solves['cpu']['seconds']:.2f} s "
            f"(far field {solves['cpu']['timings'].get('far_field', 0):.2f} s); largest relative difference "
            f"{solves['largest_relative_difference']:.1e}.",
        ]
    for run in payload.get("relit", []):
        relit = run["lights"]
        later = [row for row in relit if row["reused"]]
        lines += [
            "",
            f"Relighting the {run['mesh']} torus, far field on the GPU by {relit[0]['far_on_gpu']} (tol 0.01): "
            f"prepared in {relit[0]['prepare_seconds']:.1f} s; a later light "
            f"{1e3 * min(r['apply_seconds'] for r in later):.1f}–{1e3 * max(r['apply_seconds'] for r in later):.1f} "
            f"ms, p99 against exact {max(r['error_p99'] for r in relit):.1e} at most ({len(relit)} lights).",
        ]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a small torus in numba's CUDA simulator")
    parser.add_argument("--receivers", type=int, default=2000, help="random vertices compared with the CPU")
    parser.add_argument("--repeats", type=int, default=3, help="timed repeats of each light (the best is kept)")
    parser.add_argument("--full-seconds", type=float, default=60.0, help="longest whole light run (estimate), s")
    parser.add_argument("--mesh", action="append", default=[], help="an .npz of points (mm) and triangles")
    parser.add_argument("--sizes", type=int, default=len(TORI), help="how many of the tori, smallest first")
    parser.add_argument("--export", metavar="FOLDER", help="write the default bunny and the Igea as .npz to carry")
    parser.add_argument(
        "--tree-whole-up-to", type=int, default=TREE_WHOLE_UP_TO, help="largest mesh tree solves whole (else patches)"
    )
    args = parser.parse_args(argv)
    args.tree_patches, args.groups, args.lights, args.reference = TREE_PATCHES, GROUPS, 5, "gpu"
    if args.export:
        return export_scans(Path(args.export))
    if args.quick:  # before numba.cuda is imported (on a GPU machine, --sizes 1 is the short run on the GPU)
        os.environ["NUMBA_ENABLE_CUDASIM"] = "1"
        args.receivers, args.repeats = min(args.receivers, 40), 1
        args.tree_whole_up_to, args.tree_patches = 100, (3, 20)  # the small torus's tree solve by patches, as 10M's
        # the simulator makes every point in Python: each path once, exact's references on the CPU
        args.groups, args.lights, args.reference = GROUPS[-1:], 1, "cpu"
    from translucency.scatter.gpu.probe import gpu_status

    status = gpu_status()
    if not status.usable:
        print(f"no GPU: {status.reason}", file=sys.stderr)
        return 1
    meshes = [(label, *torus_mesh(a, b)) for label, a, b in (QUICK_TORI if args.quick else TORI[: args.sizes])]
    for path in args.mesh:  # after the tori: the whole solves and relighting run on the first torus
        data = np.load(path)
        meshes.append((Path(path).stem, np.asarray(data["points"], float), np.asarray(data["triangles"])))
    payload = {"machine": machine_info(), "device": status.name, "rows": []}
    rate = None
    for k, (label, points, triangles) in enumerate(meshes):
        row, geometry, phi, w12, medium, rate = measure(label, points, triangles, args, rate)
        payload["rows"].append(row)
        print(f"{label}: {row}", flush=True)
        if k == 0:
            payload["whole_solves"] = whole_solves(geometry, phi, w12, medium)
        if k < 2:  # the bunny-sized torus both ways, the Igea-sized by the tree's walk
            for limit in (float("inf"), 0.0) if k == 0 else (0.0,):
                lights = relit_lights(points, triangles, args.lights, limit, args.reference)
                payload.setdefault("relit", []).append({"mesh": label, "lights": lights})
    table = markdown(payload)
    write_results(output_dir(args.quick), "gpu", payload, table)
    print(table)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
