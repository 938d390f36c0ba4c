"""The GPU back end of the pair sums (translucency.scatter.gpu): its kernels against the float64 reference formulas
and against the CPU's solves, run on the GPU where one works and otherwise in numba's CUDA simulator (no GPU needed;
a process of its own, as the simulator must be chosen before numba.cuda is imported), their PTX compiled where
numba-cuda is installed, and the choice of device with its sentences."""

import importlib.util
import os
from pathlib import Path

import numpy as np
import pytest

from tests.scatter.gpu_child import run_python, vertex_sum_arguments
from tests.scatter.test_kernels import _pairs
from tests.scatter.test_solve import _lit, _unit
from translucency.errors import DeviceError, InvalidParameterError, command_line_spelling
from translucency.geometry.synthetic import icosphere
from translucency.scatter import dipoles, fresnel, hierarchy, kernels, solve
from translucency.scatter.gpu import probe
from translucency.scatter.materials import material

ROOT = Path(__file__).resolve().parents[2]
#: Output channels per model: three rows; one row for three channels; three rows for five (two lane groups).
CHANNEL_MAPS = {"directional": [0, 1, 2], "standard": [0, 0, 0], "better": [0, 1, 2, 2, 0]}
#: Receivers per model (sources: 300, so the GPU splits them into chunks).
RECEIVERS = {"directional": 24, "standard": 8, "better": 8}


def _reference(model, x_i, n_i, w12, x_o, n_o, medium):
    """``S_d`` (receivers, sources, channel) from translucency.scatter.dipoles (the float64 formulas)."""
    out = []
    for c in range(3):
        coefficients = (medium.sigma_a[c], medium.sigma_s[c], medium.g[c], medium.eta)
        if model == "directional":
            S = dipoles.directional_dipole(x_i[None], n_i[None], w12[None], x_o[:, None], n_o[:, None], *coefficients)
        else:
            r = np.linalg.norm(x_o[:, None] - x_i[None], axis=2)
            profile = dipoles.standard_dipole_profile if model == "standard" else dipoles.better_dipole_profile
            scale = 1.0 / np.pi if model == "standard" else 1.0 / (np.pi * 4.0 * fresnel.C_phi(1.0 / medium.eta))
            S = scale * profile(r, *coefficients)
        out.append(S)
    return np.stack(out, axis=2)


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """The cases, the simulated GPU's answers, the mediums and the sphere's CPU solve."""
    rng = np.random.default_rng(41)
    medium = material("skin1").medium()
    cases, references = {}, {}
    for name, channel_of in CHANNEL_MAPS.items():
        x_i, n_i, light, _, _ = _pairs(rng, 300, 2.0)
        x_i[:2] = x_i[2]  # coincident sources: r = 0 at receiver 2
        w12 = fresnel.refract(light, n_i, medium.eta)
        rcv = RECEIVERS[name]
        rows = max(channel_of) + 1
        cases[f"{name}_sources"] = np.hstack([x_i, n_i, w12])
        cases[f"{name}_receivers"] = np.hstack([x_i[:rcv], n_i[:rcv]])
        cases[f"{name}_flux"] = rng.random((300, len(channel_of)))
        cases[f"{name}_params"] = kernels.channel_parameters(
            medium.sigma_a[:rows], medium.sigma_s[:rows], medium.g[:rows], medium.eta, name
        )
        cases[f"{name}_channel_of"] = np.array(channel_of, dtype=np.int64)
        cases[f"{name}_model"] = kernels.MODELS[name]
        references[name] = _reference(name, x_i, n_i, w12, x_i[:rcv], n_i[:rcv], medium)
    marble = material("marble").medium()
    points, triangles = icosphere(1, 10.0)
    normals, phi, w12 = _lit(points, triangles, marble, _unit([0.2, 0.3, 1.0]))
    cases.update(points=points, triangles=triangles, normals=normals, phi=phi, w12=w12)
    cpu = solve.solve(solve.SurfaceGeometry(points, triangles, normals), phi, w12, marble, method="exact", device="cpu")
    points, triangles = icosphere(2, 20.0)
    normals, phi, w12 = _lit(points, triangles, marble, _unit([-0.3, 0.5, 0.8]))
    cases.update(tree_points=points, tree_triangles=triangles, tree_normals=normals, tree_phi=phi, tree_w12=w12)
    degree3, solve.NEAR_DEGREE3_RATIO = solve.NEAR_DEGREE3_RATIO, 0.0  # the GPU's near field: exact's rules
    float32_tol, hierarchy.FLOAT32_TOL = hierarchy.FLOAT32_TOL, 1.0  # the GPU sums its clusters in float64
    try:
        tree = solve.solve(solve.SurfaceGeometry(points, triangles, normals), phi, w12, marble, method="tree", tol=0.1)
    finally:
        solve.NEAR_DEGREE3_RATIO = degree3
        hierarchy.FLOAT32_TOL = float32_tol
    points, triangles = icosphere(3, 10.0)  # fine enough that the far field's fit shows on the CPU (0.15 %)
    cases.update(relit_points=points, relit_triangles=triangles)
    exact_relit = []
    for k, direction in enumerate(([0.2, 0.3, 1.0], [-1.0, 0.4, -0.2])):
        normals, phi, w12 = _lit(points, triangles, marble, _unit(direction))
        cases.update({"relit_normals": normals, f"relit_phi{k}": phi, f"relit_w12{k}": w12})
        geometry = solve.SurfaceGeometry(points, triangles, normals)
        exact_relit.append(solve.solve(geometry, phi, w12, marble, method="exact", device="cpu").B)
    folder = tmp_path_factory.mktemp("gpu")
    np.savez(folder / "cases.npz", **cases)
    return _on_the_gpu(folder, "sums"), cases, references, cpu, exact_relit, tree, folder


def _on_the_gpu(folder, part: str) -> dict:
    """The GPU's answers to ``part`` of the cases in ``folder`` (tests/scatter/gpu_child.py), in a process of its own:
    on the GPU where one works here, else in numba's simulator."""
    simulator = "0" if _real_gpu() else "1"
    env = {**os.environ, "NUMBA_ENABLE_CUDASIM": simulator, "PYTHONPATH": str(ROOT)}
    out = folder / f"{part}.npz"
    child = run_python(["-m", "tests.scatter.gpu_child", str(folder / "cases.npz"), str(out), part], env)
    assert child.returncode == 0, child.stderr[-3000:]
    return dict(np.load(out))


@pytest.fixture(scope="module")
def relit(simulated):
    """The GPU's answers for relighting (about 30 s in the simulator), the cases and exact's B of each light."""
    _, cases, _, _, exact_relit, _, folder = simulated
    return _on_the_gpu(folder, "relight"), cases, exact_relit


def _real_gpu() -> bool:
    """Whether this machine has a GPU that works (not the simulator, which a parent process may have chosen)."""
    status = probe.gpu_status()
    return status.usable and status.name != probe.SIMULATOR


def _device_name() -> str:
    """What a solve on the GPU says it ran on: the GPU of this machine, or the simulator."""
    return f"gpu ({probe.gpu_status().name if _real_gpu() else probe.SIMULATOR})"


def test_the_gpu_kernel_is_the_dense_sum_of_the_reference_formulas(simulated):
    """Every model, one to three parameter rows mapped to three or five output channels, the sources in chunks: the
    GPU's B is the reference S_d times the flux, summed (relative 1e-12), and it counts the CPU kernel's clamps.
    """
    out, cases, references, *_ = simulated
    for name in CHANNEL_MAPS:
        channel_of = cases[f"{name}_channel_of"]
        flux = cases[f"{name}_flux"]
        S = references[name]
        assert out[f"{name}_chunk"] < 300, name  # the sources went in more than one chunk
        for c, row in enumerate(channel_of):
            expected = S[:, :, row] @ flux[:, c]
            assert np.allclose(out[f"{name}_B"][:, c], expected, rtol=1e-12, atol=0), (name, c)
        _, clamped = kernels.vertex_sum(*vertex_sum_arguments(cases, name))
        assert np.array_equal(out[f"{name}_clamped"], clamped), name


def test_exact_on_the_gpu_is_exact_on_the_cpu(simulated):
    """A whole solve (far field on the GPU, near field on the CPU) equals the CPU's and says where it ran."""
    out, _, _, cpu, *_ = simulated
    assert np.allclose(out["solve_B"], cpu.B, rtol=1e-12, atol=0)
    assert str(out["solve_device"]) == _device_name()
    assert int(out["solve_clamped"]) == cpu.stats["clamped_values"]
    assert cpu.stats["device"] == "cpu"


def test_tree_on_the_gpu_is_tree_on_the_cpu(simulated):
    """The GPU walks the tree and sums as it goes (gpu.tree); the CPU lists, then sums: the same sources and clusters
    for every receiver (the same counts, clusters among them), the same B but for the order of the sums (the near
    field with exact's rules on both: the GPU's has no degree-3 rule; the CPU's clusters in float64, as the GPU's)."""
    out, _, _, _, _, cpu, _ = simulated
    assert cpu.stats["device"] == "cpu" and str(out["tree_device"]) == _device_name()
    assert cpu.stats["cluster_evaluations"] > 0
    for key in ("pairs_direct", "cluster_evaluations"):
        assert int(out[f"tree_{key}"]) == cpu.stats[key], key
    assert np.allclose(out["tree_B"], cpu.B, rtol=1e-12, atol=0)
    assert not bool(out["near_held_after_solve"])  # the near field's copies on the device given back


def test_the_near_field_on_the_gpu_is_the_cpus_with_exacts_rules(simulated):
    """Each receiver's quadrature made and summed by one GPU thread (gpu.nearfield): the CPU's near field with
    exact's rules (fan, subdivision, Dunavant) to 1e-12 of its largest; with a thread's scratch space too small for
    any fan or subdivision, those receivers are the CPU's, the same answer."""
    out, cases, *_ = simulated
    from translucency.scatter import kernels, nearfield, solve

    medium = material("marble").medium()
    geometry = solve.SurfaceGeometry(cases["tree_points"], cases["tree_triangles"], cases["tree_normals"])
    receivers = np.arange(geometry.n_vertices)
    offsets, ids = nearfield.lists_of(geometry, receivers, solve.near_radius(geometry, medium))
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta)
    cpu, points = nearfield.near_field_correction(
        0, geometry.points, geometry.triangles, geometry.triangle_areas, geometry.normals, cases["tree_w12"],
        cases["tree_phi"], receivers, offsets, ids, params, np.arange(3), solve.NEAR_BETA, float(np.min(medium.D)),
    )  # fmt: skip
    scale = np.abs(cpu).max(axis=0)
    assert np.all(np.abs(out["near_B"] - cpu) <= 1e-12 * scale)
    assert np.all(np.abs(out["near_small_B"] - cpu) <= 1e-12 * scale)
    # every receiver with light on its own triangles needs a fan: those went to the CPU
    lit_own = np.zeros(geometry.n_vertices, dtype=bool)
    lit_own[geometry.triangles[(cases["tree_phi"].sum(axis=1) > 0)[geometry.triangles].any(axis=1)].ravel()] = True
    assert int(out["near_small_on_cpu"]) == np.count_nonzero(lit_own) > 0
    assert out["near_points"].sum() > points.sum()  # a GPU thread evaluates every corner of every triangle


@pytest.mark.slow
def test_relighting_with_its_far_field_on_the_gpu_is_closer_to_exact_than_its_fit(relit):
    """Relighting's near field prepared once (its product made on the GPU), its far field every pair per light on
    the GPU: two lights, each within 0.1 % of exact at the 99th percentile per vertex (docs/physics.md §8.5; the
    CPU's fitted far field is 0.14-0.15 % off on this sphere, so the far field is not fitted), the second reusing
    the first's near field."""
    out, _, exact = relit
    for k in range(2):
        B, reference = out[f"relit_B{k}"], exact[k]
        counted = reference >= 1e-4 * reference.max(axis=0)
        error = np.abs(B - reference)[counted] / reference[counted]
        assert np.percentile(error, 99) <= 1e-3, (k, np.percentile(error, 99))
        assert bool(out[f"relit_reused{k}"]) == (k == 1)
        assert str(out[f"relit_device{k}"]) == _device_name()
        assert str(out[f"relit_fallback{k}"]) == ""  # the operators' own answer, not tree's in their place
        assert bool(out[f"relit_near_on_gpu{k}"])  # the near field's product on the GPU too
    # where the near field's operator does not fit the GPU, its product is the CPU's: the same B
    assert not bool(out["relit_cpu_near_on_gpu"])
    assert np.allclose(out["relit_cpu_near_B"], out["relit_B1"], rtol=1e-12, atol=0)


@pytest.mark.slow
def test_relighting_a_large_surface_on_the_gpu_walks_the_tree_per_light_within_tol(relit):
    """Past ``ALL_PAIRS_UP_TO`` pairs a light's far field on the GPU is tree's walk at the operators' tol, not every
    pair: within tol (0.01) of exact at the 99th percentile, the operators' own answer (no fallback to tree), fewer
    far-field evaluations than lit sources times vertices (the rest counted as skipped), and not every pair's B."""
    out, cases, exact = relit
    B, reference = out["relit_tree_B"], exact[1]
    counted = reference >= 1e-4 * reference.max(axis=0)
    error = np.abs(B - reference)[counted] / reference[counted]
    assert str(out["relit_tree_far"]) == "tree" and str(out["relit_tree_fallback"]) == ""
    assert np.percentile(error, 99) <= 1e-2, np.percentile(error, 99)
    every_pair = int(np.count_nonzero(cases["relit_phi1"].max(axis=1) > 0)) * len(cases["relit_points"])
    evaluated, skipped = int(out["relit_tree_far_entries"]), int(out["relit_tree_skipped"])
    assert 0 < evaluated < every_pair and evaluated + skipped == every_pair
    assert not np.allclose(B, out["relit_B1"], rtol=1e-9, atol=0)


@pytest.mark.skipif(importlib.util.find_spec("numba_cuda") is None, reason="numba-cuda (the gpu extra) not installed")
def test_the_kernel_compiles_to_ptx():
    """Where numba-cuda and CUDA's compiler libraries are installed (no GPU needed): the kernels (the pair sums, the
    tree's walk, the near field) with the CPU's loops, tests and device functions inside them compile for the A100's
    and the H100's architectures (sm_80, sm_90)."""
    code = (
        "from numba import cuda, types as t\n"
        "from translucency.scatter.gpu import nearfield, pairs, tree\n"
        "f8, i8, p = t.float64, t.int64, t.UniTuple(t.float64, 8)\n"
        "sig = (i8, f8[:, ::1], f8[::1], f8[::1], f8[::1], p, p, p, i8, i8, i8, f8[:, ::1], f8[:, ::1], i8,"
        " f8[:, :, ::1], i8[:, ::1])\n"
        "listed = (i8, f8[:, ::1], f8[::1], f8[::1], f8[::1], p, p, p, i8[::1], t.int32[::1], t.float32[::1],"
        " f8[:, ::1], f8[:, ::1], f8[:, ::1])\n"
        "near = (i8[::1], t.int32[::1], t.float32[:, ::1], f8[:, ::1], t.boolean[::1], i8, f8[:, ::1])\n"
        "a1, a2, b1 = f8[::1], f8[:, ::1], t.boolean[::1]\n"
        "walk = (i8, t.Tuple((i8[::1],) * 5 + (a2, a1)), a2, b1, a2, a2, t.UniTuple(a1, 3), t.UniTuple(p, 3),"
        " f8[:, :, ::1], t.UniTuple(a2, 2), t.Tuple((a2, a1)), a2, t.Tuple((i8, f8)), t.Tuple((f8, f8, a2, f8, f8,"
        " a1)), a2, i8[:, ::1])\n"
        "kernels = ((pairs._chunk_sums, sig), (pairs._listed_sums, listed), (pairs._near_rows, near),"
        " (tree._walked_sums, walk))\n"
        "a2i, i1 = t.int64[:, ::1], t.int64[::1]\n"
        "near = (i8, t.Tuple((a2, a2, a2i, a1)), t.UniTuple(a2, 2), t.Tuple((a1, a2)), i1, t.UniTuple(i1, 2),"
        " t.Tuple((a2, a1, a1, a1, a1, a1)), t.UniTuple(f8, 2), t.UniTuple(p, 3), t.UniTuple(i8, 3), a2, i1, i1)\n"
        "kernels += ((nearfield._near_sums, near),)\n"
        "import numba.cuda.dispatcher as d, types\n"
        "codes = []\n"
        "for cc in ((8, 0), (9, 0)):\n"
        "    d.get_current_device = lambda: types.SimpleNamespace(compute_capability=cc)  # no driver here\n"
        "    codes += [cuda.compile_ptx(k.py_func, s, cc=cc)[0] for k, s in kernels]\n"
        "print(all('.entry' in code for code in codes))\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_ENABLE_CUDASIM"}
    child = run_python(["-c", code], env)
    if "NvvmSupportError" in child.stderr or "DynamicLibNotFoundError" in child.stderr:
        pytest.skip("CUDA's compiler libraries (NVVM, NVRTC) are not installed")
    assert child.returncode == 0 and child.stdout.strip() == "True", child.stderr[-3000:]


def _status(monkeypatch, usable, name="", reason=""):
    monkeypatch.setattr(probe, "gpu_status", lambda: probe.GpuStatus(usable, name, reason))


def test_auto_takes_the_gpu_for_exact_and_relight_only_and_never_the_simulator(monkeypatch):
    """``auto``: exact and relighting on a GPU, tree (not measured on one yet) and cutoff on the CPU; ``gpu``: tree
    too."""
    _status(monkeypatch, True, "NVIDIA H100 80GB HBM3")
    for method in ("exact", "relight"):
        assert probe.pair_device("auto", method) == ("gpu", "gpu (NVIDIA H100 80GB HBM3)")
    assert probe.pair_device("auto", "tree") == ("cpu", "cpu")
    assert probe.pair_device("gpu", "tree") == ("gpu", "gpu (NVIDIA H100 80GB HBM3)")
    assert probe.pair_device("auto", "cutoff") == ("cpu", "cpu")
    assert probe.pair_device("cpu", "exact") == ("cpu", "cpu")
    _status(monkeypatch, True, probe.SIMULATOR)
    assert probe.pair_device("auto", "exact") == ("cpu", "cpu")
    assert probe.pair_device("gpu", "exact") == ("gpu", f"gpu ({probe.SIMULATOR})")
    _status(monkeypatch, False, reason="numba-cuda found no CUDA driver or no NVIDIA GPU")
    assert probe.pair_device("auto", "exact") == ("cpu", "cpu")


def test_a_gpu_that_cannot_be_had_is_a_sentence(monkeypatch):
    _status(monkeypatch, False, reason=f"the GPU back end is not installed ({probe.INSTALL})")
    with pytest.raises(InvalidParameterError, match=r"device='gpu' needs an NVIDIA GPU, and the GPU back end is not"):
        probe.pair_device("gpu", "exact")
    with command_line_spelling(), pytest.raises(InvalidParameterError, match=r"choose --device cpu or --device auto"):
        probe.pair_device("gpu", "exact")
    with pytest.raises(
        InvalidParameterError,
        match=r"methods exact, tree, relight and auto; choose one of them, or device='auto' for method cutoff",
    ):
        probe.pair_device("gpu", "cutoff")


def test_without_the_extra_the_status_says_what_to_install(monkeypatch):
    """On a machine without numba-cuda (CI's), the probe imports nothing and names the extra."""
    if importlib.util.find_spec("numba_cuda") is not None:
        pytest.skip("numba-cuda is installed here")
    monkeypatch.delenv("NUMBA_ENABLE_CUDASIM", raising=False)
    probe.gpu_status.cache_clear()
    try:
        status = probe.gpu_status()
    finally:
        probe.gpu_status.cache_clear()
    assert not status.usable and 'pip install "translucency[gpu]"' in status.reason


def test_a_solve_on_the_cpu_says_so_and_a_bad_device_is_a_sentence():
    medium = material("marble").medium()
    points, triangles = icosphere(2, 10.0)
    normals, phi, w12 = _lit(points, triangles, medium, _unit([0.2, 0.3, 1.0]))
    geometry = solve.SurfaceGeometry(points, triangles, normals)
    tree = solve.solve(geometry, phi, w12, medium, method="tree", tol=0.1, device="auto")
    assert tree.stats["device"] == "cpu"
    with pytest.raises(InvalidParameterError, match="device must be one of cpu, gpu, auto, got 'tpu'"):
        solve.solve(geometry, phi, w12, medium, device="tpu")


def test_a_cuda_error_is_a_sentence_that_names_the_cpu():
    """CUDA's own exceptions (numba-cuda raises them from its driver module) become one sentence; others pass."""

    class CudaAPIError(Exception):
        pass

    CudaAPIError.__module__ = "numba.cuda.cudadrv.driver"

    @probe.said_plainly
    def out_of_memory():
        raise CudaAPIError("[2] Call to cuMemAlloc results in CUDA_ERROR_OUT_OF_MEMORY\nmore detail")

    with pytest.raises(DeviceError) as info:
        out_of_memory()
    assert str(info.value) == (
        "the GPU could not sum the pairs ([2] Call to cuMemAlloc results in CUDA_ERROR_OUT_OF_MEMORY); run with "
        "device='cpu', or free the GPU's memory for it."
    )
    assert DeviceError.exit_code == 1

    @probe.said_plainly
    def not_cuda():
        raise ValueError("a bug of our own")

    with pytest.raises(ValueError, match="a bug of our own"):
        not_cuda()
