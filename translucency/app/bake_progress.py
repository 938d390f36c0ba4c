"""How a batch bake shows its progress: :class:`BakeProgress` (what :func:`translucency.app.bake.bake_files` tells)
and :class:`ConsoleProgress` (bars on a terminal, lines elsewhere), and the summary table at its end.
"""

from __future__ import annotations

import sys
from pathlib import Path

__all__ = ["BakeProgress", "ConsoleProgress", "format_summary"]


class BakeProgress:
    """Receives a batch's progress; this base class ignores it (subclass to show it).

    :func:`~translucency.app.bake.bake_files` calls :meth:`start` once the outputs are planned, :meth:`stage` while a
    file
    is baked in this process (not from worker processes or Dask), :meth:`finished` when a file is
    done (in whatever order files finish) and :meth:`end` at the end, also after an error.
    """

    def start(self, sources: list[str], outputs: list[str]) -> None:
        """The batch starts: the inputs and their planned outputs, in order."""

    def stage(self, index: int, stage: str, fraction: float) -> None:
        """File ``index`` is at ``fraction`` (0 to 1) of ``stage`` (loading, far field, near field, bounces,
        writing)."""

    def said(self, index: int, kind: str, message: str) -> None:
        """File ``index``, baked in this process, has a ``"warning"`` or a ``"note"`` to say now (the same
        line is also in its record's ``warnings`` or ``notes``)."""

    def finished(self, index: int, record) -> None:
        """File ``index`` is done, baked or failed (its :class:`~translucency.app.bake.BakeRecord`)."""

    def end(self) -> None:
        """The batch is over."""


class ConsoleProgress(BakeProgress):
    """Progress of a batch on stderr, by the rule of :mod:`translucency.app.progress`.

    On a terminal: a tqdm bar of files done and, below it, the stage of the file baked in this
    process. Elsewhere (a pipe, a log file): one line per stage of a file baked in this process
    (``bunny.ply: far field done (0.41 s)``) and one line per file done (``[1/3] bunny.ply: baked
    (1.32 s)``). Files baked in worker processes or on Dask report no stages, so they give their file
    line only. With ``quiet``: no progress. Failures and loading warnings are printed in every mode,
    one line each, as they happen.

    Parameters
    ----------
    file : file-like, optional
        Where to write (default: ``sys.stderr``).
    quiet : bool
        No progress (``--quiet``).
    terminal : bool, optional
        Force bars (True) or lines (False); None: look at ``file``.
    """

    def __init__(self, file=None, *, quiet: bool = False, terminal: bool | None = None):
        self.file = file
        self.quiet = quiet
        self.terminal = terminal
        self._files = None
        self._stages: dict = {}
        self._sources: list[str] = []
        self._done = 0
        self._said: set = set()  # (index, message) already printed while the file was baked

    def _stream(self):
        return self.file if self.file is not None else sys.stderr

    def _mode(self) -> str:
        from .progress import progress_mode

        return progress_mode(self._stream(), self.quiet, self.terminal)

    def _print(self, line: str) -> None:
        if self._files is not None:  # above the bars
            self._files.write(line, file=self._stream())
        else:
            print(line, file=self._stream(), flush=True)

    def start(self, sources, outputs):
        """Open the bar of files (on a terminal)."""
        self._sources, self._done = list(sources), 0
        if self._mode() == "bars":
            from tqdm import tqdm

            self._files = tqdm(
                total=len(sources), desc="baking", unit="file", file=self._stream(), position=0, dynamic_ncols=True
            )

    def stage(self, index, stage, fraction):
        """Show the stage of the file baked in this process."""
        from .progress import StageProgress

        if index not in self._stages:
            for other in self._stages.values():  # one stage bar at a time
                other.close()
            self._stages[index] = StageProgress(
                Path(self._sources[index]).name, self._stream(), quiet=self.quiet, terminal=self.terminal, position=1
            )
        self._stages[index](stage, fraction)

    def said(self, index, kind, message):
        """Print a note or warning of a file baked in this process as it happens (once)."""
        self._said.add((index, message))
        self._print(self._line(self._sources[index] if index < len(self._sources) else "", kind, message))

    @staticmethod
    def _line(source: str, kind: str, message: str) -> str:
        """``translucency: [warning: |error: ]<file>: <message>``, the file named once (most messages start with its
        name; an error names it as given, with its folder, which tells apart two files of one name in a batch)."""
        lead = {"warning": "warning: ", "error": "error: "}.get(kind, "")
        name = Path(source).name if source else ""
        if not source or message.startswith(source):
            return f"translucency: {lead}{message}"
        if name and message.startswith(name):
            return f"translucency: {lead}{source if kind == 'error' else name}{message[len(name) :]}"
        return f"translucency: {lead}{source}: {message}"

    def finished(self, index, record):
        """Count the file; print its notes, warnings and error not printed yet, and its line when not on a
        terminal."""
        if index in self._stages:
            self._stages.pop(index).close()
        self._done += 1
        for kind, messages in (("note", record.notes), ("warning", record.warnings)):
            for message in messages:
                if (index, message) not in self._said:
                    self._print(self._line(record.source, kind, message))
        if not record.ok:
            self._print(self._line(record.source, "error", record.error))
        if self._files is not None:
            self._files.update(1)
        elif self._mode() == "lines":
            name = Path(self._sources[index]).name if index < len(self._sources) else record.source
            status = "baked" if record.ok else "failed"
            self._print(f"[{self._done}/{len(self._sources)}] {name}: {status} ({record.seconds:.2f} s)")

    def end(self):
        """Close the bars."""
        for stage in self._stages.values():
            stage.close()
        if self._files is not None:
            self._files.close()
        self._files, self._stages = None, {}


# --------------------------------------------------------------------------------------------------
# one file
# --------------------------------------------------------------------------------------------------


def format_summary(records, seconds: float | None = None) -> str:
    """The summary table of a batch: file, vertices, lit solver vertices (incident flux > 0), wall time,
    output, status; and a total line."""
    header = ("file", "vertices", "lit solver vertices", "time [s]", "output", "status")
    rows = [
        (
            r.source,
            "-" if r.vertices is None else str(r.vertices),
            "-" if r.lit_sources is None else str(r.lit_sources),
            f"{r.seconds:.1f}",
            r.output or "-",
            r.status,
        )
        for r in records
    ]
    widths = [max(len(row[i]) for row in rows + [header]) for i in range(len(header) - 1)]
    lines = [
        "  ".join(cell.ljust(w) for cell, w in zip(row, widths + [0])).rstrip()
        for row in [header, tuple("-" * w for w in widths) + ("------",)] + rows
    ]
    failed = sum(not r.ok for r in records)
    total = f"baked {len(records) - failed} of {len(records)} files"
    if seconds is not None:
        total += f" in {seconds:.1f} s (wall time)"
    if failed:
        total += f"; {failed} failed"
    return "\n".join(lines + [total])
