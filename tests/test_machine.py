"""core.machine: the memory a size guard may count on."""

import ctypes
import ctypes.util
import os

import pytest

from meicp.core.machine import available_memory, release_free_heap

libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
libc.malloc.restype, libc.malloc.argtypes = ctypes.c_void_p, [ctypes.c_size_t]
libc.free.argtypes = [ctypes.c_void_p]


def resident_bytes() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_free_heap_held_by_the_allocator_is_handed_back_before_memory_is_counted():
    # 128 MiB in 64 KiB blocks (below glibc's mmap threshold: they live in the heap), each
    # followed by a smaller block kept alive, so that freeing them leaves holes the heap's
    # top-trim cannot return: what a block-low-rank factor leaves behind when destroyed
    big, small = [], []
    for _ in range(2048):
        p = libc.malloc(64 * 1024)
        ctypes.memset(p, 1, 64 * 1024)
        big.append(p)
        small.append(libc.malloc(40000))
    try:
        for p in big:
            libc.free(p)
        held = resident_bytes()
        if not release_free_heap():
            pytest.skip("no glibc malloc_trim here")
        assert held - resident_bytes() > 100 * 2**20
        assert available_memory() > 0
    finally:
        for p in small:
            libc.free(p)


def test_memory_is_measured_again_after_reclaiming_only_when_short(monkeypatch):
    from meicp.core import machine
    from meicp.core import comm as core_comm

    calls = []
    monkeypatch.setattr(core_comm, "available_memory", lambda reclaim=False: calls.append(reclaim) or
                        (5000 if reclaim else 1000))
    assert core_comm.available_memory_on(None) == (1000, "this machine") and calls == [False]
    calls.clear()
    assert core_comm.available_memory_on(None, need=800)[0] == 1000 and calls == [False]
    calls.clear()
    assert core_comm.available_memory_on(None, need=3000)[0] == 5000 and calls == [False, True]
    assert machine.available_memory(reclaim=True) > 0
