"""GPIO ports, SYSCFG's EXTI routing and the EXTI controller (RM0090 §8,
§9, §12).

A pin's level is what drives it: its output latch when it is an output
(MODER 01, or an alternate function whose peripheral drives it, reported
by `drive`), else what the plant drives from outside (`set_input`), else
the board's resistor (`resistors`: 10 kΩ, stronger than the internal
40 kΩ), else its internal pull (PUPDR), else the last level (a floating
input keeps its charge).
Every change of an output's level is logged with its time, and so is the
level a pin takes when it stops being driven (a reset); every change of a
level reaches the EXTI."""

from __future__ import annotations

from typing import Protocol

from .bus import Block
from .nvic import Nvic

GPIO_BASE = 0x4002_0000
SYSCFG_BASE, EXTI_BASE = 0x4001_3800, 0x4001_3C00
# EXTI lines' IRQs: 0–4 one each, 5–9 and 10–15 shared (RM0090 Table 61).
EXTI_IRQ = [6, 7, 8, 9, 10] + [23] * 5 + [40] * 6
# Reset values (RM0090 §8.4): PA13–15 and PB3–4 are the debug port's
# alternate functions, with their pulls, SWDIO (PA13) and SWO (PB3) fast.
MODER_RESET = {"A": 0xA800_0000, "B": 0x0000_0280}
OSPEEDR_RESET = {"A": 0x0C00_0000, "B": 0x0000_00C0}
PUPDR_RESET = {"A": 0x6400_0000, "B": 0x0000_0100}


class Wiring(Protocol):
    """What a port tells the board it is on (the board's `Board`)."""

    def log_pin(self, port: Port, pin: int, level: int) -> None:
        """A driven pin's level changed, or the pin started or stopped being driven."""

    def edge(self, port: Port, pin: int, level: int) -> None:
        """A pin's level changed."""

    def reading(self, port: Port) -> None:
        """The image is about to read the port's inputs."""


class Port(Block):
    def __init__(self, letter: str, board: Wiring) -> None:
        self.name = f"GPIO{letter}"
        self.letter = letter
        self.index = ord(letter) - ord("A")
        self.board = board
        self.outside: dict[int, int] = {}  # pin → level the plant drives
        self.resistors: dict[int, int] = {}  # pin → level the board's pull resistor gives
        self.level = [0] * 16
        self._registers_reset()

    def _registers_reset(self) -> None:
        self.moder = MODER_RESET.get(self.letter, 0)
        self.otyper = 0
        self.ospeedr = OSPEEDR_RESET.get(self.letter, 0)
        self.pupdr = PUPDR_RESET.get(self.letter, 0)
        self.odr = 0
        self.afr = [0, 0]
        self.alternate: dict[int, int] = {}  # pin → level a peripheral drives

    def reset(self) -> None:
        """A system reset: the registers to their reset values, the pins
        let go."""
        before = self.moder
        self._registers_reset()
        self._settle(before)

    def mode(self, pin: int) -> int:
        return self.moder >> (2 * pin) & 3

    def _resolve(self, pin: int) -> int:
        mode = self.mode(pin)
        if mode == 1:
            return self.odr >> pin & 1
        if mode == 2 and pin in self.alternate:
            return self.alternate[pin]
        if pin in self.outside:
            return self.outside[pin]
        if pin in self.resistors:
            return self.resistors[pin]
        pull = self.pupdr >> (2 * pin) & 3
        return {1: 1, 2: 0}.get(pull, self.level[pin])

    def _settle(self, modes_before: int | None = None) -> None:
        for pin in range(16):
            driven = self.mode(pin) in (1, 2)
            was_driven = modes_before is not None and modes_before >> (2 * pin) & 3 in (1, 2)
            new = self._resolve(pin)
            changed = new != self.level[pin]
            self.level[pin] = new
            if (modes_before is not None and driven != was_driven) or (changed and driven):
                self.board.log_pin(self, pin, new)
            if changed:
                self.board.edge(self, pin, new)

    def set_input(self, pin: int, level: int) -> None:
        self.outside[pin] = level
        self._settle()

    def drive(self, pin: int, level: int | None) -> None:
        """An alternate function's output (a timer's PWM); None: the
        peripheral does not drive it."""
        if level is None:
            self.alternate.pop(pin, None)
        else:
            self.alternate[pin] = level
        self._settle()

    def read(self, offset: int) -> int:
        if offset == 0x10:
            self.board.reading(self)
        return {
            0x00: self.moder,
            0x04: self.otyper,
            0x08: self.ospeedr,
            0x0C: self.pupdr,
            0x10: sum(l << p for p, l in enumerate(self.level)),
            0x14: self.odr,
            0x20: self.afr[0],
            0x24: self.afr[1],
        }.get(offset, 0)

    def write(self, offset: int, value: int) -> None:
        before = self.moder
        if offset == 0x00:
            self.moder = value
        elif offset == 0x04:
            self.otyper = value & 0xFFFF
        elif offset == 0x08:
            self.ospeedr = value
        elif offset == 0x0C:
            self.pupdr = value
        elif offset == 0x14:
            self.odr = value & 0xFFFF
        elif offset == 0x18:  # BSRR: BR clears, BS sets, BS wins (RM0090 §8.4.7)
            self.odr = (self.odr & ~(value >> 16) | value) & 0xFFFF
        elif offset in (0x20, 0x24):
            self.afr[(offset - 0x20) // 4] = value
        self._settle(before)


class Syscfg(Block):
    name = "SYSCFG"

    def __init__(self) -> None:
        self.regs: dict[int, int] = {}

    def port_of(self, line: int) -> int:
        """The port index EXTICR routes to `line`."""
        return self.regs.get(0x08 + 4 * (line // 4), 0) >> (4 * (line % 4)) & 0xF

    def read(self, offset: int) -> int:
        return self.regs.get(offset, 0)

    def write(self, offset: int, value: int) -> None:
        self.regs[offset] = value


class Exti(Block):
    """Edges on the routed pins set PR when their trigger is selected; PR is
    written 1 to clear; a line asserts its IRQ while PR and IMR are both
    set (RM0090 §12.2)."""

    name = "EXTI"

    def __init__(self, nvic: Nvic, syscfg: Syscfg) -> None:
        self.nvic = nvic
        self.syscfg = syscfg
        self.imr = self.emr = self.rtsr = self.ftsr = self.pr = 0
        self.edges: list[tuple[int, bool, bool]] = []  # (line, rising, latched)

    def edge(self, port_index: int, pin: int, rising: bool) -> None:
        if pin > 15 or self.syscfg.port_of(pin) != port_index:
            return
        selected = (self.rtsr if rising else self.ftsr) >> pin & 1
        if selected:
            self.pr |= 1 << pin
        # The edges of lines in use (a trigger selected, or unmasked).
        if (self.rtsr | self.ftsr | self.imr) >> pin & 1:
            self.edges.append((pin, rising, bool(selected)))
        self._lines()

    def _lines(self) -> None:
        asserted = self.pr & self.imr
        for irq in sorted(set(EXTI_IRQ)):
            self.nvic.line(irq, any(asserted >> n & 1 for n in range(16) if EXTI_IRQ[n] == irq))

    def read(self, offset: int) -> int:
        return {0x00: self.imr, 0x04: self.emr, 0x08: self.rtsr, 0x0C: self.ftsr, 0x14: self.pr}.get(offset, 0)

    def write(self, offset: int, value: int) -> None:
        if offset == 0x00:
            self.imr = value
        elif offset == 0x04:
            self.emr = value
        elif offset == 0x08:
            self.rtsr = value
        elif offset == 0x0C:
            self.ftsr = value
        elif offset == 0x10:  # SWIER
            self.pr |= value & self.imr
        elif offset == 0x14:
            self.pr &= ~value
        self._lines()
