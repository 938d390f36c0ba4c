"""Mitsuba 3 path-traced radiance along the normal on icospheres: the ground truth other tracers are checked against.

Two configurations, each an icosphere (``translucency.geometry.synthetic.icosphere``, flat faces: the
object is the polyhedron) lit by one light along +z, the radiance estimated at face centroids along
the face normals by :func:`translucency.reference.mitsuba_check.volpath_radiance`:

* ``marble``: radius 20 mm, level 5 (20480 faces), marble from the catalogue (Jensen et al. 2001:
  reduced ``sigma_s`` with ``g = 0``, ``eta = 1.5``), 50 sensor faces from 6 to 110 deg off the
  light (further round, the radiance is below 1 % of the lit side's and the noise swamps it), all
  three channels at a light half-angle of 4 deg, and the green channel again at 2 deg on the same
  faces: the difference measures the bias of the light's finite size (of order its square).
* ``fast``: radius 5 mm, level 3 (1280 faces), ``sigma_a = 0.1``, ``sigma_s = 1`` /mm, ``g = 0``,
  ``eta = 1.3``, 8 faces from 10 to 120 deg, one channel, half-angle 5 deg: short paths, cheap
  enough for a test of another tracer.

Writes ``bench/results/reference_mitsuba.json`` (``--quick``: ``bench/results/tmp/``, smaller sample
counts) with everything that reproduces the numbers: mesh construction, the sensor faces (index,
centroid, normal, angle to the light), coefficients, eta, light, spp, batches, seeds, depth settings,
Mitsuba's version and variant, and the time taken.

    .venv/bin/python bench/reference_mitsuba.py                   # both configurations (about 15 min on 2 cores)
    .venv/bin/python bench/reference_mitsuba.py --only fast       # the fast one
    .venv/bin/python bench/reference_mitsuba.py --quick           # a smoke run
    .venv/bin/python bench/reference_mitsuba.py --spp-scale 8     # 8 times the samples (sqrt(8) less noise)
    .venv/bin/python bench/reference_mitsuba.py --variant llvm_ad_rgb   # vectorised (libLLVM 16 or newer)
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np  # noqa: E402
from report import load_average, machine_info, output_dir, write_results  # noqa: E402

from translucency.geometry.measure import triangle_normals  # noqa: E402
from translucency.geometry.synthetic import icosphere  # noqa: E402
from translucency.reference.mitsuba_check import VARIANTS, volpath_radiance  # noqa: E402
from translucency.scatter.materials import material  # noqa: E402
from translucency.scatter.medium import Medium  # noqa: E402

CHANNELS = ("red", "green", "blue")
LIGHT = (0.0, 0.0, 1.0)
CONFIGS = {
    "marble": {
        "radius_mm": 20.0,
        "level": 5,
        "material": "marble",
        "points": 50,
        "polar_deg": (6.0, 110.0),
        # (half-angle in degrees, channels, samples per point and channel)
        "runs": ((4.0, (0, 1, 2), 16384), (2.0, (1,), 16384)),
    },
    "fast": {
        "radius_mm": 5.0,
        "level": 3,
        "coefficients": {"sigma_a": 0.1, "sigma_s": 1.0, "g": 0.0, "eta": 1.3},
        "points": 8,
        "polar_deg": (10.0, 120.0),
        "runs": ((5.0, (0,), 1048576),),
    },
}
#: Sensor faces counted as lit: at most this far off the light, degrees.
LIT_DEG = 80.0
GOLDEN_DEG = 180.0 * (3.0 - math.sqrt(5.0))


def sensor_faces(normals: np.ndarray, count: int, polar_deg: tuple) -> np.ndarray:
    """Faces whose normals are nearest ``count`` directions spread in polar angle from the light (+z) and in azimuth.

    The directions are at polar angles evenly spaced over ``polar_deg`` (degrees from +z) and azimuths
    advancing by the golden angle; each picks the face whose normal is closest, without repeats.
    """
    polar = np.radians(np.linspace(polar_deg[0], polar_deg[1], count))
    azimuth = np.radians(GOLDEN_DEG * np.arange(count))
    targets = np.stack([np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth), np.cos(polar)], axis=1)
    chosen = []
    for target in targets:
        order = np.argsort(-(normals @ target))
        chosen.append(next(int(i) for i in order if int(i) not in chosen))
    return np.array(chosen)


def config_medium(config: dict) -> Medium:
    """The configuration's medium: a catalogue material or the given coefficients (1/mm)."""
    if "material" in config:
        return material(config["material"]).medium()
    c = config["coefficients"]
    return Medium([c["sigma_a"]], [c["sigma_s"]], [c["g"]], c["eta"], name="fast")


def run_config(name: str, config: dict, spp_scale: float, seed: int, variant: str = "scalar_rgb") -> dict:
    """Trace one configuration; print the time per point and the relative standard error reached."""
    points, triangles = icosphere(config["level"], config["radius_mm"])
    normals = triangle_normals(points, triangles)
    faces = sensor_faces(normals, config["points"], config["polar_deg"])
    centroids = points[triangles[faces]].mean(axis=1)
    polar = np.degrees(np.arccos(np.clip(normals[faces] @ np.asarray(LIGHT), -1.0, 1.0)))
    lit = polar <= LIT_DEG
    medium = config_medium(config)
    runs = []
    for half_angle, channels, spp in config["runs"]:
        spp = max(16, int(round(spp * spp_scale)))
        one = Medium(
            medium.sigma_a[list(channels)], medium.sigma_s[list(channels)], medium.g[list(channels)], medium.eta
        )
        start = time.perf_counter()
        result = volpath_radiance(
            points,
            triangles,
            centroids,
            normals[faces],
            one,
            LIGHT,
            light_half_angle_deg=half_angle,
            spp=spp,
            seed=seed,
            variant=variant,
        )
        seconds = time.perf_counter() - start
        relative = result.relative_stderr[lit]
        per_point = seconds / (len(faces) * len(channels))
        print(
            f"{name}: half-angle {half_angle:g} deg, {', '.join(CHANNELS[c] for c in channels)}: {seconds:.0f} s "
            f"({per_point:.1f} s per point and channel, {result.spp} samples), relative standard error on the "
            f"{int(lit.sum())} lit points: median {np.median(relative) * 100:.1f} %, max {relative.max() * 100:.1f} % "
            f"(load {load_average()[0]})",
            flush=True,
        )
        runs.append(
            {
                "light_half_angle_deg": half_angle,
                "channels": [CHANNELS[c] for c in channels],
                "radiance": result.radiance,
                "stderr": result.stderr,
                "spp": result.spp,
                "n_batches": result.n_batches,
                "seed": result.seed,
                "max_depth": result.max_depth,
                "rr_depth": result.rr_depth,
                "light_radiance_W_m2_sr": result.light_radiance,
                "light_distance_mm": result.light_distance_mm,
                "sensor_offset_mm": result.sensor_offset_mm,
                "variant": result.variant,
                "mitsuba_version": result.mitsuba_version,
                "seconds": seconds,
                "seconds_per_point_and_channel": per_point,
                "relative_stderr_lit_median": float(np.median(relative)),
                "relative_stderr_lit_max": float(relative.max()),
            }
        )
    out = {
        "mesh": {
            "construction": f"translucency.geometry.synthetic.icosphere({config['level']}, {config['radius_mm']})",
            "vertices": len(points),
            "faces": len(triangles),
            "shading": "flat face normals (the polyhedron)",
        },
        "medium": {
            "name": medium.name,
            "sigma_a_per_mm": medium.sigma_a,
            "sigma_s_per_mm": medium.sigma_s,
            "g": medium.g,
            "eta": medium.eta,
            "note": "unreduced sigma_s as traced (the catalogue's jensen2001 rows are reduced with g = 0)",
        },
        "light": {
            "direction_towards_light": LIGHT,
            "irradiance_W_m2": 1.0,
            "model": "uniform sphere of angular radius half_angle: L_e = E / (pi sin^2 half_angle)",
        },
        "sensors": {
            "face": faces,
            "centroid_mm": centroids,
            "normal": normals[faces],
            "angle_to_light_deg": polar,
            "lit": lit,
            "quantity": "radiance leaving the surface along the face normal, W/(m^2 sr) per W/m^2",
        },
        "runs": runs,
    }
    out["finite_light_bias"] = finite_light_bias(runs, lit)
    return out


def finite_light_bias(runs: list, lit: np.ndarray) -> list:
    """Per channel traced at two half-angles: the ratio of the lit points' summed radiance, narrow over wide.

    The sum over the lit points weights each point by its radiance, so the ratio's noise is that of
    the total; its standard error is propagated from the per-point errors (independent runs).
    """
    found = []
    for i, wide in enumerate(runs):
        for narrow in runs[i + 1 :]:
            for c_narrow, channel in enumerate(narrow["channels"]):
                if channel not in wide["channels"]:
                    continue
                c_wide = wide["channels"].index(channel)
                a, sa = narrow["radiance"][lit, c_narrow], narrow["stderr"][lit, c_narrow]
                b, sb = wide["radiance"][lit, c_wide], wide["stderr"][lit, c_wide]
                ratio = a.sum() / b.sum()
                error = ratio * math.hypot(math.sqrt((sa**2).sum()) / a.sum(), math.sqrt((sb**2).sum()) / b.sum())
                found.append(
                    {
                        "channel": channel,
                        "half_angles_deg": [narrow["light_half_angle_deg"], wide["light_half_angle_deg"]],
                        "ratio_lit_sum": ratio,
                        "ratio_stderr": error,
                    }
                )
    return found


def table(payload: dict) -> str:
    """A Markdown summary: per configuration and run, the time and the relative standard error."""
    lines = [
        "| configuration | half-angle (°) | channels | spp | s per point and channel | rel. stderr, lit (median/max) |",
        "|---|---|---|---|---|---|",
    ]
    for name, config in payload["configurations"].items():
        for run in config["runs"]:
            lines.append(
                f"| {name} | {run['light_half_angle_deg']:g} | {', '.join(run['channels'])} | {run['spp']} | "
                f"{run['seconds_per_point_and_channel']:.1f} | {run['relative_stderr_lit_median'] * 100:.1f} % / "
                f"{run['relative_stderr_lit_max'] * 100:.1f} % |"
            )
    for name, config in payload["configurations"].items():
        for bias in config["finite_light_bias"]:
            narrow, wide = bias["half_angles_deg"]
            lines.append(
                f"\n{name}, {bias['channel']}: lit points' radiance at {narrow:g} deg / at {wide:g} deg = "
                f"{bias['ratio_lit_sum']:.4f} ± {bias['ratio_stderr']:.4f}"
            )
    return "\n".join(lines)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", choices=sorted(CONFIGS), help="run one configuration")
    parser.add_argument("--quick", action="store_true", help="1/64 of the samples, into bench/results/tmp")
    parser.add_argument("--spp-scale", type=float, default=1.0, help="multiply every sample count (default 1)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--variant", choices=VARIANTS, default="scalar_rgb", help="Mitsuba variant (default scalar_rgb)"
    )
    args = parser.parse_args(argv)
    scale = args.spp_scale / (64.0 if args.quick else 1.0)
    info = machine_info()
    start = time.perf_counter()
    configurations = {
        name: run_config(name, config, scale, args.seed, args.variant)
        for name, config in CONFIGS.items()
        if args.only in (None, name)
    }
    info["seconds"] = time.perf_counter() - start
    payload = {"info": info, "configurations": configurations}
    write_results(output_dir(args.quick), "reference_mitsuba", payload, table(payload))
    print(f"total {info['seconds']:.0f} s")


if __name__ == "__main__":
    main()
