"""Reading LCP, matrix and EiCP problems from files.

- Siconos' text ``.dat`` files (dense or sparse-block storage; format in
  ``shared/data/siconos-lcp/README.md``): :func:`read_siconos_lcp`.
- HDF5 files with datasets ``M`` (dense) or a group ``M`` with ``data``, ``indices``,
  ``indptr``, ``shape`` (CSR), and ``q`` (LCP) — or ``A``, ``B`` and optional ``J``
  (EiCP): :func:`read_hdf5_problem`.
- MATLAB ``.mat`` files (``scipy.io.loadmat``, formats up to v7) with the same names,
  e.g. the EiCP test set.

:func:`read_problem` picks by extension and validates what it read.  Every error is a
:class:`~meicp.core.errors.ProblemError` that names the file and what is wrong.

Hostile files are read within bounds: only regular files (``/dev/zero`` or a FIFO would
be read for ever), text files up to ``MAX_TEXT_BYTES``, no binary data in a text file,
every count and size from a header checked (an integer, in range, ``n² ≤ MAX_ENTRIES``)
before anything is allocated, dataset sizes checked from their metadata before they are
read, CSR index arrays checked before SciPy or PETSc index with them (a column index 10⁸
in a 3×3 matrix crashed the process), and complex data refused (never cast).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.io import loadmat, whosmat

from ..core.errors import ProblemError
from ..core.validation import as_index_set, as_matrix, as_vector, check_compressed, check_real

#: largest text file read (a dense Siconos file of n = 2000 is about 80 MB)
MAX_TEXT_BYTES = 256 * 2 ** 20
#: largest number of matrix entries (dense) or stored nonzeros (sparse) read: 2 GiB of doubles
MAX_ENTRIES = 2 ** 28

_TOKEN = re.compile(rb"\S+")


def _regular_file(path: Path, what: str = "problem") -> None:
    if not path.exists():
        raise ProblemError(f"{path}: no such file")
    if not path.is_file():
        raise ProblemError(f"{path}: not a regular file (a device, FIFO or directory cannot be read as a {what})")


def _entries_limit(path, what: str, count: int) -> None:
    if count > MAX_ENTRIES:
        raise ProblemError(f"{path}: {what} has {count:.3g} entries, above the limit of {MAX_ENTRIES:.3g} "
                           f"(meicp.io.problem_files.MAX_ENTRIES)")


def read_text(path: Path, limit: int | None = None, *, what: str = "problem",
              limit_name: str = "meicp.io.problem_files.MAX_TEXT_BYTES") -> bytes:
    """The bytes of a text file, at most ``limit`` (default ``MAX_TEXT_BYTES``); refuses
    anything but a regular file, larger files and files with NUL bytes (binary data), and
    drops a UTF-8 byte-order mark.  ``what`` names the kind of file in the messages (also
    used for scene files), ``limit_name`` the constant that sets the limit."""
    limit = MAX_TEXT_BYTES if limit is None else limit
    path = Path(path)
    _regular_file(path, what)
    try:
        with open(path, "rb") as f:
            data = f.read(limit + 1)
    except OSError as exc:
        raise ProblemError(f"{path}: cannot be read: {exc.strerror or exc}") from None
    if len(data) > limit:
        raise ProblemError(f"{path}: larger than {limit} bytes, the limit for a text {what} file ({limit_name})")
    nul = data.find(b"\0")
    if nul >= 0:
        raise ProblemError(f"{path}: binary data (a NUL byte at offset {nul}), not a text {what} file")
    if data.startswith(b"\xef\xbb\xbf"):  # a UTF-8 byte-order mark is not an error
        data = data[3:]
    return data


class _Tokens:
    """Whitespace-separated tokens of a text file, read on demand (no list of all tokens)."""

    def __init__(self, data: bytes, path):
        self.data = data
        self.tokens = _TOKEN.finditer(data)
        self.pos = 0
        self.end = 0
        self.path = path

    def _next(self, what: str) -> bytes:
        m = next(self.tokens, None)
        if m is None:
            raise ProblemError(f"{self.path}: file ends early: expected {what} after {self.pos} tokens")
        self.pos += 1
        self.end = m.end()
        return m.group()

    def _float(self, tok: bytes, what: str) -> float:
        try:
            return float(tok)
        except ValueError:
            text = tok[:40].decode("utf-8", "replace")
            raise ProblemError(f"{self.path}: expected a number for {what} at token {self.pos}, got {text!r}") from None

    def integer(self, what: str, minimum: int = 0, maximum: int | None = None) -> int:
        """An integer token: 3 (or 3.0), in [minimum, maximum]; 3.7, inf, nan, 1e300 are errors."""
        tok = self._next(what)
        v = self._float(tok, what)
        text = tok[:40].decode("utf-8", "replace")
        if not math.isfinite(v) or not v.is_integer():
            raise ProblemError(f"{self.path}: {what} must be an integer, got {text!r} (token {self.pos})")
        if v < minimum or (maximum is not None and v > maximum):
            bound = f"[{minimum}, {maximum}]" if maximum is not None else f"≥ {minimum}"
            raise ProblemError(f"{self.path}: {what} = {text} is out of range {bound} (token {self.pos})")
        return int(v)

    def integers(self, count: int, what: str, minimum: int = 0, maximum: int | None = None) -> np.ndarray:
        return np.array([self.integer(f"{what}[{k}]", minimum, maximum) for k in range(count)], dtype=np.int64)

    def numbers(self, count: int, what: str) -> np.ndarray:
        out = np.empty(count)
        for k in range(count):
            out[k] = self._float(self._next(f"{what} (entry {k + 1} of {count})"), what)
        if not np.all(np.isfinite(out)):
            k = int(np.argmax(~np.isfinite(out)))
            raise ProblemError(f"{self.path}: {what} has a non-finite entry ({out[k]}) at position {k}")
        return out

    def rest(self) -> str:
        return self.data[self.end:].decode("utf-8", "replace").strip()


def read_siconos_lcp(path) -> tuple[object, np.ndarray, str]:
    """``(M, q, remark)`` from a Siconos LCP ``.dat`` file (M dense or CSR)."""
    path = Path(path)
    tok = _Tokens(read_text(path), path)
    n_max = math.isqrt(MAX_ENTRIES)
    n = tok.integer("n (the problem size)", minimum=1, maximum=n_max)
    storage = tok.integer("the storage type", minimum=0)
    if storage == 0:
        rows, cols = tok.integer("rows", 1, n_max), tok.integer("columns", 1, n_max)
        rows2, cols2 = tok.integer("rows", 1, n_max), tok.integer("columns", 1, n_max)
        if (rows, cols) != (rows2, cols2) or rows != n or cols != n:
            raise ProblemError(f"{path}: dense header {rows}x{cols}/{rows2}x{cols2} does not match n = {n}")
        M = tok.numbers(rows * cols, f"M ({n}x{n}, column-major)").reshape(cols, rows).T
    elif storage == 1:
        M = _read_sparse_block(tok, n)
    else:
        raise ProblemError(f"{path}: unknown storage type {storage} (0 dense, 1 sparse block)")
    q = tok.numbers(n, f"q (length {n})")
    return M, q, tok.rest()


def _block_ends(tok: _Tokens, count: int, what: str, n: int) -> np.ndarray:
    ends = tok.integers(count, f"the {what}", 1, n)
    if np.any(np.diff(ends) <= 0) or ends[-1] != n:
        raise ProblemError(f"{tok.path}: the {what} {ends[:8].tolist()} must increase strictly up to n = {n}")
    return ends


def _read_sparse_block(tok: _Tokens, n: int) -> sp.csr_matrix:
    """Siconos' SparseBlockStructuredMatrix text layout, as written by SBM_write_in_file;
    every count and index is checked against the header before it is used."""
    path = tok.path
    size0, size1 = tok.integer("the block matrix rows", 1), tok.integer("the block matrix columns", 1)
    if (size0, size1) != (n, n):
        raise ProblemError(f"{path}: sparse-block header {size0}x{size1} does not describe an {n}x{n} matrix")
    nblocks = tok.integer("the number of blocks", 0, n * n)
    nb_rows, nb_cols = tok.integer("the block rows", 1, n), tok.integer("the block columns", 1, n)
    row_ends = _block_ends(tok, nb_rows, "block row ends", n)
    col_ends = _block_ends(tok, nb_cols, "block column ends", n)
    filled1 = tok.integer("the block row pointer length", nb_rows + 1, nb_rows + 1)
    filled2 = tok.integer("the number of stored blocks", nblocks, nblocks)
    block_row_ptr = tok.integers(filled1, "the block row pointer", 0, nblocks)
    block_col_idx = tok.integers(filled2, "the block column index", 0, nb_cols - 1)
    if block_row_ptr[0] != 0 or block_row_ptr[-1] != nblocks or np.any(np.diff(block_row_ptr) < 0):
        raise ProblemError(f"{path}: the block row pointer must rise from 0 to {nblocks}")
    row_start = np.concatenate([[0], row_ends[:-1]])
    col_start = np.concatenate([[0], col_ends[:-1]])
    M = np.zeros((n, n))
    for brow in range(nb_rows):
        for k in range(block_row_ptr[brow], block_row_ptr[brow + 1]):
            bcol = block_col_idx[k]
            tok.integer("a block number", 0)
            r0, r1 = row_start[brow], row_ends[brow]
            c0, c1 = col_start[bcol], col_ends[bcol]
            M[r0:r1, c0:c1] = tok.numbers((r1 - r0) * (c1 - c0), f"block ({brow}, {bcol})").reshape(
                c1 - c0, r1 - r0).T
    return sp.csr_matrix(M)


# -- HDF5 ----------------------------------------------------------------------------------

def _dataset(path, name: str, obj, ndim: tuple = (0, 1, 2), integer: bool = False) -> np.ndarray:
    """A numeric dataset read after its metadata is checked: real, at most MAX_ENTRIES."""
    import h5py

    where = f"{path}: {name}"
    if not isinstance(obj, h5py.Dataset):
        raise ProblemError(f"{where} is a {type(obj).__name__}, not a dataset")
    kind = obj.dtype.kind
    if kind == "c":
        raise ProblemError(f"{where} is complex ({obj.dtype}); meicp solves real problems")
    if kind not in "biuf" or (integer and kind not in "iu"):
        want = "an integer" if integer else "a real numeric"
        raise ProblemError(f"{where} must be {want} dataset, got dtype {obj.dtype}")
    if obj.ndim not in ndim:
        raise ProblemError(f"{where} must have {' or '.join(map(str, ndim))} dimensions, got shape {obj.shape}")
    _entries_limit(path, name, int(obj.size or 0))
    try:
        return obj[()]
    except (OSError, ValueError, TypeError) as exc:
        raise ProblemError(f"{where} cannot be read: {exc}") from None


def _csr_group(path, name: str, group) -> sp.csr_matrix:
    missing = {"data", "indices", "indptr", "shape"} - set(group)
    if missing:
        raise ProblemError(f"{path}: CSR group {name!r} lacks {sorted(missing)}")
    shape = _dataset(path, f"{name}/shape", group["shape"], ndim=(1,), integer=True)
    if shape.shape != (2,) or np.any(shape < 0):
        raise ProblemError(f"{path}: {name}/shape must be two nonnegative integers, got {shape.tolist()}")
    n_rows, n_cols = (int(v) for v in shape)
    _entries_limit(path, f"{name}/indptr", n_rows + 1)
    data = _dataset(path, f"{name}/data", group["data"], ndim=(1,))
    indices = _dataset(path, f"{name}/indices", group["indices"], ndim=(1,), integer=True)
    indptr = _dataset(path, f"{name}/indptr", group["indptr"], ndim=(1,), integer=True)
    check_compressed(indptr, indices, n_rows, n_cols, f"{path}: CSR group {name!r}", nnz=data.size)
    return sp.csr_matrix((data.astype(np.float64), indices, indptr), shape=(n_rows, n_cols))


def read_hdf5_problem(path, names=("M", "q")) -> dict:
    """Datasets from an HDF5 file: dense arrays, or CSR groups (``data``, ``indices``,
    ``indptr``, ``shape``); missing optional names are left out."""
    import h5py

    path = Path(path)
    _regular_file(path)
    out = {}
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise ProblemError(f"{path}: not a readable HDF5 file ({exc})") from None
    with f:
        for name in names:
            try:
                if name not in f:
                    continue
                obj = f[name]
            except (KeyError, OSError) as exc:  # e.g. a dangling or external link
                raise ProblemError(f"{path}: {name} cannot be opened ({exc})") from None
            if isinstance(obj, h5py.Group):
                out[name] = _csr_group(path, name, obj)
            else:
                out[name] = _dataset(path, name, obj)
    return out


# -- MATLAB --------------------------------------------------------------------------------

def read_mat_problem(path, names=("M", "q")) -> dict:
    """Variables of a MATLAB ``.mat`` file (v4 to v7), their sizes checked before loading."""
    path = Path(path)
    _regular_file(path)
    if path.stat().st_size == 0:
        raise ProblemError(f"{path}: empty file, not a MATLAB .mat file")
    try:
        listed = {name: (shape, cls) for name, shape, cls in whosmat(path)}
    except NotImplementedError:  # v7.3 is HDF5 with transposed arrays: read it as such only on purpose
        raise ProblemError(f"{path}: a MATLAB v7.3 file; save it with -v7, or write HDF5 datasets "
                           f"{', '.join(names)}") from None
    except Exception as exc:  # noqa: BLE001 - scipy raises many kinds on a damaged file
        raise ProblemError(f"{path}: not a readable MATLAB .mat file ({type(exc).__name__}: {exc})") from None
    wanted = [k for k in names if k in listed]
    for k in wanted:
        shape, cls = listed[k]
        if cls != "sparse":
            _entries_limit(path, k, int(np.prod(shape, dtype=float)))
        if cls not in ("double", "single", "sparse", "logical") and not cls.startswith(("int", "uint")):
            raise ProblemError(f"{path}: {k} is a MATLAB {cls}, not a numeric array")
    try:
        raw = loadmat(path, variable_names=wanted) if wanted else {}
    except Exception as exc:  # noqa: BLE001
        raise ProblemError(f"{path}: not a readable MATLAB .mat file ({type(exc).__name__}: {exc})") from None
    out = {}
    for k in wanted:
        value = raw[k]
        check_real(value, f"{path}: {k}")
        out[k] = value if sp.issparse(value) else np.asarray(value, dtype=np.float64)
    return out


# -- any of them ---------------------------------------------------------------------------

def read_problem(path, names=("M", "q")) -> dict:
    """A problem from ``.dat`` (Siconos LCP), ``.h5``/``.hdf5`` or ``.mat`` by extension;
    ``names``: the datasets wanted, the first two required (``("M",)``: M alone).  The
    matrices are checked (square, finite, real, one size), ``q`` against M and ``J`` as
    integer indices in range, each error naming the file."""
    path = Path(path)
    _regular_file(path)
    if path.suffix == ".dat":
        M, q, remark = read_siconos_lcp(path)
        data = {"M": M, "q": q, "remark": remark}
    elif path.suffix in (".h5", ".hdf5"):
        data = read_hdf5_problem(path, names)
    elif path.suffix == ".mat":
        data = read_mat_problem(path, names)
    else:
        raise ProblemError(f"{path}: unknown file type {path.suffix!r} (expected .dat, .h5, .hdf5 or .mat)")
    missing = [k for k in names[:2] if k not in data]
    if missing:
        raise ProblemError(f"{path}: no dataset {missing[0]!r}")
    for k in ("M", "A", "B"):
        if k in data:
            data[k] = as_matrix(data[k], f"{path}: {k}")
    shapes = {data[k].shape for k in ("M", "A", "B") if k in data}
    if len(shapes) > 1:
        raise ProblemError(f"{path}: A and B differ in shape ({data['A'].shape} and {data['B'].shape})")
    n = next(iter(shapes))[0] if shapes else None
    if "q" in data and n is not None:
        data["q"] = as_vector(data["q"], n, f"{path}: q")
    if "J" in data and n is not None:
        J = np.asarray(data["J"])
        data["J"] = as_index_set(J.ravel() if J.size else J.reshape(0), n, f"{path}: J")
    return data
