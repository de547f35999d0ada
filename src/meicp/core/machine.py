"""What this machine can hold: the memory available to a new allocation right now.

Read from Linux's ``/proc/meminfo`` (``MemAvailable``: free memory plus what the kernel can
reclaim without swapping) and the cgroup limit of a container or batch job when there is one
(cgroup v2 ``memory.max`` − ``memory.current``), else ``os.sysconf``.  Plain Python: the
size guards (:mod:`meicp.lattice.size`) compare their estimates with it before anything
large is allocated.
"""

from __future__ import annotations

import os
from pathlib import Path

MEMINFO = Path("/proc/meminfo")
CGROUP = Path("/sys/fs/cgroup")


def available_memory() -> int | None:
    """Bytes this process could allocate without swapping (None when nothing says)."""
    found = [b for b in (_meminfo_available(), _cgroup_available()) if b is not None]
    if not found:
        try:
            found.append(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
        except (ValueError, OSError, AttributeError):
            return None
    return min(found)


def _meminfo_available() -> int | None:
    try:
        for line in MEMINFO.read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def _cgroup_available() -> int | None:
    try:
        limit = (CGROUP / "memory.max").read_text().strip()
        if limit == "max":
            return None
        return max(int(limit) - int((CGROUP / "memory.current").read_text()), 0)
    except (OSError, ValueError):
        return None
