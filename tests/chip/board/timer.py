"""The general-purpose timers TIM2–TIM5 (RM0090 §18), counting up: the
prescaler and, with ARPE, the auto-reload are preloaded and take effect
at an update event (overflow or EGR.UG); a compare flag is set whenever
the counter becomes equal to its CCR, whether or not its interrupt is
enabled; status flags are cleared by writing 0 (rc_w0); the interrupt
line is asserted while a flag and its enable are both set. A timer in
external clock mode 1 (SMCR.SMS = 111) counts the update events of the
master its trigger selects (TIM3's ITR1 is TIM2, whose TRGO is its
update event when CR2.MMS = 010).

The counter is not stepped tick by tick: it is a function of the virtual
time between changes, flags are brought up to date whenever the timer is
touched, and only what the core can observe by itself is scheduled on the
clock (an overflow or compare whose interrupt is enabled, an update that
loads a preload). A slave's input edges are its master's update instants,
computed, not scheduled.

A channel's output (OCx, RM0090 §18.3.9–18.3.11) follows its reference
OCxREF: forced low or high (OCxM 100, 101), PWM mode 1 (high while
CNT < CCRx) or 2 (the opposite), set, cleared or toggled at a match
(001–011), or frozen (000); CCxP inverts it; with CCxE clear the timer
does not drive the pin (RM0090 Table 100: the pin is then what its GPIO
settings make it). While a driven output can change, its changes are
scheduled, so the pin log has every edge at its instant. Not modelled:
down and centre-aligned counting, input capture, the compare preload
(OCxPE: CCRx takes effect at once)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

from .bus import Block
from .clock import HZ, Clock, Cycles, Event, cycles
from .nvic import Nvic
from .system import Rcc

if TYPE_CHECKING:
    from .gpio import Port

UIE_UIF = 1


class Slave(Protocol):
    """What counts a timer's update events (a slave timer, an ADC)."""

    def _advance(self) -> None: ...

    def _schedule(self) -> None: ...

    def _trigger_edge(self, master: Timer) -> None: ...


class Timer(Block):
    def __init__(self, name: str, irq: int, bits: int, clock: Clock, nvic: Nvic, rcc: Rcc) -> None:
        self.name = name
        self.irq = irq
        self.top = (1 << bits) - 1
        self.clock = clock
        self.nvic = nvic
        self.rcc = rcc
        self.cr1 = self.cr2 = self.smcr = self.dier = self.sr = self.ccer = 0
        self.ccmr = [0, 0]
        self.psc = self.psc_pre = 0
        self.arr = self.arr_pre = self.top
        self.ccr = [0, 0, 0, 0]
        self.cnt0 = 0
        self.t0: Cycles = 0
        self.event: Event | None = None
        self.triggers: dict[int, Timer] = {}  # ITRx → the master timer
        self.slaves: list[Slave] = []  # what counts this timer's updates: slave timers, an ADC
        self.outputs: dict[int, tuple[Port, int]] = {}  # channel → (port, pin) its output drives
        self.ref = [0, 0, 0, 0]  # OCxREF

    # --- the counter's input ----------------------------------------------------
    @property
    def running(self) -> int:
        return self.cr1 & 1

    def _master(self) -> Timer | None:
        """The master whose updates clock this timer, in external clock
        mode 1 on an internal trigger."""
        if self.smcr & 7 == 7:
            return self.triggers.get(self.smcr >> 4 & 7)
        return None

    def _tick(self) -> Cycles:
        return cycles(HZ * (self.psc + 1), self.rcc.apb1_timer_hz())

    def _edges(self, a: Cycles, b: Cycles) -> int:
        """Counter ticks in (a, b]."""
        master = self._master()
        if self._external():
            return master.updates_in(a, b) // (self.psc + 1) if master else 0
        return (b - a) // self._tick()

    def _external(self) -> bool:
        return self.smcr & 7 == 7

    def _after(self, n: int) -> Cycles | None:
        """The instant of the n-th tick after t0."""
        master = self._master()
        if self._external():
            return master.update_at(self.t0, n * (self.psc + 1)) if master and master.running else None
        return self.t0 + n * self._tick()

    def reached(self, ch: int) -> Cycles | None:
        """The instant the counter became (or, less than half its range
        ahead, will become) equal to CCRx: a compare written after the
        counter passed it never matches, yet it says when the event it was
        written for was due. Reads the counter without touching its flags;
        None for a timer stopped or clocked by another."""
        if not self.running or self._external():
            return None
        k = self._edges(self.t0, self.clock.now)
        span = self.arr + 1
        back = (self.cnt0 + k - self.ccr[ch]) % span
        if back > span // 2:
            back -= span  # not reached yet: an edge now is early
        return self.t0 + (k - back) * self._tick()

    # --- this timer as a master ---------------------------------------------------
    def _first_overflow(self) -> Cycles:
        return self.t0 + (self.arr + 1 - self.cnt0) * self._tick()

    def updates_in(self, a: Cycles, b: Cycles) -> int:
        """Its overflows in (a, b], at its present settings."""
        if not self.running or self._external() or b <= a:
            return 0
        first, period = self._first_overflow(), (self.arr + 1) * self._tick()

        def upto(t: Cycles) -> int:  # overflows at or before t
            return 0 if t < first else (t - first) // period + 1

        return upto(b) - upto(a)

    def update_at(self, after: Cycles, n: int) -> Cycles:
        """The instant of its n-th overflow after `after`."""
        first, period = self._first_overflow(), (self.arr + 1) * self._tick()
        k = 0 if after < first else (after - first) // period + 1
        return first + (k + n - 1) * period

    # --- time ---------------------------------------------------------------
    def _advance(self) -> None:
        """Brings the counter and its flags to now."""
        now = self.clock.now
        if not self.running:
            self.t0 = now
            return
        k = self._edges(self.t0, now)
        if self._external():
            self.t0 = now
        else:
            self.t0 += k * self._tick()
        if k == 0:
            return
        span = self.arr + 1
        old = self.cnt0
        for ch in range(4):
            if self.ccr[ch] <= self.arr and (k >= span or (self.ccr[ch] - old - 1) % span < k):
                self.sr |= 1 << (ch + 1)
                first = (self.ccr[ch] - old - 1) % span + 1
                matches = (k - first) // span + 1
                self._on_match(ch, matches)
        wrapped = old + k > self.arr
        self.cnt0 = (old + k) % span
        if wrapped:
            self._update_event(hardware=True)

    # --- outputs ----------------------------------------------------------------
    def _oc_mode(self, ch: int) -> int:
        return self.ccmr[ch // 2] >> (4 + 8 * (ch % 2)) & 7

    def _on_match(self, ch: int, matches: int) -> None:
        mode = self._oc_mode(ch)
        if mode == 1:
            self.ref[ch] = 1
        elif mode == 2:
            self.ref[ch] = 0
        elif mode == 3:
            self.ref[ch] ^= matches & 1

    def _drive_outputs(self) -> None:
        """The outputs' levels at the counter's present value."""
        for ch, (port, pin) in self.outputs.items():
            mode = self._oc_mode(ch)
            if mode in (4, 5):
                self.ref[ch] = mode - 4
            elif mode in (6, 7):
                below = self.cnt0 < self.ccr[ch]
                self.ref[ch] = int(below) if mode == 6 else int(not below)
            if self.ccer >> (4 * ch) & 1:
                port.drive(pin, self.ref[ch] ^ (self.ccer >> (4 * ch + 1) & 1))
            else:
                port.drive(pin, None)

    def _output_changes(self) -> bool:
        """Whether a driven output changes as the counter runs."""
        return any(self.ccer >> (4 * ch) & 1 and self._oc_mode(ch) in (1, 2, 3, 6, 7) for ch in self.outputs)

    def _schedule(self) -> None:
        if self.event:
            self.event.cancel()
            self.event = None
        if not self.running:
            return
        span = self.arr + 1
        ahead = []
        preload_pending = self.psc_pre != self.psc or self.arr_pre != self.arr
        outputs = self._output_changes()
        if self.dier & UIE_UIF or preload_pending or outputs:
            ahead.append(self.arr - self.cnt0 + 1)
        for ch in range(4):
            watched = self.dier >> (ch + 1) & 1 or (outputs and ch in self.outputs)
            if watched and self.ccr[ch] <= self.arr:
                d = (self.ccr[ch] - self.cnt0) % span
                ahead.append(d or span)
        if not ahead:
            return
        at = self._after(min(ahead))
        if at is not None:
            self.event = self.clock.at(-(-at // 1), self._due)

    def _due(self) -> None:
        self.event = None
        # The slaves count this timer's updates at its settings up to now,
        # before an update here loads new ones.
        for s in self.slaves:
            s._advance()
        self._advance()
        self._line()
        self._drive_outputs()
        self._schedule()
        for s in self.slaves:
            s._schedule()

    def _update_event(self, hardware: bool) -> None:
        """UEV: preloads take effect; UIF unless UG with URS set. UDIS
        suppresses it (a UG still restarts the counter)."""
        if self.cr1 >> 1 & 1:
            return
        self.psc = self.psc_pre
        self.arr = self.arr_pre
        if hardware or not self.cr1 >> 2 & 1:
            self.sr |= 1

    def _line(self) -> None:
        self.nvic.line(self.irq, bool(self.sr & self.dier & 0x5F))

    # --- registers -------------------------------------------------------------
    def read(self, offset: int) -> int:
        # Its settings may change after this, its slaves must have counted.
        for s in self.slaves:
            s._advance()
        self._advance()
        self._line()
        if offset == 0x24:
            return self.cnt0
        return {
            0x00: self.cr1,
            0x04: self.cr2,
            0x08: self.smcr,
            0x0C: self.dier,
            0x10: self.sr,
            0x18: self.ccmr[0],
            0x1C: self.ccmr[1],
            0x20: self.ccer,
            0x28: self.psc_pre,
            0x2C: self.arr_pre,
        }.get(offset, self.ccr[(offset - 0x34) // 4] if 0x34 <= offset <= 0x40 else 0)

    def write(self, offset: int, value: int) -> None:
        # A slave counts this timer's updates at its settings until now.
        for s in self.slaves:
            s._advance()
        self._advance()
        if offset == 0x00:
            self.cr1 = value & 0x3FF
        elif offset == 0x04:
            self.cr2 = value
        elif offset == 0x08:
            self.smcr = value
        elif offset == 0x0C:
            self.dier = value
        elif offset == 0x10:
            self.sr &= value | ~0x1E5F
        elif offset == 0x14:
            if value & 1:  # UG: the counter restarts, the preloads load
                self.cnt0 = 0
                self.t0 = self.clock.now
                self._update_event(hardware=False)
                for s in self.slaves:
                    s._trigger_edge(self)
            self.sr |= value & 0x1E
        elif offset in (0x18, 0x1C):
            self.ccmr[(offset - 0x18) // 4] = value
        elif offset == 0x20:
            self.ccer = value
        elif offset == 0x24:
            self.cnt0 = value & self.top
            self.t0 = self.clock.now
        elif offset == 0x28:
            self.psc_pre = value & 0xFFFF
        elif offset == 0x2C:
            self.arr_pre = value & self.top
            if not self.cr1 >> 7 & 1:
                self.arr = self.arr_pre
        elif 0x34 <= offset <= 0x40:
            self.ccr[(offset - 0x34) // 4] = value & self.top
        self._line()
        self._drive_outputs()
        self._schedule()
        for s in self.slaves:
            s._schedule()

    def _trigger_edge(self, master: Timer) -> None:
        """A software update of `master` (EGR.UG) is one more input edge
        when this timer counts its updates (psc 0)."""
        if self.running and self._master() is master and self.psc == 0:
            span = self.arr + 1
            for ch in range(4):
                if self.ccr[ch] == (self.cnt0 + 1) % span:
                    self.sr |= 1 << (ch + 1)
            if self.cnt0 == self.arr:
                self._update_event(hardware=True)
            self.cnt0 = (self.cnt0 + 1) % span
            self._line()
            self._drive_outputs()
            self._schedule()
