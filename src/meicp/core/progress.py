"""Progress lines for long loops (support enumerations, searches): count, rate and the
estimated time left, through the ``meicp`` logger at INFO level — so on rank 0 only, shown
by ``meicp solve`` by default and by the other commands with ``-v``, silent under ``-q``.

Cheap by construction: :meth:`Progress.update` reads a clock and returns unless
``INTERVAL`` seconds have passed since the last line (the first line waits ``FIRST``
seconds, so short loops print nothing).  :class:`Ticker` does the same for a phase that
says in its own words where it is (a SLEPc eigen-solve's restarts, a SNES's iterations, the
windows of a condensed proof: :mod:`meicp.petsc.monitor`, :mod:`meicp.contact.divergence.cover`).
The intervals are read when a line is due, so setting them to 0 (a test) shows every line.
"""

from __future__ import annotations

import logging
import math
import time

#: seconds before the first line (a loop that ends sooner prints nothing)
FIRST = 2.0
#: seconds between lines
INTERVAL = 3.0

log = logging.getLogger("meicp")


def duration(seconds: float) -> str:
    """A time span for a progress line or an estimate: ``under 1 s``, ``42 s``, ``3.5 min``,
    ``1.2 h`` (``?`` when not finite)."""
    if not math.isfinite(seconds):
        return "?"
    if seconds < 1:
        return "under 1 s"
    if seconds < 60:
        return f"{seconds:.0f} s"
    if seconds < 3600:
        return f"{seconds / 60:.1f} min"
    return f"{seconds / 3600:.1f} h"


class Progress:
    """Report the progress of a loop over ``total`` items (None: unknown).

    ``work``: the total cost in any unit, when items cost unequal amounts (e.g. supports of
    growing size: the estimate of the time left then follows the cost, not the count);
    ``unit``: what an item is (``"supports"``).  Call :meth:`update` with the items done
    (and the work done) as often as is convenient::

        progress = Progress("enumeration", total=2 ** 13, unit="supports")
        for k, chunk in enumerate(chunks):
            ...
            progress.update(done)
    """

    def __init__(self, what: str, total: int | None = None, *, unit: str = "", work: float | None = None,
                 clock=time.monotonic):
        self.what, self.total, self.unit = what, total, unit
        self.work = float(work) if work is not None else (float(total) if total is not None else None)
        self.clock = clock
        self.start = clock()
        self.next = self.start + FIRST
        self.lines = 0

    def update(self, done: int, work_done: float | None = None, detail: str = "") -> None:
        """``done`` items (and ``work_done`` units of work) finished; ``detail``: appended text."""
        now = self.clock()
        if now < self.next or not log.isEnabledFor(logging.INFO):
            return
        self.next = now + INTERVAL
        self.lines += 1
        elapsed = max(now - self.start, 1e-9)
        unit = f" {self.unit}" if self.unit else ""
        text = f"{self.what}: {done:,}" + (f" of {self.total:,}" if self.total is not None else "") + unit
        if self.total:
            text += f" ({100.0 * done / self.total:.0f} %)"
        rate = done / elapsed
        text += (f", {rate:,.0f}" if rate >= 100 else f", {rate:.3g}") + f"{unit}/s"
        fraction = None
        if self.work:
            fraction = (done if work_done is None else work_done) / self.work
        if fraction and 0 < fraction < 1:
            left = duration(elapsed * (1 - fraction) / fraction)
            text += f", {left if left.startswith('under') else 'about ' + left} left"
        log.info(text + (f"; {detail}" if detail else ""))


class Ticker:
    """Lines about one phase in its own words, at most one per ``interval`` seconds (default
    :data:`INTERVAL`), the first after :data:`FIRST` seconds: a phase that ends sooner says
    nothing.  ``what`` starts every line::

        ticker = Ticker("eigen-solve -meicp_as_")
        ...
        ticker.say(lambda: f"restart {its}, {nconv} of {nev} converged")

    ``say`` takes the text or a function making it, called only when a line is due."""

    def __init__(self, what: str, *, interval: float | None = None, clock=time.monotonic):
        self.what, self.interval, self.clock = what, interval, clock
        self.start = clock()
        self.next = None
        self.lines = 0

    def due(self) -> bool:
        """Whether a line would be printed now (the logger shows INFO and the time has come)."""
        now = self.clock()
        if self.next is None:
            self.next = self.start + FIRST
        return now >= self.next and log.isEnabledFor(logging.INFO)

    def say(self, text) -> None:
        if not self.due():
            return
        now = self.clock()
        self.next = now + (INTERVAL if self.interval is None else self.interval)
        self.lines += 1
        log.info("%s: %s (%s)", self.what, text() if callable(text) else text, _clock(now - self.start))


def _clock(seconds: float) -> str:
    return f"{seconds:.1f} s" if seconds < 60 else duration(seconds)
