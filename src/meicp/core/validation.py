"""Input checks that raise :class:`~meicp.core.errors.ProblemError` naming the argument.

Plain NumPy/SciPy: PETSc matrices are checked where they are used (collectively).  Every
check runs before compiled code sees the data: a sparse matrix's index arrays are checked
for range and order (SciPy's constructors do not, and an out-of-range column index then
reads or writes outside the arrays), complex data is refused rather than cast (the
imaginary part would be dropped), and tolerances, bounds and integer arguments are checked
for range, finiteness and integrality.  Keyword arguments are checked by name
(:func:`check_keywords`, :func:`checked_keywords`): a misspelt keyword is a TypeError that
suggests the nearest known one, never silently dropped.
"""

from __future__ import annotations

import difflib
import functools
import inspect
import numbers

import numpy as np
import scipy.sparse as sp

from .errors import ProblemError


def check_numeric(values: np.ndarray, name: str, what: str) -> None:
    """Text is an error, never parsed: ``np.asarray(["1", "2"])`` would become [1.0, 2.0]
    under a float cast, so a column read as strings would pass for numbers."""
    kind = values.dtype.kind
    if kind in "USVMm" or (kind == "O" and any(isinstance(v, (str, bytes)) for v in values.ravel())):
        raise ProblemError(f"{name} is not a numeric {what}: it holds {values.dtype} values "
                           f"(e.g. {values.ravel()[0]!r}); pass numbers, not text")


def check_real(values, name: str) -> None:
    """Complex data is an error, never cast: the imaginary part would be dropped silently."""
    if np.iscomplexobj(values):
        raise ProblemError(f"{name} is complex ({values.dtype}); meicp solves real problems "
                           f"(pass {name}.real if the imaginary part is meant to be dropped)")


def check_compressed(indptr, indices, n_major: int, n_minor: int, name: str, *, nnz: int | None = None,
                     major: str = "row", minor: str = "column") -> None:
    """The index arrays of a compressed sparse matrix (CSR: major = rows): integer, 1-D,
    ``indptr`` of length n_major + 1 from 0 to nnz and nondecreasing, every index in
    ``[0, n_minor)``.  Raises ProblemError naming what is wrong."""
    indptr, indices = np.asarray(indptr), np.asarray(indices)
    for label, arr in (("indptr", indptr), ("indices", indices)):
        if arr.ndim != 1 or not (np.issubdtype(arr.dtype, np.integer) or arr.size == 0):
            raise ProblemError(f"{name}: {label} must be a 1-D integer array, got {arr.dtype} shape {arr.shape}")
    nnz = indices.size if nnz is None else nnz
    if indptr.size != n_major + 1:
        raise ProblemError(f"{name}: indptr has length {indptr.size}, expected {n_major + 1} "
                           f"(one more than the number of {major}s)")
    if indptr[0] != 0 or indptr[-1] != nnz or indices.size != nnz:
        raise ProblemError(f"{name}: indptr runs from {int(indptr[0])} to {int(indptr[-1])} but there are "
                           f"{indices.size} indices and {nnz} values (expected 0 to {nnz}, all equal)")
    steps = np.diff(indptr)
    if np.any(steps < 0):
        k = int(np.argmax(steps < 0))
        raise ProblemError(f"{name}: indptr decreases at {major} {k} ({int(indptr[k])} then {int(indptr[k + 1])})")
    if indices.size:
        lo, hi = int(indices.min()), int(indices.max())
        if lo < 0 or hi >= n_minor:
            bad = lo if lo < 0 else hi
            raise ProblemError(f"{name}: {minor} index {bad} out of range [0, {n_minor})")


def check_shape(shape, name: str) -> tuple[int, int]:
    """A matrix shape: two nonnegative integers."""
    try:
        dims = tuple(shape)
    except TypeError:
        raise ProblemError(f"{name}: shape must be two integers, got {shape!r}") from None
    if len(dims) != 2:
        raise ProblemError(f"{name}: shape must be two integers, got {dims!r}")
    return tuple(as_int(d, f"{name} shape", minimum=0) for d in dims)


def checked_csr(M, name: str = "M") -> sp.csr_matrix:
    """A SciPy sparse matrix as float64 CSR, its index arrays checked before conversion."""
    check_real(M, name)
    n_rows, n_cols = check_shape(M.shape, name)
    fmt = M.format
    if fmt in ("csr", "csc"):
        major, minor = (n_rows, n_cols) if fmt == "csr" else (n_cols, n_rows)
        if np.ndim(M.data) != 1:
            raise ProblemError(f"{name}: data must be a 1-D array, got shape {np.shape(M.data)}")
        check_compressed(M.indptr, M.indices, major, minor, name, nnz=np.size(M.data),
                         major="row" if fmt == "csr" else "column",
                         minor="column" if fmt == "csr" else "row")
    elif fmt == "coo":
        for label, idx, bound in (("row", M.row, n_rows), ("column", M.col, n_cols)):
            idx = np.asarray(idx)
            if idx.shape != np.shape(M.data):
                raise ProblemError(f"{name}: {label} indices and values differ in length")
            if idx.size and (idx.min() < 0 or idx.max() >= bound):
                bad = int(idx.min()) if idx.min() < 0 else int(idx.max())
                raise ProblemError(f"{name}: {label} index {bad} out of range [0, {bound})")
    elif fmt == "bsr":
        R, C = M.blocksize
        check_compressed(M.indptr, M.indices, n_rows // R, n_cols // C, name, nnz=len(M.data),
                         major="block row", minor="block column")
    try:
        return sp.csr_matrix(M, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ProblemError(f"{name} is not a numeric sparse matrix: {exc}") from None


def as_matrix(M, name: str = "M", *, square: bool = True, allow_sparse: bool = True):
    """Return ``M`` as a float64 ndarray or SciPy CSR matrix after checking it.

    Rejects empty, non-2-D, non-square (when ``square``), complex, non-numeric and
    non-finite input, and sparse matrices with inconsistent index arrays.
    """
    if sp.issparse(M):
        M = checked_csr(M, name)
        data = M.data
        if not allow_sparse:
            M = M.toarray()
    else:
        try:
            arr = np.asarray(M)
            check_numeric(arr, name, "matrix")
            check_real(arr, name)
            M = np.array(arr, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            if isinstance(exc, ProblemError):
                raise
            raise ProblemError(f"{name} is not a numeric matrix: {exc}") from None
        data = M
    if M.ndim != 2:
        raise ProblemError(f"{name} must be 2-D, got {M.ndim}-D with shape {M.shape}")
    if M.shape[0] == 0 or M.shape[1] == 0:
        raise ProblemError(f"{name} is empty (shape {M.shape})")
    if square and M.shape[0] != M.shape[1]:
        raise ProblemError(f"{name} must be square, got shape {M.shape}")
    if not np.all(np.isfinite(data)):
        raise ProblemError(f"{name} contains NaN or Inf")
    return M


def as_vector(q, n: int, name: str = "q") -> np.ndarray:
    """Return ``q`` as a finite real float64 vector of length ``n``."""
    try:
        arr = np.asarray(q)
        check_numeric(arr, name, "vector")
        check_real(arr, name)
        q = np.array(arr, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        if isinstance(exc, ProblemError):
            raise
        raise ProblemError(f"{name} is not a numeric vector: {exc}") from None
    if q.ndim == 2 and 1 in q.shape:
        q = q.ravel()
    if q.ndim != 1:
        raise ProblemError(f"{name} must be a vector, got shape {q.shape}")
    if q.shape[0] != n:
        raise ProblemError(f"{name} has length {q.shape[0]}, expected {n}")
    if not np.all(np.isfinite(q)):
        raise ProblemError(f"{name} contains NaN or Inf")
    return q


# -- scalar arguments --------------------------------------------------------------------

def as_real(value, name: str, *, finite: bool = True) -> float:
    """A real number (not bool, not complex, not a string), finite unless ``finite=False``;
    NaN is always refused."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Real, np.floating, np.integer)):
        raise ProblemError(f"{name} must be a real number, got {value!r}")
    v = float(value)
    if np.isnan(v) or (finite and not np.isfinite(v)):
        raise ProblemError(f"{name} must be a finite number, got {v!r}")
    return v


#: the loosest certificate tolerance accepted: at 0.9 a certificate accepted w = −2 with
#: |q| = 2 as an LCP solution; at 1e-2 (the loosest the accuracy benchmarks use) a certified
#: λ was already found 37 % off
MAX_TOL = 1e-2


def check_tol(tol, name: str = "tol") -> float:
    """A relative certificate tolerance: a real number in (0, MAX_TOL]."""
    if isinstance(tol, (bool, np.bool_)) or not isinstance(tol, (numbers.Real, np.floating, np.integer)):
        raise ProblemError(f"{name} must be a real number in (0, {MAX_TOL:g}], got {tol!r}")
    v = float(tol)
    if not 0.0 < v <= MAX_TOL:  # NaN fails this too
        raise ProblemError(f"{name} must lie in (0, {MAX_TOL:g}] (a relative certificate tolerance; "
                           f"a looser one certifies nothing), got {v!r}")
    return v


def as_int(value, name: str, *, minimum: int | None = None, maximum: int | None = None) -> int:
    """An integer argument; an integral float (3.0) is accepted, 1.7 or 1e300 is not."""
    if isinstance(value, (bool, np.bool_)):
        raise ProblemError(f"{name} must be an integer, got {value!r}")
    if isinstance(value, (numbers.Integral, np.integer)):
        v = int(value)
    elif isinstance(value, (numbers.Real, np.floating)) and np.isfinite(value) and float(value).is_integer() \
            and abs(value) < 2 ** 53:
        v = int(value)
    else:
        raise ProblemError(f"{name} must be an integer, got {value!r}")
    if minimum is not None and v < minimum:
        raise ProblemError(f"{name} must be ≥ {minimum}, got {v}")
    if maximum is not None and v > maximum:
        raise ProblemError(f"{name} must be ≤ {maximum}, got {v}")
    return v


def as_positive(value, name: str, *, maximum: float | None = None) -> float:
    """A finite real number > 0 (and ≤ ``maximum``): a bound, a step, a tolerance."""
    v = as_real(value, name)
    if not v > 0:
        raise ProblemError(f"{name} must be > 0, got {v!r}")
    if maximum is not None and v > maximum:
        raise ProblemError(f"{name} must be ≤ {maximum:g}, got {v!r}")
    return v


def as_flag(value, name: str, *, allow_none: bool = False) -> bool | None:
    """True or False (NumPy's bool too), or None when ``allow_none``; 1, "yes" are refused."""
    if value is None and allow_none:
        return None
    if not isinstance(value, (bool, np.bool_)):
        raise ProblemError(f"{name} must be True or False{' or None' if allow_none else ''}, got {value!r}")
    return bool(value)


# -- keyword arguments -------------------------------------------------------------------

def unknown_keyword(function: str, name: str, known) -> TypeError:
    """The TypeError Python raises for an unexpected keyword, with the nearest known one."""
    near = difflib.get_close_matches(str(name), sorted(known), n=1)
    hint = f"; did you mean {near[0]!r}?" if near else f"; it takes {', '.join(sorted(known))}"
    return TypeError(f"{function}() got an unexpected keyword argument {name!r}{hint}")


def check_keywords(function: str, given, known, refused=None) -> None:
    """Every name in ``given`` among ``known``: else a TypeError naming the nearest known
    one.  ``refused``: names a caller might expect to work, each with the reason it does not
    (a ProblemError: the name is right, the request is not)."""
    for name in given:
        if refused and name in refused:
            raise ProblemError(f"{function} does not take {name!r}: {refused[name]}")
        if name not in known:
            raise unknown_keyword(function, name, known)


def checked_keywords(*, more=None, refused=None):
    """Decorator: the function's keyword arguments checked by name before it runs
    (:func:`check_keywords`), so that ``analyze(scene, flutterr=False)`` is a TypeError
    that says ``did you mean 'flutter'?``.  Known: the function's own parameters, and
    ``more()`` (the options its ``**options`` hands on, e.g. a solver registry's, read at
    call time) when given.  ``help()`` and :func:`inspect.signature` show the function's own
    signature and docstring."""
    def wrap(func):
        kinds = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
        own = {n for n, p in inspect.signature(func).parameters.items() if p.kind in kinds}
        not_own = {k: v for k, v in (refused or {}).items() if k not in own}

        @functools.wraps(func)
        def checked(*args, **kwargs):
            check_keywords(func.__name__, kwargs, own | set(more() if more else ()), not_own)
            return func(*args, **kwargs)
        return checked
    return wrap


def scale(M) -> float:
    """A matrix scale for relative tolerances: the largest absolute entry (1 for zero)."""
    data = M.data if sp.issparse(M) else np.asarray(M)
    s = float(np.max(np.abs(data))) if data.size else 0.0
    return s if s > 0 else 1.0


def row_max_abs(M) -> np.ndarray:
    """``max_j |m_ij|`` for every row i of a NumPy or SciPy matrix: the row scales of the
    row-wise certificates, which hold whatever the scale of each row (any kind of matrix:
    :func:`meicp.core.matrix.row_max_abs`)."""
    if sp.issparse(M):
        return np.asarray(abs(M).max(axis=1).toarray()).ravel()
    return np.abs(np.asarray(M)).max(axis=1)


def symmetry_error(M) -> float:
    """``max|M - Mᵀ|`` relative to the scale of ``M``."""
    D = M - M.T
    d = abs(D).max() if sp.issparse(D) else np.max(np.abs(D))
    return float(d) / scale(M)


def is_symmetric(M, rtol: float = 1e-12) -> bool:
    return symmetry_error(M) <= rtol


def check_symmetric(M, name: str = "M", rtol: float = 1e-12) -> None:
    err = symmetry_error(M)
    if err > rtol:
        raise ProblemError(f"{name} must be symmetric: max|{name} - {name}ᵀ| / max|{name}| = {err:.3g} > {rtol:g}")


def check_spd(M, name: str = "B", rtol: float = 1e-12) -> None:
    """Symmetric and positive definite, by a Cholesky factorisation (dense) or LDLᵀ-free test.

    Sparse diagonal matrices are checked by their diagonal; other sparse matrices by a
    sparse LU's pivots only when small, otherwise densified up to a size limit.
    """
    check_symmetric(M, name, rtol)
    if sp.issparse(M):
        offdiag = M - sp.diags(M.diagonal())
        if offdiag.count_nonzero() == 0:
            d = M.diagonal()
            if np.all(d > 0):
                return
            i = int(np.argmin(d))
            raise ProblemError(f"{name} must be positive definite: diagonal entry {i} is {d[i]:.3g}")
        M = M.toarray()
    try:
        np.linalg.cholesky(0.5 * (M + M.T))
    except np.linalg.LinAlgError:
        w = np.linalg.eigvalsh(0.5 * (M + M.T))
        raise ProblemError(
            f"{name} must be positive definite: smallest eigenvalue {w[0]:.3g}") from None


def as_index_set(J, n: int, name: str = "J") -> np.ndarray:
    """Return a sorted int array of distinct indices in ``[0, n)``; ``None`` means all.

    A boolean mask of length n is accepted; so are floats with integral values (MATLAB
    files store indices as doubles), but 1.7 is an error, never truncated to 1."""
    if J is None:
        return np.arange(n)
    try:
        J = np.asarray(J)
    except (TypeError, ValueError) as exc:
        raise ProblemError(f"{name} is not an array of indices: {exc}") from None
    if J.dtype == bool:
        if J.shape != (n,):
            raise ProblemError(f"{name} as a mask must have length {n}, got shape {J.shape}")
        return np.flatnonzero(J)
    if J.size == 0:
        return np.zeros(0, dtype=np.int64)
    if J.ndim != 1 or not (np.issubdtype(J.dtype, np.integer) or np.issubdtype(J.dtype, np.floating)):
        raise ProblemError(f"{name} must be a 1-D array of integer indices, got {J.dtype} shape {J.shape}")
    if np.issubdtype(J.dtype, np.floating):
        bad = J[~np.isfinite(J) | (J != np.round(J))]
        if bad.size:
            raise ProblemError(f"{name} has a non-integer index {bad[0]!r} (indices must be integers)")
    bad = J[(J < 0) | (J >= n)]
    if bad.size:
        raise ProblemError(f"{name} has index {bad[0]:.15g} out of range [0, {n})")
    J = J.astype(np.int64)
    uniq, counts = np.unique(J, return_counts=True)
    if np.any(counts > 1):
        raise ProblemError(f"{name} repeats index {int(uniq[np.argmax(counts > 1)])}")
    return uniq
