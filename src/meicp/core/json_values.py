"""Numbers for JSON: every document meicp prints or stores as JSON writes its numbers this way.

JSON has no infinity and no NaN, and a string where a number belongs breaks every reader that
does arithmetic on it.  So a number is always a JSON number or ``null``:

* a finite float is itself;
* NaN (unknown, not computed) is ``null``;
* ±∞ is ``null`` too, and the object that holds it says so in a sibling key
  ``<key>_infinite`` (:data:`INFINITE_SUFFIX`): ``1`` for +∞, ``-1`` for −∞.  For a list of
  numbers the sibling is a list of the same length, ``0`` where the entry is finite.  The
  sibling is written only when something is infinite: ``doc.get("upper_infinite")`` is the
  test, and ``null`` without it means unknown.

An infinite value often carries meaning — μ_c = ∞ "no σ = 0 mode up to the search's bound", a
σ-window [0, ∞) — which is why it is not folded into ``null`` alone.  Example::

    >>> json_ready({"value": float("inf"), "window": [0.0, float("inf")], "tol": float("nan")})
    {'value': None, 'window': [0.0, None], 'tol': None, 'value_infinite': 1, 'window_infinite': [0, 1]}
"""

from __future__ import annotations

import math

import numpy as np

#: the suffix of the key that marks an infinite number (see the module docstring)
INFINITE_SUFFIX = "_infinite"

#: the version of every JSON document's layout (``--json`` and sweep.json).  2: numbers are
#: numbers (±∞ as null with a ``<key>_infinite`` flag; version 1 wrote the strings
#: "inf"/"-inf"), and every document starts with ``format``, ``format_version`` and
#: ``meicp_version``
FORMAT_VERSION = 2


def _sign_of_infinity(value) -> int:
    """1 for +∞, −1 for −∞, 0 otherwise (a finite number, NaN, or not a float)."""
    if isinstance(value, (float, np.floating)) and math.isinf(value):
        return 1 if value > 0 else -1
    return 0


def _infinities(value):
    """The ``<key>_infinite`` flag of a value: ±1 for an infinite float, a list of signs for a
    list holding one, None when nothing in it is infinite."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        signs = [_sign_of_infinity(v) for v in value]
        return signs if any(signs) else None
    return _sign_of_infinity(value) or None


def json_ready(value):
    """``value`` with every number as the module docstring says, NumPy scalars and arrays as
    Python ones, tuples as lists; dicts and lists walked (dict keys as strings).  Anything
    else is returned as it is."""
    if isinstance(value, dict):
        out, flags = {}, {}
        for key, item in value.items():
            key = str(key)
            out[key] = json_ready(item)
            flag = _infinities(item)
            if flag is not None:
                flags[key + INFINITE_SUFFIX] = flag
        out.update((k, v) for k, v in flags.items() if k not in out)
        return out
    if isinstance(value, np.ndarray):
        return json_ready(value.tolist())
    if isinstance(value, (list, tuple)):
        return [json_ready(item) for item in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return value if math.isfinite(value) else None
    return value


def restore_infinities(doc: dict) -> dict:
    """The inverse of :func:`json_ready` on one dict level: each ``<key>_infinite`` flag
    removed and its ±∞ put back in ``<key>`` (a number, or the flagged items of a list)."""
    out = {k: v for k, v in doc.items() if not k.endswith(INFINITE_SUFFIX)}
    for key, flag in doc.items():
        if not key.endswith(INFINITE_SUFFIX):
            continue
        name = key[:-len(INFINITE_SUFFIX)]
        if isinstance(flag, list):
            out[name] = [math.copysign(math.inf, f) if f else v for v, f in zip(out[name], flag)]
        elif flag:
            out[name] = math.copysign(math.inf, flag)
    return out

