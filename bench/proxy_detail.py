"""Where a proxy's error comes from, and what a local correction at full resolution buys.

For each shared scan (bunny, horse, Igea) and material (marble, skim milk), one directional light with
Embree shadows, no bounce, ``tree`` at 1 %: the full-resolution solve is the reference, and on the
proxy of the light's detail (:func:`~translucency.app.shading.resolution.proxy_edge_length`, what ``resolution="auto"``
takes at a tolerance of about 0.5; a 2 mm one where that keeps every vertex; ``B`` solved on the decimated
mesh and interpolated back) the per-vertex
figure that ``tol`` bounds (docs/physics.md §8.5: 99th percentile of ``|B - B_full| / B_full`` over the
(vertex, channel) pairs with ``B_full`` at least 1e-4 of the channel's largest), split into

* **lit** vertices (light enters there) and **unlit** ones (all their ``B`` comes from elsewhere);
* the proxy solved with its **own light** (traced at its own vertices, with its own normals and shadows) and with
  the full mesh's light **carried** onto its vertices with the flux kept (docs/physics.md §8.6); the pipeline
  carries it onto a proxy finer than a tenth of a diffusion length (``carries_full_light``), and the rest of the
  row is of the light it uses; a finer proxy of the Igea (0.5 mm) besides;
* the **flux part**: the full solve fed the proxy's incident flux interpolated to every vertex, against
  the full solve (the shadow edges and the fine relief the proxy's flux misses), and the **transport
  part**: the proxy's ``B`` against that same solve (the proxy's coarser surface and normals);
* the share of vertices whose flux density differs from the proxy's interpolated one by more than 1 %
  of the largest (where a correction of the flux would have to act);
* the proxy's ``B`` carried to every vertex **log-linearly** (:func:`log_linear`) instead of linearly: past a
  shadow edge ``B`` falls as ``exp(-sigma_tr d)``, which that interpolation follows exactly.

Then the **local correction** (docs/physics.md §8.8): ``B = interp(B_proxy) + L_full - interp(L_proxy)``
with ``L`` the local part of ``B`` from the sources within a reach ``rho`` of each receiver
(:func:`translucency.scatter.solve.solve` with ``reach_mm``), computed on the full mesh with its own flux
and on the proxy with the proxy's; at ``rho`` = the smallest reach both meshes allow, and twice that.
Every time is the wall time of one warm call, side by side in one run, with the load. Written to
``bench/results/proxy_detail.json`` and ``.md``.

    .venv/bin/python bench/proxy_detail.py             # about 7 min on 2 cores
    .venv/bin/python bench/proxy_detail.py --scans bunny --materials marble
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
from solver import LIGHT, SCANS, detail_resolution, per_vertex_error, prepare, present_scans  # noqa: E402

from translucency import __version__  # noqa: E402,F401  (first: it selects numba's threading layer)
from translucency.app.shading.resolution import carries_full_light  # noqa: E402
from translucency.app.shading.scene import Scene  # noqa: E402
from translucency.scatter.materials import material  # noqa: E402
from translucency.scatter.solve import TOL_FLOOR, local_reach_floor, solve  # noqa: E402

RESULTS = ROOT / "bench" / "results"
METHOD, TOL = "tree", 0.01
MATERIALS = ("marble", "skim_milk")
#: The proxy of the light's detail ("detail": proxy_edge_length), and a 2 mm one where it keeps every vertex (the
#: bunny in marble).
RESOLUTIONS = ("detail", 2.0)
#: A finer proxy besides, where the full mesh's light is near being carried onto it (max σ_tr h = 0.13 in marble).
FINE_RESOLUTIONS = {"igea": 0.5}
#: Flux density differences above this fraction of the largest count as "needing a correction".
FLUX_SHARE = 0.01


def timed(fn):
    """``(result, seconds)`` of one call."""
    start = time.perf_counter()
    result = fn()
    return result, time.perf_counter() - start


#: Floor of the log-linear interpolation, relative to each channel's largest value on the proxy.
LOG_FLOOR = 1e-12


def log_linear(mapping, values):
    """``values (n_proxy, C) >= 0`` carried to the full mesh linearly in their logarithm: ``prod_i v_i^(w_i)``
    with the mapping's barycentric weights (exact for a value that falls exponentially across a triangle, as
    ``B`` past a shadow edge does; a one-hot weight reproduces the vertex's value). Values are floored at
    :data:`LOG_FLOOR` of each channel's largest."""
    values = np.maximum(values, LOG_FLOOR * values.max(axis=0))
    rows = np.arange(mapping.weights.shape[0])
    base = mapping.vertex_index[rows, np.argmax(mapping.weights, axis=1)]  # the heaviest corner: v^0 == 1 exactly
    out = values[base].copy()
    for i in range(3):
        out *= (values[mapping.vertex_index[:, i]] / values[base]) ** mapping.weights[:, i, None]
    return out


def split_errors(B, reference, lit):
    """The per-vertex figure over all, lit and unlit vertices (``lit``: (n, C) bool), and the rel RMS."""
    figures = {"p99": per_vertex_error(B, reference)}
    for name, keep in (("p99_lit", lit), ("p99_unlit", ~lit)):
        # the floor stays TOL_FLOOR of each channel's largest over every vertex, as in the whole figure
        floor = TOL_FLOOR * reference.max(axis=0)
        rel = [
            np.abs(B[k, c] - reference[k, c]) / reference[k, c]
            for c in range(reference.shape[1])
            for k in [keep[:, c] & (reference[:, c] >= floor[c]) & (reference[:, c] > 0)]
        ]
        rel = np.concatenate(rel)
        figures[name] = float(np.percentile(rel, 99)) if rel.size else 0.0
    figures["rms"] = float(np.linalg.norm(B - reference) / np.linalg.norm(reference))
    return figures


def measure(scan: str, name: str, resolution) -> dict | None:
    """One scan, material and proxy resolution: the reference, the proxy, its error parts and the local
    correction; None when the resolution keeps the full mesh."""
    mesh, _ = prepare(scan)
    medium = material(name).medium()
    scene = Scene(mesh)
    label, resolution = resolution, detail_resolution(scene, medium) if resolution == "detail" else resolution
    if scene.solver_mesh(medium, resolution)[1] is None:
        print(f"{scan}, {name}: resolution {resolution!r} keeps the full mesh")
        return None

    def shade(resolution):
        return scene.shade(medium, LIGHT, method=METHOD, tol=TOL, resolution=resolution, bounces=0)

    shade("full"), shade(resolution)  # compilation, geometry caches, Embree scenes, the proxy's decimation
    full, full_seconds = timed(lambda: shade("full"))
    proxy, proxy_seconds = timed(lambda: shade(resolution))
    incident, _ = scene.light_cache.incident_on_mesh(medium, [LIGHT])
    _, _, _, geometry, _ = scene.solver_mesh(medium, "full")
    proxy_mesh, decimation, edge, proxy_geometry, _ = scene.solver_mesh(medium, resolution)
    lit = incident.phi_rgb > 0
    carried = carries_full_light(medium, edge)
    proxy_light, _ = scene.light_cache.solver_light(
        proxy_geometry, proxy_mesh, decimation if carried else None, [LIGHT], medium.eta
    )
    other_light, _ = scene.light_cache.solver_light(
        proxy_geometry, proxy_mesh, None if carried else decimation, [LIGHT], medium.eta
    )
    other = solve(proxy_geometry, other_light.phi_rgb, other_light.w12, medium, method=METHOD, tol=TOL).B
    other = split_errors(np.maximum(decimation.interpolate(other), 0.0), full.B, lit)
    seen = decimation.interpolate(proxy_light.phi_rgb)  # the proxy's flux density interpolated to every vertex
    fed, fed_seconds = timed(lambda: solve(geometry, seen, incident.w12, medium, method=METHOD, tol=TOL).B)
    on_proxy = solve(proxy_geometry, proxy_light.phi_rgb, proxy_light.w12, medium, method=METHOD, tol=TOL).B
    differs = np.abs(incident.phi_rgb - seen).max(axis=1) > FLUX_SHARE * incident.phi_rgb.max()
    row = {
        "scan": scan,
        "material": name,
        "resolution": label,
        "vertices": mesh.n_points,
        "proxy_vertices": proxy_mesh.n_points,
        "proxy_edge_mm": edge,
        "sigma_tr_per_mm": medium.sigma_tr.tolist(),
        "sigma_tr_times_edge": float(medium.sigma_tr.max() * edge),
        "full_seconds": full_seconds,
        "proxy_seconds": proxy_seconds,
        "light": "carried" if carried else "own",
        "proxy": split_errors(proxy.B, full.B, lit),
        "proxy_own_light": other if carried else split_errors(proxy.B, full.B, lit),
        "proxy_carried_light": split_errors(proxy.B, full.B, lit) if carried else other,
        "proxy_log_linear": split_errors(log_linear(decimation.mapping, on_proxy), full.B, lit),
        "flux_part_p99": per_vertex_error(fed, full.B),
        "transport_part_p99": per_vertex_error(proxy.B, fed),
        "flux_differs_share": float(differs.mean()),
        "load": os.getloadavg()[0],
        "local": [],
    }
    floor = max(local_reach_floor(geometry, medium, 1e-3), local_reach_floor(proxy_geometry, medium, 1e-3))
    for reach in (floor, 2.0 * floor):
        local_full, full_local_seconds = timed(
            lambda reach=reach: (
                solve(geometry, incident.phi_rgb, incident.w12, medium, method="cutoff", reach_mm=reach).B
            )
        )
        local_proxy, proxy_local_seconds = timed(
            lambda reach=reach: (
                solve(proxy_geometry, proxy_light.phi_rgb, proxy_light.w12, medium, method="cutoff", reach_mm=reach).B
            )
        )
        corrected = np.maximum(proxy.B + local_full - decimation.interpolate(local_proxy), 0.0)
        row["local"].append(
            {
                "reach_mm": reach,
                "seconds": full_local_seconds + proxy_local_seconds,
                "full_local_seconds": full_local_seconds,
                **split_errors(corrected, full.B, lit),
            }
        )
    print(json.dumps({k: v for k, v in row.items() if k != "sigma_tr_per_mm"}))
    return row


def markdown(rows) -> str:
    """The table of bench/README.md's "Proxy error, measured apart"."""
    lines = [
        "| scan, material | vertices (proxy) | σ_tr h | full solve | proxy: time, p99 (lit / unlit), rms "
        "| its own light / the full mesh's carried: p99 (lit / unlit), rms "
        "| log-linear interpolation: p99 (lit / unlit), rms | flux part / transport part | flux differs "
        "| local correction ρ: time, p99 (lit / unlit), rms |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        p, g, o, c = r["proxy"], r["proxy_log_linear"], r["proxy_own_light"], r["proxy_carried_light"]
        mark = {"own": (" (used)", ""), "carried": ("", " (used)")}[r["light"]]
        local = "<br>".join(
            f"{c['reach_mm']:.1f} mm: +{c['seconds']:.1f} s, {c['p99']:.0%} ({c['p99_lit']:.1%} / "
            f"{c['p99_unlit']:.0%}), {c['rms']:.2%}"
            for c in r["local"]
        )
        lines.append(
            f"| {r['scan']}, {r['material'].replace('_', ' ')} | {r['vertices']:,} ({r['proxy_vertices']:,}, "
            f"{r['resolution'] if r['resolution'] == 'detail' else str(r['resolution']) + ' mm'}) | "
            f"{r['sigma_tr_times_edge']:.2f} | {r['full_seconds']:.1f} s | {r['proxy_seconds']:.1f} s, "
            f"{p['p99']:.0%} ({p['p99_lit']:.0%} / {p['p99_unlit']:.0%}), {p['rms']:.2%} | "
            f"{o['p99']:.1%} ({o['p99_lit']:.1%} / {o['p99_unlit']:.1%}), {o['rms']:.2%}{mark[0]}<br>"
            f"{c['p99']:.1%} ({c['p99_lit']:.1%} / {c['p99_unlit']:.1%}), {c['rms']:.2%}{mark[1]} | "
            f"{g['p99']:.0%} ({g['p99_lit']:.0%} / {g['p99_unlit']:.0%}), {g['rms']:.2%} | "
            f"{r['flux_part_p99']:.0%} / {r['transport_part_p99']:.0%} | {r['flux_differs_share']:.0%} | {local} |"
        )
    return "\n".join(lines) + "\n"


def main() -> None:
    """Measure every scan and material asked for, write the JSON and the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scans", nargs="+", choices=list(SCANS), default=list(SCANS))
    parser.add_argument("--materials", nargs="+", default=list(MATERIALS))
    args = parser.parse_args()
    rows = []
    for scan in present_scans(args.scans):
        for name in args.materials:
            for resolution in RESOLUTIONS:
                row = measure(scan, name, resolution)
                if row is not None:
                    rows.append(row)
                    break
            if scan in FINE_RESOLUTIONS and (row := measure(scan, name, FINE_RESOLUTIONS[scan])) is not None:
                rows.append(row)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "proxy_detail.json").write_text(json.dumps(rows, indent=1))
    (RESULTS / "proxy_detail.md").write_text(markdown(rows))
    print(markdown(rows))


if __name__ == "__main__":
    main()
