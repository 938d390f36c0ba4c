"""Numerical stability of the three diffusion models over millions of extreme configurations.

Every implementation -- the float64 reference formulas of :mod:`translucency.scatter.dipoles` and the
numba kernels of :mod:`translucency.scatter.kernels` (``model_pair`` per pair, ``vertex_sum`` as the
solver's ``exact`` method calls it) -- is evaluated on
the same configurations (``translucency/scatter/extremes.py``: eta 1 to 2.5, reduced albedo 1e-6 to 1 - 1e-9,
reduced mean free path 1e-4 to 1e4 times the mesh size, r from 0 to the far field, grazing and
backlit incidence, exit points on the normal axis and at the virtual source, exact coordinate-axis
normals), once with float64 input and once with the same input rounded to float32. Counted: NaN, inf
and negative values (all must be 0). Measured: the float32-vs-float64 relative difference where the
value matters, ``|S(float32 input) - S(float64 input)| / S(float64 input)`` over values at least
``THRESHOLD`` times the material's peak (``S_d`` at ``r = 0`` under normal incidence on a flat surface),
over *regular* pairs (away from the model's discontinuities, see ``translucency/scatter/extremes.py``) and over all.

Writes ``bench/results/stability.json`` and ``bench/results/stability.md``.

    .venv/bin/python bench/stability.py                        # 8192 blocks: 2.1 M pairs x 3 channels per model
    .venv/bin/python bench/stability.py --blocks 256 --out bench/results/tmp   # quick look
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numba  # noqa: E402
import numpy as np  # noqa: E402

from translucency import __version__  # noqa: E402  (first: it selects numba's threading layer)
from translucency.scatter import extremes  # noqa: E402

RESULTS = ROOT / "bench" / "results"
THRESHOLD = 1e-6  # values compared: at least this fraction of the material's peak
LARGE = 1e-3  # ... and the same for values at least this fraction (away from the clamp's cancellation)
PERCENTILE = 99.9


def _summary(rel: np.ndarray) -> dict:
    """Size, median, high percentile and maximum of relative differences."""
    if rel.size == 0:
        return {"compared": 0, "median": None, f"p{PERCENTILE}": None, "max": None}
    return {
        "compared": int(rel.size),
        "median": float(np.median(rel)),
        f"p{PERCENTILE}": float(np.percentile(rel, PERCENTILE)),
        "max": float(rel.max()),
    }


def _difference(values, reference, scale, regular) -> dict:
    """Relative differences where the reference matters, over regular entries and over all."""
    masked = np.where(regular, values, np.nan)
    return {
        "regular": _summary(extremes.relative_differences(masked, reference, scale, THRESHOLD)),
        "regular_large": _summary(extremes.relative_differences(masked, reference, scale, LARGE)),
        "all": _summary(extremes.relative_differences(values, reference, scale, THRESHOLD)),
    }


def _worst_regular(values, reference, scale, regular, blocks, geometry) -> dict:
    """The regular pair with the largest relative difference: where it is, in the model's length scales."""
    values, reference = np.broadcast_arrays(values, reference)
    keep = regular[..., None] & np.isfinite(values) & (reference >= THRESHOLD * scale) & (reference > 0)
    rel = np.where(keep, np.abs(values - reference) / np.where(keep, reference, 1.0), -1.0)
    g, o, j, c = np.unravel_index(int(np.argmax(rel)), rel.shape)
    D = 1.0 / (3.0 * (blocks.sigma_s[g, c] * (1.0 - blocks.g[g, c]) + blocks.sigma_a[g, c]))
    return {
        "relative_difference": float(rel[g, o, j, c]),
        "value_over_peak": float(reference[g, o, j, c] / scale[g, 0, 0, c]),
        "r_over_D": float(geometry["r"][g, o, j] / D),
        "D_over_coordinates": float(D / geometry["magnitude"][g, o, j]),
        "mu0": float(geometry["mu0"][g, o, j]),
        "eta": float(blocks.eta[g]),
    }


def run_model(model: str, blocks, blocks32, flux, geometry, regular_pairs, regular_receivers, sum_blocks: int) -> dict:
    """Counts and differences of every implementation of one model (the sums over the first ``sum_blocks``)."""
    seconds = {}
    peak = extremes.peak(blocks, model)  # (G, 3)
    pair_scale = peak[:, None, None, :]
    sum_scale = (peak * flux.max(axis=1))[:sum_blocks, None, :]
    sum_set = (blocks.subset(sum_blocks), blocks32.subset(sum_blocks))
    values: dict[str, dict[str, np.ndarray]] = {}
    start = time.perf_counter()
    values["reference"] = {"float64": extremes.reference(blocks, model), "float32": extremes.reference(blocks32, model)}
    seconds["reference"] = time.perf_counter() - start
    start = time.perf_counter()
    params = {
        "float64": extremes.kernel_parameters(blocks, model),
        "float32": extremes.kernel_parameters(blocks32, model),
    }
    values["kernel model_pair"] = {
        "float64": extremes.kernel_pairs(blocks, model, params["float64"]),
        "float32": extremes.kernel_pairs(blocks32, model, params["float32"]),
    }
    seconds["kernel model_pair"] = time.perf_counter() - start
    clamped = 0
    for name in ("kernel vertex_sum",):
        start = time.perf_counter()
        values[name] = {}
        for precision, b in zip(("float64", "float32"), sum_set):
            values[name][precision], count = extremes.kernel_sums(
                b, model, flux[:sum_blocks], params[precision][:sum_blocks]
            )
            clamped = int(count.sum()) if precision == "float64" else clamped
        seconds[name] = time.perf_counter() - start

    ref64 = values["reference"]["float64"]
    result = {
        "counts": {name: {p: extremes.bad_counts(v) for p, v in pv.items()} for name, pv in values.items()},
        "float32_vs_float64": {},
        "kernel_vs_reference_float64": _difference(
            values["kernel model_pair"]["float64"], ref64, pair_scale, regular_pairs[..., None]
        ),
        "kernel_float32_vs_reference_same_input": _difference(
            values["kernel model_pair"]["float32"], values["reference"]["float32"], pair_scale, regular_pairs[..., None]
        ),
        "worst_regular_float32_reference": _worst_regular(
            values["reference"]["float32"], ref64, pair_scale, regular_pairs, blocks, geometry
        ),
        "largest_value_over_peak": float(np.nanmax(ref64 / pair_scale)),
        "zero_values_fraction": float(np.mean(ref64 == 0)),
        "pairs_clamped_by_vertex_sum": clamped,
        "seconds": seconds,
    }
    for name, pv in values.items():
        is_sum = pv["float64"].ndim == 3
        result["float32_vs_float64"][name] = _difference(
            pv["float32"],
            pv["float64"],
            sum_scale if is_sum else pair_scale,
            (regular_receivers if is_sum else regular_pairs)[..., None],
        )
    reference_sum = np.einsum("gojc,gjc->goc", ref64[:sum_blocks], flux[:sum_blocks])
    result["vertex_sum_vs_reference_sum_float64"] = _difference(
        values["kernel vertex_sum"]["float64"], reference_sum, sum_scale, regular_receivers[..., None]
    )
    return result


def _fmt(value) -> str:
    return "–" if value is None else f"{value:.1e}"


def markdown(results: dict) -> str:
    """Two Markdown tables: bad-value counts, and float32-vs-float64 differences."""
    s = results["settings"]
    lines = [
        f"{results['pairs']:,} pairs x 3 channels = {3 * results['pairs']:,} values per model and implementation, "
        f"float64 and float32 input ({s['blocks']} materials x {s['sources']} sources x {s['receivers']} receivers, "
        f"seed {s['seed']}); the sums B (per receiver, over the 8 sources of its material) on the first "
        f"{s['sum_blocks']} materials.",
        "",
        "| model | implementation | input | values | NaN | inf | negative |",
        "|---|---|---|---:|---:|---:|---:|",
    ]
    for model, r in results["models"].items():
        for name, per in r["counts"].items():
            for precision, c in per.items():
                lines.append(
                    f"| {model} | {name} | {precision} | {c['values']:,} | {c['nan']} | {c['inf']} | {c['negative']} |"
                )
    lines += [
        "",
        f"Relative difference float32 input vs float64 input, where the float64 value is at least {THRESHOLD:g} of the "
        f"material's peak; *regular*: pairs away from the model's discontinuities (|mu0| >= {s['regular_mu0']:g}, "
        f"exit point >= {s['regular_axis_angle_rad']:g} rad off the n_i axis, r = 0 or r >= "
        f"{s['regular_r_over_magnitude']:g} "
        f"x the coordinates' magnitude); for sums, receivers all of whose pairs are regular.",
        "",
        f"| model | implementation | compared (regular) | median | p{PERCENTILE} | max (regular) | "
        f"max (regular, >= {LARGE:g} of peak) | p{PERCENTILE} (all) | max (all) |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    key = f"p{PERCENTILE}"
    for model, r in results["models"].items():
        rows = dict(r["float32_vs_float64"])
        rows["kernel in float32 vs reference, same float32 input"] = r["kernel_float32_vs_reference_same_input"]
        rows["kernel vs reference, float64 input"] = r["kernel_vs_reference_float64"]
        rows["vertex_sum vs reference sum, float64 input"] = r["vertex_sum_vs_reference_sum_float64"]
        for name, d in rows.items():
            reg, large, every = d["regular"], d["regular_large"], d["all"]
            lines.append(
                f"| {model} | {name} | {reg['compared']:,} | {_fmt(reg['median'])} | {_fmt(reg[key])} | "
                f"{_fmt(reg['max'])} | {_fmt(large['max'])} | {_fmt(every[key])} | {_fmt(every['max'])} |"
            )
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    """Run every model and implementation, write the JSON and Markdown results; exit 1 if any value is bad."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--blocks", type=int, default=8192, help="materials (each 8 sources x 32 receivers)")
    parser.add_argument("--sum-blocks", type=int, default=2048, help="materials whose vertex sums are evaluated")
    parser.add_argument("--seed", type=int, default=2024)
    parser.add_argument("--out", type=Path, default=RESULTS, help="folder for stability.json and stability.md")
    args = parser.parse_args(argv)

    start = time.perf_counter()
    blocks = extremes.random_blocks(args.blocks, seed=args.seed)
    blocks32 = blocks.as_dtype(np.float32)
    flux = np.random.default_rng(args.seed + 1).random(blocks.x_i.shape[:2] + (3,))
    flux[:, ::5] = 0.0  # sources without light, as the solver sees them when it does not drop them
    geometry = extremes.pair_geometry(blocks)
    regular_pairs = extremes.regular_pairs(geometry)
    sum_blocks = min(args.sum_blocks, args.blocks)
    regular_receivers = regular_pairs[:sum_blocks].all(axis=2)
    results = {
        "version": __version__,
        "machine": {
            "python": platform.python_version(),
            "numpy": np.__version__,
            "numba": numba.__version__,
            "threads": numba.get_num_threads(),
        },
        "settings": {
            "blocks": args.blocks,
            "sum_blocks": min(args.sum_blocks, args.blocks),
            "sources": blocks.x_i.shape[1],
            "receivers": blocks.x_o.shape[1],
            "seed": args.seed,
            "threshold_of_peak": THRESHOLD,
            "eta": extremes.ETA_RANGE,
            "reduced_albedo": extremes.ALBEDO_RANGE,
            "mean_free_path_over_size": extremes.MFP_OVER_SIZE_RANGE,
            "g": extremes.G_RANGE,
            "size_mm": extremes.SIZE_RANGE_MM,
            "distance_exponents": extremes.DISTANCE_EXPONENTS,
            "regular_mu0": extremes.REGULAR_MU0,
            "regular_axis_angle_rad": extremes.REGULAR_AXIS_ANGLE,
            "regular_r_over_magnitude": extremes.REGULAR_R_OVER_MAGNITUDE,
        },
        "pairs": blocks.n_pairs,
        "regular_pair_fraction": float(regular_pairs.mean()),
        "models": {},
    }
    for model in extremes.MODELS:
        results["models"][model] = run_model(
            model, blocks, blocks32, flux, geometry, regular_pairs, regular_receivers, sum_blocks
        )
        print(f"{model}: {results['models'][model]['seconds']}", flush=True)
    results["seconds"] = time.perf_counter() - start
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "stability.json").write_text(json.dumps(results, indent=1) + "\n")
    table = markdown(results)
    (args.out / "stability.md").write_text(table)
    print(table)
    print(f"{results['seconds']:.0f} s")
    total_bad = sum(
        c["nan"] + c["inf"] + c["negative"]
        for r in results["models"].values()
        for per in r["counts"].values()
        for c in per.values()
    )
    return 0 if total_bad == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
