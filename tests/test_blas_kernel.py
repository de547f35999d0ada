"""OpenBLAS's kernels chosen from the CPU's flags (core/blas_kernel.py): never over a value the
user set, nothing where the flags are unknown, and set before NumPy loads OpenBLAS."""

import json
import os
import subprocess
import sys

from meicp.core.blas_kernel import choose_openblas_kernel, cpu_flags, kernel_for


def test_the_kernel_follows_the_instruction_sets():
    assert kernel_for({"avx512f", "avx512dq", "avx512bw", "avx512vl", "avx2", "fma", "sse3"}) == "SkylakeX"
    assert kernel_for({"avx512f", "avx2", "fma"}) == "Haswell"  # AVX-512 without its BW/DQ/VL parts
    assert kernel_for({"avx2", "fma"}) == "Haswell"
    assert kernel_for({"avx", "sse3"}) is None and kernel_for(set()) is None


def test_a_value_the_user_set_is_kept_and_an_unreadable_cpuinfo_sets_nothing(tmp_path):
    env = {"OPENBLAS_CORETYPE": "Prescott"}
    assert choose_openblas_kernel(env) is None and env == {"OPENBLAS_CORETYPE": "Prescott"}
    env = {}
    assert choose_openblas_kernel(env, path=str(tmp_path / "absent")) is None and env == {}
    info = tmp_path / "cpuinfo"
    info.write_text("processor\t: 0\nflags\t\t: fpu sse3 avx avx2 fma\n")
    assert cpu_flags(str(info)) == {"fpu", "sse3", "avx", "avx2", "fma"}
    assert choose_openblas_kernel(env, path=str(info)) == "Haswell" and env == {"OPENBLAS_CORETYPE": "Haswell"}


def test_import_meicp_sets_it_before_numpy_loads_openblas():
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}
    code = ("import json, os, meicp, numpy, threadpoolctl; print(json.dumps([os.environ.get('OPENBLAS_CORETYPE'), "
            "[d.get('architecture') for d in threadpoolctl.threadpool_info() if d['internal_api'] == 'openblas']]))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    chosen, running = json.loads(done.stdout)
    expected = kernel_for(cpu_flags())
    assert chosen == expected
    if expected is not None and running:  # NumPy's BLAS is OpenBLAS here: it runs that kernel
        assert running == [expected]
