"""Reading LCP, matrix and EiCP problems from files.

- Siconos' text ``.dat`` files (dense or sparse-block storage; format in
  ``shared/data/siconos-lcp/README.md``): :func:`read_siconos_lcp`.
- HDF5 files with datasets ``M`` (dense) or a group ``M`` with ``data``, ``indices``,
  ``indptr``, ``shape`` (CSR), and ``q`` (LCP) — or ``A``, ``B`` and optional ``J``
  (EiCP): :func:`read_hdf5_problem`.
- MATLAB ``.mat`` files (``scipy.io.loadmat``) with the same names, e.g. the EiCP test set.

:func:`read_problem` picks by extension.  Errors name the file and what is wrong.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.io import loadmat

from ..core.errors import ProblemError


class _Tokens:
    def __init__(self, text: str, path):
        self.items = text.split()
        self.pos = 0
        self.path = path

    def number(self, kind=float):
        if self.pos >= len(self.items):
            raise ProblemError(f"{self.path}: file ends early (token {self.pos})")
        tok = self.items[self.pos]
        self.pos += 1
        try:
            return kind(float(tok)) if kind is int else float(tok)
        except ValueError:
            raise ProblemError(f"{self.path}: expected a number at token {self.pos}, got {tok!r}") from None

    def numbers(self, count: int, kind=float) -> np.ndarray:
        return np.array([self.number(kind) for _ in range(count)],
                        dtype=np.int64 if kind is int else np.float64)


def read_siconos_lcp(path) -> tuple[object, np.ndarray, str]:
    """``(M, q, remark)`` from a Siconos LCP ``.dat`` file (M dense or CSR)."""
    path = Path(path)
    tok = _Tokens(path.read_text(), path)
    n = tok.number(int)
    storage = tok.number(int)
    if storage == 0:
        rows, cols = tok.number(int), tok.number(int)
        rows2, cols2 = tok.number(int), tok.number(int)
        if (rows, cols) != (rows2, cols2) or rows != n or cols != n:
            raise ProblemError(f"{path}: dense header {rows}x{cols}/{rows2}x{cols2} does not match n = {n}")
        M = tok.numbers(rows * cols).reshape(cols, rows).T  # column-major
    elif storage == 1:
        M = _read_sparse_block(tok, n)
    else:
        raise ProblemError(f"{path}: unknown storage type {storage} (0 dense, 1 sparse block)")
    q = tok.numbers(n)
    remark = " ".join(tok.items[tok.pos:])
    return M, q, remark


def _read_sparse_block(tok: _Tokens, n: int) -> sp.csr_matrix:
    """Siconos' SparseBlockStructuredMatrix text layout, as written by SBM_write_in_file."""
    size0, size1 = tok.number(int), tok.number(int)
    nblocks = tok.number(int)
    nb_rows, nb_cols = tok.number(int), tok.number(int)
    row_ends = tok.numbers(nb_rows, int)
    col_ends = tok.numbers(nb_cols, int)
    filled1, filled2 = tok.number(int), tok.number(int)
    block_row_ptr = tok.numbers(filled1, int)
    block_col_idx = tok.numbers(filled2, int)
    if (size0, size1) != (n, n) or row_ends[-1] != n or col_ends[-1] != n or filled2 != nblocks:
        raise ProblemError(f"{tok.path}: sparse-block header does not describe an {n}x{n} matrix")
    row_start = np.concatenate([[0], row_ends[:-1]])
    col_start = np.concatenate([[0], col_ends[:-1]])
    M = np.zeros((n, n))
    for brow in range(nb_rows):
        for k in range(block_row_ptr[brow], block_row_ptr[brow + 1]):
            bcol = block_col_idx[k]
            tok.number(int)  # the block's own number
            r0, r1 = row_start[brow], row_ends[brow]
            c0, c1 = col_start[bcol], col_ends[bcol]
            M[r0:r1, c0:c1] = tok.numbers((r1 - r0) * (c1 - c0)).reshape(c1 - c0, r1 - r0).T
    return sp.csr_matrix(M)


def read_hdf5_problem(path, names=("M", "q")) -> dict:
    """Datasets from an HDF5 file: dense arrays, or CSR groups (``data``, ``indices``,
    ``indptr``, ``shape``); missing optional names are left out."""
    import h5py

    path = Path(path)
    out = {}
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise ProblemError(f"{path}: not a readable HDF5 file ({exc})") from None
    with f:
        for name in names:
            if name not in f:
                continue
            obj = f[name]
            if isinstance(obj, h5py.Group):
                missing = {"data", "indices", "indptr", "shape"} - set(obj)
                if missing:
                    raise ProblemError(f"{path}: CSR group {name!r} lacks {sorted(missing)}")
                out[name] = sp.csr_matrix((obj["data"][()], obj["indices"][()], obj["indptr"][()]),
                                          shape=tuple(obj["shape"][()]))
            else:
                out[name] = obj[()]
    return out


def write_hdf5_problem(path, **arrays) -> None:
    """Write dense arrays and SciPy sparse matrices (as CSR groups); temporary name, then rename."""
    import h5py

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


def read_problem(path, names=("M", "q")) -> dict:
    """A problem from ``.dat`` (Siconos LCP), ``.h5``/``.hdf5`` or ``.mat`` by extension;
    ``names``: the datasets wanted, the first two required."""
    path = Path(path)
    if not path.exists():
        raise ProblemError(f"{path}: no such file")
    if path.suffix == ".dat":
        M, q, remark = read_siconos_lcp(path)
        return {"M": M, "q": q, "remark": remark}
    if path.suffix in (".h5", ".hdf5"):
        data = read_hdf5_problem(path, names)
    elif path.suffix == ".mat":
        raw = loadmat(path)
        data = {k: (raw[k] if sp.issparse(raw[k]) else np.asarray(raw[k], dtype=float)) for k in names if k in raw}
    else:
        raise ProblemError(f"{path}: unknown file type {path.suffix!r} (expected .dat, .h5, .hdf5 or .mat)")
    missing = [k for k in names[:2] if k not in data]
    if missing:
        raise ProblemError(f"{path}: no dataset {missing[0]!r}")
    return data
