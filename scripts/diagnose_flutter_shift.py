"""Diagnose one complex shift-and-invert flutter solve at scale (issue 15): for each pair SLEPc
converges on the real 2n form at the proxy's target, print |σ − τ|, SLEPc's own absolute and
backward errors and the backward error recomputed on (A, B) for both halves of the vector.

    mpirun -n 2 .venv/bin/python scripts/diagnose_flutter_shift.py DOFS TOL[,TOL...] [option=value ...]

e.g. ``300000 1e-10,1e-12`` or ``300000 1e-10 st_mat_mumps_icntl_10=-2`` (options under the
``meicp_flutter_`` prefix, without it); ``shift=0.1j`` moves the target off the proxy's σ by
that complex offset.  Findings in docs/benchmarks.md, Flutter."""
import sys, time
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent))
import numpy as np, scipy.sparse as sp
from mpi4py import MPI
from bench_flutter import scene_of
from meicp.contact.problem import pencil
from meicp.contact import flutter as fl
from meicp.petsc import import_slepc, import_petsc
from meicp.petsc.flutter import SlidingPencilOps, _I2, _J2, shift_defaults
from meicp.petsc.mat import mat_from_local_csr
from meicp.petsc.options import FLUTTER, OptionsScope
comm = MPI.COMM_WORLD
dofs = int(sys.argv[1]); tols = [float(t) for t in sys.argv[2].split(",")]
extra = dict(a.split("=") for a in sys.argv[3:])
offset = complex(extra.pop("shift", "0"))
scene = scene_of(dofs)
SLEPc = import_slepc()
with pencil(scene, comm=comm) as pen:
    base = next(cs.states for cs in pen.sets if cs.name == "base")
    tau = complex(fl.proxy_targets(scene, list(base), 1)[0]) + offset
    if comm.rank == 0: print("tau", tau, flush=True)
    with SlidingPencilOps(pen.A, pen.B) as ops:
        n = pen.A.getSize()[0]
        K_local = (sp.kron(ops.A_local - tau.real * ops.B_local, _I2, format="csr") + tau.imag * sp.kron(ops.B_local, _J2, format="csr"))
        K = mat_from_local_csr(pen.A.getComm(), K_local, 2 * n)
        B2 = mat_from_local_csr(pen.A.getComm(), sp.kron(ops.B_local, _I2, format="csr"), 2 * n)
        for tol in tols:
            t0 = time.perf_counter()
            eps = SLEPc.EPS().create(comm=pen.A.getComm())
            eps.setOperators(K, B2)
            opts = dict(extra)
            with OptionsScope(FLUTTER, shift_defaults(4, 24, tol), opts) as scope:
                scope.configure(eps); eps.solve()
            zr, zi = K.createVecRight(), K.createVecRight()
            if comm.rank == 0: print(f"tol {tol}: nconv {eps.getConverged()} its {eps.getIterationNumber()} {time.perf_counter()-t0:.1f}s", flush=True)
            for i in range(eps.getConverged()):
                mu = complex(eps.getEigenpair(i, zr, zi))
                ea = eps.computeError(i, SLEPc.EPS.ErrorType.ABSOLUTE); er = eps.computeError(i, SLEPc.EPS.ErrorType.BACKWARD)
                z = zr.getArray(readonly=True) + 1j * zi.getArray(readonly=True)
                xp, xm = z[0::2] + 1j * z[1::2], z[0::2] - 1j * z[1::2]
                rp = ops.residual(tau + mu, xp); rm = ops.residual(tau.conjugate() + mu, xm)
                if comm.rank == 0: print(f"  mu {mu:.3e} |mu| {abs(mu):.2e} slepc abs {ea:.2e} backward {er:.2e} ours+ {rp:.2e} ours- {rm:.2e}", flush=True)
            eps.destroy(); zr.destroy(); zi.destroy()
        K.destroy(); B2.destroy()
