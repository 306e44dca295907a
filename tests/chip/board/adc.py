"""ADC1 and the ADCs' common registers (RM0090 §13): regular conversions
of the first channel of the sequence, started by the rising edges of
TIM2's TRGO (EXTSEL 0110) or by SWSTART, each taking the channel's
sampling time plus 12 ADC clocks (ADCCLK = PCLK2 / 2·(ADCPRE+1)); the
input is sampled at the end of the sampling time, from the plant.

The results leave through the data register: with CR2.DMA set a request
takes each one to DMA2 stream 0 (which reads DR, clearing EOC, §13.13.1);
a result the DMA does not take stays in DR with EOC set, and the next one
is lost: OVR is set ("overrun detection is enabled only when DMA = 1 or
EOCS = 1") and "further regular triggers are ignored" until software
clears it (§13.8.1). A result waiting in DR goes to the stream as soon as
the stream takes requests again.

Conversions are not stepped one by one: the triggers are TIM2's update
instants, computed, and the conversions are brought up to now whenever
the ADC, the DMA or TIM2 is touched, or when a DMA flag whose interrupt is
enabled falls due (the only moment the core can observe by itself).
Assumed where RM0090 is silent: a trigger during a conversion is ignored
(the image's triggers are a sample period, at least 5 µs, apart).
Not modelled: scan sequences, continuous mode, injected channels, the
analog watchdog, ADC2 and ADC3 (their registers hold what is written)."""

from .bus import Block
from .clock import HZ, Clock, Cycles, Event, cycles
from .dma import Dma
from .nvic import Nvic
from .plant import Plant
from .system import Rcc
from .timer import Timer

ADC_BASE = 0x4001_2000
ADC_IRQ = 18
DR = ADC_BASE + 0x4C
EXTSEL_TIM2_TRGO = 0b0110
# Sampling time in ADC clocks per SMPx code.
SAMPLE_CLOCKS = (3, 15, 28, 56, 84, 112, 144, 480)
AWD, EOC, JEOC, JSTRT, STRT, OVR = 1, 2, 4, 8, 16, 32


class Adc(Block):
    name = "ADC"

    def __init__(self, clock: Clock, nvic: Nvic, rcc: Rcc, trigger_timer: Timer, dma: Dma) -> None:
        self.clock = clock
        self.nvic = nvic
        self.rcc = rcc
        self.timer = trigger_timer
        self.dma = dma
        self.plant: Plant | None = None  # the photodiode's source; None: the input at ground
        self.sr = self.cr1 = self.cr2 = self.dr = self.ccr = 0
        self.regs: dict[int, int] = {}  # sampling times, sequences, other ADCs: held as written
        self.seen: Cycles = 0  # triggers up to here are collected
        self.waiting: list[Cycles] = []  # trigger instants whose conversions have not ended
        self.event: Event | None = None
        self.conversions = 0  # ended, for the board's report
        self.lost = 0  # results overwritten or dropped by an overrun
        dma.before_access = self._advance
        dma.after_write = self._after_dma_write

    # --- timing ------------------------------------------------------------------
    def _adcclk_cycles(self) -> Cycles:
        """Core cycles per ADC clock."""
        prescaler = 2 * ((self.ccr >> 16 & 3) + 1)
        return cycles(HZ * prescaler, self.rcc.apb2_hz())

    def _channel(self) -> int:
        return self.regs.get(0x34, 0) & 0x1F

    def _sample_cycles(self) -> Cycles:
        ch = self._channel()
        smpr = self.regs.get(0x10, 0) if ch < 10 else self.regs.get(0x0C, 0)
        smp = smpr >> (3 * (ch % 10)) & 7
        return SAMPLE_CLOCKS[smp] * self._adcclk_cycles()

    def _conversion_cycles(self) -> Cycles:
        return self._sample_cycles() + 12 * self._adcclk_cycles()

    def _listening(self) -> bool:
        """Whether the ADC is on and takes TIM2's TRGO as its trigger."""
        return bool(self.cr2 & 1 and self.cr2 >> 28 & 3 and self.cr2 >> 24 & 0xF == EXTSEL_TIM2_TRGO)

    def _triggered(self) -> bool:
        """Whether TIM2's updates start conversions now."""
        t = self.timer
        return bool(self._listening() and t.cr2 >> 4 & 7 == 0b010 and t.running and not t._external())

    # --- the chain, brought up to now ---------------------------------------------
    def _advance(self) -> None:
        now = self.clock.now
        self._offer_waiting_result()
        if self._triggered() and now > self.seen:
            n = self.timer.updates_in(self.seen, now)
            if n:
                first = self.timer.update_at(self.seen, 1)
                period = (self.timer.arr + 1) * self.timer._tick()
                if period < self._conversion_cycles():
                    raise NotImplementedError("ADC1 triggered faster than it converts")
                self.waiting.extend(first + k * period for k in range(n))
        self.seen = now
        conv = self._conversion_cycles()
        done = 0
        while done < len(self.waiting) and self.waiting[done] + conv <= now:
            done += 1
        if done:
            triggers, self.waiting = self.waiting[:done], self.waiting[done:]
            self._convert(triggers)

    def _convert(self, triggers: list[Cycles]) -> None:
        """The conversions started at `triggers` (evenly spaced, in order)
        have ended: their results go to the DMA or to DR."""
        if self.sr & OVR:
            return  # "further regular triggers are ignored"
        self.sr |= STRT
        n = len(triggers)
        step = triggers[1] - triggers[0] if n > 1 else 0
        start = triggers[0] + self._sample_cycles()
        data = self.plant.convert(n, float(start), float(step)) if self.plant else bytes(2 * n)
        self.conversions += n
        taken = self.dma.receive(data) if self._requests() else 0
        if taken:
            self.dr = data[2 * taken - 2] | data[2 * taken - 1] << 8
        for k in range(taken, n):
            code = data[2 * k] | data[2 * k + 1] << 8
            if self.sr & EOC and (self.cr2 >> 8 & 1 or self.cr2 >> 10 & 1):
                self.sr |= OVR
                self.lost += n - k
                break
            if self.sr & EOC:
                self.lost += 1
            self.dr = code
            self.sr |= EOC
        self._line()

    def overrun(self) -> None:
        """A result the DMA did not take in time (a test's fault): lost, and
        OVR set."""
        self.sr |= OVR
        self.lost += 1
        self._line()
        self._schedule()

    def _requests(self) -> bool:
        """Whether a result goes to the DMA (DMA bit set, no overrun, the
        stream taking this ADC's requests)."""
        return bool(self.cr2 >> 8 & 1 and not self.sr & OVR and self.dma.accepts(DR))

    def _offer_waiting_result(self) -> None:
        """A result left in DR is requested again: it goes once the stream
        takes it."""
        if self.sr & EOC and self._requests() and self.dma.receive(bytes((self.dr & 0xFF, self.dr >> 8))):
            self.sr &= ~EOC
            self._line()

    def _trigger_edge(self, master: Timer) -> None:
        """A software update of TIM2 (EGR.UG) is a TRGO edge too when its
        master mode is reset or update."""
        if self._listening() and master.cr2 >> 4 & 7 in (0, 2) and not self.sr & OVR:
            self.waiting.append(self.clock.now)
            self._schedule()

    def _schedule(self) -> None:
        """An event when the DMA next sets a flag the core has enabled."""
        if self.event:
            self.event.cancel()
            self.event = None
        items = self.dma.until_flag() if self._requests() else None
        if items is None:
            return
        conv = self._conversion_cycles()
        if items <= len(self.waiting):
            end = self.waiting[items - 1] + conv
        elif self._triggered():
            end = self.timer.update_at(self.seen, items - len(self.waiting)) + conv
        else:
            return
        self.event = self.clock.at(-(-end // 1), self._due)

    def _due(self) -> None:
        self.event = None
        self._advance()
        self._schedule()

    def _after_dma_write(self) -> None:
        self._offer_waiting_result()
        self._schedule()

    def _line(self) -> None:
        enabled = (EOC if self.cr1 >> 5 & 1 else 0) | (OVR if self.cr1 >> 26 & 1 else 0)
        enabled |= (JEOC if self.cr1 >> 7 & 1 else 0) | (AWD if self.cr1 >> 6 & 1 else 0)
        self.nvic.line(ADC_IRQ, bool(self.sr & enabled))

    # --- registers (offsets from ADC1's base; the common block at 0x300) ----------
    def read(self, offset: int) -> int:
        self._advance()
        if offset == 0x00:
            return self.sr
        if offset == 0x04:
            return self.cr1
        if offset == 0x08:
            return self.cr2
        if offset == 0x4C:
            self.sr &= ~EOC
            self._line()
            return self.dr
        if offset == 0x304:
            return self.ccr
        return self.regs.get(offset, 0)

    def write(self, offset: int, value: int) -> None:
        self._advance()
        if offset == 0x00:  # rc_w0
            self.sr &= value | ~0x3F
        elif offset == 0x04:
            self.cr1 = value
        elif offset == 0x08:
            self.cr2 = value & ~(1 << 30 | 1 << 22)
            if value >> 30 & 1 and value & 1 and not self.sr & OVR:  # SWSTART
                self.waiting.append(self.clock.now)
        elif offset == 0x304:
            self.ccr = value
        else:
            self.regs[offset] = value
        self._offer_waiting_result()
        self._line()
        self._schedule()
