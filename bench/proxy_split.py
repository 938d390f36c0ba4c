"""Where the fine proxy's per-vertex error comes from, on the 2.1M-vertex Igea of the scaling benchmark.

The 2.1M mesh of ``bench/scaling.py`` (the Igea subdivided twice, with scan-like noise) is baked with the defaults
and no bounce: the plan at full resolution is over the time limit, so the pipeline solves it on a proxy of about
half its vertices, given the light traced at every vertex of the full mesh with shadows against the proxy
(docs/physics.md §8.6). At 2000 random vertices every row below is ``exact`` (no far-field tolerance) and compared
with ``exact`` on the full mesh with its own light (the reference; shadows from the full mesh), by the figure
``tol`` bounds (docs/physics.md §8.5: 99th percentile of the relative error over the (vertex, channel) pairs with
the reference at least 1e-4 of its channel's largest), with the 90th percentile, the median and the mean signed
error beside it. One thing of the proxy is given to the full solve at a time:

* the **shadows** the proxy casts (the light the bake traces, on the full mesh's own surface);
* the **sources' positions** moved onto the proxy's surface (each full vertex to its closest proxy point; the
  receivers stay where they are), then the proxy's **normals** at the sources too;
* the **refracted direction** smoothed through the proxy (the proxy's flux-weighted mean, interpolated back);
* the **flux density** smoothed through the proxy: the flux gathered onto the proxy's vertices over the full
  mesh's area gathered the same way, interpolated back (the proxy's light as a field over the surface);
* the full solve's own **convergence**: its near field (docs/physics.md §8.2) twice and three times as wide;
* the proxy's solve with its near field twice as wide (its ``B`` evaluated at each full vertex itself);
* the **local correction** of docs/physics.md §8.8, ``interp(B_proxy) + L_full - interp(L_proxy)`` at the
  smallest reach both meshes allow, with its cost at every vertex (each local part solved once over the whole
  mesh, in the solver's spatial order).

Written to ``bench/results/proxy_split.json`` and ``.md``. About 10 min on 2 cores; the shared Igea is needed.

    .venv/bin/python bench/proxy_split.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
from report import RESULTS, load_average, machine_info, write_results  # noqa: E402
from scaling import build_mesh  # noqa: E402
from solver import MESHES, SCANS, TOL_FLOOR, prepare  # noqa: E402

from translucency import __version__  # noqa: E402,F401  (first: it selects numba's threading layer)
from translucency.app.shading.scene import Scene  # noqa: E402
from translucency.app.shading.settings import DEFAULT_MATERIAL, default_light_direction, resolve_medium  # noqa: E402
from translucency.geometry.mesh import TriangleMesh  # noqa: E402
from translucency.io.clean import clean_mesh  # noqa: E402
from translucency.scatter import solve as solver  # noqa: E402
from translucency.scatter.lights import DirectionalLight  # noqa: E402

RECEIVERS = 2000


def figures(B, reference):
    """p99, p90, median and mean signed relative error over the pairs with the reference >= TOL_FLOOR of its
    channel's largest (docs/physics.md §8.5)."""
    keep = reference >= TOL_FLOOR * reference.max(axis=0)
    signed = (B[keep] - reference[keep]) / reference[keep]
    relative = np.abs(signed)
    return {
        "p99": float(np.percentile(relative, 99)),
        "p90": float(np.percentile(relative, 90)),
        "median": float(np.median(relative)),
        "mean_signed": float(signed.mean()),
    }


def exact(geometry, phi, w12, medium, receivers, **kw):
    """``exact`` at ``receivers`` (``method="cutoff"`` with ``reach_mm`` for a local part)."""
    return solver.solve(geometry, phi, w12, medium, method=kw.pop("method", "exact"), receivers=receivers, **kw).B


def with_near_field(edges, mean_free_paths, fn):
    """``fn()`` with the near field's radius set to ``max(edges mean edges, mean_free_paths / min sigma_t')``."""
    saved = solver.NEAR_EDGES, solver.NEAR_MEAN_FREE_PATHS
    solver.NEAR_EDGES, solver.NEAR_MEAN_FREE_PATHS = edges, mean_free_paths
    try:
        return fn()
    finally:
        solver.NEAR_EDGES, solver.NEAR_MEAN_FREE_PATHS = saved


def measure() -> dict:
    """Every row of the module docstring on the 2.1M mesh."""
    start = time.perf_counter()
    igea, _ = prepare("igea")
    points, triangles, how = build_mesh("2.1M", igea)
    mesh, _ = clean_mesh(TriangleMesh(points, triangles))
    n = mesh.n_points
    receivers = np.sort(np.random.default_rng(0).choice(n, RECEIVERS, replace=False))
    scene = Scene(mesh)
    medium = resolve_medium(DEFAULT_MATERIAL)
    lights = [DirectionalLight(default_light_direction(scene.up), 1.0)]
    t = time.perf_counter()
    baked = scene.shade(warn=lambda line: None, bounces=0)
    bake_seconds = time.perf_counter() - t
    # the proxy the bake chose (over the time limit at full resolution), from the Scene's cache
    proxy, decimation, _, geometry = next(v for v in scene._solver_meshes.values() if v[1] is not None)
    mapping = decimation.mapping
    carried, _ = scene.light_cache.solver_light(geometry, proxy, decimation, lights, medium.eta)
    traced, _ = scene.light_cache.full_light_for_proxy(geometry, proxy, decimation, lights, medium.eta)
    own, _ = scene.light_cache.incident_on_mesh(medium, lights)
    normals = mesh.vertex_normals()
    full = solver.SurfaceGeometry(mesh.points, mesh.triangles, normals)
    reference = exact(full, own.phi_rgb, own.w12, medium, receivers)
    rows = [("the bake (`tree` on the proxy, interpolated)", baked.B[receivers])]
    shadowed = exact(full, traced.phi_rgb, traced.w12, medium, receivers)
    rows.append(("full solve, the proxy's shadows", shadowed))

    def appended(source_points, source_normals, phi, w12):
        # the receivers appended at their own place and normal, as sources of no flux
        geometry_ = solver.SurfaceGeometry(
            np.vstack([source_points, mesh.points[receivers]]),
            mesh.triangles,
            np.vstack([source_normals, normals[receivers]]),
        )
        phi_ = np.vstack([phi, np.zeros((receivers.size, 3))])
        w12_ = np.vstack([w12, -normals[receivers]])
        return exact(geometry_, phi_, w12_, medium, np.arange(n, n + receivers.size))

    on_proxy = mapping.interpolate(geometry.points)
    rows.append(("+ sources moved onto the proxy's surface", appended(on_proxy, normals, traced.phi_rgb, traced.w12)))
    proxy_normals = mapping.interpolate(geometry.normals)
    proxy_normals /= np.linalg.norm(proxy_normals, axis=1, keepdims=True)
    rows.append(("+ the proxy's normals at the sources", appended(on_proxy, proxy_normals, traced.phi_rgb, traced.w12)))
    smooth_w12 = mapping.interpolate(carried.w12)
    smooth_w12 /= np.linalg.norm(smooth_w12, axis=1, keepdims=True)
    rows.append(
        (
            "full solve, the proxy's shadows, refracted direction smoothed",
            exact(full, traced.phi_rgb, smooth_w12, medium, receivers),
        )
    )
    gathered_area = decimation.gather(full.vertex_areas)
    smooth_phi = mapping.interpolate(carried.flux_rgb / np.where(gathered_area > 0, gathered_area, 1.0)[:, None])
    rows.append(
        (
            "full solve, the proxy's shadows, flux density smoothed",
            exact(full, smooth_phi, traced.w12, medium, receivers),
        )
    )
    rows.append(
        ("full solve, the proxy's shadows, both smoothed", exact(full, smooth_phi, smooth_w12, medium, receivers))
    )
    for edges, mfp in ((6.0, 2.0), (10.0, 3.0)):
        wide = with_near_field(edges, mfp, lambda: exact(full, own.phi_rgb, own.w12, medium, receivers))
        rows.append((f"full solve, near field {edges:g} edges / {mfp:g} mean free paths (convergence)", wide))
    n_proxy = geometry.n_vertices
    proxy_receivers = solver.SurfaceGeometry(
        np.vstack([geometry.points, mesh.points[receivers]]),
        geometry.triangles,
        np.vstack([geometry.normals, normals[receivers]]),
    )
    phi_p = np.vstack([carried.phi_rgb, np.zeros((receivers.size, 3))])
    w12_p = np.vstack([carried.w12, -normals[receivers]])
    for edges, mfp in ((3.0, 1.0), (6.0, 2.0)):
        at_full = with_near_field(
            edges,
            mfp,
            lambda: exact(proxy_receivers, phi_p, w12_p, medium, np.arange(n_proxy, n_proxy + receivers.size)),
        )
        rows.append(
            (f"`exact` on the proxy, at each full vertex itself, near field {edges:g} edges / {mfp:g} mfp", at_full)
        )
    reach = max(solver.local_reach_floor(full, medium, 1e-2), solver.local_reach_floor(geometry, medium, 1e-2))
    corners = np.unique(mapping.vertex_index[receivers])
    local_full = exact(full, traced.phi_rgb, traced.w12, medium, receivers, method="cutoff", tol=1e-2, reach_mm=reach)
    local_proxy = np.zeros((n_proxy, 3))
    local_proxy[corners] = exact(
        geometry, carried.phi_rgb, carried.w12, medium, corners, method="cutoff", tol=1e-2, reach_mm=reach
    )
    corrected = baked.B[receivers] + local_full - mapping.interpolate(local_proxy)[receivers]
    rows.append((f"the bake + L_full - interp(L_proxy), reach {reach:.2f} mm (docs/physics.md §8.8)", corrected))
    t = time.perf_counter()
    exact(full, traced.phi_rgb, traced.w12, medium, None, method="cutoff", tol=1e-2, reach_mm=reach)
    full_cost = time.perf_counter() - t
    t = time.perf_counter()
    exact(geometry, carried.phi_rgb, carried.w12, medium, None, method="cutoff", tol=1e-2, reach_mm=reach)
    proxy_cost = time.perf_counter() - t
    return {
        "mesh": {
            "vertices": n,
            "how": how,
            "proxy_vertices": n_proxy,
            "proxy_mean_edge_mm": geometry.mean_edge_length,
            "proxy_longest_edge_mm": geometry.longest_edge,
        },
        "why_a_proxy": baked.stats["coarser"],
        "receivers": RECEIVERS,
        "bake_seconds_bounces_0": bake_seconds,
        "rows": [
            {"what": what, **figures(B, reference), "against_proxy_shadows": figures(B, shadowed)} for what, B in rows
        ],
        "local_correction": {
            "reach_mm": reach,
            "seconds_full_every_vertex": full_cost,
            "seconds_proxy_every_vertex": proxy_cost,
        },
        "seconds": time.perf_counter() - start,
    }


def markdown(result) -> str:
    """The table of the rows and the correction's cost."""
    mesh = result["mesh"]
    lines = [
        f"2.1M Igea ({mesh['vertices']:,} vertices; {mesh['how']}), solved by the bake on a proxy of "
        f"{mesh['proxy_vertices']:,} vertices ({mesh['proxy_mean_edge_mm']:.3f} mm mean edge, the longest "
        f"{mesh['proxy_longest_edge_mm']:.2f} mm); marble, the default light, no bounce; {result['receivers']} random "
        f'vertices, `exact` unless said. Load {result["load"]}. The bake said: "{result["why_a_proxy"]}"',
        "",
        "| what | p99 | p90 | median | mean signed | p99 against the full solve with the proxy's shadows |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for row in result["rows"]:
        lines.append(
            f"| {row['what']} | {100 * row['p99']:.2f} % | {100 * row['p90']:.2f} % | {100 * row['median']:.3f} % | "
            f"{100 * row['mean_signed']:+.3f} % | {100 * row['against_proxy_shadows']['p99']:.2f} % |"
        )
    cost = result["local_correction"]
    lines += [
        "",
        f"The local correction at every vertex: L_full {cost['seconds_full_every_vertex']:.0f} s, "
        f"L_proxy {cost['seconds_proxy_every_vertex']:.0f} s, "
        f"against {result['bake_seconds_bounces_0']:.0f} s for the whole bake's shade without bounce.",
    ]
    return "\n".join(lines) + "\n"


def main() -> int:
    if not (MESHES / SCANS["igea"][0]).exists():
        print(f"the shared Igea ({SCANS['igea'][0]} in ../shared/meshes) is not present; nothing to measure")
        return 0
    load_start = load_average()[0]
    result = measure()
    result["load"] = f"{load_start:.1f}-{load_average()[0]:.1f}"
    result["info"] = machine_info()
    write_results(RESULTS, "proxy_split", result, markdown(result))
    print(markdown(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
