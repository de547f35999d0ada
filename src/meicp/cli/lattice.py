"""``meicp lattice SCENE.toml -o DIR``: build the scene's lattice, assemble K and M on all
ranks, and write ``DIR/NAME.h5`` + ``DIR/NAME.xdmf`` (open the .xdmf in ParaView) and
``DIR/NAME.png``; ``--json``: one document of format ``meicp-lattice`` with the sizes and the
files (:mod:`meicp.cli.output`)."""

from __future__ import annotations

import time
from pathlib import Path

from ..core.comm import available_memory_on
from ..core.errors import ProblemError
from ..core.log import rank0_print
from ..io.lattice_output import write_lattice
from ..io.scene import load_scene
from ..lattice.model import LatticeModel
from ..lattice.size import check_size
from ..petsc.assembly import assemble
from ..petsc.comm import index_max
from ..petsc.mat import destroying, diagonal, nonzeros
from ..petsc.stages import stage
from ..plotting.lattice import plot_lattice
from .arguments import output_directory, verbosity
from .exit import Exit
from .output import json_header, print_json


def register(sub) -> None:
    p = sub.add_parser("lattice", help="build a scene's lattice, assemble K and M, write HDF5 + XDMF + PNG")
    p.add_argument("scene", help="scene file (TOML)")
    p.add_argument("-o", "--output", default=".", type=output_directory,
                   help="output directory, created if missing (default: .)")
    p.add_argument("--name", help="file name stem (default: the scene file's)")
    p.add_argument("--no-plot", action="store_true", help="skip the PNG")
    p.add_argument("--no-assemble", action="store_true",
                   help="skip K and M (geometry, bonds and materials only)")
    p.add_argument("--json", action="store_true",
                   help="one JSON document (format meicp-lattice): sizes, nonzeros and the files written")
    verbosity(p)
    p.set_defaults(run=run)


def _make_dir(comm, out: Path) -> None:
    error = None
    if comm.Get_rank() == 0:
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            error = f"cannot create output directory {str(out)!r}: {exc.strerror or exc}"
    error = comm.bcast(error, root=0)
    if error:
        raise ProblemError(error)


def run(args) -> int:
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    scene = load_scene(args.scene)
    memory, where = available_memory_on(comm)
    check_size(scene, memory=memory, index_max=None if args.no_assemble else index_max(), ranks=comm.Get_size(),
               use="geometry" if args.no_assemble else "lattice", where=where)
    model = LatticeModel(scene)
    out = Path(args.output)
    stem = args.name or Path(args.scene).stem
    if not stem or "/" in stem:
        raise ProblemError(f"--name {stem!r} must be a plain file name stem")
    _make_dir(comm, out)
    say = (lambda *a: None) if args.json else rank0_print
    say(model.describe())
    doc = {**json_header("lattice"), "scene": str(args.scene), "nx": model.nx, "ny": model.ny,
           "dofs": model.n_dofs, "ranks": comm.Get_size(), "total_mass": model.total_mass(), "K": None}

    fields, matrices = {}, ()
    if not args.no_assemble:
        comm.Barrier()
        t0 = time.perf_counter()
        with stage("assemble"):
            matrices = assemble(scene, comm)
        comm.Barrier()
        dt = time.perf_counter() - t0
        K = matrices[0]
        nz = nonzeros(K)
        doc["K"] = {"nonzeros": nz["nz_used"], "preallocated": nz["nz_allocated"], "mallocs": nz["mallocs"],
                    "seconds": dt}
        say(f"K: {model.n_dofs} x {model.n_dofs}, {nz['nz_used']:,} nonzeros "
                    f"(preallocated {nz['nz_allocated']:,}, mallocs {nz['mallocs']}); "
                    f"M: lumped, total mass {model.total_mass():.6g}; assembled in {dt:.3f} s "
                    f"on {comm.Get_size()} rank(s)")
        fields["K_diagonal"] = diagonal(K)
    with destroying(*fields.values(), *matrices), stage("write"):
        files = write_lattice(out / f"{stem}.h5", model, fields=fields, comm=comm)
    say(f"wrote {files.h5}")
    say(f"wrote {files.xdmf}  (open it in ParaView)")
    doc["files"] = {"h5": str(files.h5), "xdmf": str(files.xdmf), "png": None}
    if not args.no_plot:
        error = None
        if comm.Get_rank() == 0:
            try:
                png = plot_lattice(model, out / f"{stem}.png")
                doc["files"]["png"] = str(png)
                say(f"wrote {png}")
            except ProblemError as exc:
                error = str(exc)
        error = comm.bcast(error, root=0)
        if error:
            raise ProblemError(error)
    if args.json:
        print_json(doc)
    return Exit.OK
