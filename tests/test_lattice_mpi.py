"""The lattice on 2 ranks (``make test-mpi``): distributed assembly identical to the serial
one, row-band ownership, exact preallocation, a SLEPc solve against the analytic
frequencies, and the same HDF5 file from collective, gathered and serial writes."""

import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest

from meicp.core.errors import ProblemError
from meicp.io.scene import load_scene, scene_from_dict
from meicp.petsc.assembly import assemble
from meicp.lattice.model import LatticeModel

from .test_lattice import SCENES, free_scene, single_row_frequencies, single_row_scene, slepc_smallest

pytestmark = pytest.mark.mpi(min_size=2)

ONE_ROW = {"lattice": {"nx": 9, "spacing": 1.0, "shear": 0.1},
           "layers": [{"name": "a", "rows": 1, "stiffness": 1.0, "density": 1.0}]}


def scenes():
    yield "sheared", load_scene(SCENES / "sheared.toml")
    yield "embedded", load_scene(SCENES / "embedded_layer.toml")
    yield "frictional", load_scene(SCENES / "frictional_interface.toml")
    yield "three layers, odd rows", free_scene()
    yield "one row (a rank without rows)", scene_from_dict(ONE_ROW)


@pytest.mark.parametrize("name", [n for n, _ in scenes()])
def test_distributed_assembly_equals_serial(comm, name):
    from meicp.petsc.mat import mat_to_scipy

    scene = dict(scenes())[name]
    model = LatticeModel(scene)
    K, M = assemble(scene, comm)
    try:
        j0, j1 = model.row_band(comm.rank, comm.size)
        assert K.getOwnershipRange() == model.dof_range(j0, j1) == M.getOwnershipRange()
        assert K.getSize() == (model.n_dofs, model.n_dofs)
        assert K.getType() == "mpiaij"
        Ks, Ms = assemble(scene)
        assert abs(mat_to_scipy(K) - Ks).max() == 0
        assert abs(mat_to_scipy(M) - Ms).max() == 0
        info = K.getInfo(K.InfoType.LOCAL)
        assert info["mallocs"] == 0 and info["nz_unneeded"] == 0
        assert comm.allreduce(int(info["nz_used"])) == Ks.nnz
    finally:
        K.destroy()
        M.destroy()


@pytest.mark.parametrize("name", [n for n, _ in scenes()])
def test_the_whole_matrices_gathered_on_every_rank_are_the_serial_assembly(comm, name):
    """What ``LatticeMatrices.whole`` hands the condenser and the static equilibrium on several
    ranks: the serial assembly's CSR arrays exactly, the same on every rank."""
    from meicp.petsc.assembly import LatticeMatrices

    scene = dict(scenes())[name]
    Ks, Ms = assemble(scene)
    with LatticeMatrices(LatticeModel(scene), comm) as lattice:
        for got, ref in zip(lattice.whole(), (Ks, Ms)):
            assert np.array_equal(got.indptr, ref.indptr) and np.array_equal(got.indices, ref.indices)
            assert np.array_equal(got.data, ref.data) and got.indices.dtype == ref.indices.dtype


def test_row_bands_cover_the_lattice_once(comm):
    model = LatticeModel(free_scene())
    bands = comm.allgather(model.row_band(comm.rank, comm.size))
    assert bands[0][0] == 0 and bands[-1][1] == model.ny
    assert all(a[1] == b[0] for a, b in zip(bands, bands[1:]))


def test_two_rank_frequencies_match_analytic(comm):
    nx, k, rho, a, shear = 30, 2.0, 3.0, 0.5, 0.2
    vals, resid = slepc_smallest(single_row_scene(nx, k, rho, a, shear), nev=10, target=0.0, comm=comm)
    assert resid < 1e-10
    assert np.allclose(vals, single_row_frequencies(nx, k, rho, a, shear)[:10], rtol=1e-9, atol=0)
    gathered = comm.allgather(vals)
    assert all(np.array_equal(gathered[0], g) for g in gathered)


_TMP_DIRS = []


def _shared_tmp(comm) -> Path:
    """A directory every rank sees (made by rank 0; removed at the end of the module)."""
    path = tempfile.mkdtemp(prefix="meicp-mpi-") if comm.rank == 0 else None
    path = Path(comm.bcast(path, root=0))
    _TMP_DIRS.append(path)
    return path


@pytest.fixture(scope="module", autouse=True)
def _remove_tmp_dirs():
    yield
    from mpi4py import MPI

    MPI.COMM_WORLD.Barrier()
    if MPI.COMM_WORLD.rank == 0:
        for path in _TMP_DIRS:
            shutil.rmtree(path, ignore_errors=True)


def _read_all(path):
    import h5py

    out = {}
    with h5py.File(path, "r") as f:
        out["/"] = {k: (v.tolist() if hasattr(v, "tolist") else v) for k, v in f.attrs.items()}
        f.visititems(lambda name, obj: out.__setitem__(name, obj[()]) if hasattr(obj, "shape") else None)
    return out


@pytest.mark.parametrize("name", ["embedded", "one row (a rank without rows)"])
def test_same_hdf5_file_collective_gathered_and_serial(comm, name):
    from meicp.io.lattice_output import write_lattice

    scene = dict(scenes())[name]
    model = LatticeModel(scene)
    tmp = _shared_tmp(comm)
    K, M = assemble(scene, comm)
    diag = K.getDiagonal()
    u = np.arange(model.n_dofs, dtype=float) * 0.5
    fields = {"K_diagonal": diag, "u": u, "level": np.arange(model.n_nodes)}
    try:
        write_lattice(tmp / "coll.h5", scene, fields=fields, comm=comm, parallel_io="collective")
        write_lattice(tmp / "gath.h5", scene, fields=fields, comm=comm, parallel_io="gather")
    finally:
        diag.destroy()
        K.destroy()
        M.destroy()
    if comm.rank == 0:
        Ks, _ = assemble(scene)
        serial_fields = {"K_diagonal": Ks.diagonal(), "u": u, "level": np.arange(model.n_nodes)}
        write_lattice(tmp / "ser.h5", scene, fields=serial_fields)
        ref = _read_all(tmp / "ser.h5")
        for other in ("coll.h5", "gath.h5"):
            got = _read_all(tmp / other)
            assert got.keys() == ref.keys(), other
            for key in ref:
                if key == "/":
                    assert got[key] == ref[key], other
                else:
                    assert np.array_equal(got[key], ref[key]), (other, key)
            assert (tmp / other.replace(".h5", ".xdmf")).read_text().replace(other, "X") == \
                (tmp / "ser.xdmf").read_text().replace("ser.h5", "X")
        assert sorted(p.name for p in tmp.iterdir()) == sorted(
            f"{s}.{e}" for s in ("coll", "gath", "ser") for e in ("h5", "xdmf"))
    comm.Barrier()


def test_vec_field_must_be_distributed_like_the_lattice(comm):
    from meicp.io.lattice_output import write_lattice
    from meicp.petsc import import_petsc

    PETSc = import_petsc()
    scene = load_scene(SCENES / "embedded_layer.toml")  # 15 rows: bands of 8 and 7 rows
    model = LatticeModel(scene)
    v = PETSc.Vec().createMPI(model.n_dofs, comm=comm)  # PETSc's even split, not row bands
    try:
        with pytest.raises(ProblemError, match="not distributed like the lattice's DOFs"):
            write_lattice(_shared_tmp(comm) / "v.h5", scene, fields={"v": v}, comm=comm)
    finally:
        v.destroy()


def test_bad_field_on_one_rank_fails_on_every_rank_before_writing(comm):
    from meicp.io.lattice_output import write_lattice

    scene = load_scene(SCENES / "sheared.toml")
    model = LatticeModel(scene)
    tmp = _shared_tmp(comm)
    n = model.n_dofs if comm.rank == 0 else 5
    with pytest.raises(ProblemError, match="field 'u' has 5 values"):
        write_lattice(tmp / "bad.h5", scene, fields={"u": np.zeros(n)}, comm=comm)
    comm.Barrier()
    assert list(tmp.iterdir()) == []
