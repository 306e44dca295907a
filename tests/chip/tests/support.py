"""What the models' tests share: the chip's clock tree as the image sets it
up, and virtual time moved on as the core would move it while it sleeps."""

from board.clock import HZ, Clock
from board.gpio import Exti, Port
from board.nvic import Nvic
from board.system import Rcc

# RCC_CFGR as the image programs it (RM0090 §7.3.3): SW = PLL (SYSCLK
# 168 MHz), PPRE1 = /4 (PCLK1 42 MHz, TIM2–TIM5 at 84 MHz), PPRE2 = /2
# (PCLK2 84 MHz).
CFGR = 0b10 | 0b101 << 10 | 0b100 << 13
# RCC_PLLCFGR as the image programs it: the 8 MHz crystal /4 *168 /2
# (168 MHz), /7 for USB (48 MHz); and RCC_CR with the crystal and the PLL on.
PLLCFGR = 4 | 168 << 6 | 1 << 22 | 7 << 24
CR_ON = 1 | 1 << 16 | 1 << 24
TIMER_HZ = 84_000_000
# Core cycles per timer clock.
TIMER_CYCLES = HZ // TIMER_HZ


class Chip:
    """A clock, the NVIC and the RCC: what the peripheral models hang on."""

    def __init__(self) -> None:
        self.clock = Clock()
        self.nvic = Nvic()
        self.nvic.clock = self.clock
        self.rcc = Rcc()
        self.rcc.write(0x04, PLLCFGR)
        self.rcc.write(0x00, CR_ON)
        self.rcc.write(0x08, CFGR)

    @property
    def now(self) -> int:
        return self.clock.now

    def run_to(self, cycle: int) -> None:
        """Virtual time to `cycle`, each event due on the way handled at its
        own cycle (as the core's run does while it sleeps)."""
        while True:
            due = self.clock.next()
            if due is None or due > cycle:
                break
            self.clock.base = max(due, self.clock.base)
            self.clock.fire_due()
        self.clock.base = max(cycle, self.clock.base)

    def run(self, cycles: int) -> None:
        self.run_to(self.clock.now + cycles)


class Recorder:
    """The board as a port sees it (`board.gpio.Wiring`): what the port
    reports, recorded with the time, and each edge passed to an EXTI."""

    def __init__(self, clock: Clock | None = None, exti: Exti | None = None) -> None:
        self.clock = clock
        self.exti = exti
        self.logged: list[tuple[int, str, int]] = []  # (cycle, pin, level): driven levels
        self.edges: list[tuple[int, str, int]] = []  # (cycle, pin, level): every change
        self.readings = 0

    def _now(self) -> int:
        return self.clock.now if self.clock else 0

    def log_pin(self, port: Port, pin: int, level: int) -> None:
        self.logged.append((self._now(), f"P{port.letter}{pin}", level))

    def edge(self, port: Port, pin: int, level: int) -> None:
        self.edges.append((self._now(), f"P{port.letter}{pin}", level))
        if self.exti:
            self.exti.edge(port.index, pin, rising=bool(level))

    def reading(self, port: Port) -> None:
        self.readings += 1
