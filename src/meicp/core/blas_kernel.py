"""OpenBLAS's kernels on a CPU it does not recognise.

Debian's OpenBLAS (0.3.21, built for every x86-64 CPU at once) picks its kernels from the
CPU's model when it loads; on this project's machines (a VM's "Intel(R) Xeon(R) Processor",
AVX-512) it falls back to the generic Prescott (SSE3) kernels: dense products five times
slower (12.6 against 65–75 GFlop/s per core), and MUMPS' frontal matrices with them — a
factorisation of a 10⁶-DOF pencil about twice as slow (docs/benchmarks-notes.md,
"OpenBLAS kernel").  OpenBLAS's own remedy is the environment variable ``OPENBLAS_CORETYPE``, read when
the library loads; :func:`choose_openblas_kernel` sets it from the instruction sets the
Linux kernel reports, before NumPy or PETSc load OpenBLAS (``import meicp`` calls it first),
and never over a value already set — ``OPENBLAS_CORETYPE=Prescott`` restores the old
behaviour.  A process that loaded OpenBLAS before importing meicp keeps what it has.
"""

from __future__ import annotations

import os

#: the OpenBLAS kernel for the instruction sets a CPU has, best first
KERNELS = (("SkylakeX", {"avx512f", "avx512dq", "avx512bw", "avx512vl", "avx2", "fma"}),
           ("Haswell", {"avx2", "fma"}))


def cpu_flags(path: str = "/proc/cpuinfo") -> set[str]:
    """The instruction-set flags of the first CPU in ``path`` (empty where there is none: not
    Linux, or unreadable)."""
    try:
        with open(path, encoding="ascii", errors="replace") as f:
            for line in f:
                if line.startswith("flags"):
                    return set(line.partition(":")[2].split())
    except OSError:
        pass
    return set()


def kernel_for(flags: set[str]) -> str | None:
    """The OpenBLAS kernel :data:`KERNELS` gives for ``flags``, or None (leave OpenBLAS's own
    choice)."""
    return next((name for name, needs in KERNELS if needs <= flags), None)


def choose_openblas_kernel(environ=os.environ, path: str = "/proc/cpuinfo") -> str | None:
    """Set ``OPENBLAS_CORETYPE`` in ``environ`` from the CPU's flags unless it is set; returns
    the value it set (None: nothing set)."""
    if "OPENBLAS_CORETYPE" in environ:
        return None
    kernel = kernel_for(cpu_flags(path))
    if kernel is not None:
        environ["OPENBLAS_CORETYPE"] = kernel
    return kernel
