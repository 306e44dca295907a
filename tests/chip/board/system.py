"""Clocks, flash interface, power and the independent watchdog, as RM0090
describes them (§6 RCC, §3.8 FLASH, §5 PWR, §21 IWDG)."""

from collections.abc import Callable
from typing import ClassVar

from .bus import Block
from .clock import HZ, Clock, Event

RCC_BASE, FLASH_BASE, PWR_BASE, IWDG_BASE = 0x4002_3800, 0x4002_3C00, 0x4000_7000, 0x4000_3000


class Rcc(Block):
    """Every ready bit follows its enable (HSI, HSE, PLL, PLLI2S, LSE, LSI),
    SWS follows SW, and CSR keeps the reset flags (cleared by RMVF). The
    oscillators are taken to start at once: the image polls, and nothing
    times them."""

    name = "RCC"
    # CR, BDCR (LSE), CSR (LSI): the enables' bits, each ready bit the next.
    READY: ClassVar[dict[int, tuple[int, ...]]] = {0x00: (0, 16, 24, 26), 0x70: (0,), 0x74: (0,)}

    def __init__(self) -> None:
        self.regs = self._reset_values()

    @staticmethod
    def _reset_values() -> dict[int, int]:
        # RM0090 reset values: CR HSION|HSIRDY, PLLCFGR, CFGR 0, CSR PORRSTF|PINRSTF.
        return {0x00: 0x0000_0083, 0x04: 0x2400_3010, 0x74: 0x0E00_0000}

    def read(self, offset: int) -> int:
        v = self.regs.get(offset, 0)
        if offset == 0x08:
            v = (v & ~0xC) | (v & 3) << 2
        return v

    def write(self, offset: int, value: int) -> None:
        if offset in self.READY:
            for on in self.READY[offset]:
                value = value | 1 << (on + 1) if value >> on & 1 else value & ~(1 << (on + 1))
        if offset == 0x74:  # CSR: LSION, LSIRDY; RMVF clears the reset flags
            flags = 0 if value >> 24 & 1 else self.regs.get(0x74, 0) & 0xFE00_0000
            value = value & 3 | flags
        self.regs[offset] = value

    def reset(self, cause_bit: int) -> None:
        """A system reset: registers to their reset values, CSR's flags kept
        with `cause_bit` (29 IWDGRSTF, 28 SFTRSTF) and PINRSTF set, BDCR kept
        (the backup domain is not reset)."""
        flags = self.regs.get(0x74, 0) & 0xFE00_0000 | 1 << cause_bit | 1 << 26
        bdcr = self.regs.get(0x70, 0)
        self.regs = self._reset_values()
        self.regs[0x74] = flags
        self.regs[0x70] = bdcr

    def _sysclk(self) -> int:
        return HZ if self.regs.get(0x08, 0) & 3 == 2 else 16_000_000

    def apb2_hz(self) -> int:
        """PCLK2: the ADCs' clock source (RM0090 §6.2)."""
        ppre2 = self.regs.get(0x08, 0) >> 13 & 7
        return self._sysclk() if ppre2 < 4 else self._sysclk() // (2 << (ppre2 - 4))

    def apb1_timer_hz(self) -> int:
        """TIM2–5's clock: PCLK1, doubled when APB1 is divided (RM0090 §6.2)."""
        sysclk = self._sysclk()
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
