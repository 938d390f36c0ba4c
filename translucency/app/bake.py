"""Batch baking: many scans, one material and one set of lights, one baked PLY per scan.

* :func:`bake_file` bakes one scan (load, clean, shade, write) and returns a :class:`BakeRecord`; it
  never raises for a problem of that file: the record says what went wrong in one sentence.
* :func:`bake_files` plans the output names and runs :func:`bake_file` over a list of scans: in this
  process, in ``workers`` spawned processes, or on a Dask distributed cluster.
* :func:`bake` is the same from Python, with the settings as keyword arguments.
* :func:`format_summary` and :func:`exit_code` turn the records into the table and the exit status
  of ``translucency bake``; :class:`ConsoleProgress` shows its progress (bars on a terminal, lines elsewhere).

Output names are ``<stem>_<material>.<format>`` in the output folder (``format`` ply, vtp, vtk, glb
or gltf: :func:`translucency.app.shading.result.write_result`; default ply); a stem met twice (``a/scan.ply``,
``b/scan.obj``) gets ``-2``, ``-3``, ... and a name is never that of an input, so no input is ever
written over. A single scan may be baked to one file named by ``output`` (``x.vtp``: that format). Each
file is written atomically: a failed file leaves no partial output.

Threads: ``workers`` processes each run numba with ``cores // workers`` threads. On Dask every task
runs numba with ``cores // nthreads`` threads of its worker (start workers with ``--nthreads 1`` and
let numba use the cores, or cap it with ``NUMBA_NUM_THREADS`` in the workers' environment). Dask
workers read the scans and write the PLYs themselves: the input files and the output folder must be
reachable from every worker under the same paths (a shared file system); only the records travel
back to the client.

Faults: the output folders are checked (and swept of an earlier killed run's temporaries, see
:mod:`translucency.io.atomic`) before any work, and an output name taken by a folder stops the batch
then; a write that fails later fails that file with one sentence. Local worker processes end with
their parent, also when it is killed (:func:`translucency.processes.end_with_parent`). On Dask the workers belong to the
cluster: when the client goes away the scheduler drops its tasks that have not started, and a task
already running finishes its file, written atomically like every output (a complete PLY or none).
"""

from __future__ import annotations

import contextlib
import os
import re
import time
from dataclasses import dataclass, field, fields, replace
from pathlib import Path

from ..errors import (
    BudgetError,
    InvalidParameterError,
    TranslucencyError,
    command_line_active,
    command_line_spelling,
    option,
)
from ..processes import available_cores, child_pool, run_in_child
from .bake_progress import BakeProgress, ConsoleProgress, format_summary
from .shading.settings import ShadeSettings, settings_with

__all__ = [
    "BakeSettings",
    "BakeRecord",
    "BakeProgress",
    "ConsoleProgress",
    "bake",
    "bake_file",
    "bake_files",
    "output_paths",
    "format_summary",
    "exit_code",
    "DASK_CONNECT_TIMEOUT_S",
]

#: Seconds to wait for a Dask scheduler to answer before giving up.
DASK_CONNECT_TIMEOUT_S = 20.0

#: Message of a file whose worker process died (see :func:`_run_in_processes`).
_CRASHED = (
    "the worker process stopped while baking this file (a crash, or the machine ran out of memory); "
    "bake it alone to see more."
)


@dataclass(frozen=True, kw_only=True)
class BakeSettings(ShadeSettings):
    """Everything a bake needs besides the file names: the shading settings, the lights and the files'
    unit; validated on construction.

    Parameters
    ----------
    material, model, method, device, tol, resolution, shadows, per_direction, exposure, memory_limit, time_limit, up,
    bounces, albedo
        As in :class:`~translucency.app.shading.settings.ShadeSettings` (``up`` places the default light and is
        recorded; the memory limit in GB, the time limit in seconds).
    lights : light or sequence of lights, optional
        Default: the pipeline's white directional light (1 W/m²).
    unit : str or float, optional
        Length unit of the scan files: ``mm``, ``cm``, ``m``, ``in`` or mm per unit; None: inferred
        from each file's size (:func:`translucency.io.units.infer_unit`). Ignored for the embedded
        default scan, which has its own size.
    preview : bool
        Also write a PNG beside each output, same name with ``.png``: the sRGB and the false-colour
        views, labelled (:func:`translucency.app.figure.write_figure`).
    """

    lights: tuple | None = None
    unit: str | float | None = None
    preview: bool = False

    def __post_init__(self):
        from ..io.units import parse_unit
        from ..scatter.lights import as_light_list

        super().__post_init__()
        if self.lights is not None:
            object.__setattr__(self, "lights", as_light_list(self.lights))
        if self.unit is not None:
            parse_unit(self.unit)

    @classmethod
    def of(cls, settings: ShadeSettings, lights=None, unit=None, preview=False) -> BakeSettings:
        """The bake of ``settings`` under ``lights`` for files in ``unit`` (with ``preview`` PNGs)."""
        return cls(
            **{f.name: getattr(settings, f.name) for f in fields(ShadeSettings)},
            lights=lights,
            unit=unit,
            preview=preview,
        )

    @property
    def material_name(self) -> str:
        """The material's name as it appears in output file names (letters, digits and ``_``)."""
        return re.sub(r"[^A-Za-z0-9]+", "_", self.material.name).strip("_") or "material"


@dataclass(frozen=True)
class BakeRecord:
    """What happened to one scan of a batch (one row of the summary).

    Attributes
    ----------
    source : str
        The input as given (or the embedded default scan's file name).
    output : str or None
        The PLY written; None when the file failed.
    vertices : int or None
        Vertices of the cleaned mesh that was baked.
    lit_sources : int or None
        Vertices of the solver's mesh that receive light (the sources of the sum).
    seconds : float
        Wall time of this file, loading to writing, s.
    error : str or None
        One sentence saying what went wrong; None when the file was baked.
    warnings : tuple of str
        Warnings while loading and solving (an implausible size for the unit, a coarser proxy, say).
    notes : tuple of str
        Notes while loading: the line that says which unit was inferred.
    threads : int or None
        numba threads the solver used.
    over_budget : bool
        The file failed because its solve would not fit the memory or time budget.
    """

    source: str
    output: str | None = None
    vertices: int | None = None
    lit_sources: int | None = None
    seconds: float = 0.0
    error: str | None = None
    warnings: tuple = field(default=())
    threads: int | None = None
    over_budget: bool = False
    notes: tuple = field(default=())

    @property
    def ok(self) -> bool:
        """True when the file was baked."""
        return self.error is None

    @property
    def status(self) -> str:
        """``"baked"`` or ``"failed: <sentence>"``."""
        return "baked" if self.ok else f"failed: {self.error}"


def bake_file(path, output, settings: BakeSettings, progress=None, said=None, solver=None) -> BakeRecord:
    """Bake one scan to a PLY; a problem with this file is returned in the record, never raised.

    Parameters
    ----------
    path : str or path-like or None
        The scan (in ``settings.unit``); None for the embedded default scan.
    output : str or path-like
        The PLY to write (its folder must exist); written atomically, so a failure leaves nothing. With
        ``settings.preview`` its picture is written beside it (same name, ``.png``).
    settings : BakeSettings
    progress : callable, optional
        ``progress(stage, fraction)`` with stages ``loading``, the solver's (``far field``,
        ``near field``, and ``bounces`` when light re-enters) and ``writing``.
    said : callable, optional
        ``said(kind, message)`` as soon as there is a ``"note"`` (the unit inferred) or a ``"warning"``;
        they are in the record too.
    solver : callable, optional
        Stands in for :func:`translucency.scatter.solve.solve` (a
        :class:`~translucency.app.shading.distributed.BlockSolver`: one scan's receivers on a Dask cluster).

    Returns
    -------
    BakeRecord
    """
    from .shading.result import write_result
    from .shading.scan import load_scan
    from .shading.scene import shade_scan

    report = progress or (lambda stage, fraction: None)
    start = time.perf_counter()
    source = _source_label(path)
    warnings: list[str] = []
    notes: list[str] = []

    def warn(message):
        warnings.append(message)
        if said is not None:
            said("warning", message)

    def note(message):
        notes.append(message)
        if said is not None:
            said("note", message)

    vertices = lit = threads = None
    try:
        import numba

        threads = numba.get_num_threads()
        report("loading", 0.0)
        mesh, _, _ = load_scan(path, settings.unit, warn=warn, note=note)
        vertices = mesh.n_points
        report("loading", 1.0)
        result = shade_scan(mesh, settings, settings.lights, progress=report, warn=warn, note=note, solver=solver)
        lit = int(result.stats["incident"]["n_lit"])
        report("writing", 0.0)
        write_result(result, output)
        if settings.preview:
            from .figure import write_figure

            write_figure(
                Path(output).with_suffix(".png"),
                mesh,
                result,
                name=_default_stem() if path is None else Path(path).stem,
            )
        report("writing", 1.0)
    except Exception as exc:  # noqa: BLE001 -- every failure of one file becomes its record
        return BakeRecord(
            source,
            None,
            vertices,
            lit,
            time.perf_counter() - start,
            failure_sentence(exc),
            tuple(warnings),
            threads,
            isinstance(exc, BudgetError),
            tuple(notes),
        )
    return BakeRecord(
        source,
        str(output),
        vertices,
        lit,
        time.perf_counter() - start,
        None,
        tuple(warnings),
        threads,
        notes=tuple(notes),
    )


def _bake_file_spelled(command_line: bool, path, output, settings: BakeSettings) -> BakeRecord:
    """:func:`bake_file` in a worker process, with its sentences spelling settings as the parent does."""
    with command_line_spelling(command_line):
        return bake_file(path, output, settings)


def _source_label(path) -> str:
    if path is None:
        from .shading.scan import default_scan_path

        return f"{default_scan_path().name} (embedded default scan)"
    return str(path)


def failure_sentence(exc: BaseException) -> str:
    """One line that says why a file failed, from the exception that stopped it."""
    from concurrent.futures.process import BrokenProcessPool

    if isinstance(exc, TranslucencyError):
        text = str(exc)
    elif isinstance(exc, (BrokenProcessPool, ChildProcessError)):
        text = _CRASHED
    elif isinstance(exc, ImportError):  # a Dask worker without the package
        text = (
            f"the worker cannot import {exc.name or 'a module'} ({exc}); install translucency, the same "
            "version, on every worker."
        )
    elif isinstance(exc, MemoryError):
        text = (
            "ran out of memory; bake it on a proxy (--resolution with an edge length in mm) or on a machine with "
            "more memory."
        )
    elif isinstance(exc, OSError):
        where = f" ({exc.filename})" if exc.filename else ""
        text = f"{exc.strerror or exc}{where}."
    else:
        text = f"unexpected {type(exc).__name__}: {exc} (a bug: please report it with the file)."
    return " ".join(text.split()) or type(exc).__name__


# --------------------------------------------------------------------------------------------------
# output names
# --------------------------------------------------------------------------------------------------
def _other_file_suffixes() -> set:
    """Suffixes that name a file a bake does not write (the meshes it reads, pictures, tables): an output ending in
    one is a mistake, not a folder's name."""
    from ..io.load import SUPPORTED_FORMATS
    from .exports import RESULT_SUFFIXES

    return (set(SUPPORTED_FORMATS) | {".png", ".jpg", ".jpeg", ".npz", ".csv", ".json", ".txt"}) - set(RESULT_SUFFIXES)


def output_paths(sources, output, material_name: str, format: str | None = None) -> list[Path]:
    """The file each source is baked to (``<stem>_<material>.<format>``); creates nothing.

    Parameters
    ----------
    sources : list of path-like or None
        The scans (None: the embedded default scan, stem ``bunny``).
    output : path-like
        A file for one source, whose suffix (``.ply``, ``.vtp``, ``.vtk``, ``.glb``, ``.gltf``) names
        its format; else a folder (existing, or to be created); a name ending in a path separator is
        always a folder.
    material_name : str
        The material part of the names.
    format : {"ply", "vtp", "vtk", "glb", "gltf"}, optional
        The format of the files in a folder (default ply); for a file output, its suffix (a
        different ``format`` is refused).

    Raises
    ------
    InvalidParameterError
        A file name for several sources, a folder name that is an existing file, or an output file
        that is an input.
    """
    from .exports import DEFAULT_FORMAT, RESULT_SUFFIXES, check_format

    text = os.fspath(output)
    output = Path(text)
    suffix = output.suffix.lower()
    as_file = suffix in RESULT_SUFFIXES and not output.is_dir() and not text.endswith(("/", os.sep))
    inputs = {_key(path) for path in sources if path is not None}
    if format is not None:
        check_format(format)
    if as_file and format is not None and suffix != f".{format}":
        raise InvalidParameterError(
            f"the output {text} names a {suffix} file but {option('format', format)} was given; the suffix of "
            f"a file output names its format, so pass one of the two (or a folder for {option('format')})."
        )
    if as_file:
        if len(sources) != 1:
            raise InvalidParameterError(
                f"the output {text} names one file, but {len(sources)} meshes were given; "
                f"pass a folder to bake several (e.g. -o {output.with_suffix('')}/)."
            )
        if _key(output) in inputs:
            raise InvalidParameterError(
                f"the output {text} is the input scan; inputs are never written over, choose another name."
            )
        return [output]
    if output.exists() and not output.is_dir():
        raise InvalidParameterError(
            f"the output {text} is an existing file, not a folder; pass a folder, or a file name ending in "
            f"{', '.join(RESULT_SUFFIXES)} when baking one mesh."
        )
    if suffix in _other_file_suffixes() and not output.is_dir() and not text.endswith(("/", os.sep)):
        raise InvalidParameterError(
            f"the output {text} names a {suffix} file, which a bake does not write; end it in "
            f"{', '.join(RESULT_SUFFIXES)}, or give a folder ({output.with_suffix('')}/)."
        )
    taken = set(inputs)
    paths = []
    for source in sources:
        stem = _default_stem() if source is None else Path(source).stem
        extension = format or DEFAULT_FORMAT
        candidate, k = output / f"{stem}_{material_name}.{extension}", 2
        while _key(candidate) in taken:
            candidate, k = output / f"{stem}-{k}_{material_name}.{extension}", k + 1
        taken.add(_key(candidate))
        paths.append(candidate)
    return paths


def _key(path) -> str:
    return os.path.normcase(os.path.realpath(path)).casefold()


def _default_stem() -> str:
    from .shading.scan import default_scan_path

    return default_scan_path().stem


# --------------------------------------------------------------------------------------------------
# a batch
# --------------------------------------------------------------------------------------------------
def bake_files(
    paths,
    output,
    settings: BakeSettings,
    *,
    workers: int = 1,
    scheduler=None,
    progress: BakeProgress | None = None,
    format: str | None = None,
) -> list[BakeRecord]:
    """Bake every scan of ``paths`` with the same settings; one failed file does not stop the others.

    Parameters
    ----------
    paths : sequence of path-like or None
        The scans; None (or an empty sequence) stands for the embedded default scan.
    output : path-like or None
        A ``.ply`` file for a single scan, else a folder, created when missing (default
        ``translucency-output``); see :func:`output_paths` for the names.
    settings : BakeSettings
    workers : int
        Processes to bake in (spawned; each runs numba with ``cores // workers`` threads). 1: here.
    scheduler : str or distributed.Client, optional
        Bake on a Dask cluster: the scheduler's address (``tcp://host:8786``) or a client. Several
        scans go one per task: the workers read the scans and write the PLYs, so both must be reachable
        from them. A single scan is loaded and written here and its receivers are solved in blocks on
        the workers (:class:`~translucency.app.shading.distributed.BlockSolver`).
    progress : BakeProgress, optional
    format : {"ply", "vtp", "vtk", "glb", "gltf"}, optional
        Format of the files in an output folder (default ply); a file output's suffix names its own.

    Returns
    -------
    list of BakeRecord
        In the order of ``paths``.

    Raises
    ------
    InvalidParameterError, TranslucencyError
        Only for problems that stop the whole batch before it starts (output names, an output
        folder that cannot be written, ``workers``, the scheduler); problems of single files are in
        their records.
    """
    progress = progress or BakeProgress()
    sources = list(paths) if paths else [None]
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InvalidParameterError(f"the number of workers (--workers) must be a whole number >= 1, got {workers!r}.")
    if scheduler is not None and workers > 1:
        raise InvalidParameterError("pass either workers (local processes) or a Dask scheduler, not both.")
    if output is None:
        from .default_job import OUTPUT_FOLDER

        output = OUTPUT_FOLDER
    outputs = output_paths(sources, output, settings.material_name, format)
    labels = [_source_label(source) for source in sources]
    _check_outputs(outputs)
    client = None if scheduler is None else _dask_client(scheduler)
    made: list = []
    try:
        made = _make_folders(outputs)
        records: list = [None] * len(sources)

        def done(index, result):
            if isinstance(result, BakeRecord):  # the names as given here, whatever the worker saw
                result = replace(result, source=labels[index], output=result.output and str(outputs[index]))
            else:
                result = BakeRecord(labels[index], error=failure_sentence(result))
            records[index] = result
            progress.finished(index, result)

        progress.start(labels, [str(o) for o in outputs])
        try:
            if client is not None and len(sources) == 1:  # one scan: here, its receivers in blocks on the cluster
                from .shading.distributed import BlockSolver

                def stage(name, fraction):
                    progress.stage(0, name, fraction)

                def said(kind, message):
                    progress.said(0, kind, message)

                done(0, bake_file(sources[0], outputs[0], settings, stage, said, solver=BlockSolver(client)))
            elif client is not None:  # the workers may run elsewhere: absolute paths
                jobs = [
                    (
                        command_line_active(),
                        None if source is None else os.path.abspath(source),
                        os.path.abspath(target),
                        settings,
                    )
                    for source, target in zip(sources, outputs)
                ]
                _run_on_dask(client, jobs, done)
            elif min(workers, len(sources)) > 1:
                jobs = [(command_line_active(), source, target, settings) for source, target in zip(sources, outputs)]
                _run_in_processes(_bake_file_spelled, jobs, min(workers, len(jobs)), done)
            else:
                for index, (source, target) in enumerate(zip(sources, outputs)):

                    def stage(name, fraction, index=index):
                        progress.stage(index, name, fraction)

                    def said(kind, message, index=index):
                        progress.said(index, kind, message)

                    done(index, bake_file(source, target, settings, progress=stage, said=said))
        finally:
            progress.end()
    finally:
        if client is not None and client is not scheduler:
            client.close()
        for folder in made:  # made for this bake and still empty (every input failed): not left behind
            with contextlib.suppress(OSError):
                folder.rmdir()
    return records


def _check_outputs(outputs) -> None:
    """Before any work: every output folder writable (or creatable), no output name taken by a folder.

    Stale temporaries of an earlier, killed run in those folders are swept here.
    """
    from ..io.atomic import prepare_output_folder

    for folder in sorted({Path(o).parent for o in outputs}):
        prepare_output_folder(folder, create=True, setting="output")
    for target in outputs:
        if Path(target).is_dir():
            raise InvalidParameterError(
                f"the output {target} is a folder; remove or rename it, or choose another "
                f"output folder with {option('output')}."
            )


def _make_folders(outputs) -> list[Path]:
    """Make the outputs' folders; the ones made here, deepest first."""
    made = set()
    for folder in {Path(o).parent for o in outputs}:
        made.update(p for p in (folder, *folder.parents) if not p.exists())
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise TranslucencyError(
                f"cannot create the output folder {folder} ({exc.strerror or exc}); choose a writable place."
            ) from exc
    return sorted(made, key=lambda path: len(path.parts), reverse=True)


# --------------------------------------------------------------------------------------------------
# local processes
# --------------------------------------------------------------------------------------------------
def _use_threads(threads: int) -> None:
    """Run numba's parallel loops called from this thread on ``threads`` threads (numba's limit is per thread)."""
    import numba

    numba.set_num_threads(max(1, min(threads, numba.config.NUMBA_NUM_THREADS)))


def in_worker(threads: int, module: str, name: str, *args):
    """In a worker process: ``threads`` threads for numba and for the BLAS libraries it loads, then ``module.name``
    called with ``args`` (what :func:`_run_in_processes` runs in each child)."""
    import importlib

    for variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[variable] = str(threads)
    _use_threads(threads)
    return getattr(importlib.import_module(module), name)(*args)


def _run_in_processes(function, jobs, workers: int, done) -> None:
    """Call ``function(*job)`` for every job, each in a worker process of its own, ``workers`` at a time;
    ``done(index, result)``.

    ``result`` is what the function returned, or the exception it raised; a worker that dies (a crash, out of
    memory) loses its own job only (a :class:`ChildProcessError`, :data:`_CRASHED`). The workers are ``python -c``
    children (:func:`translucency.processes.run_in_child`), not :mod:`multiprocessing`'s: a spawned process imports
    the caller's main script again, so a plain script without ``if __name__ == "__main__":`` would start its bake
    again in every worker. They end with this process, even when it is killed
    (:func:`translucency.processes.end_with_parent`). Not forked: numba's threads and a forked copy of them do not
    mix.
    """
    from concurrent.futures import as_completed

    threads = max(1, available_cores() // workers)
    with child_pool(workers) as (pool, started):
        futures = {
            pool.submit(
                run_in_child, in_worker, threads, function.__module__, function.__qualname__, *job, started=started
            ): index
            for index, job in enumerate(jobs)
        }
        for future in as_completed(futures):
            try:
                result = future.result()
            except ChildProcessError:
                result = ChildProcessError(_CRASHED)
            except Exception as exc:  # noqa: BLE001 -- e.g. an argument that does not pickle
                result = exc
            done(futures[future], result)


# --------------------------------------------------------------------------------------------------
# Dask
# --------------------------------------------------------------------------------------------------
def _dask_client(scheduler):
    """A ``distributed.Client`` for an address (or the client given), or one sentence why not."""
    if hasattr(scheduler, "submit"):
        return scheduler
    try:
        from distributed import Client
    except ImportError:
        raise TranslucencyError(
            "baking on a Dask cluster needs the 'distributed' package; "
            "install it with: pip install 'translucency[dask]'."
        ) from None
    try:
        return Client(str(scheduler), timeout=DASK_CONNECT_TIMEOUT_S)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        raise TranslucencyError(
            f"cannot reach the Dask scheduler at {scheduler} "
            f"({' '.join(str(exc).split()) or type(exc).__name__}); "
            "check the address (tcp://host:8786) and that the scheduler runs."
        ) from None


def _dask_task(command_line: bool, path, output, settings):
    """:func:`bake_file` on a Dask worker, with numba limited to ``cores // nthreads`` of the worker and its
    sentences spelling settings as the parent does."""
    from distributed import get_worker

    _use_threads(max(1, available_cores() // max(1, get_worker().state.nthreads)))
    with command_line_spelling(command_line):
        return bake_file(path, output, settings)


def _run_on_dask(client, jobs, done) -> None:
    """Submit every job to the cluster; ``done(index, record or exception)`` as they come back."""
    from distributed import as_completed

    futures = [client.submit(_dask_task, *job, pure=False) for job in jobs]
    index_of = {future.key: index for index, future in enumerate(futures)}
    try:
        for future in as_completed(futures):
            try:
                result = future.result()
            except Exception as exc:  # noqa: BLE001 -- a worker that died, a task that was lost
                result = exc
            done(index_of[future.key], result)
    except BaseException:
        client.cancel(futures)
        raise


# --------------------------------------------------------------------------------------------------
# summary
# --------------------------------------------------------------------------------------------------
def exit_code(records) -> int:
    """0 when every file was baked, 1 when any failed, 2 when every file failed for being over the
    memory or time budget (an option to change, like the errors before the batch)."""
    if all(r.ok for r in records):
        return 0
    return 2 if all(r.over_budget for r in records) else 1


def bake(
    meshes=None,
    output=None,
    material=None,
    lights=None,
    *,
    settings: ShadeSettings | None = None,
    unit=None,
    workers=1,
    scheduler=None,
    progress=None,
    format=None,
    preview=False,
    **changes,
) -> list[BakeRecord]:
    """Bake scans to files of per-vertex translucent radiance (PLY by default), one file per scan.

    Parameters
    ----------
    meshes : path-like or sequence of path-like, optional
        Scan files; None: the embedded default scan (the Stanford bunny, 155 mm across).
    output : path-like, optional
        A file for one scan (``.ply``, ``.vtp``, ``.vtk``, ``.glb`` or ``.gltf``: the suffix names the
        format), else a folder (created when missing), default ``translucency-output``; files are
        named ``<stem>_<material>.<format>``.
    material : str or Material or Medium, optional
        Shortcut for the ``material`` setting: catalogue name or coefficients (1/mm).
    lights : light or sequence of lights, optional
        Default: one white directional light of 1 W/m².
    settings : ShadeSettings, optional
        Every setting of the solve (default: the defaults; :class:`~translucency.app.shading.settings.ShadeSettings`);
        ``up`` places the default light above and in front of each scan and is recorded in the bake.
    **changes
        Any field of the settings by name (``tol=0.05``, ``time_limit=None``, ...), replacing the one of
        ``settings``, as in :func:`translucency.shade`.
    unit : str or float, optional
        Length unit of the files: ``mm``, ``cm``, ``m``, ``in`` or a number of mm per unit; None
        (default): inferred from each file's size, said in one line and recorded in the bake.
    workers : int
        Local processes to bake in (1: in this process).
    scheduler : str or distributed.Client, optional
        A Dask scheduler's address or a client: the cluster's workers bake and write the files, so
        the scans and the output folder must be reachable from them under the same paths.
    progress : BakeProgress, optional
        E.g. :class:`ConsoleProgress` for progress bars.
    format : {"ply", "vtp", "vtk", "glb", "gltf"}, optional
        Format of the files in an output folder (default ply; see
        :func:`translucency.app.shading.result.write_result`).
    preview : bool
        Also write ``<stem>_<material>.png`` beside each output: its sRGB and false-colour views, labelled.

    Returns
    -------
    list of BakeRecord
        One per scan, in order: the PLY written (radiance in W/(m² sr) per W/m² of irradiance,
        positions in mm), or the sentence saying why it failed.
    """
    if meshes is not None and isinstance(meshes, (str, os.PathLike)):
        meshes = [meshes]
    if material is not None:
        changes["material"] = material
    settings = BakeSettings.of(settings_with(settings, **changes), lights=lights, unit=unit, preview=preview)
    return bake_files(meshes, output, settings, workers=workers, scheduler=scheduler, progress=progress, format=format)
