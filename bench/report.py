"""Helpers shared by the benchmark scripts: the state of the machine, results files, generated tables.

Every results JSON carries :func:`machine_info` (CPU count, numba threads and the load average at
the start and at the end of the run), so that timings inflated by other jobs on the machine are
visible. The tables in ``bench/README.md`` that the suite generates sit between marker comments::

    <!-- solver-table:start -->
    ...generated...
    <!-- solver-table:end -->

and :func:`replace_marked` swaps only what is between them.
"""

from __future__ import annotations

import json
import os
import platform
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results"
README = ROOT / "bench" / "README.md"


def load_average() -> list[float]:
    """The 1-, 5- and 15-minute load averages of the machine (runnable processes), rounded."""
    return [round(x, 2) for x in os.getloadavg()]


def cpu_model() -> str:
    """The processor's model name (from ``/proc/cpuinfo``), or the platform's description."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine_info() -> dict:
    """Versions, processor, CPU count, numba's thread count and the current load average."""
    import numba

    from translucency import __version__

    return {
        "version": __version__,
        "python": platform.python_version(),
        "machine": platform.machine(),
        "cpu": cpu_model(),
        "cpu_count": os.cpu_count(),
        "threads": numba.get_num_threads(),
        "load_average_start": load_average(),
    }


def output_dir(quick: bool) -> Path:
    """Where a run writes: ``bench/results`` or, for a quick smoke run, ``bench/results/tmp``."""
    out = RESULTS / "tmp" if quick else RESULTS
    out.mkdir(parents=True, exist_ok=True)
    return out


def write_results(out: Path, name: str, payload: dict, table: str) -> None:
    """Write ``<name>.json`` (with the end-of-run load average added to ``payload["info"]``) and ``<name>.md``."""
    payload.setdefault("info", {})["load_average_end"] = load_average()
    (out / f"{name}.json").write_text(json.dumps(payload, indent=1, default=_plain))
    (out / f"{name}.md").write_text(table.rstrip("\n") + "\n")


def _plain(value):
    """JSON form of numpy scalars and arrays, and of paths."""
    if hasattr(value, "tolist"):
        return value.tolist()
    return str(value)


def _markers(name: str) -> tuple[str, str]:
    """The start and end marker comments of the generated table ``name``."""
    return f"<!-- {name}:start -->", f"<!-- {name}:end -->"


def replace_marked(text: str, name: str, content: str) -> str:
    """``text`` with what lies between the markers of ``name`` replaced by ``content``.

    Raises ``KeyError`` when the markers are missing or out of order.
    """
    start, end = _markers(name)
    i, j = text.find(start), text.find(end)
    if i < 0 or j < i:
        raise KeyError(f"no {start} ... {end} block")
    return text[: i + len(start)] + "\n" + content.strip("\n") + "\n" + text[j:]


def update_readme(tables: dict[str, str], readme: Path = README) -> list[str]:
    """Put each generated table into its marked block of the README; returns the names replaced."""
    text = readme.read_text()
    done = []
    for name, content in tables.items():
        try:
            text = replace_marked(text, name, content)
        except KeyError:
            continue
        done.append(name)
    readme.write_text(text)
    return done
