"""What this machine can hold: the memory available to a new allocation right now.

Read from Linux's ``/proc/meminfo`` (``MemAvailable``: free memory plus what the kernel can
reclaim without swapping) and the cgroup limit of a container or batch job when there is one
(cgroup v2 ``memory.max`` − ``memory.current``), else ``os.sysconf``.  Plain Python: the
size guards (:mod:`meicp.lattice.size`) compare their estimates with it before anything
large is allocated.  Memory this process freed but its allocator still holds (glibc keeps
freed small blocks, e.g. a block-low-rank MUMPS factor's, in its heap) is not seen there:
``reclaim=True`` hands it back first (:func:`release_free_heap`) — a search after a large
factorisation was refused with several GiB of the process's own free heap uncounted.  Not
by default: memory kept is memory not faulted in again, and faulting it in again is slow
at scale (docs/benchmarks-notes.md).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
from pathlib import Path

MEMINFO = Path("/proc/meminfo")
CGROUP = Path("/sys/fs/cgroup")


def release_free_heap() -> bool:
    """Hand the free pages of this process's C heap back to the system (glibc's
    ``malloc_trim(0)``); False where there is no glibc."""
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        trim = libc.malloc_trim
    except (OSError, AttributeError):
        return False
    trim.argtypes, trim.restype = [ctypes.c_size_t], ctypes.c_int
    trim(0)
    return True


def available_memory(reclaim: bool = False) -> int | None:
    """Bytes this process could allocate without swapping (None when nothing says);
    ``reclaim``: its own free heap handed back first."""
    if reclaim:
        release_free_heap()
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
