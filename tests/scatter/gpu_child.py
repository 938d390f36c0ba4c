"""The GPU side of tests/scatter/test_gpu.py, run in a process of its own, on the GPU where one works and otherwise
under numba's CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``, which must be set before numba.cuda is imported):
``python -m tests.scatter.gpu_child IN OUT`` reads the cases from the ``.npz`` file IN and writes what the GPU code
gave to the ``.npz`` file OUT."""

import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]


def run_python(arguments, env) -> subprocess.CompletedProcess:
    """``python ARGUMENTS`` (this interpreter) from the repository's root with the environment ``env``, its output
    captured, 300 s at most: how the GPU's tests start a process whose numba.cuda is chosen afresh."""
    return subprocess.run([sys.executable, *arguments], env=env, cwd=ROOT, capture_output=True, text=True, timeout=300)


def vertex_sum_arguments(cases, name: str) -> tuple:
    """The arguments of ``vertex_sum`` (the CPU's and the GPU's) for the case ``name`` of the ``.npz`` file."""
    src, rcv = cases[f"{name}_sources"], cases[f"{name}_receivers"]
    return (
        int(cases[f"{name}_model"]),
        src[:, 0:3],
        src[:, 3:6],
        src[:, 6:9],
        cases[f"{name}_flux"],
        rcv[:, 0:3],
        rcv[:, 3:6],
        cases[f"{name}_params"],
        cases[f"{name}_channel_of"],
    )


def near_field_cases(out, geometry, phi, w12, medium) -> None:
    """The near field's correction on the GPU at every vertex of ``geometry``, as it is and with the scratch space of
    a thread too small for any fan or subdivision (those receivers corrected on the CPU, counted)."""
    from translucency.scatter import kernels, nearfield, solve
    from translucency.scatter.gpu import nearfield as on_the_gpu

    receivers = np.arange(geometry.n_vertices)
    offsets, ids = nearfield.lists_of(geometry, receivers, solve.near_radius(geometry, medium))
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta)
    arguments = (0, geometry.points, geometry.triangles, geometry.triangle_areas, geometry.normals, w12, phi)
    arguments += (receivers, offsets, ids, params, np.arange(3), solve.NEAR_BETA, float(np.min(medium.D)))
    out["near_B"], out["near_points"] = on_the_gpu.near_field_correction(*arguments, nearfield.tables_of(geometry))
    cpu, calls = nearfield.near_field_correction, []
    nearfield.near_field_correction = lambda *a, **k: calls.append(len(a[7])) or cpu(*a, **k)
    on_the_gpu.FAN_ROWS = on_the_gpu.PIECES = 1  # the simulator reads them as it runs
    try:
        out["near_small_B"], _ = on_the_gpu.near_field_correction(*arguments, nearfield.tables_of(geometry))
    finally:
        nearfield.near_field_correction, on_the_gpu.FAN_ROWS, on_the_gpu.PIECES = cpu, 256, 256
    out["near_small_on_cpu"] = sum(calls)


def main(cases_path: str, out_path: str, part: str = "sums") -> None:
    """Run the ``part`` of the cases (``sums``: the pair sums, exact, tree, the near field; ``relight``: relighting)
    and write what the GPU gave."""
    from translucency.scatter.materials import material

    cases = np.load(cases_path)
    medium = material("marble").medium()
    out = sums(cases, medium) if part == "sums" else relit(cases, medium)
    np.savez(out_path, **out)


def sums(cases, medium) -> dict:
    """The pair sums of every model, a whole exact solve, a tree solve and the near field, on the GPU."""
    from translucency.scatter import solve
    from translucency.scatter.gpu import pairs

    out = {}
    for name in ("directional", "standard", "better"):
        B, clamped = pairs.vertex_sum(*vertex_sum_arguments(cases, name))
        out[f"{name}_B"], out[f"{name}_clamped"] = B, clamped
        out[f"{name}_chunk"] = pairs.chunk_size(len(cases[f"{name}_receivers"]), len(cases[f"{name}_sources"]))
    geometry = solve.SurfaceGeometry(cases["points"], cases["triangles"], cases["normals"])
    solution = solve.solve(geometry, cases["phi"], cases["w12"], medium, method="exact", device="gpu")
    out["solve_B"] = solution.B
    out["solve_device"] = np.array(solution.stats["device"])
    out["solve_clamped"] = solution.stats["clamped_values"]
    walked = solve.SurfaceGeometry(cases["tree_points"], cases["tree_triangles"], cases["tree_normals"])
    near_field_cases(out, walked, cases["tree_phi"], cases["tree_w12"], medium)
    tree = solve.solve(walked, cases["tree_phi"], cases["tree_w12"], medium, method="tree", tol=0.1, device="gpu")
    out["tree_B"] = tree.B
    from translucency.scatter.gpu import nearfield as on_the_gpu

    out["near_held_after_solve"] = bool(on_the_gpu._HELD)  # the mesh's and the light's copies given back
    out["tree_device"] = np.array(tree.stats["device"])
    for key in ("pairs_direct", "cluster_evaluations"):
        out[f"tree_{key}"] = tree.stats[key]
    return out


def relit(cases, medium) -> dict:
    """Relighting with its far field on the GPU: two lights, the near field's product on the CPU, the tree's walk."""
    from translucency.scatter import solve
    from translucency.scatter.gpu import pairs

    out = {}
    relit = solve.SurfaceGeometry(cases["relit_points"], cases["relit_triangles"], cases["relit_normals"])
    for k in range(2):  # the first light prepares the near field, the second reuses it
        light = solve.solve(
            relit, cases[f"relit_phi{k}"], cases[f"relit_w12{k}"], medium, method="relight", tol=0.01, device="gpu"
        )
        out[f"relit_B{k}"] = light.B
        out[f"relit_reused{k}"] = light.stats["operators_reused"]
        out[f"relit_device{k}"] = np.array(light.stats["device"])
        out[f"relit_fallback{k}"] = np.array(light.stats.get("relight_fallback", ""))
        out[f"relit_near_on_gpu{k}"] = bool(light.stats.get("near_on_gpu"))
    pairs.NEAR_SHARE_OF_FREE = 0.0  # a GPU too small for the near field: its product on the CPU, the same B
    again = solve.SurfaceGeometry(cases["relit_points"], cases["relit_triangles"], cases["relit_normals"])
    light = solve.solve(
        again, cases["relit_phi1"], cases["relit_w121"], medium, method="relight", tol=0.01, device="gpu"
    )
    out["relit_cpu_near_B"] = light.B
    out["relit_cpu_near_on_gpu"] = bool(light.stats.get("near_on_gpu"))
    pairs.ALL_PAIRS_UP_TO = 0  # a surface too large for every pair per light: the far field by the tree's walk
    walked = solve.SurfaceGeometry(cases["relit_points"], cases["relit_triangles"], cases["relit_normals"])
    light = solve.solve(
        walked, cases["relit_phi1"], cases["relit_w121"], medium, method="relight", tol=0.01, device="gpu"
    )
    out["relit_tree_B"] = light.B
    out["relit_tree_far"] = np.array(light.stats["far_on_gpu"])
    out["relit_tree_far_entries"] = light.stats["far_entries"]
    out["relit_tree_skipped"] = light.stats["pairs_skipped"]
    out["relit_tree_fallback"] = np.array(light.stats.get("relight_fallback", ""))
    return out


if __name__ == "__main__":
    main(*sys.argv[1:4])
