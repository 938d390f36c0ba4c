"""What the operating system says about memory: how much this process may still take and how much it holds.

Every layer asks (the solver's budget, the readers that refuse a file too large to decode), so it sits at the
package's root with :mod:`translucency.threads`.
"""

from __future__ import annotations

import os

__all__ = ["available_memory", "resident_memory"]


def available_memory() -> float | None:
    """Bytes this process can still take: ``MemAvailable`` of ``/proc/meminfo``, lowered to what a
    cgroup memory limit (v2 ``memory.max``, v1 ``memory.limit_in_bytes``) leaves; None where unknown."""
    values = []
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    values.append(float(line.split()[1]) * 1024)
                    break
    except (OSError, ValueError, IndexError):
        pass
    for limit_file, usage_file in (
        ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
        ("/sys/fs/cgroup/memory/memory.limit_in_bytes", "/sys/fs/cgroup/memory/memory.usage_in_bytes"),
    ):
        try:
            with open(limit_file) as f:
                limit = f.read().strip()
            with open(usage_file) as f:
                usage = float(f.read().strip())
        except (OSError, ValueError):
            continue
        if limit != "max" and float(limit) < 2**60:  # "max" or a huge number: no limit
            values.append(max(0.0, float(limit) - usage))
    return min(values) if values else None


def resident_memory() -> float:
    """Bytes of memory this process holds now (resident set); 0 where unknown."""
    try:
        with open("/proc/self/statm") as f:
            return float(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0.0
