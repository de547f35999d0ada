"""Static equilibrium, mixed formulation, on 2 ranks: the same answer as serial."""

import numpy as np
import pytest

pytestmark = pytest.mark.mpi(min_size=2)


def _scenes():
    from tests.test_static import MIXED_SCENES

    return MIXED_SCENES


@pytest.mark.parametrize("name", ["compression_large_mu_stick", "shear_small_mu_slip", "uplift_separated",
                                  "frictional_interface", "medium_shear_slip", "medium_interface",
                                  "base_and_interface_floating"])
def test_mixed_on_two_ranks_equals_serial(comm, name):
    from meicp.contact.static import static_equilibrium
    from tests.test_static import assert_same_equilibrium

    s = _scenes()[name]()
    par = static_equilibrium(s, formulation="mixed", comm=comm)
    ser = static_equilibrium(s, formulation="mixed")
    assert par.success and ser.success, par.message
    assert_same_equilibrium(ser, par)
    assert par.residual <= 1e-9 and par.equilibrium_residual <= 1e-9
    same = comm.allgather((par.states, par.interface_states, par.u))
    assert all(x[0] == same[0][0] and x[1] == same[0][1] and np.array_equal(x[2], same[0][2]) for x in same)
    cond = static_equilibrium(s, formulation="condensed")
    assert_same_equilibrium(cond, par)


@pytest.mark.parametrize("name", ["interface_family", "base_side_shortening", "medium_stick"])
def test_schur_on_two_ranks_equals_serial(comm, name):
    """The Schur formulation: the MUMPS factor distributed over 2 ranks, the problem on G solved
    on rank 0 and broadcast — the same states on every rank and as the serial run."""
    from meicp.contact.static import static_equilibrium
    from tests.test_static import assert_same_equilibrium
    from tests.test_static_schur import SCENES

    s = SCENES[name]()
    par = static_equilibrium(s, formulation="schur", comm=comm)
    ser = static_equilibrium(s, formulation="schur")
    assert par.success and ser.success, par.message
    assert par.layout["formulation"] == "schur"
    assert_same_equilibrium(ser, par, rtol=1e-9)
    assert par.residual <= 1e-10 and par.equilibrium_residual <= 1e-10
    same = comm.allgather((par.states, par.interface_states, par.u))
    assert all(x[0] == same[0][0] and x[1] == same[0][1] and np.array_equal(x[2], same[0][2]) for x in same)
