"""TIM11 as a crystal check uses it (RM0090 §19, TIM10/11/13/14): the
counter on PCLK2's timer clock through PSC, up to ARR; UIF at each
overflow and at EGR.UG; channel 1 capturing its input (CC1S = 01) every
IC1PSC-th rising edge into CCR1 with CC1IF, the input being HSE_RTC (the
crystal divided by RCC_CFGR.RTCPRE) when TIM11_OR.TI1_RMP = 10. Flags
clear by writing 0 (rc_w0), CC1IF also by reading CCR1.

Like the other timers it is not stepped tick by tick: the counter, the
overflows and the captures are functions of the virtual time since the
counter started and since the capture was armed. Not modelled: the
interrupt, the output compare, the input filter and polarity (rising edges
only), the overcapture flag, PSC's preload (it takes effect at once), a GPIO input (an unrouted input never
captures), and the counter's pause while CEN is clear (it reads as it was)."""

from fractions import Fraction

from .bus import Block
from .clock import HZ, Clock
from .system import Rcc

TIM11_BASE = 0x4001_4800
UIF, CC1IF = 1, 1 << 1
HSE_RTC = 0b10


class Tim11(Block):
    name = "TIM11"

    def __init__(self, clock: Clock, rcc: Rcc) -> None:
        self.clock = clock
        self.rcc = rcc
        self.cr1 = self.psc = self.ccmr1 = self.ccer = self.or_ = 0
        self.arr = 0xFFFF
        self.t0 = 0  # the cycle the counter was last 0 (enabled, or UG)
        self.frozen: int | None = 0  # the count while the counter is stopped
        self.overflows_seen = 0  # overflows software has cleared UIF for
        self.uif = False  # UIF from UG
        self.armed_at: int | None = None  # the cycle the capture's input was routed
        self.captures_read = 0

    # --- the counter ------------------------------------------------------------
    def _tick(self) -> Fraction:
        """Core cycles per count."""
        return Fraction(HZ * (self.psc + 1), self.rcc.apb2_timer_hz())

    def _ticks_at(self, cycle: int | Fraction) -> int:
        """Counts since the counter was last 0, at `cycle` (not wrapped)."""
        return int((cycle - self.t0) / self._tick())

    def _overflows(self) -> int:
        return 0 if self.frozen is not None else self._ticks_at(self.clock.now) // (self.arr + 1)

    # --- the capture --------------------------------------------------------------
    def _routed(self) -> bool:
        return self.ccmr1 & 3 == 1 and self.ccer & 1 == 1 and self.or_ & 3 == HSE_RTC

    def _capture_period(self) -> Fraction | None:
        """Core cycles between captures, None while HSE_RTC has no clock."""
        prescaler, hz = self.rcc.rtc_prescaler(), self.rcc.hse_hz()
        if prescaler < 2 or not hz:
            return None
        edges = 1 << (self.ccmr1 >> 2 & 3)
        return Fraction(HZ * prescaler * edges, hz)

    def _captures(self) -> int:
        period = self._capture_period()
        if self.armed_at is None or period is None or self.frozen is not None:
            return 0
        return int((self.clock.now - self.armed_at) / period)

    def _rearm(self) -> None:
        routed = self._routed()
        if routed and self.armed_at is None:
            self.armed_at, self.captures_read = self.clock.now, 0
        elif not routed:
            self.armed_at = None

    # --- registers ------------------------------------------------------------------
    def read(self, offset: int) -> int:
        if offset == 0x00:
            return self.cr1
        if offset == 0x10:
            uif = self.uif or self._overflows() > self.overflows_seen
            return (UIF if uif else 0) | (CC1IF if self._captures() > self.captures_read else 0)
        if offset == 0x18:
            return self.ccmr1
        if offset == 0x20:
            return self.ccer
        if offset == 0x24:
            count = self.frozen if self.frozen is not None else self._ticks_at(self.clock.now)
            return count % (self.arr + 1)
        if offset == 0x28:
            return self.psc
        if offset == 0x2C:
            return self.arr
        if offset == 0x34:
            n = self._captures()
            if n == 0 or self.armed_at is None:
                return 0
            self.captures_read = n
            period = self._capture_period()
            assert period is not None
            return self._ticks_at(self.armed_at + n * period) % (self.arr + 1)
        if offset == 0x50:
            return self.or_
        return 0

    def write(self, offset: int, value: int) -> None:
        if offset == 0x00:
            if value & 1 and self.frozen is not None:
                self.t0 = self.clock.now - int(self.frozen * self._tick())
                self.frozen = None
            elif not value & 1 and self.frozen is None:
                self.frozen = self._ticks_at(self.clock.now) % (self.arr + 1)
            self.cr1 = value & 0x3FF
        elif offset == 0x10:  # rc_w0
            if not value & UIF:
                self.uif, self.overflows_seen = False, self._overflows()
            if not value & CC1IF:
                self.captures_read = self._captures()
        elif offset == 0x14 and value & 1:  # EGR.UG: the counter to 0, PSC loaded, UIF
            self.t0, self.overflows_seen, self.uif = self.clock.now, 0, True
            if self.frozen is not None:
                self.frozen = 0
        elif offset == 0x18:
            self.ccmr1 = value & 0xFFFF
        elif offset == 0x20:
            self.ccer = value & 0xF
        elif offset == 0x28:
            self.psc = value & 0xFFFF
        elif offset == 0x2C:
            self.arr = value & 0xFFFF
        elif offset == 0x50:
            self.or_ = value & 3
        self._rearm()
