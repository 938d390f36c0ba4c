"""Validate the diffusion models against the Monte Carlo half-space reference.

Reproduces the kind of evidence FHK14 shows, for a semi-infinite medium lit by a collimated beam
(docs/physics.md §4.7, §9.3, §9.1):

1. the Monte Carlo itself against the exact index-matched totals of docs/physics.md §9.3 (eta = 1, g = 0);
2. exitance maps and 1D cuts in the plane of incidence at 0, 30, 45 and 60 degrees for catalogue
   materials (red channel), Monte Carlo against the directional, standard and better dipoles, with
   a table of errors (relative RMS over the brightest cells and error of the total);
3. the same at normal incidence for the green and blue channels;
4. total diffuse reflectance against reduced albedo for eta = 1.0, 1.3 and 1.4.

Everything is per refracted photon (the Monte Carlo launches along the refracted ray with weight
1); the models' entry transmittance T12 multiplies every model and the MC alike, so it cancels.
Model exitance per refracted photon (docs/physics.md §6.3, §9.2):

============================ ======================================== =======
model                        exitance M(x_o) per refracted photon     unit
============================ ======================================== =======
directional dipole (FHK14)   pi S_d 4 C_phi(1/eta)                    1/mm^2
standard dipole (Jensen)     R_d(r) (1 - 2 C1(1/eta))                 1/mm^2
better dipole (d'Eon)        R(r)                                     1/mm^2
============================ ======================================== =======

Run ``python bench/validate_models.py`` (about 10 minutes on two cores); it writes
``bench/results/validate_models.json``, ``validate_models.md`` (the tables) and
``validate_models_*.png``. ``--quick`` runs with a tenth of the photons and writes to
``bench/results/tmp/``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("NUMBA_THREADING_LAYER", "omp")

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.colors as mcolors  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy import ndimage  # noqa: E402

from translucency.scatter import dipoles, fresnel  # noqa: E402
from translucency.scatter.materials import material  # noqa: E402
from translucency.scatter.medium import alpha_reduced, sigma_t_reduced  # noqa: E402
from translucency.scatter.montecarlo import simulate_half_space  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
ANGLES = (0.0, 30.0, 45.0, 60.0)
CHANNELS = ("red", "green", "blue")
MODELS = ("directional", "standard", "better")
MODEL_LABELS = {"directional": "directional dipole", "standard": "standard dipole", "better": "better dipole"}
MODEL_STYLES = {
    "directional": dict(color="tab:red", linestyle="-"),
    "standard": dict(color="tab:blue", linestyle="--"),
    "better": dict(color="tab:green", linestyle=":"),
}

#: (catalogue key, photons per run). Counts are set so that each material costs roughly the same
#: time; cheap (strongly absorbing) materials get more photons.
MATERIALS = (
    ("marble", 400_000),
    ("skim_milk", 600_000),
    ("ketchup", 3_000_000),
    ("potato", 600_000),
    ("regular_chocolate_milk", 300_000),
    ("regular_soy_milk", 200_000),
    ("grape_juice", 20_000_000),
)

#: Map geometry in reduced mean free paths 1/sigma_t': cells of 0.2, half-width 4.1 (41 x 41 cells,
#: one centred on the point of incidence; the central row is the strip |y| < 0.1/sigma_t').
CELL_MFP = 0.2
GRID_CELLS = 41
SUBSAMPLES = 6  # model cell averages: SUBSAMPLES^2 midpoints per cell
REGION_FRACTION = 0.8  # error region: the brightest MC cells that hold this fraction of the map's exitance

MC_CHECK_ALBEDOS = (0.3, 0.5, 0.9, 0.99)
MC_CHECK_PHOTONS = 1_000_000
SPEC_3_3 = {  # docs/physics.md §9.3: exact R(mu0) = 1 - H(mu0) sqrt(1 - alpha), eta = 1, g = 0
    0.3: (0.057214, 0.062152, 0.069298, 0.081716),
    0.5: (0.115226, 0.124479, 0.137688, 0.160144),
    0.9: (0.414947, 0.436124, 0.464423, 0.507939),
    0.99: (0.752721, 0.768333, 0.787838, 0.815140),
}

SWEEP_ETAS = (1.0, 1.3, 1.4)
SWEEP_ALBEDOS = (0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 0.98, 0.99, 0.995, 0.999)
SWEEP_PHOTONS = 100_000


# --------------------------------------------------------------------------------------------------
# Exact reference (eta = 1, isotropic): Chandrasekhar's H function
# --------------------------------------------------------------------------------------------------


def chandrasekhar_H(albedo, mu, n_nodes=200, tolerance=1e-13, max_iterations=100_000):
    """Chandrasekhar's H function for isotropic scattering, ``H(mu)`` at the cosines ``mu``.

    Solves ``1/H(mu) = sqrt(1 - albedo) + (albedo/2) int_0^1 mu' H(mu') / (mu + mu') dmu'`` (the
    form that converges fast near albedo = 1) by fixed-point iteration on Gauss-Legendre nodes,
    then evaluates it at ``mu`` by the same equation (Nystrom interpolation).
    """
    nodes, weights = np.polynomial.legendre.leggauss(n_nodes)
    nodes = 0.5 * (nodes + 1.0)
    weights = 0.5 * weights
    root = math.sqrt(1.0 - albedo)
    H = np.ones(n_nodes)
    for _ in range(max_iterations):
        kernel = nodes[None, :] * H[None, :] * weights[None, :] / (nodes[:, None] + nodes[None, :])
        updated = 1.0 / (root + 0.5 * albedo * kernel.sum(axis=1))
        if np.max(np.abs(updated - H)) < tolerance:
            H = updated
            break
        H = updated
    mu = np.atleast_1d(np.asarray(mu, dtype=np.float64))
    kernel = nodes[None, :] * H[None, :] * weights[None, :] / (mu[:, None] + nodes[None, :])
    return 1.0 / (root + 0.5 * albedo * kernel.sum(axis=1))


def exact_total_reflectance(albedo, theta_deg):
    """Exact total diffuse reflectance of an index-matched isotropic half-space (docs/physics.md §9.3)."""
    mu0 = math.cos(math.radians(theta_deg))
    return float(1.0 - chandrasekhar_H(albedo, mu0)[0] * math.sqrt(1.0 - albedo))


# --------------------------------------------------------------------------------------------------
# Model predictions, per refracted photon
# --------------------------------------------------------------------------------------------------


def model_exitance(model, points_xy, theta_deg, sigma_a, sigma_s, g, eta):
    """Model exitance per refracted photon (1/mm^2) at points (..., 2) on the surface (mm)."""
    if model == "directional":
        S_d = dipoles.directional_dipole_profile(points_xy, theta_deg, sigma_a, sigma_s, g, eta)
        return np.pi * S_d * 4.0 * fresnel.C_phi(1.0 / eta)  # docs/physics.md §5.2: pi S_d / norm
    r = np.hypot(points_xy[..., 0], points_xy[..., 1])
    if model == "standard":
        return dipoles.standard_dipole_profile(r, sigma_a, sigma_s, g, eta) * (1.0 - fresnel.two_C1(1.0 / eta))
    if model == "better":
        return dipoles.better_dipole_profile(r, sigma_a, sigma_s, g, eta)
    raise ValueError(model)


def model_total(model, theta_deg, sigma_a, sigma_s, g, eta):
    """Model total diffuse reflectance per refracted photon (integral of :func:`model_exitance`)."""
    albedo = float(alpha_reduced(sigma_a, sigma_s, g))
    if model == "directional":
        return float(dipoles.directional_dipole_total_reflectance(sigma_a, sigma_s, g, eta, theta_deg))
    if model == "standard":
        return float(dipoles.standard_dipole_total_reflectance(albedo, eta) * (1.0 - fresnel.two_C1(1.0 / eta)))
    if model == "better":
        return float(dipoles.better_dipole_total_reflectance(albedo, eta))
    raise ValueError(model)


def cell_averages(model, edges, theta_deg, sigma_a, sigma_s, g, eta):
    """Model exitance averaged over each grid cell (midpoint rule on SUBSAMPLES^2 sub-cells)."""
    n = edges.size - 1
    width = edges[1] - edges[0]
    offsets = (np.arange(SUBSAMPLES) + 0.5) / SUBSAMPLES * width
    coords = (edges[:-1, None] + offsets[None, :]).ravel()  # n * SUBSAMPLES sub-cell centres
    xx, yy = np.meshgrid(coords, coords, indexing="xy")  # [y, x]
    values = model_exitance(model, np.stack([xx, yy], axis=-1), theta_deg, sigma_a, sigma_s, g, eta)
    return values.reshape(n, SUBSAMPLES, n, SUBSAMPLES).mean(axis=(1, 3))


def annulus_averages(model, edges, sigma_a, sigma_s, g, eta):
    """Radially symmetric model exitance (normal incidence) averaged over annuli (area-weighted)."""
    sub = 16
    t = (np.arange(sub) + 0.5) / sub
    r = edges[:-1, None] + t[None, :] * np.diff(edges)[:, None]
    points = np.stack([r, np.zeros_like(r)], axis=-1)
    values = model_exitance(model, points, 0.0, sigma_a, sigma_s, g, eta)
    return np.sum(values * r, axis=1) / np.sum(r, axis=1)


# --------------------------------------------------------------------------------------------------
# Error measures
# --------------------------------------------------------------------------------------------------


def error_region(mc_map):
    """Mask of the cells that hold most of the exitance: the brightest REGION_FRACTION of the map.

    Cells are ranked on the MC map smoothed with a one-cell Gaussian, so the region is a compact
    patch around the point of incidence rather than a speckle of lucky cells; it is then the
    smallest set of top-ranked cells whose (smoothed) exitance adds up to REGION_FRACTION of the map.
    """
    smooth = ndimage.gaussian_filter(mc_map, sigma=1.0, mode="nearest").ravel()
    order = np.argsort(smooth)[::-1]
    cumulative = np.cumsum(smooth[order])
    count = int(np.searchsorted(cumulative, REGION_FRACTION * cumulative[-1])) + 1
    mask = np.zeros(smooth.size, dtype=bool)
    mask[order[:count]] = True
    return mask.reshape(mc_map.shape) & (mc_map > 0)


def relative_rms(model_map, mc_map, mc_se, region):
    """Relative RMS error of a model over the region, with the Monte Carlo noise taken out.

    ``raw = sqrt(sum((model - MC)^2) / sum(MC^2))`` over the region's (equal-area) cells, i.e. the
    RMS error divided by the RMS exitance; ``floor = sqrt(sum(se^2) / sum(MC^2))`` is what a perfect
    model would score against this MC; the reported error is ``sqrt(max(raw^2 - floor^2, 0))`` (the
    expected squared deviation is the model's squared error plus the MC variance).

    Returns
    -------
    tuple of float
        ``(corrected, raw, floor)``.
    """
    mc = mc_map[region]
    scale = float(np.sum(mc * mc))
    raw = math.sqrt(float(np.sum((model_map[region] - mc) ** 2)) / scale)
    floor = math.sqrt(float(np.sum(mc_se[region] ** 2)) / scale)
    return math.sqrt(max(raw * raw - floor * floor, 0.0)), raw, floor


def median_relative_error(model_map, mc_map, region):
    """Median over the region's cells of ``|model - MC| / MC`` (every cell counts the same)."""
    mc = mc_map[region]
    return float(np.median(np.abs(model_map[region] - mc) / mc))


# --------------------------------------------------------------------------------------------------
# Runs
# --------------------------------------------------------------------------------------------------


def mc_self_check(scale, seed):
    """MC total against the exact index-matched values of docs/physics.md §9.3."""
    rows = []
    for albedo in MC_CHECK_ALBEDOS:
        for theta, spec_value in zip(ANGLES, SPEC_3_3[albedo]):
            tally = simulate_half_space(
                1.0 - albedo,
                albedo,
                0.0,
                1.0,
                theta,
                n_photons=max(int(MC_CHECK_PHOTONS * scale), 64),
                seed=seed,
                grid_cells=3,
                radial_bins=3,
            )
            exact = exact_total_reflectance(albedo, theta)
            rows.append(
                {
                    "albedo": albedo,
                    "theta_i_deg": theta,
                    "exact_spec_3_3": spec_value,
                    "exact_recomputed": exact,
                    "mc": tally.total_reflectance,
                    "mc_se": tally.total_reflectance_se,
                    "relative_difference": tally.total_reflectance / spec_value - 1.0,
                    "difference_in_se": (tally.total_reflectance - spec_value) / tally.total_reflectance_se,
                    "n_photons": tally.n_photons,
                    "elapsed_s": tally.elapsed_s,
                }
            )
            print(
                f"  MC check alpha={albedo:<5} theta={theta:4.0f}: {tally.total_reflectance:.6f} +- "
                f"{tally.total_reflectance_se:.6f} (exact {spec_value:.6f}, "
                f"{rows[-1]['difference_in_se']:+.2f} SE)",
                flush=True,
            )
    return rows


def material_run(key, channel, theta, n_photons, seed):
    """One MC run of a catalogue material's channel and the three models on the same grid."""
    entry = material(key)
    sigma_a, sigma_s, g, eta = entry.sigma_a[channel], entry.sigma_s[channel], entry.g[channel], entry.eta
    mfp = 1.0 / float(sigma_t_reduced(sigma_a, sigma_s, g))  # reduced mean free path, mm
    half_width = 0.5 * GRID_CELLS * CELL_MFP * mfp
    tally = simulate_half_space(
        sigma_a,
        sigma_s,
        g,
        eta,
        theta,
        n_photons=n_photons,
        seed=seed,
        grid_extent_mm=half_width,
        grid_cells=GRID_CELLS,
        radial_bins=int(round(GRID_CELLS / 2)),
    )
    edges = tally.grid_edges_mm
    region = error_region(tally.exitance)
    mid = GRID_CELLS // 2
    record = {
        "material": key,
        "table": entry.table,
        "channel": CHANNELS[channel],
        "theta_i_deg": theta,
        "sigma_a_per_mm": sigma_a,
        "sigma_s_per_mm": sigma_s,
        "g": g,
        "eta": eta,
        "alpha_reduced": float(alpha_reduced(sigma_a, sigma_s, g)),
        "reduced_mean_free_path_mm": mfp,
        "mc": tally.summary(),
        "map_half_width_mm": half_width,
        "region_cells": int(region.sum()),
        # what a perfect model would score on the median measure: median |N(0, se)| / MC = 0.674 se / MC
        "median_cell_noise_floor": float(np.median(0.6745 * tally.exitance_se[region] / tally.exitance[region])),
        "region_fraction_of_map_exitance": REGION_FRACTION,
        "map_fraction_of_total": float(tally.exitance.sum() * tally.cell_area_mm2 / tally.total_reflectance),
        "models": {},
        "cut": {
            "x_mm": tally.grid_centres_mm.tolist(),
            "strip_half_width_mm": 0.5 * CELL_MFP * mfp,
            "mc": tally.exitance[mid].tolist(),
            "mc_se": tally.exitance_se[mid].tolist(),
            "mc_multiple": tally.exitance_multiple[mid].tolist(),
        },
    }
    maps = {"mc": tally.exitance, "mc_se": tally.exitance_se, "mc_multiple": tally.exitance_multiple}
    for model in MODELS:
        prediction = cell_averages(model, edges, theta, sigma_a, sigma_s, g, eta)
        maps[model] = prediction
        rms, rms_raw, floor = relative_rms(prediction, tally.exitance, tally.exitance_se, region)
        rms_multiple = relative_rms(prediction, tally.exitance_multiple, tally.exitance_multiple_se, region)[0]
        total = model_total(model, theta, sigma_a, sigma_s, g, eta)
        record["models"][model] = {
            "relative_rms": rms,
            "relative_rms_uncorrected": rms_raw,
            "relative_rms_noise_floor": floor,
            "median_cell_relative_error": median_relative_error(prediction, tally.exitance, region),
            "relative_rms_vs_mc_multiple": rms_multiple,
            "total": total,
            "total_relative_error": total / tally.total_reflectance - 1.0,
            "total_relative_error_vs_mc_multiple": total / tally.multiple_reflectance - 1.0,
        }
        centres = tally.grid_centres_mm
        for side, half in (("forward", centres[None, :] > 0.0), ("backward", centres[None, :] < 0.0)):
            cells = region & np.broadcast_to(half, region.shape)
            record["models"][model][f"{side}_flux_ratio"] = float(prediction[cells].sum() / tally.exitance[cells].sum())
        record["cut"][model] = prediction[mid].tolist()
    if theta == 0.0:
        radial_edges = tally.radial_edges_mm
        record["radial"] = {
            "edges_mm": radial_edges.tolist(),
            "mc": tally.radial_exitance.tolist(),
            "mc_se": tally.radial_exitance_se.tolist(),
            "mc_multiple": tally.radial_exitance_multiple.tolist(),
            **{m: annulus_averages(m, radial_edges, sigma_a, sigma_s, g, eta).tolist() for m in MODELS},
        }
    return record, maps, region


def albedo_sweep(scale, seed):
    """Total diffuse reflectance against reduced albedo (g = 0, sigma_t = 1/mm, normal incidence)."""
    rows = []
    for eta in SWEEP_ETAS:
        for albedo in SWEEP_ALBEDOS:
            sigma_a, sigma_s = 1.0 - albedo, albedo
            tally = simulate_half_space(
                sigma_a,
                sigma_s,
                0.0,
                eta,
                0.0,
                n_photons=max(int(SWEEP_PHOTONS * scale), 64),
                seed=seed,
                grid_cells=3,
                radial_bins=3,
            )
            row = {
                "eta": eta,
                "alpha_reduced": albedo,
                "mc": tally.total_reflectance,
                "mc_se": tally.total_reflectance_se,
                "mc_single": tally.single_reflectance,
                "mc_multiple": tally.multiple_reflectance,
                "n_photons": tally.n_photons,
                "elapsed_s": tally.elapsed_s,
                "standard_dipole_raw_Rd": float(dipoles.standard_dipole_total_reflectance(albedo, eta)),
            }
            for model in MODELS:
                row[model] = model_total(model, 0.0, sigma_a, sigma_s, 0.0, eta)
            if eta == 1.0:
                row["exact"] = exact_total_reflectance(albedo, 0.0)
            rows.append(row)
        print(f"  albedo sweep eta={eta}: done", flush=True)
    return rows


# --------------------------------------------------------------------------------------------------
# Figures
# --------------------------------------------------------------------------------------------------


def _save(fig, title, path, dpi):
    """Title (optional), tight layout, write the PNG and free the figure."""
    if title:
        fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def figure_cuts(key, records, out):
    fig, axes = plt.subplots(1, len(records), figsize=(4.2 * len(records), 3.8), sharey=True)
    for ax, record in zip(axes, records):
        cut = record["cut"]
        x = np.asarray(cut["x_mm"])
        mc = np.asarray(cut["mc"])
        se = np.asarray(cut["mc_se"])
        positive = mc > 0
        ax.errorbar(
            x[positive], mc[positive], yerr=2 * se[positive], fmt="o", ms=3, color="k", label="MC (all orders, ±2 SE)"
        )
        multiple = np.asarray(cut["mc_multiple"])
        ax.plot(
            x[multiple > 0], multiple[multiple > 0], "o", ms=3, mfc="none", color="0.45", label="MC multiple scattering"
        )
        for model in MODELS:
            ax.plot(x, cut[model], label=MODEL_LABELS[model], **MODEL_STYLES[model])
        ax.set_yscale("log")
        ax.set_title(f"θi = {record['theta_i_deg']:.0f}°")
        ax.set_xlabel("x (mm), plane of incidence; refracted ray → +x")
        ax.grid(alpha=0.3, which="both")
    axes[0].set_ylabel("exitance per refracted photon (1/mm²)")
    first = records[0]
    top = max(np.max(r["cut"]["mc"]) for r in records)
    axes[0].set_ylim(top * 2e-3, top * 3)
    axes[-1].legend(fontsize=7, loc="upper right")
    title = (
        f"{key} ({first['channel']} channel; σa = {first['sigma_a_per_mm']:g}, σs = {first['sigma_s_per_mm']:g} /mm, "
        f"g = {first['g']:g}, η = {first['eta']:g}, α′ = {first['alpha_reduced']:.4f}); strip |y| < "
        f"{first['cut']['strip_half_width_mm']:.3g} mm"
    )
    _save(fig, title, out / f"validate_models_cuts_{key}.png", dpi=90)


def figure_maps(key, records, all_maps, regions, out):
    columns = ("mc", "directional", "directional/mc", "standard/mc", "better/mc")
    fig, axes = plt.subplots(len(records), len(columns), figsize=(3.0 * len(columns), 2.75 * len(records)))
    ratio_norm = mcolors.LogNorm(vmin=0.25, vmax=4.0)
    for row, (record, maps, region) in enumerate(zip(records, all_maps, regions)):
        half = record["map_half_width_mm"]
        extent = (-half, half, -half, half)
        mc = maps["mc"]
        top = mc.max()
        exitance_norm = mcolors.LogNorm(vmin=top * 1e-3, vmax=top)
        for col, name in enumerate(columns):
            ax = axes[row, col]
            if "/" in name:
                model = name.split("/")[0]
                with np.errstate(divide="ignore", invalid="ignore"):
                    ratio = np.where(region, maps[model] / mc, np.nan)
                image = ax.imshow(ratio, origin="lower", extent=extent, cmap="RdBu_r", norm=ratio_norm)
                ax.set_facecolor("0.85")
                errors = record["models"][model]
                ax.set_title(
                    f"{MODEL_LABELS[model]} / MC\nrel. RMS {_fraction(errors['relative_rms'])}, "
                    f"median {_fraction(errors['median_cell_relative_error'])}",
                    fontsize=8,
                )
            else:
                image = ax.imshow(
                    np.where(maps[name] > 0, maps[name], np.nan),
                    origin="lower",
                    extent=extent,
                    cmap="magma",
                    norm=exitance_norm,
                )
                ax.set_title(
                    ("MC" if name == "mc" else MODEL_LABELS[name]) + f", θi = {record['theta_i_deg']:.0f}°", fontsize=8
                )
            ax.tick_params(labelsize=6)
            if col in (1, 4):
                fig.colorbar(image, ax=ax, fraction=0.046, pad=0.02).ax.tick_params(labelsize=6)
        axes[row, 0].set_ylabel("y (mm)", fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("x (mm)", fontsize=7)
    title = (
        f"{key} ({records[0]['channel']}): exitance per refracted photon (1/mm², log, 3 decades) and model/MC "
        f"ratio (log, 1/4 … 4) over the error region (the brightest cells, holding {int(100 * REGION_FRACTION)} % "
        "of the map's MC exitance)"
    )
    _save(fig, title, out / f"validate_models_maps_{key}.png", dpi=80)


def figure_albedo(rows, out):
    fig, axes = plt.subplots(
        2, len(SWEEP_ETAS), figsize=(5.0 * len(SWEEP_ETAS), 7.5), sharex=True, gridspec_kw={"height_ratios": [2.2, 1]}
    )
    fine = 1.0 - np.geomspace(0.99, 5e-4, 160)  # reduced albedo, dense toward 1
    ticks = (0.05, 0.5, 0.8, 0.9, 0.95, 0.98, 0.99, 0.995, 0.999)
    for col, eta in enumerate(SWEEP_ETAS):
        sub = [r for r in rows if r["eta"] == eta]
        albedo = np.array([r["alpha_reduced"] for r in sub])
        mc = np.array([r["mc"] for r in sub])
        ax = axes[0, col]
        ax.errorbar(
            1 - albedo, mc, yerr=[2 * r["mc_se"] for r in sub], fmt="o", color="k", ms=4, label="MC (all orders, ±2 SE)"
        )
        ax.plot(
            1 - albedo,
            [r["mc_multiple"] for r in sub],
            "o",
            mfc="none",
            color="0.45",
            ms=4,
            label="MC multiple scattering",
        )
        for model in MODELS:
            curve = [model_total(model, 0.0, 1.0 - a, a, 0.0, eta) for a in fine]
            ax.plot(1 - fine, curve, label=MODEL_LABELS[model], **MODEL_STYLES[model])
        if eta == 1.0:
            ax.plot(
                1 - fine,
                [exact_total_reflectance(a, 0.0) for a in fine],
                color="0.3",
                lw=3,
                alpha=0.35,
                label="exact (Chandrasekhar H)",
            )
        ax.set_title(f"η = {eta}, normal incidence, g = 0")
        ax.set_ylabel("total diffuse reflectance per refracted photon")
        ax.grid(alpha=0.3)
        ax.set_ylim(0, 1.3)
        ratio_ax = axes[1, col]
        for model in MODELS:
            ratio_ax.plot(
                1 - albedo,
                np.array([r[model] for r in sub]) / mc,
                marker=".",
                label=MODEL_LABELS[model],
                **MODEL_STYLES[model],
            )
        ratio_ax.axhline(1.0, color="k", lw=0.8)
        ratio_ax.set_yscale("log")
        ratio_ax.set_ylim(0.05, 40)
        ratio_ax.set_xscale("log")
        ratio_ax.invert_xaxis()
        ratio_ax.set_xticks([1 - t for t in ticks], [f"{t:g}" for t in ticks], fontsize=7)
        ratio_ax.minorticks_off()
        ratio_ax.set_xlabel("reduced albedo α′ (axis: log(1 − α′))")
        ratio_ax.set_ylabel("model / MC")
        ratio_ax.grid(alpha=0.3, which="both")
    axes[0, 0].legend(fontsize=7, loc="upper left")
    _save(fig, None, out / "validate_models_albedo.png", dpi=90)


ERROR_MEASURES = (
    ("relative_rms", "rel. RMS, exitance-weighted (%)"),
    ("median_cell_relative_error", "median cell |error| (%)"),
    ("total_relative_error", "error of the total (%)"),
)


def _compact_factor(value):
    """A large ratio as a short label: 12100 -> '×1e4'."""
    if value < 100:
        return f"×{value:.0f}"
    return f"×{value:.0e}".replace("e+0", "e").replace("e+", "e")


def figure_errors(records, out):
    """Heat maps of the three error measures per model, material (red channel) and angle."""
    keys = [k for k, _ in MATERIALS]
    fig, axes = plt.subplots(len(ERROR_MEASURES), len(MODELS), figsize=(3.6 * len(MODELS), 3.2 * len(ERROR_MEASURES)))
    for col, model in enumerate(MODELS):
        for row, (kind, title) in enumerate(ERROR_MEASURES):
            ax = axes[row, col]
            grid = np.full((len(keys), len(ANGLES)), np.nan)
            for record in records:
                if record["channel"] == "red":
                    i, j = keys.index(record["material"]), ANGLES.index(record["theta_i_deg"])
                    grid[i, j] = record["models"][model][kind]
            if kind == "total_relative_error":
                ax.imshow(np.log2(1 + grid), cmap="RdBu_r", vmin=-2, vmax=2)
                labels = [[f"{100 * v:+.0f}" if abs(v) < 10 else _compact_factor(1 + v) for v in line] for line in grid]
                colours = np.where(np.abs(np.log2(1 + grid)) > 1.4, "w", "k")
            else:
                ax.imshow(100 * grid, cmap="viridis", norm=mcolors.LogNorm(vmin=3, vmax=300))
                labels = [[f"{100 * v:.0f}" if v < 10 else _compact_factor(v) for v in line] for line in grid]
                colours = np.where(grid > 2.0, "k", "w")
            for i in range(len(keys)):
                for j in range(len(ANGLES)):
                    ax.text(j, i, labels[i][j], ha="center", va="center", fontsize=7, color=colours[i, j])
            ax.set_xticks(range(len(ANGLES)), [f"{a:.0f}°" for a in ANGLES], fontsize=7)
            ax.set_yticks(range(len(keys)), keys if col == 0 else [""] * len(keys), fontsize=7)
            ax.set_title(f"{MODEL_LABELS[model]}: {title}", fontsize=8)
    title = "Model against Monte Carlo, red channel, per refracted photon (total: blue = too dark, red = too bright)"
    _save(fig, title, out / "validate_models_errors.png", dpi=90)


# --------------------------------------------------------------------------------------------------
# Tables
# --------------------------------------------------------------------------------------------------


def _percent(value):
    if not math.isfinite(value):
        return "—"
    if abs(value) >= 10:  # more than 1000 %: say it as a factor
        return f"×{1 + value:.3g}"
    return f"{100 * value:+.0f} %"


def _fraction(value):
    return f"{100 * value:.0f} %" if value < 10 else f"×{value:.2g}"


def _material_row(record, with_angle):
    mc = record["mc"]
    m = record["models"]
    rms = " / ".join(_fraction(m[k]["relative_rms"]) for k in MODELS)
    median = " / ".join(_fraction(m[k]["median_cell_relative_error"]) for k in MODELS)
    total = " / ".join(_percent(m[k]["total_relative_error"]) for k in MODELS)
    where = f"{record['theta_i_deg']:.0f}°" if with_angle else record["channel"]
    floors = (
        f"{100 * m['directional']['relative_rms_noise_floor']:.1f} / {100 * record['median_cell_noise_floor']:.0f} %"
    )
    return (
        f"| {record['material']} | {record['alpha_reduced']:.4f} | {where} | "
        f"{mc['total_reflectance']:.4g} ± {mc['total_reflectance_se']:.2g} | "
        f"{100 * mc['single_reflectance'] / mc['total_reflectance']:.0f} % | {rms} | {median} | {total} | {floors} |"
    )


def markdown_tables(mc_rows, records, sweep_rows, timings):
    lines = ["### Monte Carlo against the exact index-matched totals (docs/physics.md §9.3, η = 1, g = 0)", ""]
    lines += ["| α | θi | exact | MC ± SE | difference | in SE |", "|---|---|---|---|---|---|"]
    for row in mc_rows:
        lines.append(
            f"| {row['albedo']} | {row['theta_i_deg']:.0f}° | {row['exact_spec_3_3']:.6f} | {row['mc']:.6f} ± "
            f"{row['mc_se']:.6f} | {100 * row['relative_difference']:+.3f} % | {row['difference_in_se']:+.2f} |"
        )
    lines += ["", "### Errors per model, material and angle (red channel, per refracted photon)", ""]
    lines += [
        "Columns per model (dir. / std. / better): relative RMS over the error region (exitance-weighted, MC noise "
        "removed); median over the region's cells of |model − MC| / MC; error of the total reflectance.",
        "",
        "| material | α′ | θi | MC total ± SE | MC single | rel. RMS | median cell error | total error | "
        "noise RMS / median |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for record in records:
        if record["channel"] == "red":
            lines.append(_material_row(record, with_angle=True))
    lines += ["", "### Normal incidence, all channels", ""]
    lines += [
        "| material | α′ | channel | MC total ± SE | MC single | rel. RMS | median cell error | total error | "
        "noise RMS / median |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for record in records:
        if record["theta_i_deg"] == 0.0:
            lines.append(_material_row(record, with_angle=False))
    lines += ["", "### Forward and backward halves of the error region (red channel)", ""]
    lines += [
        "Model / MC ratio of the exitance summed over the region's cells with x > 0 (forward: the side the "
        "refracted ray travels to) and x < 0 (backward).",
        "",
        "| material | θi | directional fwd / back | standard fwd / back | better fwd / back |",
        "|---|---|---|---|---|",
    ]
    for record in records:
        if record["channel"] == "red":
            m = record["models"]
            cells = " | ".join(f"{m[k]['forward_flux_ratio']:.2f} / {m[k]['backward_flux_ratio']:.2f}" for k in MODELS)
            lines.append(f"| {record['material']} | {record['theta_i_deg']:.0f}° | {cells} |")
    lines += ["", "### Total diffuse reflectance against reduced albedo (normal incidence, g = 0)", ""]
    lines += [
        "| η | α′ | MC ± SE | MC single | exact | directional | standard | better |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for row in sweep_rows:
        exact = f"{row['exact']:.4f}" if "exact" in row else "—"
        lines.append(
            f"| {row['eta']} | {row['alpha_reduced']} | {row['mc']:.4f} ± {row['mc_se']:.4f} | "
            f"{row['mc_single']:.4f} | "
            f"{exact} | {row['directional']:.4f} | {row['standard']:.4f} | {row['better']:.4f} |"
        )
    lines += ["", "Run time (s): " + ", ".join(f"{k} {v:.0f}" for k, v in timings.items())]
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------------------------------
# Main
# --------------------------------------------------------------------------------------------------


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a tenth of the photons; results to bench/results/tmp/")
    parser.add_argument("--out", type=Path, default=None, help="output folder (default bench/results)")
    parser.add_argument("--seed", type=int, default=2014)
    args = parser.parse_args(argv)
    scale = 0.1 if args.quick else 1.0
    out = args.out or (RESULTS / "tmp" if args.quick else RESULTS)
    out.mkdir(parents=True, exist_ok=True)
    timings = {}
    started = time.perf_counter()

    print("1. Monte Carlo against the exact eta = 1 totals", flush=True)
    clock = time.perf_counter()
    mc_rows = mc_self_check(scale, args.seed)
    timings["mc_check"] = time.perf_counter() - clock

    print("2. materials", flush=True)
    clock = time.perf_counter()
    records = []
    for key, photons in MATERIALS:
        n_photons = max(int(photons * scale), 64)
        red_records, red_maps, red_regions = [], [], []
        for theta in ANGLES:
            record, maps, region = material_run(key, 0, theta, n_photons, args.seed)
            records.append(record)
            red_records.append(record)
            red_maps.append(maps)
            red_regions.append(region)
            m = record["models"]
            print(
                f"  {key:24s} red {theta:3.0f}°: MC {record['mc']['total_reflectance']:.4g} "
                f"({record['mc']['elapsed_s']:.1f} s); rel. RMS "
                + " ".join(f"{k} {m[k]['relative_rms']:.3g}" for k in MODELS)
                + "; total err "
                + " ".join(f"{k} {m[k]['total_relative_error']:+.3g}" for k in MODELS),
                flush=True,
            )
        figure_cuts(key, red_records, out)
        figure_maps(key, red_records, red_maps, red_regions, out)
        entry = material(key)
        for channel in (1, 2):
            if not entry.scattering_channels[channel]:
                print(f"  {key:24s} {CHANNELS[channel]}: does not scatter, skipped", flush=True)
                continue
            record, _, _ = material_run(key, channel, 0.0, n_photons, args.seed)
            records.append(record)
    timings["materials"] = time.perf_counter() - clock

    print("3. total reflectance against albedo", flush=True)
    clock = time.perf_counter()
    sweep_rows = albedo_sweep(scale, args.seed)
    timings["albedo_sweep"] = time.perf_counter() - clock

    clock = time.perf_counter()
    figure_albedo(sweep_rows, out)
    figure_errors(records, out)
    timings["figures_and_tables"] = time.perf_counter() - clock
    timings["total"] = time.perf_counter() - started

    settings = {
        "seed": args.seed,
        "quick": args.quick,
        "per": "refracted photon (MC launched along the refracted ray with weight 1)",
        "map_cell_in_reduced_mean_free_paths": CELL_MFP,
        "map_cells_per_side": GRID_CELLS,
        "model_subsamples_per_cell_side": SUBSAMPLES,
        "error_region_fraction": REGION_FRACTION,
        "relative_rms": "sqrt((sum over the region's cells of (model - MC)^2 - sum se^2) / sum MC^2)",
        "model_exitance": {
            "directional": "pi * S_d * 4 C_phi(1/eta)",
            "standard": "R_d(r) * (1 - 2 C1(1/eta))",
            "better": "R(r)",
        },
        "materials_photons": dict(MATERIALS),
        "mc_check_photons": MC_CHECK_PHOTONS,
        "sweep_photons": SWEEP_PHOTONS,
        "photon_scale": scale,
        "threads": int(__import__("numba").get_num_threads()),
    }
    payload = {
        "settings": settings,
        "timings_s": timings,
        "mc_check": mc_rows,
        "materials": records,
        "albedo_sweep": sweep_rows,
    }
    (out / "validate_models.json").write_text(json.dumps(payload, indent=1))
    tables = markdown_tables(mc_rows, records, sweep_rows, timings)
    (out / "validate_models.md").write_text(tables)
    print(tables)
    print(f"wrote {out}/validate_models.json, .md and PNGs in {timings['total']:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
