"""Clocks, flash interface, power and the independent watchdog, as RM0090
describes them (§6 RCC, §3.8 FLASH, §5 PWR, §21 IWDG)."""

from collections.abc import Callable
from typing import ClassVar

from .bus import Block
from .clock import HZ, Clock, Event

RCC_BASE, FLASH_BASE, PWR_BASE, IWDG_BASE = 0x4002_3800, 0x4002_3C00, 0x4000_7000, 0x4000_3000


HSI_HZ = 16_000_000
# RCC_CR's bits (RM0090 §7.3.1).
HSEON, HSERDY, CSSON, PLLON, PLLRDY = 1 << 16, 1 << 17, 1 << 19, 1 << 24, 1 << 25
# RCC_CIR: the clock security system's flag and its clear.
CSSF, CSSC = 1 << 7, 1 << 23


class Rcc(Block):
    """The clock tree from its registers: HSIRDY, LSERDY, LSIRDY and
    PLLI2SRDY follow their enables; HSERDY follows HSEON only while a
    crystal (`crystal_hz`, None for none fitted) oscillates, PLLRDY PLLON
    only while the PLL's source is ready; SWS follows SW; CSR keeps the
    reset flags (cleared by RMVF). SYSCLK and the USB clock are computed
    from SW and PLLCFGR (M, N, P, Q, the source), so that a wrong crystal
    gives the clocks it would give. The oscillators start at once: the
    image polls, and nothing times them.

    A crystal that stops (`stop_crystal`) with CSSON set raises the clock
    security system's NMI (`on_css`), sets CIR.CSSF and switches SYSCLK to
    the HSI, the HSE and a PLL fed by it off (RM0090 §7.2.7); without CSSON
    a core clocked from it stops (`on_clock_lost`). CSSON stays as software
    set it. The virtual time stays in 168 MHz cycles; the core charges
    168 MHz / SYSCLK of them per instruction (core.py)."""

    name = "RCC"
    # BDCR (LSE), CSR (LSI): the enables' bits, each ready bit the next.
    READY: ClassVar[dict[int, tuple[int, ...]]] = {0x70: (0,), 0x74: (0,)}

    def __init__(self, crystal_hz: int | None = 8_000_000) -> None:
        self.crystal_hz = crystal_hz
        self.oscillating = crystal_hz is not None
        self.regs = self._reset_values()
        self.on_css: Callable[[], object] = lambda: None
        self.on_clock_lost: Callable[[], object] = lambda: None
        # Every SYSCLK the image selected, and the USB clock with it.
        self.selected: list[tuple[int, int | None]] = []

    @staticmethod
    def _reset_values() -> dict[int, int]:
        # RM0090 reset values: CR HSION|HSIRDY, PLLCFGR, CFGR 0, CSR PORRSTF|PINRSTF.
        return {0x00: 0x0000_0083, 0x04: 0x2400_3010, 0x74: 0x0E00_0000}

    def read(self, offset: int) -> int:
        v = self.regs.get(offset, 0)
        if offset == 0x08:
            v = (v & ~0xC) | (v & 3) << 2
        return v

    def _cr(self, value: int) -> int:
        """CR's ready bits from its enables and the oscillators."""
        value = value | 2 if value & 1 else value & ~2  # HSI
        hse = bool(value & HSEON) and self.oscillating
        value = value | HSERDY if hse else value & ~HSERDY
        pll_ready = value & PLLON and (hse if self.pll_from_hse() else value & 2)
        value = value | PLLRDY if pll_ready else value & ~PLLRDY
        return value | 1 << 27 if value >> 26 & 1 else value & ~(1 << 27)  # PLLI2S

    def write(self, offset: int, value: int) -> None:
        if offset == 0x00:
            value = self._cr(value)
        if offset in self.READY:
            for on in self.READY[offset]:
                value = value | 1 << (on + 1) if value >> on & 1 else value & ~(1 << (on + 1))
        if offset == 0x0C:  # CIR: CSSC clears CSSF; the flags are read-only
            flags = self.regs.get(0x0C, 0) & 0xFF
            value = value & 0x7F00 | (flags & ~CSSF if value & CSSC else flags)
        if offset == 0x74:  # CSR: LSION, LSIRDY; RMVF clears the reset flags
            flags = 0 if value >> 24 & 1 else self.regs.get(0x74, 0) & 0xFE00_0000
            value = value & 3 | flags
        switched = offset == 0x08 and value & 3 != self.regs.get(0x08, 0) & 3
        self.regs[offset] = value
        if offset == 0x04:
            self.regs[0x00] = self._cr(self.regs.get(0x00, 0))
        if switched:
            self.selected.append((self.sysclk_hz(), self.usb_hz()))

    def reset(self, cause_bit: int) -> None:
        """A system reset: registers to their reset values, CSR's flags kept
        with `cause_bit` (29 IWDGRSTF, 28 SFTRSTF) and PINRSTF set, BDCR kept
        (the backup domain is not reset)."""
        flags = self.regs.get(0x74, 0) & 0xFE00_0000 | 1 << cause_bit | 1 << 26
        bdcr = self.regs.get(0x70, 0)
        self.regs = self._reset_values()
        self.regs[0x74] = flags
        self.regs[0x70] = bdcr

    def stop_crystal(self) -> None:
        """The crystal stops oscillating (a broken joint, a cracked crystal)."""
        cr = self.regs.get(0x00, 0)
        was_ready = bool(cr & HSERDY)
        self.oscillating = False
        if not was_ready:
            return
        on_hse = self._on_hse()
        if cr & CSSON:
            self.regs[0x0C] = self.regs.get(0x0C, 0) | CSSF
            cr &= ~HSEON
            if self.pll_from_hse():
                cr &= ~PLLON
            self.regs[0x00] = self._cr(cr)
            if on_hse:
                self.regs[0x08] = self.regs.get(0x08, 0) & ~3
                self.selected.append((self.sysclk_hz(), self.usb_hz()))
            self.on_css()
        else:
            self.regs[0x00] = self._cr(cr)
            if on_hse:
                self.on_clock_lost()

    def pll_from_hse(self) -> bool:
        return bool(self.regs.get(0x04, 0) >> 22 & 1)

    def _on_hse(self) -> bool:
        """Whether SYSCLK comes from the crystal (directly or by the PLL)."""
        sw = self.regs.get(0x08, 0) & 3
        return sw == 1 or (sw == 2 and self.pll_from_hse())

    def _vco_hz(self) -> float:
        pllcfgr = self.regs.get(0x04, 0)
        source = (self.crystal_hz or 0) if self.pll_from_hse() else HSI_HZ
        m, n = pllcfgr & 0x3F, pllcfgr >> 6 & 0x1FF
        return source / m * n if m else 0.0

    def sysclk_hz(self) -> int:
        """SYSCLK as SW and PLLCFGR make it (RM0090 §7.2)."""
        sw = self.regs.get(0x08, 0) & 3
        if sw == 1:
            return self.crystal_hz or 0
        if sw == 2:
            p = 2 * ((self.regs.get(0x04, 0) >> 16 & 3) + 1)
            return round(self._vco_hz() / p)
        return HSI_HZ

    def usb_hz(self) -> int | None:
        """The PLL's 48 MHz output (Q), None while the PLL is off."""
        if not self.regs.get(0x00, 0) & PLLRDY:
            return None
        q = self.regs.get(0x04, 0) >> 24 & 0xF
        return round(self._vco_hz() / q) if q >= 2 else None

    def rtc_prescaler(self) -> int:
        """CFGR.RTCPRE: the crystal's divider into HSE_RTC (0 and 1: no clock)."""
        return self.regs.get(0x08, 0) >> 16 & 0x1F

    def hse_hz(self) -> int:
        """The crystal's frequency while it oscillates and HSEON is set, else 0."""
        return (self.crystal_hz or 0) if self.regs.get(0x00, 0) & HSERDY else 0

    def apb2_hz(self) -> int:
        """PCLK2: the ADCs' clock source (RM0090 §6.2)."""
        ppre2 = self.regs.get(0x08, 0) >> 13 & 7
        return self.sysclk_hz() if ppre2 < 4 else self.sysclk_hz() // (2 << (ppre2 - 4))

    def apb2_timer_hz(self) -> int:
        """TIM1 and TIM8–11's clock: PCLK2, doubled when APB2 is divided."""
        return self.apb2_hz() * (1 if self.regs.get(0x08, 0) >> 13 & 7 < 4 else 2)

    def apb1_timer_hz(self) -> int:
        """TIM2–5's clock: PCLK1, doubled when APB1 is divided (RM0090 §6.2)."""
        sysclk = self.sysclk_hz()
        ppre1 = self.regs.get(0x08, 0) >> 10 & 7
        return sysclk if ppre1 < 4 else 2 * sysclk // (2 << (ppre1 - 4))


class Iwdg(Block):
    """The independent watchdog on the 32 kHz LSI: KR 0xCCCC starts it,
    0xAAAA reloads, 0x5555 unlocks PR and RLR; it counts RLR down at
    LSI/(4·2^PR) and resets the system at 0. DBGMCU's freeze bit matters
    under a debugger only, and no debugger halts this core."""

    name = "IWDG"
    LSI_HZ = 32_000

    def __init__(self, clock: Clock, on_expiry: Callable[[], object]) -> None:
        self.clock = clock
        self.on_expiry = on_expiry
        self.pr, self.rlr = 0, 0xFFF
        self.unlocked = False
        self.running = False
        self.expiry: Event | None = None
        self.reloads: list[int] = []  # cycles of every reload

    def _period(self, count: int | None = None) -> int:
        """Cycles to count `count` (RLR's) down to 0: LSI over 4·2^PR, at most
        256."""
        count = self.rlr if count is None else count
        return min(4 << self.pr, 256) * (count + 1) * HZ // self.LSI_HZ

    def _arm(self, count: int | None = None) -> None:
        if self.expiry:
            self.expiry.cancel()
        self.expiry = self.clock.at(self.clock.now + self._period(count), self.on_expiry)

    def read(self, offset: int) -> int:
        return {0x04: self.pr, 0x08: self.rlr}.get(offset, 0)

    def write(self, offset: int, value: int) -> None:
        value &= 0xFFFF
        if offset == 0x00:
            if value == 0xCCCC:  # the count starts from its reset value, 0xFFF
                self.running = True
                self._arm(0xFFF)
            elif value == 0xAAAA and self.running:
                self.reloads.append(self.clock.now)
                self._arm()
            self.unlocked = value == 0x5555
        elif offset == 0x04 and self.unlocked:
            self.pr = value & 7
        elif offset == 0x08 and self.unlocked:
            self.rlr = value & 0xFFF
