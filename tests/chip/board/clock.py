"""The board's virtual time: CPU cycles at 168 MHz, advanced by the
instructions the core executes (one cycle each at the PLL's 168 MHz, 10.5
on the 16 MHz HSI the chip starts on: core.py) and skipped over while it
sleeps, with the events the peripherals schedule on it."""

import heapq
from collections.abc import Callable
from fractions import Fraction

HZ = 168_000_000

# An instant or a span of virtual time in cycles: whole as a rule, exact
# fractions where a peripheral's clock does not divide the core's.
Cycles = int | Fraction


def cycles(numerator: int, denominator: int) -> Cycles:
    """`numerator / denominator` cycles: an int when it is whole (the usual
    case, and much faster to compute with), else exact as a Fraction."""
    whole, rest = divmod(numerator, denominator)
    return Fraction(numerator, denominator) if rest else whole


class Event:
    __slots__ = ("action", "cancelled", "cycle")

    def __init__(self, cycle: int, action: Callable[[], object]) -> None:
        self.cycle = cycle
        self.action = action
        self.cancelled = False

    def cancel(self) -> None:
        self.cancelled = True


class Clock:
    def __init__(self) -> None:
        self.base = 0  # cycles at the start of the current run of the core
        self.executed: Callable[[], int] = lambda: 0  # instructions since then (the core's counter)
        self._queue: list[tuple[int, int, Event]] = []
        self._seq = 0
        self._due: int | None = None  # the cycle of the event being handled
        # Where the core's current run ends, and how to end it sooner: an
        # event scheduled during a run (a compare the image arms) may fall
        # due before that end, and must not wait for it.
        self.run_end = 0
        self.shorten_run: Callable[[], None] = lambda: None

    @property
    def now(self) -> int:
        return self.base + self.executed()

    def instant(self) -> int:
        """When what happens now happened: an event's own cycle while it is
        handled (the core may have run a few instructions past it, to the
        end of a block), else now."""
        return self.now if self._due is None else self._due

    def at(self, cycle: int, action: Callable[[], object]) -> Event:
        """Calls `action()` once the clock reaches `cycle` (never earlier
        than now)."""
        e = Event(max(cycle, self.now), action)
        self._seq += 1
        heapq.heappush(self._queue, (e.cycle, self._seq, e))
        if e.cycle < self.run_end:
            self.shorten_run()
        return e

    def next(self) -> int | None:
        while self._queue and self._queue[0][2].cancelled:
            heapq.heappop(self._queue)
        return self._queue[0][0] if self._queue else None

    def fire_due(self) -> None:
        while True:
            n = self.next()
            if n is None or n > self.now:
                return
            _, _, e = heapq.heappop(self._queue)
            self._due = e.cycle
            try:
                e.action()
            finally:
                self._due = None
