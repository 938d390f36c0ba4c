"""The ``translucency`` command line: a thin layer over the Python API.

Subcommands (more arrive with the solver and the viewer):

* ``translucency materials`` -- the material catalogue with coefficients and length scales;
* ``translucency report`` -- versions of the stack and whether off-screen rendering works;
* ``translucency`` with no subcommand -- the main job on the embedded default scan.

Errors the user can cause are printed as one sentence on stderr with exit code 2; no traceback.
"""

from __future__ import annotations

import argparse
import sys

from .. import __version__
from ..errors import TranslucencyError


def _format_triplet(values, fmt="{:.4g}") -> str:
    return ", ".join(fmt.format(v) for v in values)


def cmd_materials(args) -> int:
    """Print the catalogue: name, source table, eta, sigma_a, sigma_s (or sigma_s'), g, length scales."""
    from ..scatter.materials import catalogue, material_tables

    tables = material_tables()
    rows = []
    for entry in catalogue():
        if args.table and entry.table != args.table:
            continue
        if entry.is_diffusive:
            medium = entry.medium()
            mfp = _format_triplet(medium.mean_free_path, "{:.3g}")
            diffusion = _format_triplet(medium.diffusion_length, "{:.3g}")
        else:
            mfp = diffusion = "(does not scatter in every channel)"
        rows.append((entry.key, entry.table, f"{entry.eta:g}", _format_triplet(entry.sigma_a), _format_triplet(entry.sigma_s),
                     _format_triplet(entry.g, "{:g}"), mfp, diffusion))
    header = ("name", "table", "eta", "sigma_a [1/mm]", "sigma_s [1/mm]", "g", "1/sigma_t' [mm]", "1/sigma_tr [mm]")
    widths = [max(len(str(r[i])) for r in rows + [header]) for i in range(len(header))]
    for row in [header, tuple("-" * w for w in widths)] + rows:
        print("  ".join(str(c).ljust(w) for c, w in zip(row, widths)).rstrip())
    print()
    for key, table in tables.items():
        if args.table and key != args.table:
            continue
        reduced = "reduced sigma_s' (g = 0)" if table["sigma_s_is_reduced"] else "unreduced sigma_s with g"
        print(f"{key}: {table['source']} Units {table['units']}; {reduced}. {table['notes']}")
    return 0


def cmd_report(args) -> int:
    """Print the versions of the stack and check off-screen rendering."""
    from importlib import metadata
    import platform

    print(f"translucency {__version__} on Python {platform.python_version()} ({platform.platform()})")
    for package in ("numpy", "scipy", "numba", "llvmlite", "pyvista", "vtk", "pymeshlab", "fast-simplification",
                    "embreex", "plyfile", "matplotlib", "imageio", "tqdm"):
        try:
            version = metadata.version(package)
        except metadata.PackageNotFoundError:
            version = "NOT INSTALLED"
        print(f"  {package:<20} {version}")
    from .render import offscreen_check

    ok, detail = offscreen_check()
    print(f"off-screen rendering: {'works' if ok else 'FAILS'} ({detail})")
    return 0 if ok else 1


def cmd_inspect(args) -> int:
    """Load a scan, print its size and defects, repair it and print what changed; optionally save it."""
    import warnings

    from ..io.clean import clean_mesh
    from ..io.load import load_mesh
    from ..io.save import check_output_path, save_mesh

    if args.output:
        check_output_path(args.output, args.mesh)  # before any work: a bad output path fails at once
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mesh = load_mesh(args.mesh, unit=args.unit)
    for warning in caught:
        print(f"translucency: warning: {warning.message}", file=sys.stderr)
    low, high = mesh.bounds
    print(f"{args.mesh}: {mesh.n_points} vertices, {mesh.n_triangles} triangles, "
          f"{mesh.extent:.4g} mm across ({' x '.join(f'{v:.4g}' for v in high - low)} mm), area {mesh.surface_area:.4g} mm^2")
    cleaned, report = clean_mesh(mesh, max_hole_edges=args.max_hole_edges)
    print(report)
    if args.output:
        save_mesh(args.output, cleaned)
        print(f"wrote the repaired mesh to {args.output}")
    return 0


def cmd_main_job(args) -> int:
    """The main job on the embedded default scan (see :mod:`translucency.app.default_job`)."""
    from .default_job import run_default_job

    return run_default_job()


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="translucency",
        description="Translucent shading of 3D scans with the directional dipole BSSRDF.",
    )
    parser.add_argument("--version", action="version", version=f"translucency {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    p = sub.add_parser("materials", help="list the material catalogue")
    p.add_argument("--table", choices=["jensen2001", "narasimhan2006"], help="only one source table")
    p.set_defaults(func=cmd_materials)

    p = sub.add_parser("report", help="versions of the stack and whether off-screen rendering works")
    p.set_defaults(func=cmd_report)

    p = sub.add_parser("inspect", help="load a scan, show its defects and repair it")
    p.add_argument("mesh", help="mesh file (PLY, OBJ, STL, OFF, VTK, VTP, ...)")
    p.add_argument("--unit", default="mm", help="length unit of the file: mm, cm, m, in or mm per unit (default mm)")
    p.add_argument("--max-hole-edges", type=int, default=100, help="close holes of at most this many edges")
    p.add_argument("-o", "--output", help="save the repaired mesh (any format PyVista writes)")
    p.set_defaults(func=cmd_inspect)

    parser.set_defaults(func=cmd_main_job)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``translucency`` and ``python -m translucency``; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except TranslucencyError as exc:
        print(f"translucency: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("translucency: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
