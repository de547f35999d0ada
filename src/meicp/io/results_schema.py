"""The vocabulary of results.h5 (layout in :mod:`meicp.io.results`): its format name and
version, the contact state codes and their legends, the CF-style descriptions of its datasets
and of the XDMF fields added to lattice.h5, and the file names of an output directory.
"""

from __future__ import annotations

from ..scene import STATES
from .lattice_output import coded

FORMAT = "meicp-results"
#: 2: the JSON attribute ``divergence_proofs`` writes an infinite σ-window end as null with a
#: ``sigma_window_infinite`` flag (1 wrote the string "inf"; :mod:`meicp.core.json_values`),
#: and ``/critical_friction`` may hold ``error`` alone (μ_c asked for and not determined)
FORMAT_VERSION = 2
#: contact state → code (0 = not a contact node, -1 = unknown state)
STATE_CODES = {s: k for k, s in enumerate(STATES, start=1)}
CODE_LEGEND = "0 not a contact node, " + ", ".join(f"{k} {s}" for s, k in STATE_CODES.items()) \
    + ", -1 unknown"
#: CF attributes of a contact state code (``/contact/*/code``, the XDMF field ``contact_state``)
STATE_FLAGS = coded(("not_a_contact_node",) + STATES + ("unknown",), [0, *STATE_CODES.values(), -1],
                    long_name="contact state code")
#: CF-style attributes of results.h5's datasets, by (top group, dataset name)
DESCRIPTIONS = {
    ("modes", "sigma"): {"long_name": "sigma = lambda^2 of each mode: a divergence mode grows as exp(sqrt(sigma) t), "
                                      "a vibration mode has sigma = -omega^2 (1/time^2)"},
    ("modes", "growth_rate"): {"long_name": "growth rate lambda = sqrt(sigma), 0 when sigma < 0 (1/time)"},
    ("modes", "frequency"): {"long_name": "angular frequency omega = sqrt(-sigma), 0 when sigma >= 0 (1/time)"},
    ("modes", "residual"): {"long_name": "certificate residual of each mode, relative to the pencil's scale"},
    ("modes", "display_scale"): {"long_name": "factor that scales x to the picture of mode.png"},
    ("modes", "x"): {"long_name": "mode shape in natural DOF numbering (2n: x, 2n+1: y of node n = j*nx + i), "
                                  "unit 2-norm"},
    ("modes", "support"): {"long_name": "columns of the base contacts whose slip is active"},
    ("modes", "interface_support"): {"long_name": "columns of the interface's contacts whose slip is active"},
    ("flutter_modes", "sigma_real"): {"long_name": "real part of sigma = lambda^2 of each flutter mode (1/time^2)"},
    ("flutter_modes", "sigma_imag"): {"long_name": "imaginary part of sigma (> 0: one mode per conjugate pair) "
                                                   "(1/time^2)"},
    ("flutter_modes", "growth_rate"): {"long_name": "growth rate Re sqrt(sigma) > 0 of each flutter mode (1/time)"},
    ("flutter_modes", "frequency"): {"long_name": "angular frequency |Im sqrt(sigma)| of each flutter mode "
                                                  "(1/time)"},
    ("flutter_modes", "residual"): {"long_name": "backward error |Ax - sigma Bx| / ((|A|_1 + |sigma| |B|_1) |x|) "
                                                 "of each flutter mode"},
    ("flutter_modes", "radius"): {"long_name": "how far rounding may move sigma; |Im sigma| exceeds it (1/time^2)"},
    ("flutter_modes", "x_real"): {"long_name": "real part of the complex flutter mode shape, natural DOF "
                                               "numbering, unit 2-norm"},
    ("flutter_modes", "x_imag"): {"long_name": "imaginary part of the complex flutter mode shape (a quarter "
                                               "period after the real part)"},
    ("flutter_modes", "branch"): {"long_name": "grazing branch of each flutter mode (empty: no grazing contact)"},
    ("flutter_modes", "found_by"): {"long_name": "the method that found each flutter mode"},
    ("flutter_modes", "support"): {"long_name": "columns of the base contacts sliding in this flutter mode"},
    ("flutter_modes", "interface_support"): {"long_name": "columns of the interface's contacts sliding in "
                                                          "this flutter mode"},
    ("contact", "states"): {"long_name": "contact state of each column, left to right"},
    ("contact", "code"): STATE_FLAGS,
    ("contact", "nodes"): {"long_name": "node number j*nx + i of each base contact"},
    ("contact", "lower_nodes"): {"long_name": "node number of the lower side of each interface contact"},
    ("contact", "upper_nodes"): {"long_name": "node number of the upper side of each interface contact"},
    ("static", "r_n"): {"long_name": "normal contact reaction r_n >= 0 (force)"},
    ("static", "r_t"): {"long_name": "tangential contact reaction r_t, |r_t| <= mu r_n (force)"},
    ("static", "gap"): {"long_name": "normal gap g >= 0 (length)"},
    ("static", "slip"): {"long_name": "tangential slip (length)"},
    ("static", "held"): {"long_name": "1 where the boundary holds the contact node"},
    ("static", "u"): {"long_name": "static displacement in natural DOF numbering (length)"},
    ("certificates", "mode_residual"): {"long_name": "certificate residual of each mode"},
    ("", "scene"): {"long_name": "scene file (TOML)"},
    ("scene_summary", "name"): {"long_name": "name"},
    ("scene_summary", "rows"): {"long_name": "node rows of each layer"},
    ("scene_summary", "stiffness"): {"long_name": "bond stiffness (force per length)"},
    ("scene_summary", "density"): {"long_name": "density (mass per length^3)"},
    ("scene_summary", "below"): {"long_name": "the layer below each interface"},
    ("scene_summary", "kind"): {"long_name": "interface kind (bonded | frictional)"},
    ("scene_summary", "friction"): {"long_name": "Coulomb friction coefficient mu (NaN: bonded)"},
}
#: CF-style attributes of the XDMF fields results.h5's writer adds to lattice.h5
FIELD_DESCRIPTIONS = {
    "contact_state": STATE_FLAGS,
    "static_u": {"long_name": "static displacement (length)"},
    "r_n": {"long_name": "normal contact reaction r_n >= 0 of the static equilibrium (force), NaN off contacts"},
    "r_t": {"long_name": "tangential contact reaction r_t of the static equilibrium (force), NaN off contacts"},
}
#: file names inside the output directory (keys of the returned dict)
FILES = {"results": "results.h5", "lattice": "lattice.h5", "xdmf": "lattice.xdmf",
         "mode_png": "mode.png", "flutter_png": "flutter_mode.png", "contacts_png": "contacts.png"}
STATIC_FIELDS = ("r_n", "r_t", "gap", "slip")


def group_key(name: str) -> str:
    """A material's name as an HDF5 link name (``contact/interfaces/<name>``,
    ``interface_support/<name>``): '%' and '/' percent-encoded, and a name of dots alone ('.',
    '..') too — HDF5 reads '/' as a path separator and refuses '.' as a new link.  Any name the
    scene accepts is stored and read back (:func:`name_of_key`)."""
    key = name.replace("%", "%25").replace("/", "%2F")
    return key.replace(".", "%2E") if set(key) <= {"."} else key


def name_of_key(key: str) -> str:
    """The inverse of :func:`group_key`."""
    return key.replace("%2E", ".").replace("%2F", "/").replace("%25", "%")
