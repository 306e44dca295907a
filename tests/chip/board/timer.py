"""The general-purpose timers TIM2–TIM5 (RM0090 §18), counting up: the
prescaler and, with ARPE, the auto-reload are preloaded and take effect
at an update event (overflow or EGR.UG); a compare flag is set whenever
the counter becomes equal to its CCR, whether or not its interrupt is
enabled; status flags are cleared by writing 0 (rc_w0); the interrupt
line is asserted while a flag and its enable are both set.

The counter is not stepped tick by tick: it is a linear function of the
virtual time between events, and the next overflow or match is scheduled
on the clock."""

from fractions import Fraction

from bus import Block
from clock import HZ


class Timer(Block):
    def __init__(self, name, irq, bits, clock, nvic, rcc):
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
        self.t0 = Fraction(0)
        self.event = None
        self.on_trgo = None  # called at each update event when CR2.MMS = 010
        self.updates = 0
        self.matches = [0, 0, 0, 0]

    # --- time ----------------------------------------------------------------
    def _tick(self):
        return Fraction(HZ * (self.psc + 1), self.rcc.apb1_timer_hz())

    @property
    def running(self):
        return self.cr1 & 1

    def _advance(self):
        """Brings the counter to now; returns whether it wrapped."""
        if not self.running:
            self.t0 = Fraction(self.clock.now)
            return False
        tick = self._tick()
        ticks = int((self.clock.now - self.t0) / tick)
        self.t0 += ticks * tick
        count = self.cnt0 + ticks
        wrapped = count > self.arr
        self.cnt0 = count % (self.arr + 1)
        return wrapped

    def _schedule(self):
        if self.event:
            self.event.cancel()
            self.event = None
        if not self.running:
            return
        span = self.arr + 1
        ahead = [self.arr - self.cnt0 + 1]
        for ccr in self.ccr:
            if ccr <= self.arr:
                d = (ccr - self.cnt0) % span
                ahead.append(d or span)
        at = self.t0 + min(ahead) * self._tick()
        self.event = self.clock.at(int(-(-at // 1)), self._due)

    def _due(self):
        self.event = None
        if self._advance():
            self._update_event(hardware=True)
        for ch in range(4):
            if self.cnt0 == self.ccr[ch]:
                self.sr |= 1 << (ch + 1)
                self.matches[ch] += 1
        self._line()
        self._schedule()

    def _update_event(self, hardware):
        """UEV: preloads take effect; UIF unless UG with URS set."""
        self.psc = self.psc_pre
        self.arr = self.arr_pre
        self.updates += 1
        if hardware or not self.cr1 >> 2 & 1:
            self.sr |= 1
        if self.cr2 >> 4 & 7 == 2 and self.on_trgo:
            self.on_trgo()

    def _line(self):
        self.nvic.line(self.irq, bool(self.sr & self.dier & 0x5F))

    # --- registers -------------------------------------------------------------
    def read(self, offset):
        if offset == 0x24:
            self._advance()
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

    def write(self, offset, value):
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
                self.t0 = Fraction(self.clock.now)
                self._update_event(hardware=False)
            self.sr |= value & 0x1E
        elif offset in (0x18, 0x1C):
            self.ccmr[(offset - 0x18) // 4] = value
        elif offset == 0x20:
            self.ccer = value
        elif offset == 0x24:
            self.cnt0 = value & self.top
            self.t0 = Fraction(self.clock.now)
        elif offset == 0x28:
            self.psc_pre = value & 0xFFFF
        elif offset == 0x2C:
            self.arr_pre = value & self.top
            if not self.cr1 >> 7 & 1:
                self.arr = self.arr_pre
        elif 0x34 <= offset <= 0x40:
            self.ccr[(offset - 0x34) // 4] = value & self.top
        self._line()
        self._schedule()
