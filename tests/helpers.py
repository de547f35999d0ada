"""What the tests need and the package does not: an independent, bond-by-bond stiffness
assembly for arbitrary node positions (a reference for :mod:`meicp.lattice.assembly`'s
stencil rows), and a writer of the HDF5 problem files :func:`meicp.io.problem_files.read_problem`
reads."""

from pathlib import Path

import numpy as np
import scipy.sparse as sp

from meicp.core.errors import ProblemError


def bond_stiffness(points, ends, k, n_nodes: int | None = None) -> sp.csr_matrix:
    """Reference assembly, bond by bond, for arbitrary node positions.

    points (N, 2): node positions; ends (m, 2): node pairs; k (m,) or scalar: stiffness.
    Each bond adds ``k [[A, −A], [−A, A]]`` with ``A = e eᵀ`` from its own direction.
    Vectorised (COO); meant for small problems, deformed cells and cross-checks.
    """
    points = np.asarray(points, dtype=float)
    ends = np.asarray(ends, dtype=np.int64).reshape(-1, 2)
    k = np.broadcast_to(np.asarray(k, dtype=float), (ends.shape[0],))
    n_nodes = points.shape[0] if n_nodes is None else n_nodes
    d = points[ends[:, 1]] - points[ends[:, 0]]
    length = np.linalg.norm(d, axis=1)
    if np.any(length == 0):
        raise ProblemError("a bond joins two nodes at the same position")
    e = d / length[:, None]
    A = k[:, None, None] * e[:, :, None] * e[:, None, :]  # (m, 2, 2)
    dofs = 2 * ends[:, :, None] + np.arange(2)  # (m, 2 ends, 2 comps)
    dofs = dofs.reshape(-1, 4)  # [a_x, a_y, b_x, b_y]
    blocks = np.concatenate([np.concatenate([A, -A], axis=2),
                             np.concatenate([-A, A], axis=2)], axis=1)  # (m, 4, 4)
    rows = np.repeat(dofs, 4, axis=1).ravel()
    cols = np.tile(dofs, (1, 4)).ravel()
    return sp.csr_matrix((blocks.ravel(), (rows, cols)), shape=(2 * n_nodes, 2 * n_nodes))


def write_hdf5_problem(path, **arrays) -> None:
    """Write dense arrays and SciPy sparse matrices (as CSR groups); temporary name, then rename."""
    import h5py  # optional, as in meicp.io.problem_files

    path = Path(path)
    tmp = path.with_name(path.name + ".part")
    with h5py.File(tmp, "w") as f:
        for name, value in arrays.items():
            if sp.issparse(value):
                value = sp.csr_matrix(value)
                g = f.create_group(name)
                for key in ("data", "indices", "indptr"):
                    g[key] = getattr(value, key)
                g["shape"] = np.array(value.shape)
            else:
                f[name] = np.asarray(value)
    tmp.replace(path)


def interface_chain_scene(nx: int, mu: float, *, sides: str = "fixed", states="slip+"):
    """Three layers with a one-row middle layer between two frictional interfaces: its nodes
    belong to two pairs, where per-pair centres of mass do not compose (the fallback
    coordinates of :func:`meicp.contact.maps.interface_transform`, B not diagonal)."""
    from meicp.io.scene import scene_from_dict

    layers = [("lower", 3, 2.0), ("middle", 1, 1.5), ("upper", 3, 1.0)]
    return scene_from_dict({
        "lattice": {"nx": nx},
        "layers": [{"name": n, "rows": r, "stiffness": k, "density": 1.0} for n, r, k in layers],
        "boundary": {"top": "fixed", "bottom": "fixed", "left": sides, "right": sides},
        "interfaces": [{"below": n, "kind": "frictional", "friction": mu, "states": states}
                       for n in ("lower", "middle")]})
