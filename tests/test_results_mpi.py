"""``write_results`` from 2 ranks (``make test-mpi``): one consistent set of files, the
same paths on every rank, and errors raised on every rank alike (nothing left behind)."""

import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest

from meicp.core.errors import MeicpError, ProblemError
from meicp.io.results import write_results
from meicp.io.scene import load_scene
from meicp.plotting.lattice import display_scale

from .test_results import EXPECTED, SCENES, unstable_result

pytestmark = pytest.mark.mpi(min_size=2)


@pytest.fixture
def shared_dir(comm):
    """A directory every rank sees (rank 0's), removed afterwards."""
    path = tempfile.mkdtemp(prefix="meicp-results-mpi-") if comm.rank == 0 else None
    path = Path(comm.bcast(path, root=0))
    yield path
    comm.Barrier()
    if comm.rank == 0:
        shutil.rmtree(path, ignore_errors=True)


def test_two_ranks_write_one_set(comm, shared_dir):
    import h5py

    scene = load_scene(SCENES / "two_layers.toml")
    result = unstable_result(scene)
    out = shared_dir / "run"
    files = write_results(out, scene, result, comm=comm)
    everyone = comm.allgather({k: str(v) for k, v in files.items()})
    assert all(d == everyone[0] for d in everyone)
    assert {p.name for p in out.iterdir()} == EXPECTED  # nothing temporary, nothing per rank
    comm.Barrier()
    if comm.rank == 0:
        with h5py.File(files["results"], "r") as f:
            assert f.attrs["ranks"] == comm.size and f.attrs["n_modes"] == 2
            np.testing.assert_array_equal(f["modes/x"][()], np.stack([m.x for m in result.modes]))
        with h5py.File(files["lattice"], "r") as f:
            assert f["geometry/points"].shape == (scene.n_nodes, 3)
            scale = display_scale(scene, result.modes[0].x)
            np.testing.assert_allclose(f["fields/mode_0"][:, :2].ravel(), scale * result.modes[0].x)
    comm.Barrier()
    # a second run over the first replaces the files (same names, still one set)
    files2 = write_results(out, scene, result, comm=comm)
    assert files2 == files and {p.name for p in out.iterdir()} == EXPECTED


def test_bad_result_raises_on_every_rank(comm, shared_dir):
    scene = load_scene(SCENES / "two_layers.toml")
    result = unstable_result(scene)
    result.modes[0].x = result.modes[0].x[:-1]
    with pytest.raises(ProblemError, match="mode 0"):
        write_results(shared_dir / "bad", scene, result, comm=comm)
    comm.Barrier()
    assert not (shared_dir / "bad").exists()


def test_failure_on_rank0_reaches_every_rank(comm, shared_dir, monkeypatch):
    import meicp.io.results as results

    def broken(*args, **kwargs):
        raise RuntimeError("disk full (simulated)")

    # lattice.h5's writer, after results.h5 (a picture is an extra: its failure is a warning)
    monkeypatch.setattr(results, "write_lattice", broken)
    scene = load_scene(SCENES / "two_layers.toml")
    with pytest.raises((RuntimeError, MeicpError), match="simulated"):
        write_results(shared_dir / "half", scene, unstable_result(scene), comm=comm)
    comm.Barrier()
    assert not (shared_dir / "half").exists()
