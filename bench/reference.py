"""The models against the path-traced reference: time against error by region, and the tracer's own.

For the shared Stanford bunny (``../shared/meshes/stanford_bunny_zipper.ply``, metres; skipped when
absent) and a 20 mm icosphere (10,242 vertices), both in marble under one directional light:

1. the path-traced reference at every vertex (docs/physics.md §9.5), kept in ``bench/results/tmp`` and
   reused by later runs (``--retrace`` traces again), with its time and noise: the median per-vertex
   relative standard error and the standard error of each region's mean;
2. every model x method/tolerance x bounces, warm (the scene, Embree and visibility reused), timed, with
   the ratio of the model's mean radiance toward the normal to the reference's in each region of the
   light's cosine ``c = n . w_L`` (lit ``c > 0.2``, grazing ``0 < c <= 0.2`` and lit, shadowed: ``c > 0``
   with no direct light, and the far side ``[-0.3, 0)``, ``[-0.6, -0.3)``, ``[-1, -0.6)``), and the worst
   ``|ratio - 1|`` over regions and channels.

Results: ``bench/results/reference.json`` and ``.md``; the table in bench/README.md ("Against the
path-traced reference").

    python bench/reference.py [--spp-bunny 8] [--spp-sphere 16] [--retrace] [--quick]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np  # noqa: E402
from report import RESULTS, load_average, machine_info, output_dir, update_readme, write_results  # noqa: E402

SHARED_BUNNY = Path(__file__).resolve().parents[2] / "shared" / "meshes" / "stanford_bunny_zipper.ply"
#: A region with fewer vertices is left out of the table (a sphere has no cast shadow).
MIN_VERTICES = 20
SETTINGS = (("exact", None), ("cutoff", 1e-2), ("tree", 1e-2), ("tree", 1e-3))
MODELS = ("directional", "better", "standard")
LIGHT = np.array([0.35, 1.0, 0.45])


def scans(quick: bool):
    """``(name, mesh)`` of the benchmark's scans (the shared bunny only when present)."""
    from translucency.app.shading.scan import load_scan
    from translucency.geometry.mesh import TriangleMesh
    from translucency.geometry.synthetic import icosphere

    points, triangles = icosphere(3 if quick else 5, radius=20.0)
    out = [("sphere 20 mm", TriangleMesh(points, triangles))]
    if SHARED_BUNNY.is_file() and not quick:
        out.insert(0, ("bunny", load_scan(SHARED_BUNNY)[0]))
    return out


def traced(name, mesh, spp, retrace, cache: Path):
    """The reference of one scan (read from the cache when there), with its time."""
    from translucency.app.ground_truth import trace_reference, write_reference
    from translucency.io.reference_file import read_reference_file

    path = cache / f"reference_{name.split()[0]}_spp{spp}.npz"
    if path.is_file() and not retrace:
        return read_reference_file(path)
    start = time.perf_counter()
    truth = trace_reference(
        mesh, "marble", LIGHT, spp=spp, progress=lambda f, line: print(f"  {name}: {line}", flush=True)
    )
    print(f"  {name}: traced in {time.perf_counter() - start:.0f} s", flush=True)
    write_reference(truth, path)
    return read_reference_file(path)


def by_region(rows, key):
    """``{region: [R, G, B]}`` of one column of :func:`region_rows`' rows."""
    out = {}
    for row in rows:
        out.setdefault(row["region"], []).append(row[key])
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spp-bunny", type=int, default=8)
    parser.add_argument("--spp-sphere", type=int, default=16)
    parser.add_argument("--retrace", action="store_true")
    parser.add_argument("--quick", action="store_true", help="a small sphere only, results in bench/results/tmp")
    args = parser.parse_args()

    from translucency.app.reference_compare import REGIONS, assign_regions, region_rows
    from translucency.app.shading.scene import Scene
    from translucency.scatter.lights import DirectionalLight

    info = machine_info()
    out = output_dir(args.quick)
    cache = RESULTS / "tmp"
    cache.mkdir(parents=True, exist_ok=True)
    w_light = LIGHT / np.linalg.norm(LIGHT)
    payload = {"info": info, "light_direction": w_light.tolist(), "material": "marble", "scans": []}
    lines = []
    for name, mesh in scans(args.quick):
        spp = args.spp_sphere if name.startswith("sphere") else args.spp_bunny
        ref = traced(name, mesh, spp, args.retrace, cache)
        scene = Scene(mesh)
        light = DirectionalLight(w_light, 1.0)
        scene.shade("marble", light, bounces=0)  # compiles, builds the scene and its caches
        first = scene.shade("marble", light, bounces=0)
        regions = assign_regions(ref.normals, w_light, first.incident_flux.sum(axis=1) > 0)
        base = region_rows("-", first.radiance, ref, regions, 0.0)
        counts = {row["region"]: row["n_vertices"] for row in base}
        names = [r for r, _ in REGIONS if counts[r] >= MIN_VERTICES]
        ratio_se = by_region(base, "ratio_stderr")
        ratio = by_region(base, "ratio")
        noise = ref.radiance_stderr / np.where(ref.radiance > 0, ref.radiance, np.nan)
        entry = {
            "scan": name,
            "vertices": int(mesh.n_points),
            "regions": names,
            "reference": {
                "spp": int(ref.metadata["spp"]),
                "seconds": float(ref.metadata["seconds"]),
                "median_relative_stderr_per_vertex": float(np.nanmedian(noise)),
                "region_vertices": {r: int(counts[r]) for r in names},
                "region_relative_stderr": {r: [s / q for s, q in zip(ratio_se[r], ratio[r])] for r in names},
                "reentered_share": {r: by_region(base, "reentered_share")[r] for r in names},
            },
            "rows": [],
        }
        print(
            f"{name}: {mesh.n_points} vertices; reference {entry['reference']['spp']} paths per vertex in "
            f"{entry['reference']['seconds']:.0f} s, median error per vertex "
            f"{100 * entry['reference']['median_relative_stderr_per_vertex']:.0f} %",
            flush=True,
        )
        for model in MODELS:
            for method, tol in SETTINGS:
                for bounces in (0, 1):
                    kwargs = {"model": model, "method": method, "bounces": bounces}
                    if tol is not None:
                        kwargs["tol"] = tol
                    start = time.perf_counter()
                    result = scene.shade("marble", light, **kwargs)
                    seconds = time.perf_counter() - start
                    ratio = by_region(region_rows(model, result.radiance, ref, regions, seconds), "ratio")
                    ratio = {r: ratio[r] for r in names}
                    worst = max(abs(v - 1.0) for r in names for v in ratio[r])
                    entry["rows"].append(
                        {
                            "model": model,
                            "method": method,
                            "tol": tol,
                            "bounces": bounces,
                            "seconds": seconds,
                            "ratio": ratio,
                            "worst": worst,
                            "load": load_average()[0],
                        }
                    )
                    print(
                        f"  {model:11s} {method:6s} {tol or '':>6} b{bounces} {seconds:6.2f} s  "
                        + "  ".join(f"{np.mean(ratio[r]):.2f}" for r in names)
                        + f"  worst {worst:.2f}",
                        flush=True,
                    )
        payload["scans"].append(entry)
        lines.extend(table(entry))
    text = "\n".join(lines)
    write_results(out, "reference", payload, text)
    if not args.quick:
        update_readme({"reference-table": text})
    print(text)


def _cell(values) -> str:
    """``"0.94–0.97"`` over the channels, one number when they agree to 0.005, ``"–"`` for no region."""
    if values is None:
        return "–"
    low, high = min(values), max(values)
    return f"{low:.2f}" if high - low < 0.005 else f"{low:.2f}–{high:.2f}"


def table(entry) -> list[str]:
    """The Markdown rows of one scan: model/reference per region (the mean over channels, range in the
    notes), time and the worst deviation."""
    ref = entry["reference"]
    head = (
        f"**{entry['scan']}** ({entry['vertices']:,} vertices): reference {ref['spp']} paths per vertex and channel in "
        f"{ref['seconds']:.0f} s, median error per vertex {100 * ref['median_relative_stderr_per_vertex']:.0f} %; "
        "error of the region means "
        + ", ".join(f"{r} {100 * max(v):.1f} %" for r, v in ref["region_relative_stderr"].items())
        + "; re-entered share of the reference "
        + ", ".join(f"{r} {min(v):.2f}–{max(v):.2f}" for r, v in ref["reentered_share"].items())
    )
    rows = [
        "",
        head,
        "",
        "| model | method | tol | bounces | s | " + " | ".join(entry["regions"]) + " | worst |",
        "|---|---|---|---|---|" + "---|" * len(entry["regions"]) + "---|",
    ]
    for row in entry["rows"]:
        cells = [_cell(row["ratio"].get(r)) for r in entry["regions"]]
        rows.append(
            f"| {row['model']} | {row['method']} | {row['tol'] or ''} | {row['bounces']} | {row['seconds']:.2f} | "
            + " | ".join(cells)
            + f" | {row['worst']:.2f} |"
        )
    return rows


if __name__ == "__main__":
    main()
