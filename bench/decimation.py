"""The proxy's decimation of a large scan: the whole mesh in one pass against parts side by side.

fast-simplification runs on one core. From :data:`translucency.io.decimate.PART_TRIANGLES` triangles per
core on, :func:`translucency.io.decimate.simplify_arrays` cuts the mesh into slabs decimated in child
processes side by side (their cuts kept), welds them and decimates the whole once more. This script
decimates the same scan-like mesh both ways, to about a ninth of its triangles (the 10M bake's proxy keeps
1.1M of 10M vertices), and reports for each:

- the wall time of the decimation and the summed resident set of its processes at their peak (the calling
  process, which holds the mesh, and the children; sampled every 0.2 s);
- how close the proxy is to the mesh: the distance of every mesh vertex to the proxy surface (mean, 99th
  percentile, largest; mm and in mean edges of the mesh), the proxy's open and non-manifold edges, its
  triangles that face against the mesh vertices that map onto them, and the 1st percentile of its smallest
  angles.

The meshes are the scaling benchmark's (the Igea subdivided, with noise: ``bench/scaling.py``).

    .venv/bin/python bench/decimation.py               # 10M vertices (about 6 min on 2 cores)
    .venv/bin/python bench/decimation.py --sizes 2.1M  # another size of the scaling table
    .venv/bin/python bench/decimation.py --quick       # 537k, parts forced down to 250k triangles

Writes ``decimation.json`` and ``decimation.md`` into ``bench/results`` (``bench/results/tmp`` with
``--quick``).
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np
from report import machine_info, output_dir, write_results
from scaling import MESHES, SCANS, TreePeak, build_mesh
from solver import prepare

#: The proxy keeps this share of the mesh's triangles.
TARGET_SHARE = 1 / 9
#: The two ways a mesh is decimated: in one pass, and in parts side by side.
WAYS = ("whole", "in parts")


def proxy_quality(points, triangles, proxy_points, proxy_triangles) -> dict:
    """How close the proxy is to the mesh, and how well formed (module docstring)."""
    from translucency.geometry.measure import mean_edge_length, triangle_normals, vertex_normals
    from translucency.geometry.topology import unique_edges
    from translucency.io.decimate import map_to_proxy

    mapping = map_to_proxy(points, proxy_points, proxy_triangles)
    edge = mean_edge_length(points, triangles)
    _, edge_of_corner = unique_edges(proxy_triangles)
    uses = np.bincount(edge_of_corner.ravel())
    facing = np.zeros((len(proxy_triangles), 3))
    np.add.at(facing, mapping.triangle_index, vertex_normals(points, triangles))
    mapped = np.bincount(mapping.triangle_index, minlength=len(proxy_triangles)) > 0
    against = mapped & (np.einsum("ij,ij->i", triangle_normals(proxy_points, proxy_triangles), facing) < 0)
    corners = proxy_points[proxy_triangles]
    angles = []
    for k in range(3):
        u = corners[:, (k + 1) % 3] - corners[:, k]
        v = corners[:, (k + 2) % 3] - corners[:, k]
        cosine = np.einsum("ij,ij->i", u, v) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1))
        angles.append(np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0))))
    distance = mapping.distance
    return {
        "proxy_vertices": int(len(proxy_points)),
        "proxy_triangles": int(len(proxy_triangles)),
        "mean_edge_mm": edge,
        "distance_mean_mm": float(distance.mean()),
        "distance_p99_mm": float(np.percentile(distance, 99)),
        "distance_max_mm": float(distance.max()),
        "open_edges": int(np.count_nonzero(uses == 1)),
        "non_manifold_edges": int(np.count_nonzero(uses > 2)),
        "edges": int(uses.size),
        "triangles_against_the_mesh": int(np.count_nonzero(against)),
        "smallest_angle_p1_deg": float(np.percentile(np.min(angles, axis=0), 1)),
    }


def decimate_both_ways(points, triangles) -> dict:
    """The mesh decimated whole and in parts: each way's time, peak memory and :func:`proxy_quality`."""
    from translucency.io import decimate

    target = int(len(triangles) * TARGET_SHARE)
    record = {"target_triangles": target, "part_count": decimate.decimation_parts(len(triangles))}
    default_parts = decimate.decimation_parts
    for way in WAYS:
        decimate.decimation_parts = (lambda n: 1) if way == "whole" else default_parts
        try:
            with TreePeak() as tree:
                start = time.perf_counter()
                proxy_points, proxy_triangles = decimate.simplify_arrays(points, triangles, target)
                seconds = time.perf_counter() - start
        finally:
            decimate.decimation_parts = default_parts
        record[way] = {
            "seconds": seconds,
            "peak_rss_tree_mb": tree.peak_mb,
            **proxy_quality(points, triangles, proxy_points, proxy_triangles),
        }
        print(f"  {way}: {seconds:.1f} s, {tree.peak_mb / 1024:.2f} GB", flush=True)
    return record


def markdown(rows) -> str:
    """One row per (size, way), and the parts' time as a share of the whole pass's."""
    lines = [
        "| mesh | triangles | way | parts | time (s) | peak RSS of its processes (GB) | distance mean / p99 / max "
        "(mean edges) | open / non-manifold edges | triangles facing against the mesh | smallest angle, 1st "
        "percentile (°) | proxy vertices |",
        "|---|---:|---|---:|---:|---:|---|---|---:|---:|---:|",
    ]
    for row in rows:
        for way in WAYS:
            r, edge = row[way], row[way]["mean_edge_mm"]
            lines.append(
                f"| {row['label']} | {row['triangles']:,} | {way} | {1 if way == 'whole' else row['part_count']} | "
                f"{r['seconds']:.1f} | {r['peak_rss_tree_mb'] / 1024:.2f} | {r['distance_mean_mm'] / edge:.3f} / "
                f"{r['distance_p99_mm'] / edge:.3f} / {r['distance_max_mm'] / edge:.3f} | {r['open_edges']} / "
                f"{r['non_manifold_edges']} | {r['triangles_against_the_mesh']} | {r['smallest_angle_p1_deg']:.2f} | "
                f"{r['proxy_vertices']:,} |"
            )
    lines.append("")
    lines.append(
        "Time of the parts as a share of the whole pass: "
        + "; ".join(f"{row['label']} {row['in parts']['seconds'] / row['whole']['seconds']:.2f}" for row in rows)
        + " (measured one after the other in one run)."
    )
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", nargs="+", default=None, help="sizes of bench/scaling.py (default 10M)")
    parser.add_argument("--quick", action="store_true", help="537k with parts forced down to 250k triangles")
    args = parser.parse_args(argv)
    if not (MESHES / SCANS["igea"][0]).exists():
        print(f"the shared Igea ({SCANS['igea'][0]} in ../shared/meshes) is not present; nothing to benchmark")
        return 0
    if args.quick:
        from translucency.io import decimate

        decimate.PART_TRIANGLES = 250_000
    labels = args.sizes or (["537k"] if args.quick else ["10M"])
    info = machine_info()
    igea, _ = prepare("igea")
    rows = []
    for label in labels:
        points, triangles, how = build_mesh(label, igea)
        print(f"{label}: {len(points)} vertices ({how})", flush=True)
        rows.append({"label": label, "how": how, "vertices": len(points), "triangles": len(triangles)})
        rows[-1].update(decimate_both_ways(points, triangles))
        del points, triangles
    write_results(output_dir(args.quick), "decimation", {"info": info, "rows": rows}, markdown(rows))
    print(markdown(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
