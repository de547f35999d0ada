"""The lattice in HDF5, with an XDMF file next to it that ParaView opens.

:func:`write_lattice` writes ``NAME.h5`` and ``NAME.xdmf``:

=========================  =====================  ============================================
HDF5 path                  shape, type            content
=========================  =====================  ============================================
``/geometry/points``       (n_nodes, 3) f8        reference positions, z = 0, natural order
``/geometry/ij``           (n_nodes, 2) i4        column i and row j of each node
``/bonds/connectivity``    (n_bonds, 2) i8        node pairs (XDMF line cells)
``/bonds/kind``            (n_bonds,) i1          0 horizontal, 1 vertical, 2 diagonal
                                                  (i,j)-(i+1,j+1), 3 antidiagonal (i+1,j)-(i,j+1)
``/bonds/stiffness``       (n_bonds,) f8          k of each bond
``/bonds/viscosity``       (n_bonds,) f8          η of each bond (damped scenes only, docs/damping.md)
``/bonds/interface``       (n_bonds,) i1          1 when the bond joins two materials
``/nodes/material``        (n_nodes,) i4          index into ``/materials``
``/nodes/mass``            (n_nodes,) f8          lumped mass ρ a³
``/nodes/fixed``           (n_nodes, 3) f8        1 where a component is prescribed (Dirichlet)
``/nodes/contact``         (n_nodes,) i1          1 on the rigid base
``/nodes/i``, ``/nodes/j`` (n_nodes,) i4          column i and row j (XDMF fields ``i``, ``j``)
``/fields/NAME``           (n_nodes, 3) f8        caller's per-DOF vectors, padded to 3 comps
                           or (n_nodes,) f8       caller's per-node scalars
``/materials/*``           (n_mat,)               name, kind, stiffness, density; and
                                                  ``interface_stiffness`` (n_mat, n_mat); damped:
                                                  ``viscosity``, ``interface_viscosity``
``/scene``                 scalar string          the scene file's TOML text, when known
=========================  =====================  ============================================

Root attributes: ``format = "meicp-lattice"``, ``format_version``, ``nx, ny, spacing, shear,
n_nodes, n_dofs, n_bonds``, ``meicp_version``, ``units_convention``.

Every dataset carries CF-style ``long_name`` and ``units`` attributes.  The model is
dimensionless: meicp attaches no unit to any number, so ``units`` is ``"1"`` everywhere and
the numbers are in whatever consistent system the scene's are (lengths in the unit of
``lattice.spacing``, stiffness and density as given; ``long_name`` names the dimension where
there is one).  Coded fields carry their legend as CF ``flag_values`` / ``flag_meanings``
and as a ``legend`` sentence (``bonds/kind``, ``bonds/interface``, ``nodes/contact`` and a
caller's coded fields such as ``contact_state``); the XDMF file repeats the legends in a
comment at its top, for ParaView users.

Under MPI (collective on ``comm``) each rank contributes its band of node rows and the
bonds stored from them; with an MPI-enabled h5py the ranks write their slices collectively
(``mpio`` driver), otherwise the slices are gathered to rank 0, which writes: either way
the file is the same.  Everything is checked before any file is created, and files are
written under a temporary name and renamed when complete.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._version import __version__
from ..core.cleanup import on_interrupt
from ..core.comm import mpi_comm
from ..core.errors import ProblemError
from ..lattice.assembly import as_model
from ..lattice.model import BOND_KINDS, LatticeModel
from .scene import as_scene

FORMAT = "meicp-lattice"
FORMAT_VERSION = 1
_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.+-]*$")
#: names of /nodes/* and /bonds/* attributes in the XDMF file, not available to fields
_RESERVED = ("material", "mass", "fixed", "contact", "i", "j", "bond_kind", "bond_stiffness", "bond_interface",
             "bond_viscosity")
#: the statement every meicp file carries about units (see the module docstring)
UNITS_CONVENTION = ("dimensionless: meicp attaches no unit to any number; every value is in the consistent "
                    "system of units the scene's numbers are in (lengths in the unit of lattice.spacing, "
                    "stiffness and density as given), and units = \"1\" on every dataset says so")


def coded(meanings, values=None, **more) -> dict:
    """CF attributes of a coded dataset: ``flag_values``, ``flag_meanings`` (one word each)
    and a ``legend`` sentence ("0 horizontal, 1 vertical, ...")."""
    values = list(range(len(meanings))) if values is None else list(values)
    return {"flag_values": np.array(values, dtype=np.int32), "flag_meanings": " ".join(meanings),
            "legend": ", ".join(f"{v} {m}" for v, m in zip(values, meanings)), **more}


#: CF-style attributes of the lattice's own datasets
DESCRIPTIONS = {
    "geometry/points": {"long_name": "reference position (x, y, z = 0) of each node (length)"},
    "geometry/ij": {"long_name": "column i and row j of each node"},
    "bonds/connectivity": {"long_name": "node numbers j*nx + i of the two ends of each bond"},
    "bonds/kind": coded(BOND_KINDS, long_name="bond direction kind"),
    "bonds/stiffness": {"long_name": "bond stiffness k (force per length)"},
    "bonds/viscosity": {"long_name": "bond viscosity eta, the dashpot beside k (force time per length; damped scenes only)"},
    "bonds/interface": coded(("inside_one_material", "joins_two_materials"), long_name="bond joins two materials"),
    "nodes/material": {"long_name": "index of each node's material into /materials"},
    "nodes/mass": {"long_name": "lumped mass rho a^3 of each node, both DOFs (mass)"},
    "nodes/fixed": {"long_name": "1 where a displacement component is prescribed (Dirichlet), per x, y, z"},
    "nodes/contact": coded(("not_on_the_base", "on_the_rigid_base"), long_name="node on the rigid base"),
    "nodes/i": {"long_name": "column i of each node (0 left)"},
    "nodes/j": {"long_name": "row j of each node (0 bottom)"},
    "materials/name": {"long_name": "material name"},
    "materials/kind": {"long_name": "material kind (layer or embedded band)"},
    "materials/stiffness": {"long_name": "bond stiffness inside each material (force per length)"},
    "materials/density": {"long_name": "density of each material (mass per length^3)"},
    "materials/interface_stiffness": {"long_name": "stiffness of a bond joining two materials (force per length)"},
    "materials/viscosity": {"long_name": "bond viscosity inside each material (damped scenes only)"},
    "materials/interface_viscosity": {"long_name": "viscosity of a bond joining two materials (damped scenes only)"},
}


def _describe(dset, attrs: dict | None) -> None:
    """Write ``attrs`` (default: a bare ``units``) and ``units = "1"`` on a dataset."""
    for key, value in {"units": "1", **(attrs or {})}.items():
        dset.attrs[key] = value


@dataclass(frozen=True)
class LatticeFiles:
    h5: Path
    xdmf: Path


def _local_field(name, value, model: LatticeModel, j0: int, j1: int):
    """This rank's rows of a field: (n_local, 3) for per-DOF vectors, (n_local,) for scalars.

    A NumPy array is always the *global* field (length n_dofs or n_nodes, natural order):
    judging a local part by its length would be ambiguous (2·n_local can equal n_nodes).
    A distributed field is a PETSc Vec, whose ownership must be this rank's DOFs."""
    a, b = model.node_range(j0, j1)
    if hasattr(value, "getArray") and hasattr(value, "getOwnershipRange"):  # a PETSc Vec
        lo, hi = value.getOwnershipRange()
        if (lo, hi) != (2 * a, 2 * b) or value.getSize() != model.n_dofs:
            return None, (f"field {name!r}: Vec of size {value.getSize()} owning {lo}..{hi} is not "
                          f"distributed like the lattice's DOFs (this rank owns {2 * a}..{2 * b} "
                          f"of {model.n_dofs}: assemble with the same communicator)")
        arr = np.asarray(value.getArray(readonly=True), dtype=float)
        kind = "dof"
    else:
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            return None, f"field {name!r} is not numeric"
        if arr.ndim == 2 and arr.shape[1] == 2:
            arr = arr.reshape(-1)
        if arr.ndim != 1:
            return None, f"field {name!r} must be 1-D (per DOF or per node), got shape {arr.shape}"
        if arr.size == model.n_dofs:
            arr, kind = arr[2 * a:2 * b], "dof"
        elif arr.size == model.n_nodes:
            arr, kind = arr[a:b], "node"
        else:
            return None, (f"field {name!r} has {arr.size} values; expected {model.n_dofs} (per DOF) "
                          f"or {model.n_nodes} (per node)")
    if kind == "dof":
        out = np.zeros((b - a, 3))
        out[:, :2] = arr.reshape(b - a, 2)
        return out, None
    return arr.copy(), None


def _band_data(model: LatticeModel, j0: int, j1: int) -> dict:
    """Every per-node and per-bond array of rows ``[j0, j1)`` (bonds stored from these rows)."""
    pts = np.zeros(((j1 - j0) * model.nx, 3))
    pts[:, :2] = model.positions(j0, j1)
    jj, ii = np.divmod(np.arange(j0 * model.nx, j1 * model.nx), model.nx)
    mat = model.material(j0, j1).astype(np.int32)
    fixed = np.zeros((mat.size, 3))
    fixed[:, :2] = model.fixed_mask(j0, j1)
    contact = np.zeros(mat.size, dtype=np.int8)
    if model.boundary.bottom == "contact" and j0 == 0 and j1 > 0:
        contact[:model.nx] = 1
    ends, kinds, ks, etas = model.bonds(j0, j1, viscosity=True)
    ext = model.material(j0, min(j1 + 1, model.ny))  # bonds reach at most one row up
    base = j0 * model.nx
    iface = (ext[ends[:, 0] - base] != ext[ends[:, 1] - base]).astype(np.int8) if ends.size else \
        np.zeros(0, dtype=np.int8)
    damping = {"bonds/viscosity": etas.astype(float)} if model.damped else {}
    return damping | {
        "geometry/points": pts,
        "geometry/ij": np.stack([ii, jj], axis=1).astype(np.int32),
        "nodes/material": mat,
        "nodes/mass": model.mass_per_material[mat],
        "nodes/fixed": fixed,
        "nodes/contact": contact,
        "nodes/i": ii.astype(np.int32),
        "nodes/j": jj.astype(np.int32),
        "bonds/connectivity": ends.astype(np.int64),
        "bonds/kind": kinds.astype(np.int8),
        "bonds/stiffness": ks.astype(float),
        "bonds/interface": iface,
    }


def _materials(model: LatticeModel) -> dict:
    damping = {"materials/viscosity": np.array([m.viscosity for m in model.materials]),
               "materials/interface_viscosity": np.array(model.cmat)} if model.damped else {}
    return damping | {
        "materials/name": np.array([m.name.encode() for m in model.materials], dtype="S64"),
        "materials/kind": np.array([m.kind.encode() for m in model.materials], dtype="S16"),
        "materials/stiffness": np.array([m.stiffness for m in model.materials]),
        "materials/density": np.array([m.density for m in model.materials]),
        "materials/interface_stiffness": np.array(model.kmat),
    }


def _attrs(model: LatticeModel, n_bonds: int) -> dict:
    return {"format": FORMAT, "format_version": FORMAT_VERSION, "nx": model.nx, "ny": model.ny,
            "spacing": model.spacing, "shear": model.shear, "n_nodes": model.n_nodes,
            "n_dofs": model.n_dofs, "n_bonds": n_bonds, "meicp_version": __version__,
            "bond_kinds": ",".join(BOND_KINDS), "units_convention": UNITS_CONVENTION}


def _scene_text(model: LatticeModel, scene_text):
    if scene_text is not None:
        return scene_text or None
    src = model.scene.source
    if src and os.path.isfile(src):
        try:
            return Path(src).read_text(encoding="utf-8") or None
        except OSError:
            return None
    return None


def write_lattice(path, scene, *, fields: dict | None = None, comm=None,
                  scene_text: str | None = None, parallel_io: str = "auto",
                  field_attrs: dict | None = None) -> LatticeFiles:
    """Write ``path`` (HDF5) and the XDMF file next to it (same stem, ``.xdmf``).

    ``scene``: a Scene, a LatticeModel or a scene path.  ``fields``: name → per-DOF vector
    (length n_dofs, natural numbering; written as 3-component node vectors) or per-node
    scalar (length n_nodes) as a NumPy array holding the whole field (on every rank), or a
    PETSc Vec distributed like the matrices of ``assemble(scene, comm)``.  ``field_attrs``:
    name → attributes of that field's dataset (``long_name``, a legend from :func:`coded`;
    ``units = "1"`` is added to every one).  Collective on
    ``comm`` (mpi4py or PETSc communicator; ``None`` = this process alone).  ``parallel_io``:
    ``"auto"`` (collective when h5py has MPI, else gathered), ``"collective"`` or ``"gather"``
    (rank 0 writes everything).  Raises :class:`ProblemError` before any file is written.
    """
    if parallel_io not in ("auto", "collective", "gather"):
        raise ProblemError(f"parallel_io must be 'auto', 'collective' or 'gather', got {parallel_io!r}")
    model = as_model(scene if isinstance(scene, LatticeModel) else as_scene(scene))
    mcomm = mpi_comm(comm)
    rank, size = (0, 1) if mcomm is None else (mcomm.Get_rank(), mcomm.Get_size())
    path = Path(path)
    if path.suffix.lower() not in (".h5", ".hdf5"):
        path = path.with_name(path.name + ".h5")
    j0, j1 = model.row_band(rank, size)

    # -------- every check first, agreed on by all ranks
    error = None
    if not path.parent.is_dir():
        error = f"output directory {str(path.parent)!r} does not exist"
    elif not os.access(path.parent, os.W_OK):
        error = f"output directory {str(path.parent)!r} is not writable"
    local_fields = {}
    for name, value in (fields or {}).items():
        if error:
            break
        if not isinstance(name, str) or not _NAME.match(name):
            error = f"field name {name!r} must be letters, digits, _ . + - (no slash)"
            break
        if name in _RESERVED:
            error = f"field name {name!r} is taken by the lattice's own node data ({', '.join(_RESERVED)})"
            break
        arr, error = _local_field(name, value, model, j0, j1)
        local_fields[name] = arr
    if mcomm is not None:
        errors = [e for e in mcomm.allgather(error) if e]
        error = errors[0] if errors else None
    if error:
        raise ProblemError(error)

    try:
        import h5py
    except ImportError as exc:  # pragma: no cover - h5py is a Debian dependency
        raise ProblemError(f"h5py is needed to write HDF5: {exc}") from None

    text = _scene_text(model, scene_text)
    data = _band_data(model, j0, j1)
    attrs = dict(DESCRIPTIONS)
    for name, arr in local_fields.items():
        data[f"fields/{name}"] = arr
        attrs[f"fields/{name}"] = dict((field_attrs or {}).get(name) or {"long_name": name})
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    if mcomm is not None:
        tmp = Path(mcomm.bcast(str(tmp), root=0))
    has_mpi = bool(h5py.get_config().mpi)
    if parallel_io == "collective" and mcomm is not None and not has_mpi:
        raise ProblemError("parallel_io='collective' needs an MPI-enabled h5py (run under mpirun)")
    collective = mcomm is not None and has_mpi and parallel_io != "gather"
    xdmf = path.with_suffix(".xdmf")
    xtmp = xdmf.with_name(f".{xdmf.name}.{os.getpid()}.tmp")
    with on_interrupt(lambda: _discard(tmp, xtmp) if rank == 0 else None):  # meicp.core.cleanup
        try:
            if mcomm is None:
                n_bonds = data["bonds/connectivity"].shape[0]
                _write_serial(h5py, tmp, data, _materials(model), _attrs(model, n_bonds), text, attrs)
            elif collective:
                n_bonds = _write_collective(h5py, mcomm, tmp, data, model, text, attrs)
            else:
                n_bonds = _write_gathered(h5py, mcomm, tmp, data, model, text, attrs)
        except BaseException:
            if rank == 0 and tmp.exists():
                tmp.unlink()
            raise
        if mcomm is not None:
            mcomm.Barrier()
        if rank == 0:
            os.replace(tmp, path)
            shapes = {name: arr.shape[1:] for name, arr in data.items()}
            legends = {_xdmf_name(name): a["legend"] for name, a in attrs.items() if "legend" in a and name in data}
            xtmp.write_text(xdmf_text(path.name, model.n_nodes, n_bonds, shapes,
                                      {name: arr.dtype for name, arr in data.items()}, legends), encoding="utf-8")
            os.replace(xtmp, xdmf)
        if mcomm is not None:
            mcomm.Barrier()
    return LatticeFiles(path, xdmf)


def _discard(*paths: Path) -> None:
    for p in paths:
        p.unlink(missing_ok=True)


def _write_serial(h5py, path, data, materials, attrs, text, described):
    with h5py.File(path, "w") as f:
        for k, v in attrs.items():
            f.attrs[k] = v
        for name, arr in {**data, **materials}.items():
            _describe(f.create_dataset(name, data=arr), described.get(name))
        if text is not None:
            _describe(f.create_dataset("scene", data=np.bytes_(text.encode())), {"long_name": "scene file (TOML)"})


def _write_gathered(h5py, comm, path, data, model, text, described) -> int:
    parts = {name: comm.gather(arr, root=0) for name, arr in sorted(data.items())}
    n_bonds = comm.allreduce(data["bonds/connectivity"].shape[0])
    if comm.Get_rank() == 0:
        full = {name: np.concatenate(p, axis=0) for name, p in parts.items()}
        _write_serial(h5py, path, full, _materials(model), _attrs(model, n_bonds), text, described)
    return n_bonds


def _write_collective(h5py, comm, path, data, model, text, described) -> int:
    counts = {name: comm.allgather(arr.shape[0]) for name, arr in sorted(data.items())}
    rank = comm.Get_rank()
    n_bonds = sum(counts["bonds/connectivity"])
    dxpl = h5py.h5p.create(h5py.h5p.DATASET_XFER)
    dxpl.set_dxpl_mpio(h5py.h5fd.MPIO_COLLECTIVE)
    with h5py.File(path, "w", driver="mpio", comm=comm) as f:
        for k, v in _attrs(model, n_bonds).items():
            f.attrs[k] = v
        for name, arr in sorted(data.items()):
            c = counts[name]
            dset = f.create_dataset(name, shape=(sum(c),) + arr.shape[1:], dtype=arr.dtype)
            _write_rows(h5py, dset, sum(c[:rank]), arr, dxpl)
            _describe(dset, described.get(name))  # collective: the same attributes on every rank
        for name, arr in _materials(model).items():
            dset = f.create_dataset(name, shape=arr.shape, dtype=arr.dtype)
            _describe(dset, described.get(name))
            if rank == 0:
                dset[...] = arr
        if text is not None:
            raw = np.bytes_(text.encode())
            dset = f.create_dataset("scene", shape=(), dtype=raw.dtype)
            _describe(dset, {"long_name": "scene file (TOML)"})
            if rank == 0:
                dset[()] = raw
    return n_bonds


def _write_rows(h5py, dset, start: int, arr: np.ndarray, dxpl) -> None:
    """Collective write of ``arr`` into rows ``start:start+len(arr)`` (empty on some ranks is fine)."""
    arr = np.ascontiguousarray(arr, dtype=dset.dtype)
    fspace = dset.id.get_space()
    if arr.shape[0] == 0:
        fspace.select_none()
        buf = np.zeros((1,) + arr.shape[1:], dtype=arr.dtype)
        mspace = h5py.h5s.create_simple(buf.shape)
        mspace.select_none()
    else:
        fspace.select_hyperslab((start,) + (0,) * (arr.ndim - 1), arr.shape)
        buf = arr
        mspace = h5py.h5s.create_simple(arr.shape)
    dset.id.write(mspace, fspace, buf, dxpl=dxpl)


_XDMF_TYPES = {"f": "Float", "i": "Int", "u": "UInt"}


def _item(h5name: str, dataset: str, dims: tuple, dtype) -> str:
    dt = np.dtype(dtype)
    number = "Char" if dt.itemsize == 1 and dt.kind == "i" else _XDMF_TYPES[dt.kind]
    d = " ".join(str(x) for x in dims)
    return (f'<DataItem Dimensions="{d}" NumberType="{number}" Precision="{dt.itemsize}" '
            f'Format="HDF">{h5name}:/{dataset}</DataItem>')


def _xdmf_name(dataset: str) -> str:
    """The XDMF attribute name of a dataset: ``fields/mode_0`` → ``mode_0``, ``bonds/kind`` →
    ``bond_kind``."""
    group, _, short = dataset.partition("/")
    return f"bond_{short}" if group == "bonds" else short


def xdmf_text(h5name: str, n_nodes: int, n_bonds: int, shapes: dict, dtypes: dict,
              legends: dict | None = None) -> str:
    """XDMF 3 for ParaView: points, bonds as 2-node line cells, node and cell attributes;
    ``legends`` (attribute name → its code legend) go into a comment at the top (XDMF has no
    place for them that every reader accepts; the HDF5 datasets carry them as attributes)."""
    head = ""
    if legends:
        width = max(len(k) for k in legends)
        # "--" may not appear inside an XML comment
        legends = {name: text.replace("--", "- -") for name, text in legends.items()}
        head = "\n".join(["<!-- meicp lattice: codes of the coded fields (also attributes of their HDF5 datasets)"]
                         + [f"     {name:<{width}}  {text}" for name, text in sorted(legends.items())]
                         + ["     units: none attached, the scene's consistent system (units_convention) -->"])
    lines = ['<?xml version="1.0" ?>'] + ([head] if head else []) + [
             '<Xdmf Version="3.0" xmlns:xi="http://www.w3.org/2001/XInclude">',
             '  <Domain>',
             '    <Grid Name="lattice" GridType="Uniform">',
             f'      <Topology TopologyType="Polyline" NodesPerElement="2" NumberOfElements="{n_bonds}">',
             '        ' + _item(h5name, "bonds/connectivity", (n_bonds, 2), np.int64),
             '      </Topology>',
             '      <Geometry GeometryType="XYZ">',
             '        ' + _item(h5name, "geometry/points", (n_nodes, 3), np.float64),
             '      </Geometry>']
    for name in sorted(shapes):
        group, _, short = name.partition("/")
        if group not in ("nodes", "bonds", "fields") or name == "bonds/connectivity":
            continue
        center, n = ("Cell", n_bonds) if group == "bonds" else ("Node", n_nodes)
        shape = (n,) + tuple(shapes[name])
        kind = "Vector" if len(shape) == 2 and shape[1] == 3 else "Scalar"
        label = _xdmf_name(name)
        lines += [f'      <Attribute Name="{label}" AttributeType="{kind}" Center="{center}">',
                  '        ' + _item(h5name, name, shape, dtypes[name]),
                  '      </Attribute>']
    lines += ['    </Grid>', '  </Domain>', '</Xdmf>', '']
    return "\n".join(lines)
