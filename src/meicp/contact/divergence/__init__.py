"""The divergence verdict of one contact state's MEiCP, as a package: the driver
(:mod:`.driver`), its steps (:mod:`.steps`, :mod:`.search`, :mod:`.sigma_window`), the
enumeration of small problems (:mod:`.enumeration`), the condensed proof
(:mod:`.condensed`, :mod:`.windows`, :mod:`.cover`), and the typed result
(:mod:`.verdict`)."""

from .driver import PROCEDURES, Procedures, divergence_of, window_verdict
from .enumeration import check_enumeration_size, enumeration_is_small
from .verdict import DivergenceProof, DivergenceVerdict, all_held

__all__ = ["PROCEDURES", "DivergenceProof", "DivergenceVerdict",
           "Procedures", "all_held", "check_enumeration_size", "divergence_of", "enumeration_is_small",
           "window_verdict"]
