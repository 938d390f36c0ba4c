"""bench/gpu.py, the script a GPU machine runs, in numba's CUDA simulator (``--quick``): it runs to its end and
writes rows whose GPU sums are the CPU's, so that a GPU's scarce time is not spent finding a broken script."""

import json
import os

from tests.scatter.gpu_child import ROOT, run_python


def test_the_gpu_benchmark_runs_in_the_simulator_and_agrees_with_the_cpu():
    env = {key: value for key, value in os.environ.items() if key != "NUMBA_ENABLE_CUDASIM"}
    child = run_python([str(ROOT / "bench" / "gpu.py"), "--quick"], env)
    assert child.returncode == 0, child.stderr[-3000:]
    payload = json.loads((ROOT / "bench" / "results" / "tmp" / "gpu.json").read_text())
    assert payload["device"] == "CUDA simulator"
    (row,) = payload["rows"]
    assert row["light_measured"] and row["error_max"] < 1e-12 and row["pairs"] == row["vertices"] * row["lit"]
    assert payload["whole_solves"]["largest_relative_difference"] < 1e-10
    tree = row["tree"]  # by patches, as the 10M torus's
    assert tree["device"] == "gpu (CUDA simulator)" and tree["patches"] and tree["error_p99"] < 0.01
    assert list(row["tree_groups"]) == ["32"]  # 32 receivers sharing a walk, measured against the CPU's
    wide = row["tree_groups"]["32"]
    assert wide["device"] == tree["device"] and wide["error_p99"] < 0.01 and wide["evaluations_per_receiver"] > 0
    assert [run["lights"][0]["far_on_gpu"] for run in payload["relit"]] == ["every pair", "tree"]
    for run in payload["relit"]:
        relit = run["lights"]
        assert len(relit) == 2 and not relit[0]["reused"] and relit[1]["reused"]  # --quick: two lights
        assert max(r["error_p99"] for r in relit) < 0.01  # relighting holds its tol 0.01 against exact
