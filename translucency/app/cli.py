"""The ``translucency`` command line: a thin layer over the Python API.

Subcommands:

* ``translucency materials`` -- the material catalogue with coefficients and length scales;
* ``translucency report`` -- versions of the stack and whether off-screen rendering works;
* ``translucency inspect`` -- a scan's size and defects, repaired;
* ``translucency bake`` -- scans to baked PLY files (:mod:`translucency.app.bake`);
* ``translucency view`` -- the interactive viewer, or an off-screen screenshot (:mod:`translucency.app.viewer`);
* ``translucency compare`` -- materials and models side by side (:mod:`translucency.app.compare`);
* ``translucency`` with no subcommand -- the main job on the embedded default scan.

Errors the user can cause are printed as one sentence on stderr with exit code 2 (``bake``: 1 when
some files failed); an output that cannot be written once the work is done (disk full, quota) is one
sentence with exit code 1. No traceback.
"""

from __future__ import annotations

import argparse
import sys
import textwrap

from .. import __version__
from ..errors import InvalidParameterError, TranslucencyError, command_line_spelling


def _format_triplet(values, fmt="{:.4g}") -> str:
    return ", ".join(fmt.format(v) for v in values)


#: Columns the default ``translucency materials`` fits in (``--wide``: every column, as wide as it takes).
MATERIALS_WIDTH = 100


def _compact(values) -> str:
    """Per-channel values, two significant digits below 10 and whole numbers from 10: ``"0.0021 0.0041 0.0071"``."""
    return " ".join(f"{v:.0f}" if 10 <= v < float("inf") else f"{v:.2g}" for v in values)


def _table_lines(header, rows) -> list[str]:
    """Columns padded to their widest cell, two spaces apart, with a rule under the header."""
    widths = [max(len(str(r[i])) for r in rows + [header]) for i in range(len(header))]
    return [
        "  ".join(str(c).ljust(w) for c, w in zip(row, widths)).rstrip()
        for row in [header, tuple("-" * w for w in widths)] + rows
    ]


def _own_material_lines() -> list[str]:
    """The user's own materials (their folder and names), for ``translucency materials``."""
    from .shading.settings import user_material_files, user_materials_folder

    files = user_material_files()
    if not files:
        return [f"your own materials: none; put NAME.toml or NAME.json files in {user_materials_folder()}"]
    names = ", ".join(path.stem for path in files.values())
    return [f"your own materials, in {user_materials_folder()} (--show NAME for one): {names}"]


def _show_material(name) -> int:
    """``translucency materials --show NAME``: one material (a catalogue name or a material file) with its
    coefficients, every derived quantity of the models (docs/physics.md §2.1) and its look (§6.4)."""
    from ..scatter.appearance import appearance_of
    from .shading.settings import resolve_medium

    medium = resolve_medium(name)
    reflectance, _ = appearance_of(medium)
    rows = [
        ("sigma_a", medium.sigma_a, "1/mm", "absorption"),
        ("sigma_s", medium.sigma_s, "1/mm", "scattering"),
        ("g", medium.g, "", "Henyey-Greenstein mean cosine"),
        ("sigma_s'", medium.sigma_s_reduced, "1/mm", "reduced scattering sigma_s (1 - g)"),
        ("sigma_t'", medium.sigma_t_reduced, "1/mm", "reduced extinction"),
        ("alpha'", medium.alpha_reduced, "", "reduced albedo"),
        ("D", medium.D, "mm", "diffusion coefficient"),
        ("sigma_tr", medium.sigma_tr, "1/mm", "effective transport coefficient"),
        ("1/sigma_t'", medium.mean_free_path, "mm", "mean free path (mfp)"),
        ("1/sigma_tr", medium.diffusion_length, "mm", "diffusion length"),
        ("d_e", medium.d_e, "mm", "extrapolation distance"),
        ("R_d", reflectance, "", "diffuse reflectance (better dipole's total)"),
    ]
    print(f"{medium.name}: eta {medium.eta:g}, A {medium.A:.4g}; per channel R G B")
    lines = _table_lines(
        ("quantity", "R G B", "unit", "meaning"),
        [(key, _format_triplet(values, "{:.4g}"), unit, meaning) for key, values, unit, meaning in rows],
    )
    for line in lines:
        print(line)
    return 0


def cmd_materials(args) -> int:
    """Print the catalogue: by default name, eta, sigma_a, reduced sigma_s' and diffusion length per
    channel, grouped by source table (fits 100 columns); with ``--wide`` every column, one table."""
    import numpy as np

    from ..scatter.materials import catalogue, material_tables

    if args.show is not None:
        return _show_material(args.show)
    tables = material_tables()
    entries = [entry for entry in catalogue() if not args.table or entry.table == args.table]
    lines = []
    if args.wide:
        header = (
            "name",
            "table",
            "eta",
            "sigma_a [1/mm]",
            "sigma_s [1/mm]",
            "g",
            "1/sigma_t' [mm]",
            "1/sigma_tr [mm]",
        )
        rows = []
        for entry in entries:
            if entry.is_diffusive:
                medium = entry.medium()
                mfp = _format_triplet(medium.mean_free_path, "{:.3g}")
                diffusion = _format_triplet(medium.diffusion_length, "{:.3g}")
            else:
                mfp = diffusion = "(does not scatter in every channel)"
            rows.append(
                (
                    entry.key,
                    entry.table,
                    f"{entry.eta:g}",
                    _format_triplet(entry.sigma_a),
                    _format_triplet(entry.sigma_s),
                    _format_triplet(entry.g, "{:g}"),
                    mfp,
                    diffusion,
                )
            )
        lines = _table_lines(header, rows)
    else:
        header = ("name", "eta", "sigma_a [1/mm]", "sigma_s' [1/mm]", "1/sigma_tr [mm]")
        rows, groups = [], []
        for entry in entries:
            reduced = np.asarray(entry.sigma_s, dtype=np.float64) * (1.0 - np.asarray(entry.g, dtype=np.float64))
            diffusion = _compact(entry.medium().diffusion_length) if entry.is_diffusive else "- (not diffusive)"
            rows.append((entry.key, f"{entry.eta:g}", _compact(entry.sigma_a), _compact(reduced), diffusion))
            groups.append(entry.table)
        table_lines = _table_lines(header, rows)
        lines = [
            "per channel R G B; sigma_s' = sigma_s (1 - g); 1/sigma_tr: diffusion length; all columns: --wide",
            *table_lines[:2],
        ]
        for k, (row, group) in enumerate(zip(table_lines[2:], groups)):
            if k == 0 or group != groups[k - 1]:
                lines.append(f"[{group}]")
            lines.append(row)
    for line in lines:
        print(line)
    print()
    for key, table in tables.items():
        if args.table and key != args.table:
            continue
        reduced = "reduced sigma_s' (g = 0)" if table["sigma_s_is_reduced"] else "unreduced sigma_s with g"
        note = f"{key}: {table['source']} Units {table['units']}; {reduced}. {table['notes']}"
        print(textwrap.fill(note, MATERIALS_WIDTH, subsequent_indent="  "))
    for line in _own_material_lines():
        print(textwrap.fill(line, MATERIALS_WIDTH, subsequent_indent="  "))
    return 0


def cmd_report(args) -> int:
    """Print the versions of the stack, the GPU the pair sums would use, and check off-screen rendering."""
    import platform
    from importlib import metadata

    print(f"translucency {__version__} on Python {platform.python_version()} ({platform.platform()})")
    for package in (
        "numpy",
        "scipy",
        "numba",
        "llvmlite",
        "pyvista",
        "vtk",
        "pymeshlab",
        "fast-simplification",
        "embreex",
        "plyfile",
        "matplotlib",
        "imageio",
        "tqdm",
    ):
        try:
            version = metadata.version(package)
        except metadata.PackageNotFoundError:
            version = "NOT INSTALLED"
        print(f"  {package:<20} {version}")
    from ..scatter.gpu.probe import SIMULATOR, gpu_status
    from .render import offscreen_check

    gpu = gpu_status()
    real = gpu.usable and gpu.name != SIMULATOR  # --device auto never takes the simulator
    print(f"GPU for exact and relight (--device auto): {gpu.name if real else 'none: ' + (gpu.reason or gpu.name)}")
    ok, detail = offscreen_check()
    print(f"off-screen rendering: {'works' if ok else 'FAILS'} ({detail})")
    return 0 if ok else 1


def cmd_inspect(args) -> int:
    """Load a scan, print its size and defects, repair it and print what changed; optionally save it."""
    import warnings

    from ..io.clean import clean_mesh
    from ..io.load import load_mesh
    from ..io.save import check_output_path, save_mesh
    from ..io.units import UnitInferredWarning
    from ..io.upright import infer_up

    if args.output:
        check_output_path(args.output, args.mesh)  # before any work: a bad output path fails at once
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mesh = load_mesh(args.mesh, unit=args.unit)
    for warning in caught:
        (_note if issubclass(warning.category, UnitInferredWarning) else _warn)(str(warning.message))
    low, high = mesh.bounds
    print(
        f"{args.mesh}: {mesh.n_points} vertices, {mesh.n_triangles} triangles, "
        f"{mesh.extent:.4g} mm across (bounding box {' x '.join(f'{v:.4g}' for v in high - low)} mm), surface "
        f"area {mesh.surface_area:.4g} mm^2"
    )
    cleaned, report = clean_mesh(mesh, max_hole_edges=args.max_hole_edges)
    print(report)
    up, reason = infer_up(cleaned.points, cleaned.triangles)
    print(f"up axis for --up auto: {up} ({reason})")
    if args.output:
        save_mesh(args.output, cleaned)
        print(f"wrote the repaired mesh to {args.output}")
    return 0


def cmd_bake(args) -> int:
    """Bake each MESH (or the embedded default scan) to a PLY and print a summary (see :mod:`translucency.app.bake`)."""
    import time

    from .bake import BakeSettings, ConsoleProgress, bake_files, exit_code, format_summary
    from .options import lights_from_args, quiet, solver_settings

    settings = BakeSettings.of(
        solver_settings(args), lights=lights_from_args(args), unit=args.unit, preview=args.preview
    )
    start = time.perf_counter()
    progress = ConsoleProgress(quiet=quiet(args))
    records = bake_files(
        args.meshes,
        args.output,
        settings,
        workers=args.workers,
        scheduler=args.scheduler,
        progress=progress,
        format=args.format,
    )
    print(format_summary(records, time.perf_counter() - start))
    return exit_code(records)


def _pixels(text: str, option: str) -> tuple[int, int]:
    """``"WxH"`` as two pixel counts (16 to 8192), or a one-sentence error naming ``option``."""
    try:
        width, height = (int(part) for part in str(text).lower().split("x"))
    except ValueError:
        width = height = 0
    if not (16 <= width <= 8192 and 16 <= height <= 8192):
        raise TranslucencyError(
            f"{option} must be WIDTHxHEIGHT in pixels, each 16 to 8192 (e.g. 1024x768), got {text!r}."
        )
    return width, height


def _warn(message: str) -> None:
    print(f"translucency: warning: {message}", file=sys.stderr)


def _note(message: str) -> None:
    print(f"translucency: {message}", file=sys.stderr)


def cmd_view(args) -> int:
    """Open the desktop viewer on a scan; with ``--screenshot`` render its first picture off-screen and exit."""
    import os
    from pathlib import Path

    from ..io.atomic import prepare_output_file
    from .options import lights_from_args, solver_settings

    one_picture = args.screenshot is not None  # no later light to reuse relighting operators for
    window_size = _pixels(args.window_size or (SCREENSHOT_SIZE if one_picture else WINDOW_SIZE), "--window-size")
    if one_picture:
        screenshot = Path(args.screenshot)
        if screenshot.suffix.lower() != ".png":
            raise TranslucencyError(f"--screenshot {args.screenshot} is not a .png file name; pass e.g. view.png.")
        prepare_output_file(screenshot, setting="screenshot")
    elif sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise TranslucencyError(
            "there is no display to open the viewer on; pass --screenshot FILE.png to render "
            "off-screen, or run it under xvfb-run or on a desktop."
        )
    if not (0 < args.roughness <= 1):
        raise TranslucencyError(f"--roughness must be a GGX alpha in (0, 1], got {args.roughness!r}.")
    from ..scatter.names import DEFAULT_METHOD, DEFAULT_TOL
    from .shading.settings import VIEWER_METHOD, VIEWER_TOL

    if args.method is None:
        args.method = DEFAULT_METHOD if one_picture else VIEWER_METHOD
    if args.tol is None:
        args.tol = DEFAULT_TOL if one_picture else VIEWER_TOL
    if one_picture and args.resolution == "interactive":
        args.resolution = "full"  # one picture: every vertex (no later frame for a proxy to be quick for)
    interactive = args.resolution == "interactive"
    settings = solver_settings(args, resolution="full") if interactive else solver_settings(args)
    lights = lights_from_args(args)
    if not one_picture:
        from ..errors import MeshError
        from ..io.readable import regular_file
        from .desktop import check_can_start, run

        if args.mesh is not None:  # said here, in the terminal, before a window opens
            regular_file(args.mesh, MeshError, kind="mesh file")
        check_can_start()
        return run(
            args.mesh,
            settings=settings,
            lights=lights,
            unit=args.unit,
            output=args.output,
            view_dependent=args.view_dependent,
            specular=args.specular,
            roughness=args.roughness,
            window_size=window_size,
        )
    from .shading.scan import load_scan
    from .viewer import Viewer

    mesh, _, name = load_scan(args.mesh, args.unit, warn=_warn, note=_note)
    viewer = Viewer(
        mesh,
        lights=lights,
        settings=settings,
        resolution="interactive" if interactive else settings.resolution,
        view_dependent=args.view_dependent,
        specular=args.specular,
        roughness=args.roughness,
        window_size=window_size,
        off_screen=True,
        widgets=False,
        output=args.output,
        name=Path(name).stem,
    )
    print(viewer.status)
    viewer.screenshot(args.screenshot)
    viewer.close()
    print(f"wrote {args.screenshot}")
    return 0


#: The desktop viewer's window and ``view --screenshot``'s picture, pixels (``--window-size`` replaces them).
WINDOW_SIZE, SCREENSHOT_SIZE = "1400x900", "1024x768"


def _sweep(text):
    """``--sweep KEY=V1,V2,...`` as ``{key: [values]}`` (None when not given); a bad one is a sentence."""
    if text is None:
        return None
    key, _, values = str(text).partition("=")
    try:
        numbers = [float(v) for v in values.split(",")]
    except ValueError:
        numbers = []
    if not key.strip() or not numbers:
        raise InvalidParameterError(f"--sweep must be KEY=V1,V2,... (e.g. mfp=0.5,1,2,4), got {text!r}.")
    return {key.strip(): numbers}


def cmd_compare(args) -> int:
    """Render and measure a scan in several materials and models into a folder."""
    from pathlib import Path

    from ..io.atomic import prepare_output_folder
    from .compare import compare, validate_choices
    from .options import inline_material, lights_from_args, quiet, solver_settings
    from .shading.scan import load_scan
    from .shading.settings import DEFAULT_MATERIAL

    if inline_material(args) is not None:
        raise InvalidParameterError(
            "compare takes its materials by name or file (--materials marble,jade.toml): write the material of "
            "--sigma-a/--sigma-s or --reflectance/--mfp into a TOML file (docs/physics.md 6.4) and name it there."
        )
    settings = solver_settings(args, material=args.material or DEFAULT_MATERIAL)
    materials = args.materials if args.materials is not None else args.material
    reference = args.reference
    sweep = _sweep(args.sweep)
    if reference is None:
        materials = materials if materials is not None else DEFAULT_MATERIAL
        labels, models, media = validate_choices(
            materials, args.models if args.models is not None else args.model, sweep
        )
        materials = [media[label] for label in labels]  # resolved once: files read, sweeps made
    else:  # the materials are checked against the reference's
        _, models, _ = validate_choices(DEFAULT_MATERIAL, args.models if args.models is not None else args.model)
    cell_size = _pixels(args.cell_size, "--cell-size")
    prepare_output_folder(args.output)
    earlier = [name for name in ("statistics.json", "grid.png") if (Path(args.output) / name).exists()]
    if earlier:  # said before the work, not replaced in silence
        _note(f"{args.output} holds an earlier compare's results ({', '.join(earlier)}); they will be replaced")
    lights = lights_from_args(args)
    mesh = None
    if reference is None or args.mesh is not None:
        mesh, _, name = load_scan(args.mesh, args.unit, warn=_warn, note=_note)
        print(f"{name}: {mesh.n_points} vertices, {mesh.extent:.4g} mm across (largest side of the bounding box)")
    result = compare(
        mesh,
        materials,
        models,
        lights,
        reference=reference,
        sweep=None if reference is None else sweep,  # made above into the materials; a reference refuses one
        settings=settings,
        output=args.output,
        cell_size=cell_size,
        progress=None if quiet(args) else (lambda line: print(f"solved {line}", file=sys.stderr, flush=True)),
    )
    if reference is not None:
        _print_reference_tables(result)
    print(f"common display exposure {result.exposure:.4g} (one for every cell)")
    print(
        "per-vertex mean radiance toward the normal, W/(m^2 sr) per W/m^2 of irradiance,\nover the lit "
        f"vertices (incident flux > 0) and over all {next(iter(result.results.values())).mesh.n_points}:"
    )
    width = max(len(m) for m in result.materials)
    for material in result.materials:
        for model in result.models:
            lit, every = result.mean(material, model, "lit"), result.mean(material, model, "all")
            n_lit = next(
                row["n_vertices"]
                for row in result.statistics
                if (row["material"], row["model"], row["subset"]) == (material, model, "lit")
            )
            rgb = "  ".join  # fixed-width columns, three significant digits in scientific notation
            print(
                f"  {material:<{width}}  {model:<11}  lit ({n_lit}): "
                + (rgb(f"{c} {v:.2e}" for c, v in zip("RGB", lit)) if n_lit else "no vertex is lit")
                + ";  all: "
                + rgb(f"{c} {v:.2e}" for c, v in zip("RGB", every))
            )
    print("wrote " + ", ".join(str(path) for path in result.files.values()))
    return 0


def _print_reference_tables(result) -> None:
    """The reference's lines and one table per model (:func:`.reference_compare.reference_table_text`)."""
    from .reference_compare import reference_table_text

    setup, material = result.reference, result.materials[0]
    meta, mesh = setup.reference.metadata, setup.mesh
    stderr = meta.get("median_relative_stderr")
    print(f"reference {setup.path}: {mesh.n_points} vertices, {mesh.extent:.4g} mm across, {material}")
    print(
        f"  path traced with {meta.get('spp', '?')} paths per vertex"
        + (f" in {meta['seconds']:.1f} s" if "seconds" in meta else "")
        + (f", median standard error {100 * stderr:.0f} % per vertex" if stderr is not None else "")
    )
    times = {model: result.times[material, model] for model in result.models}
    for line in reference_table_text(result.reference_rows, result.models, times):
        print(line)


def cmd_reference(args) -> int:
    """Path-trace the radiance along the normal at every vertex of a scan and write it with its mesh."""
    from pathlib import Path

    from ..io.atomic import prepare_output_file
    from ..io.reference_file import REFERENCE_SUFFIXES
    from ..reference.trace_settings import check_seed, check_spp
    from ..scatter.budget import check_limits, format_seconds
    from .ground_truth import trace_reference, write_reference
    from .options import parse_vector, quiet
    from .progress import REFERENCE_PROGRESS_SECONDS, throttled_lines
    from .shading.scan import load_scan

    spp = check_spp(args.spp)
    check_seed(args.seed)
    check_limits(None, args.time_limit)
    output = Path(args.output)
    if output.suffix.lower() not in REFERENCE_SUFFIXES:
        raise InvalidParameterError(f"-o must name a .npz or .vtp file, got {args.output!r}.")
    prepare_output_file(output, create_folder=True, setting="-o")
    light = None if args.light_dir is None else parse_vector(args.light_dir, "--light-dir")
    mesh, _, name = load_scan(args.mesh, args.unit, warn=_warn, note=_note)
    print(f"{name}: {mesh.n_points} vertices, {mesh.extent:.4g} mm across; {spp} paths per vertex and channel")
    truth = trace_reference(
        mesh,
        args.material,
        light,
        spp=spp,
        seed=args.seed,
        up=args.up,
        time_limit=args.time_limit,
        progress=None if quiet(args) else throttled_lines(REFERENCE_PROGRESS_SECONDS, f"{Path(name).name}: tracing: "),
    )
    written = write_reference(truth, output)
    meta = truth.metadata
    print(
        f"traced {meta['stats']['paths']:,} paths in {meta['seconds']:.1f} s; median standard error "
        f"{100 * meta['median_relative_stderr']:.1f} % of the radiance per vertex; half that takes --spp "
        f"{4 * spp}, about {format_seconds(4 * meta['seconds'])}"
    )
    print(f"wrote {written}")
    return 0


def cmd_main_job(args) -> int:
    """The main job on the embedded default scan (see :mod:`translucency.app.default_job`)."""
    from .default_job import run_default_job
    from .options import quiet

    return run_default_job(quiet=quiet(args))


def _add_view_and_compare_parsers(sub) -> None:
    """The ``view`` and ``compare`` subcommands: a scan, its lights and the solver's options, and their own."""
    from .options import add_light_options, add_quiet_option, add_scan_options, add_solver_options

    def scene_parser(name, summary, description):
        parser = sub.add_parser(name, help=summary, description=description)
        for add_options in (add_scan_options, add_light_options, add_solver_options):
            add_options(parser)
        return parser

    p = scene_parser(
        "view",
        "show a scan as a translucent object, with controls that solve again",
        "Open the desktop viewer: the scan in a window with a side panel (material, model, tolerance, light, "
        "exposure, false colour), a light you drag in the view, File menu, and h for the keys. Here --method defaults "
        "to relight (operators prepared once, then every light on every vertex; auto with --screenshot, one "
        "picture, which auto solves by tree) and --resolution to 'interactive': every vertex with relight, a "
        "proxy of about 7,500 vertices otherwise.",
    )
    from ..scatter.names import DEFAULT_METHOD, DEFAULT_TOL
    from .shading.settings import VIEWER_METHOD, VIEWER_TOL

    # the viewer's own defaults: relight (operators worth preparing for the lights to come), but the default method
    # (auto: tree for one light) for --screenshot, which shows one light
    p.set_defaults(resolution="interactive", method=None, tol=None)
    own = {"method": (VIEWER_METHOD, DEFAULT_METHOD), "tol": (f"{VIEWER_TOL:g}", f"{DEFAULT_TOL:g}")}
    for action in p._actions:
        if action.dest in own and action.help:
            viewer, screenshot = own[action.dest]
            if viewer != screenshot:
                default = f" (default {viewer}; {screenshot} with --screenshot)"
                action.help = action.help.rsplit(" (default", 1)[0] + default
    p.add_argument("--screenshot", metavar="FILE.png", help="render the first picture off-screen to FILE.png and exit")
    p.add_argument("--view-dependent", action="store_true", help="show T21(eta, n.w_o) B toward the camera")
    p.add_argument("--specular", action="store_true", help="add the boundary's specular highlight (GGX)")
    p.add_argument("--roughness", type=float, default=0.25, help="GGX alpha of the highlight (default 0.25)")
    p.add_argument(
        "--window-size",
        default=None,
        metavar="WxH",
        help=f"window size in pixels (default {WINDOW_SIZE}; {SCREENSHOT_SIZE} with --screenshot)",
    )
    p.add_argument("-o", "--output", default=".", help="folder for what key s saves (default . : here)")
    p.set_defaults(func=cmd_view)

    p = scene_parser(
        "compare",
        "one scan in several materials and models: image grid, differences, statistics",
        "Solve a scan in several materials and models with the same view and light; write grid.png "
        "(common exposure), differences.png (models against the first), statistics.csv/.json and "
        "profile.png into the output folder; with --reference, also reference.csv/.json and "
        "reference_errors.png (every model against a path-traced reference).",
    )
    p.add_argument(
        "--materials", metavar="A,B,C", help="catalogue names or material files, comma-separated (default: --material)"
    )
    p.add_argument(
        "--sweep",
        metavar="KEY=V1,V2,...",
        help="one column per value of one property of the material: mfp (mm), reflectance, scale or eta "
        "(e.g. mfp=0.5,1,2,4)",
    )
    p.add_argument(
        "--models", metavar="M1,M2", help="models, comma-separated; the first is the reference (default: --model)"
    )
    p.add_argument("--cell-size", default="480x480", metavar="WxH", help="pixels of one grid cell (default 480x480)")
    p.add_argument(
        "--reference",
        metavar="REF",
        help="a path-traced reference (.npz or .vtp from 'translucency reference'): shade its mesh in its "
        "material and light and measure every model against it per region (lit, grazing, shadowed, far "
        "side): reference.csv/.json and reference_errors.png; MESH, --material(s) and --light-dir, "
        "--light, --env may be left out, and are refused with a sentence when they disagree with it",
    )
    p.set_defaults(material=None)  # none given: the default material, or the reference's
    p.add_argument(
        "-o",
        "--output",
        default="translucency-output/compare",
        help="output folder (created; default translucency-output/compare)",
    )
    add_quiet_option(p)
    p.set_defaults(func=cmd_compare)


def _add_reference_parser(sub) -> None:
    """The ``reference`` subcommand: a scan, a material and a light, the paths per vertex and their budget."""
    from .ground_truth import DEFAULT_SPP, REFERENCE_TIME_LIMIT_S
    from .options import add_quiet_option, add_scan_options

    p = sub.add_parser(
        "reference",
        help="path-trace the radiance at every vertex: the ground truth the models are measured against",
        description="Unbiased Monte Carlo light transport in the closed scan (smooth dielectric boundary, "
        "homogeneous medium, one directional light): the radiance leaving each vertex along its normal, its "
        "standard error and the part that re-entered the surface, written with the mesh to OUT.npz or OUT.vtp.",
    )
    add_scan_options(p)
    p.add_argument("--material", default="marble", help="catalogue name (default marble)")
    p.add_argument(
        "--light-dir",
        metavar="X,Y,Z",
        help="direction toward a white directional light of 1 W/m^2, scan coordinates (default: above and in "
        "front, by --up)",
    )
    p.add_argument(
        "--spp",
        type=int,
        default=DEFAULT_SPP,
        metavar="N",
        help=f"paths per vertex and channel, at least 2; the noise falls as 1/sqrt(N) (default {DEFAULT_SPP})",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the random numbers (default 0)")
    p.add_argument(
        "--time-limit",
        type=float,
        default=REFERENCE_TIME_LIMIT_S,
        metavar="SECONDS",
        help="refuse, after the first seconds of tracing, an --spp that would take longer "
        f"(default {REFERENCE_TIME_LIMIT_S})",
    )
    p.add_argument(
        "-o", "--output", default="translucency-output/reference.npz", help="OUT.npz or OUT.vtp (default %(default)s)"
    )
    add_quiet_option(p)
    p.set_defaults(func=cmd_reference)


def build_parser() -> argparse.ArgumentParser:
    from .options import ArgumentParser

    parser = ArgumentParser(
        prog="translucency",
        description="Translucent shading of 3D scans with the directional dipole BSSRDF.",
    )
    parser.add_argument("--version", action="version", version=f"translucency {__version__}")
    from .options import add_quiet_option

    add_quiet_option(parser)  # the main job's; bake and compare take it too
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    p = sub.add_parser("materials", help="list the material catalogue")
    p.add_argument("--table", choices=["jensen2001", "narasimhan2006"], help="only one source table")
    p.add_argument(
        "--wide", action="store_true", help="every column (table, sigma_s, g, 1/sigma_t'), wider than 100 columns"
    )
    p.add_argument(
        "--show",
        metavar="NAME",
        help="one material (a catalogue name or a .toml/.json material file): every derived quantity and its "
        "diffuse reflectance",
    )
    p.set_defaults(func=cmd_materials)

    p = sub.add_parser("report", help="versions of the stack and whether off-screen rendering works")
    p.set_defaults(func=cmd_report)

    from .options import UNIT_HELP

    p = sub.add_parser("inspect", help="load a scan, show its defects and repair it")
    p.add_argument("mesh", help="mesh file (PLY, OBJ, STL, OFF, VTK, VTP, ...)")
    p.add_argument("--unit", default=None, help=UNIT_HELP)
    p.add_argument(
        "--max-hole-edges", type=int, default=100, help="close holes of at most this many edges (default 100)"
    )
    p.add_argument("-o", "--output", help="save the repaired mesh (any format PyVista writes)")
    p.set_defaults(func=cmd_inspect)

    from .options import (
        add_format_option,
        add_light_options,
        add_preview_option,
        add_quiet_option,
        add_scan_options,
        add_solver_options,
    )

    p = sub.add_parser(
        "bake",
        help="bake scans to PLY files of translucent radiance",
        description="Bake each MESH to <stem>_<material>.ply. Exit code 0: every file baked; "
        "1: some files failed (see the summary); 2: nothing could start.",
    )
    add_scan_options(p, several=True)
    add_light_options(p)
    add_solver_options(p)
    add_preview_option(p)
    p.add_argument(
        "-o",
        "--output",
        help="a file for one mesh (.ply, .vtp, .vtk, .glb or .gltf: the suffix names the format), else a folder, "
        "created when missing (default translucency-output)",
    )
    add_format_option(p)
    p.add_argument(
        "--workers",
        type=int,
        default=1,
        metavar="N",
        help="bake N files at a time in local processes (default 1: in this process)",
    )
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help=(
            "bake on a Dask cluster (tcp://host:8786); several scans: its workers must reach the meshes and the "
            "output folder; one scan: its receivers are solved in blocks on the workers"
        ),
    )
    add_quiet_option(p)
    p.set_defaults(func=cmd_bake)

    _add_view_and_compare_parsers(sub)

    _add_reference_parser(sub)
    parser.set_defaults(func=cmd_main_job)
    return parser


def _first_run_notice(solves: bool):
    """For commands that solve: one line on stderr when numba really compiles the solver's kernels."""
    import contextlib

    if not solves:
        return contextlib.nullcontext()
    from .warmup import NOTICE, compile_notice

    return compile_notice(lambda: print(f"translucency: {NOTICE}", file=sys.stderr, flush=True))


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``translucency`` and ``python -m translucency``; returns the exit code."""
    import warnings

    from ..errors import TranslucencyWarning

    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with (
            command_line_spelling(),
            warnings.catch_warnings(),
            _first_run_notice(args.func in (cmd_main_job, cmd_bake, cmd_view, cmd_compare)),
        ):

            def show(message, category, *rest):  # our own warnings as one line each, like the errors
                if issubclass(category, TranslucencyWarning):
                    print(f"translucency: warning: {message}", file=sys.stderr)
                else:
                    default_show(message, category, *rest)

            default_show, warnings.showwarning = warnings.showwarning, show
            return int(args.func(args) or 0)
    except TranslucencyError as exc:
        print(f"translucency: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("translucency: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader went away (``translucency materials | head``): stop quietly, as cat does
        sys.stdout = None
        return 141


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
