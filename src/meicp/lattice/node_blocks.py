"""Sparse matrices padded to whole node blocks, so that a sparse factorisation orders nodes,
not DOFs.

A lattice node carries two DOFs (natural DOF ``2·node + c``).  Products of SciPy matrices
drop the entries that cancel, and in a spring lattice many do (a horizontal bond couples
the x-DOFs of its ends only), so the two DOFs of a node end up with different sparsity
patterns.  MUMPS' AMF ordering then cannot merge them into one supervariable, and orders a
graph twice the size with worse fill: the factorisation and the Schur complement of K̃_FF
are two to three times slower than with explicit zeros completing every node block
(docs/benchmarks-notes.md, lattice).  The PETSc pencil keeps the zeros of its
products and needs none of this; the SciPy pieces of the condensation do.

:class:`NodeBlocks` pads a matrix to the pattern in which each nonzero couples whole
groups; the values are unchanged (the padding is explicit zeros).  The padded pattern and
the scatter of the last pattern seen are kept: the matrices of one condensation (every σ)
share one pattern, so each further one costs a copy of its values.  Pure NumPy/SciPy.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

#: DOFs per lattice node: natural DOF ``2·node + c``, c = 0 (x), 1 (y)
DOFS_PER_NODE = 2


def node_of(dofs: np.ndarray) -> np.ndarray:
    """The lattice node of each natural DOF."""
    return np.asarray(dofs, dtype=np.int64) // DOFS_PER_NODE


class NodeBlocks:
    """``NodeBlocks(groups)``: ``pad(H)`` returns H (square, order ``groups.size``) with
    explicit zeros so that rows i, j of one group share one pattern (group ``groups[i]``:
    e.g. the node of each row; rows without a partner get a group of their own)."""

    def __init__(self, groups: np.ndarray):
        groups = np.asarray(groups, dtype=np.int64)
        _, self.groups = np.unique(groups, return_inverse=True)  # 0 … m−1
        self._pattern: sp.csr_matrix | None = None  # padded pattern (canonical CSR, data unused)
        self._seen: tuple | None = None             # (indptr, indices) of the last H padded
        self._where: np.ndarray | None = None       # where H's entries sit in the padded pattern

    def pad(self, H: sp.spmatrix) -> sp.csr_matrix:
        H = sp.csr_matrix(H)
        n = self.groups.size
        if H.shape != (n, n):
            raise ValueError(f"NodeBlocks of order {n} cannot pad a matrix of shape {H.shape}")
        if not H.has_canonical_format:  # sorted column indices, no duplicates
            H = H.copy()
            H.sum_duplicates()
        if not self._same_as_seen(H):
            self._locate(H)
        data = np.zeros(self._pattern.nnz, dtype=H.dtype)
        data[self._where] = H.data
        P = self._pattern
        return sp.csr_matrix((data, P.indices, P.indptr), shape=H.shape)

    def _same_as_seen(self, H) -> bool:
        return (self._seen is not None and np.array_equal(self._seen[0], H.indptr)
                and np.array_equal(self._seen[1], H.indices))

    def _locate(self, H) -> None:
        where = None if self._pattern is None else _positions(self._pattern, H)
        if where is None:  # the first matrix, or one with entries outside the padded pattern
            self._pattern = self._padded_pattern(H)
            where = _positions(self._pattern, H)
        self._seen = (H.indptr.copy(), H.indices.copy())
        self._where = where

    def _padded_pattern(self, H) -> sp.csr_matrix:
        g, n = self.groups, self.groups.size
        m = int(g.max(initial=-1)) + 1
        if n and np.all(np.diff(g) >= 0):
            # contiguous groups: the rows of group G are one run of H's rows, so H's column
            # groups, read in place, are the group-level rows (with repeats, summed away)
            runs = np.concatenate([[0], np.cumsum(np.bincount(g, minlength=m))])
            coupled = sp.csr_matrix((np.ones(H.nnz), g[H.indices], H.indptr[runs]), shape=(m, m))
            coupled.sum_duplicates()  # canonical: sorted columns, one entry per pair of groups
            return _expand_contiguous(coupled, g, runs)
        rows = np.repeat(np.arange(n), np.diff(H.indptr))
        coupled = sp.csr_matrix((np.ones(H.nnz), (g[rows], g[H.indices])), shape=(m, m))
        member = sp.csr_matrix((np.ones(n), (np.arange(n), g)), shape=(n, m))
        P = (member @ coupled @ member.T).tocsr()  # positive entries: nothing cancels
        P.sort_indices()
        return P


def _expand_contiguous(coupled: sp.csr_matrix, g: np.ndarray, runs: np.ndarray) -> sp.csr_matrix:
    """The padded pattern when every group is a contiguous run of rows in group order (the
    natural DOF numbering of a lattice: a node's DOFs are neighbours): each coupled pair of
    groups (G, c) becomes the column range of c in every row of G, already sorted.  Index
    arithmetic only: the product member·coupled·memberᵀ is slow at 10⁶ DOFs
    (docs/benchmarks-notes.md, lattice).
    ``runs``: where each group's rows begin, and the end (m + 1 entries)."""
    n = g.size
    start, size = runs[:-1], np.diff(runs)
    width = size[coupled.indices]                       # columns each coupled pair expands to
    total = int(width.sum())
    first = np.repeat(np.cumsum(width) - width, width)  # where each pair's range begins in `cols`
    cols = np.repeat(start[coupled.indices], width) + (np.arange(total) - first)
    # the expanded row of group G is cols[group_ptr[G] : group_ptr[G + 1]]
    group_ptr = np.concatenate([[0], np.cumsum(width)])[coupled.indptr]
    length = np.diff(group_ptr)[g]
    indptr = np.concatenate([[0], np.cumsum(length)])
    nnz = int(indptr[-1])
    indices = cols[np.repeat(group_ptr[:-1][g] - indptr[:-1], length) + np.arange(nnz)]
    P = sp.csr_matrix((np.ones(nnz), indices.astype(np.int32 if n < 2 ** 31 else np.int64), indptr), shape=(n, n))
    P.has_sorted_indices = True
    return P


def _positions(P: sp.csr_matrix, H: sp.csr_matrix) -> np.ndarray | None:
    """Where each entry of H (canonical CSR) sits in P's entries, or None when H has an entry
    outside P's pattern: one elementwise product of P's entry numbers with H's pattern (a merge
    of sorted rows in C; a search of every entry is slow at 10⁶ DOFs,
    docs/benchmarks-notes.md)."""
    number = sp.csr_matrix((np.arange(1, P.nnz + 1, dtype=np.float64), P.indices, P.indptr), shape=P.shape)
    pattern = sp.csr_matrix((np.ones(H.nnz), H.indices, H.indptr), shape=H.shape)
    hit = number.multiply(pattern).tocsr()
    if hit.nnz != H.nnz:
        return None
    hit.sort_indices()
    return hit.data.astype(np.int64) - 1
