"""Node-block padding of sparse matrices before MUMPS (meicp.lattice.node_blocks)."""

import numpy as np
import pytest
import scipy.sparse as sp

from meicp.contact.condensation import pieces_of
from meicp.contact.lines import contact_lines
from meicp.contact.maps import reduced_system
from meicp.lattice.assembly import assemble_scipy
from meicp.lattice.model import LatticeModel
from meicp.lattice.node_blocks import NodeBlocks, node_of

from meicp.examples import two_layer_scene


def _two_layer_FF(nx=8, ny=3):
    scene = two_layer_scene(nx, (ny, ny), mu=1.0, states="slip+", shear=0.5)
    model = LatticeModel(scene)
    K, M = assemble_scipy(model)
    maps = reduced_system(model, contact_lines(scene, model), ())
    pieces = pieces_of(K, M, maps)
    F = pieces.F
    return pieces.Kt[F][:, F].tocsr(), node_of(maps.retained[F])


def _row_patterns_agree_within_groups(H, groups) -> bool:
    H = sp.csr_matrix(H)
    for g in np.unique(groups):
        rows = np.flatnonzero(groups == g)
        cols = [tuple(H.indices[H.indptr[r]:H.indptr[r + 1]]) for r in rows]
        if any(c != cols[0] for c in cols):
            return False
    return True


def test_padding_keeps_values_and_completes_node_blocks():
    KFF, nodes = _two_layer_FF()
    # the lattice's products drop cancelled entries: the two DOFs of a node differ in pattern
    assert not _row_patterns_agree_within_groups(KFF, nodes)
    padded = NodeBlocks(nodes).pad(KFF)
    assert padded.nnz > KFF.nnz
    assert abs(padded - KFF).max() == 0.0
    assert _row_patterns_agree_within_groups(padded, nodes)
    # the columns agree too: a coupling of two nodes is a whole block
    assert _row_patterns_agree_within_groups(padded.T.tocsr(), nodes)


def test_padding_reuses_its_pattern_and_follows_a_new_one():
    KFF, nodes = _two_layer_FF()
    blocks = NodeBlocks(nodes)
    first = blocks.pad(KFF)
    shifted = (KFF + 0.25 * sp.eye(KFF.shape[0])).tocsr()  # same pattern, other values
    again = blocks.pad(shifted)
    assert np.array_equal(again.indices, first.indices) and np.array_equal(again.indptr, first.indptr)
    assert abs(again - shifted).max() == 0.0
    # a pattern with fewer entries lands in the kept one
    fewer = sp.diags(KFF.diagonal()).tocsr()
    assert abs(blocks.pad(fewer) - fewer).max() == 0.0
    # one with an entry outside it gets a padding of its own
    n = KFF.shape[0]
    wider = (KFF + sp.csr_matrix(([1.0, 1.0], ([0, n - 1], [n - 1, 0])), shape=(n, n))).tocsr()
    out = blocks.pad(wider)
    assert abs(out - wider).max() == 0.0 and _row_patterns_agree_within_groups(out, nodes)


def test_padding_sums_duplicates_and_checks_the_order():
    groups = np.array([0, 0, 1, 1, 2])
    H = sp.csr_matrix((np.array([1.0, 2.0, 3.0, 4.0]), (np.array([0, 0, 2, 4]), np.array([0, 0, 3, 1]))), shape=(5, 5))
    padded = NodeBlocks(groups).pad(H)
    assert np.array_equal(padded.toarray(), H.toarray())
    assert padded.toarray()[0, 0] == 3.0
    # rows 0 and 1 (node 0) both reach node 0's columns; row 4 reaches node 0 as a block
    assert set(padded[1].indices) == {0, 1}
    assert set(padded[4].indices) == {0, 1}
    with pytest.raises(ValueError, match="order 5"):
        NodeBlocks(groups).pad(sp.eye(4))


@pytest.mark.parametrize("states", ["slip+", "slip-"])
def test_the_condensers_bordered_matrix_is_the_pieces_one_padded(states):
    """The condenser's padded parts (what its Schur series factors): 𝓗₀ + σ𝓗₁ on one padded
    pattern, value for value the pieces' bordered matrix at every σ (0 included, where σM̃
    vanishes)."""
    from meicp.contact.condenser import Condenser

    scene = two_layer_scene(8, (3, 3), mu=1.3, states=states, shear=0.5)
    model = LatticeModel(scene)
    maps = reduced_system(model, contact_lines(scene, model), ())
    cond = Condenser(None, maps, *assemble_scipy(model))
    P0, P1, rows = cond.padded_parts
    assert np.array_equal(P0.indptr, P1.indptr) and np.array_equal(P0.indices, P1.indices)
    for sigma in (0.0, 0.37, 12.5):
        H = sp.csr_matrix((P0.data + sigma * P1.data, P0.indices, P0.indptr), shape=P0.shape)
        ref, ref_rows = cond.pieces.bordered(sigma)
        assert np.array_equal(rows, ref_rows) and abs(H - ref).max() == 0.0
        assert H.nnz >= ref.nnz


def test_a_mass_part_outside_the_stiffness_pattern_pads_the_union():
    """When 𝓗₁ has an entry outside 𝓗₀'s padded pattern (not so on a base contact, whose mass
    is diagonal), the condenser pads the union of both: 𝓗₀ + σ𝓗₁ still value for value."""
    from meicp.contact.condenser import Condenser

    scene = two_layer_scene(8, (3, 3), mu=1.3, states="slip+", shear=0.5)
    model = LatticeModel(scene)
    maps = reduced_system(model, contact_lines(scene, model), ())
    cond = Condenser(None, maps, *assemble_scipy(model))
    H0, H1, rows = cond.pieces.bordered_parts()
    n = H0.shape[0]
    far = sp.csr_matrix(([0.25, 0.25], ([0, n - 1], [n - 1, 0])), shape=(n, n))  # nodes far apart
    assert H0[0, n - 1] == 0
    H1 = (H1 + far).tocsr()
    cond.pieces.bordered_parts = lambda: (H0, H1, rows)
    P0, P1, got_rows = cond.padded_parts
    for sigma in (0.0, 0.37):
        H = sp.csr_matrix((P0.data + sigma * P1.data, P0.indices, P0.indptr), shape=P0.shape)
        assert np.array_equal(got_rows, rows) and abs(H - (H0 + sigma * H1)).max() == 0.0
    assert np.array_equal(P0.indices, P1.indices) and P0.nnz > sp.csr_matrix(H0).nnz


@pytest.mark.parametrize("contiguous", [True, False])
def test_the_padded_pattern_couples_whole_groups_and_nothing_else(contiguous):
    # contiguous groups (a node's DOFs are neighbours) take the index-arithmetic path, others
    # the product memberᵀ·coupled·member: both must give exactly the pairs of coupled groups
    rng = np.random.default_rng(3)
    groups = np.repeat(np.arange(40), rng.integers(1, 4, size=40))
    if not contiguous:
        groups = rng.permutation(groups)
    n = groups.size
    H = (sp.random(n, n, density=0.04, random_state=5) + sp.eye(n)).tocsr()
    P = NodeBlocks(groups).pad(H)
    member = np.equal.outer(groups, np.unique(groups)).astype(float)
    coupled = member.T @ (H.toarray() != 0) @ member > 0
    expected = member @ coupled @ member.T > 0
    pattern = np.zeros((n, n), dtype=bool)
    pattern[np.repeat(np.arange(n), np.diff(P.indptr)), P.indices] = True
    assert np.array_equal(pattern, expected)
    assert all(np.all(np.diff(P.indices[P.indptr[i]:P.indptr[i + 1]]) > 0) for i in range(n))  # sorted, no repeats
    assert abs(P - H).max() == 0


@pytest.mark.parametrize("mu, tau", [(3.0, 0.0), (3.0, -0.05), (0.5, 0.0), (0.5, 0.2)])
def test_the_inertia_of_a_pencil_factored_by_node_is_the_plain_one(mu, tau):
    """The Rayleigh bound of a SciPy pencil factored node by node (explicit zeros completing
    every node block: the critical friction's floor, the serial bound at 0) counts the same
    eigenvalues as without the padding — where the bound holds and where it fails — and the
    padding is there to be read (its pattern is larger)."""
    from meicp.contact.problem import pencil
    from meicp.contact.rayleigh import pencil_bound, rayleigh_bound
    from meicp.petsc.inertia import rounding_margin

    with pencil(two_layer_scene(30, (3, 3), mu=mu, states="slip+", shear=0.5)) as pen:
        plain = rayleigh_bound(pen.A, pen.B, tau, decisive=False)
        by_node = pencil_bound(pen, tau)
        S = (0.5 * (pen.A + pen.A.T) - tau * pen.B).tocsr()
        padded = NodeBlocks(node_of(pen.maps.retained)).pad(S)
    assert (by_node.proved, by_node.above, by_node.margin) == (plain.proved, plain.above, plain.margin)
    assert padded.nnz > S.nnz and abs(padded - S).max() == 0.0
    assert plain.margin == rounding_margin(S.shape[0])
