"""The virtual STM32F405 board: the core, its memory map and the
peripheral models wired together, running an unmodified image from reset.

    python3 -m board IMAGE [--seconds S] [--set PB12=1@0.5 ...]
        [--fault KIND@WHEN]

(from tests/chip, or anywhere with the package installed)

runs IMAGE for S seconds of virtual time (default 2), the plant driving
each `--set` input pin to its level at its time, and prints one JSON
object: where it stopped and why, the instructions executed, the
interrupts taken, the watchdog's reloads, every change of a driven pin
with its time, and every driven pin's level at the end.

`--fault` injects a fault (`--help` lists them) at WHEN: virtual seconds,
or `laser+S`, S seconds after the laser enable first rises (`laserN+S`:
its N-th rise; `dmaN+S`: DMA2 stream 0's N-th enable); the report's
`fault` then says when the laser enable went low and the drivers' enables
high after it. A watchdog reset ends the run, the pins let go as a reset
lets them go (the board's resistors then hold them)."""

import argparse
import itertools
import json
import os
import re
import shlex
import signal
import sys
import time
import tty
from collections import deque
from fractions import Fraction
from typing import Any

from unicorn import UC_HOOK_MEM_WRITE, Uc
from unicorn import arm_const as arm

from .adc import ADC_BASE, Adc
from .bus import Bus, Plain
from .clock import HZ, Clock
from .core import Blocked, Core, Fault
from .dma import DMA2_BASE, Dma
from .emulate import Elf, Machine, by_function
from .gpio import EXTI_BASE, GPIO_BASE, SYSCFG_BASE, Exti, Port, Syscfg
from .nvic import Nvic, SystemResetRequest
from .otg import OTG_FS_BASE, OtgFs
from .plant import Plant
from .system import FLASH_BASE, IWDG_BASE, PWR_BASE, RCC_BASE, Iwdg, Rcc
from .tim11 import TIM11_BASE, Tim11
from .timer import Timer
from .usb_host import Host, bus_power

# The reference board's wiring (firmware/src/bin/head/chip/pins.rs): the
# E-STOP and the three home switches are normally closed to ground, so they
# are held low unless a test opens them (`--set PB12=1@T`) or, for the home
# switches, a plant drives them.
CLOSED_SWITCHES = ("PB12", "PC3", "PC7", "PC11")
# The board's pull resistors (pins.rs): they hold the safe state while the
# pins float, from reset until the image drives them.
RESISTORS = {"PA6": 0, "PB0": 0, "PC0": 0, "PC4": 0, "PC8": 0, "PC2": 1, "PC6": 1, "PC10": 1}
# The STEP lines (TIM5's compare interrupt raises them): their edges are
# counted and timed against the compare, not logged one by one.
STEP = ("PC0", "PC4", "PC8")
# The safe state: laser enable and STEP low, the drivers' active-low EN high.
SAFE = {"PB0": 0, "PC0": 0, "PC4": 0, "PC8": 0, "PC2": 1, "PC6": 1, "PC10": 1}
IRQ_NAMES = {
    28: "TIM2",
    29: "TIM3",
    30: "TIM4",
    50: "TIM5",
    0: "WWDG",
    55: "TIM7",
    40: "EXTI15_10",
    56: "DMA2_STREAM0",
    67: "OTG_FS",
    18: "ADC",
}
TIM7_BASE = 0x4000_1400
UID = 0x1FFF_7A10
# The stack is the 64 KiB of CCM RAM below 0x1001_0000 (memory.x).
CCM_BASE, CCM_END = 0x1000_0000, 0x1001_0000
# What a stack overflow leaves of the stack below SP (bytes).
STACK_LEFT = 64
# Faults a test injects: what each does to the board.
FAULTS = {
    "hardfault": "a bus error at the instruction the core is at (a peripheral's, a wild pointer's)",
    "stack-overflow": f"the stack runs out: from then on the stack's memory ends {STACK_LEFT} bytes below where SP "
    "is, so the image's next deeper push, or an exception's stacking there, faults as an access outside the "
    "memory map does",
    "estop-pulse": "the E-STOP opened for 200 µs, shorter than a turn of the serve loop",
    "dma-freeze": "DMA2 stream 0 stops serving the ADC's requests, NDTR frozen, EN still set, until software "
    "disables and enables it again",
    "adc-overrun": "ADC1 loses a result (a DMA request served too late): OVR set, later triggers ignored until "
    "software clears it",
    "serve-hang": "the thread (the executor, the serve loop) stuck in a loop that never yields, interrupts "
    "still served",
    "usb-suspend": "the host suspends the bus for 50 ms, then resumes it without a reset",
    "usb-in-nak": "the host keeps the port open but stops reading: every IN transaction NAKed from then on",
    "usb-replug": "the cable pulled for 100 ms and plugged back: the bus reset, the device enumerated again, the "
    "port reopened by the program that held it, the bytes on their way lost",
    "estop-hung": "the E-STOP opens and, at the same instant, the serve loop hangs (as `serve-hang`): the drivers are "
    "left to the guard's backstop",
    "crystal-stop": "the crystal stops oscillating: with the clock security system on, its NMI and SYSCLK on the "
    "HSI; without it, the core stops with its clock",
    "stray-irq": "WWDG's interrupt (IRQ 0) enabled and pended at its reset priority 0, as a driver that enabled "
    "an interrupt with no handler would",
}
# The interrupt `stray-irq` raises: the window watchdog's, which the image
# neither uses nor binds.
STRAY_IRQ = 0
USB_SUSPEND_S = 0.05
USB_UNPLUGGED_S = 0.1
# An instruction that branches to itself, put at the top of SRAM (above the
# image's statics) for `serve-hang`.
HANG_AT = 0x2001_FFF0
# The core's registers the report gives when it faults.
FAULT_REGISTERS = (*(f"r{n}" for n in (*range(9), 12)), "sp", "lr", "pc", "xpsr", "control", "primask")
ESTOP_PULSE_S = 200e-6


class WatchdogReset(Exception):
    """The IWDG reached 0: the system resets."""


class Board:
    def __init__(self, image: str, plant: list[str] | None = None, crystal_hz: int | None = 8_000_000) -> None:
        self.elf = Elf(image)
        self.plant: Plant | None = None
        self.clock = Clock()
        self.machine = Machine(self.elf, plain=())
        uc = self.uc = self.machine.uc
        # System memory: the 96-bit unique ID the USB serial number is made of.
        uc.mem_map(0x1FFF_0000, 0x1_0000)
        uc.mem_write(UID, bytes(range(0x31, 0x3D)))
        self.nvic = Nvic()
        self.nvic.clock = self.clock
        self.rcc = Rcc(crystal_hz)
        self.pins: list[tuple[float, str, int]] = []  # (seconds, pin, level) of every driven change but STEP's
        # The laser enable's level, and when it last fell from high.
        self.laser_high = False
        self.laser_fell_at = 0
        # Rises of the laser enable and enables of DMA2 stream 0, counted.
        self.rises = {"laser": 0, "dma": 0}
        self.steps = dict.fromkeys(STEP, 0)  # rising STEP edges
        # cycles from the tick TIM5's compare was set for to a rising STEP edge → edges
        self.step_lateness: dict[int, int] = {}
        # The STEP edges that rose last (cycle, pin, lateness), and the
        # latest edge of all with those that rose just before it: whether
        # it waited for other axes' edges in the same handler.
        self.step_recent: deque[tuple[int, str, int]] = deque(maxlen=4)
        self.step_latest: dict[str, Any] | None = None
        # When each STEP line last rose, and the shortest and longest its
        # pulses were high (cycles): the driver needs the configured width.
        self.step_rose: dict[str, int] = {}
        self.step_high: list[int | None] = [None, None]
        # pin → the fastest slew rate (OSPEEDR) its driven edges had
        self.output_speed: dict[str, int] = {}
        bus = self.bus = Bus(uc)
        # TIM2–TIM5, one after the other from 0x4000_0000.
        self.tim2, self.tim3, self.tim4, self.tim5 = (
            bus.attach(0x4000_0000 + 0x400 * i, 0x400, Timer(name, irq, bits, self.clock, self.nvic, self.rcc))
            for i, (name, irq, bits) in enumerate(
                (("TIM2", 28, 32), ("TIM3", 29, 16), ("TIM4", 30, 16), ("TIM5", 50, 32))
            )
        )
        # TIM7, a basic timer: the registers it has are the general ones'.
        self.tim7 = bus.attach(TIM7_BASE, 0x400, Timer("TIM7", 55, 16, self.clock, self.nvic, self.rcc))
        bus.attach(TIM11_BASE, 0x400, Tim11(self.clock, self.rcc))
        # TIM3's internal trigger 1 is TIM2 (RM0090 Table 93).
        self.tim3.triggers[1] = self.tim2
        self.tim2.slaves.append(self.tim3)
        self.iwdg = bus.attach(IWDG_BASE, 0x400, Iwdg(self.clock, self._watchdog))
        bus.attach(PWR_BASE, 0x400, Plain("PWR", {0x04: 1 << 14}))  # CSR VOSRDY
        self.syscfg = bus.attach(SYSCFG_BASE, 0x400, Syscfg())
        self.exti = bus.attach(EXTI_BASE, 0x400, Exti(self.nvic, self.syscfg))
        self.ports: dict[str, Port] = {}
        for i, letter in enumerate("ABCDE"):
            self.ports[letter] = bus.attach(GPIO_BASE + 0x400 * i, 0x400, Port(letter, self))
        for name, level in RESISTORS.items():
            port = self.ports[name[1]]
            port.resistors[int(name[2:])] = level
            port._settle()
        # TIM3 CH1 drives PA6 (AF2): the laser's chop.
        self.tim3.outputs[0] = (self.ports["A"], 6)
        self.dma = bus.attach(DMA2_BASE, 0x400, Dma(uc, self.nvic, self.clock))
        self.dma.on_enable = lambda: self._rise("dma")
        self.adc = bus.attach(ADC_BASE, 0x400, Adc(self.clock, self.nvic, self.rcc, self.tim2, self.dma))
        self.tim2.slaves.append(self.adc)
        bus.attach(RCC_BASE, 0x400, self.rcc)
        bus.attach(FLASH_BASE, 0x400, Plain("FLASH"))
        # The core's registers and its four FIFO windows (0x1000–0x4FFF).
        self.otg = bus.attach(OTG_FS_BASE, 0x5000, OtgFs(self.nvic))
        bus.attach(0xE000_E000, 0x1000, self.nvic)
        bus.map([(0x4000_0000, 0x1000_0000), (OTG_FS_BASE, 0x4_0000), (0xE000_0000, 0x10_0000)])
        self.core = Core(self.machine, self.elf, self.nvic, self.clock)
        self.core.stop_run = bus.stop
        self.core.speed = self._cycles_per_instruction
        self.rcc.on_css = self.core.request_nmi
        self.rcc.on_clock_lost = lambda: setattr(self.core, "locked", True)
        # The thread's longest stretch awake without a turn of its loop,
        # over all and with the laser enable high at some time in it.
        self.core.on_thread_turn = self._thread_turn
        self.turn_longest = self.turn_longest_laser_on = 0
        self.machine.start_profile()
        self.host: Host | None = None
        self.stop_requested = False
        # An injected fault: its kind; the rise it is timed by (the laser
        # enable's or DMA2 stream 0's, which one) and the seconds after it,
        # until it is scheduled; the cycle it struck at.
        self.fault_plan: str | None = None
        self.fault_on_rise: tuple[str, int, float] | None = None
        self.fault_at: int | None = None
        self.reset_at: int | None = None
        # The head behind the pins (`board-plant` run as the command
        # `plant`): it drives the home switches' lines and the photodiode.
        self.plant = self.adc.plant = Plant(plant) if plant else None
        if self.plant:
            for p in self.ports.values():
                for n in range(16):
                    self.plant.output(0, f"P{p.letter}{n}", p.level[n])
            self._switches_from_plant()
        for name in CLOSED_SWITCHES:
            if not (self.plant and name in self.plant.switches):
                self.set_input(name, 0, 0.0)

    def _switches_from_plant(self) -> None:
        assert self.plant is not None
        for name, level in self.plant.switch_levels(self.clock.now).items():
            port, pin = self.ports[name[1]], int(name[2:])
            if port.outside.get(pin) != level:
                port.set_input(pin, level)

    def reading(self, port: Port) -> None:
        """The image reads `port`'s inputs: the plant's switches as they
        are now (the conversions up to now first, which the plant answers
        in time order)."""
        if self.plant and any(s[1] == port.letter for s in self.plant.switches):
            self.adc._advance()
            self._switches_from_plant()

    def plug(self, stream: int | None = None, replug: bool = False) -> None:
        """A USB host on the bus from now on, bridging `stream` (a file
        descriptor) to the CDC-ACM port while a program holds it open;
        `replug`: the cable pulled and plugged back after each session."""
        self.host = Host(self.otg, self.clock, stream, replug)
        self.host.start()

    def log_pin(self, port: Port, pin: int, level: int) -> None:
        """A driven pin's level, when it changes or when it starts to be
        driven; a STEP edge counted, with how late it rose after the tick
        the step timer's compare was set for, matched or already passed
        when written (the firmware then runs its event at once). A step the
        handler serves with an earlier event, the counter having passed its
        tick, is timed from that earlier tick: overstated, never understated;
        an edge before its compare's tick counts as early (negative)."""
        name = f"P{port.letter}{pin}"
        speed = port.ospeedr >> (2 * pin) & 3
        if port.mode(pin) in (1, 2) and speed >= self.output_speed.get(name, 0):
            self.output_speed[name] = speed
        if name == "PB0":
            if self.laser_high and not level:
                self.laser_fell_at = self.clock.now
            if level and not self.laser_high:
                self._rise("laser")
            self.laser_high = bool(level)
        if name in self.steps:
            if not level and name in self.step_rose:
                high = self.clock.now - self.step_rose.pop(name)
                shortest, longest = self.step_high
                self.step_high = [
                    high if shortest is None else min(shortest, high),
                    high if longest is None else max(longest, high),
                ]
            if level:
                self.step_rose[name] = self.clock.now
                self.steps[name] += 1
                due = self.tim5.reached(0)
                if due is not None:
                    late = int(self.clock.now - due)
                    self.step_lateness[late] = self.step_lateness.get(late, 0) + 1
                    if self.step_latest is None or late > self.step_latest["late_cycles"]:
                        self.step_latest = {
                            "pin": name,
                            "t_s": self.clock.now / HZ,
                            "late_cycles": late,
                            "before": [
                                {"pin": p, "cycles_before": self.clock.now - c, "late_cycles": l}
                                for c, p, l in reversed(self.step_recent)
                            ],
                        }
                    self.step_recent.append((self.clock.now, name, late))
            return
        self.pins.append((self.clock.now / HZ, name, level))

    def _thread_turn(self, since: int, now: int) -> None:
        self.turn_longest = max(self.turn_longest, now - since)
        if self.laser_high or self.laser_fell_at > since:
            self.turn_longest_laser_on = max(self.turn_longest_laser_on, now - since)

    def edge(self, port: Port, pin: int, level: int) -> None:
        """Every change of a pin's level: to the EXTI and the plant."""
        self.exti.edge(port.index, pin, rising=bool(level))
        if self.plant:
            self.plant.output(self.clock.now, f"P{port.letter}{pin}", level)

    def set_input(self, name: str, level: int, at: float) -> None:
        """The plant drives pin `name` (`PB12`) to `level` from `at` seconds."""
        port, pin = self.ports[name[1]], int(name[2:])
        self.clock.at(int(at * HZ), lambda: port.set_input(pin, level))

    def _rise(self, source: str) -> None:
        """The laser enable rose, or DMA2 stream 0 was enabled: a fault
        timed by the N-th such rise is scheduled."""
        self.rises[source] += 1
        if self.fault_on_rise and self.fault_on_rise[:2] == (source, self.rises[source]):
            self._schedule_fault(self.clock.now + int(self.fault_on_rise[2] * HZ))

    def inject(self, kind: str, when: str) -> None:
        """Injects fault `kind` (FAULTS) at `when`: seconds, or `laser+S`
        (S seconds after the laser enable first rises), `laserN+S` (after
        its N-th rise), `dmaN+S` (after DMA2 stream 0 is enabled for the
        N-th time: a measurement's conversions start)."""
        if kind not in FAULTS:
            raise ValueError(f"unknown fault {kind!r}: one of {', '.join(FAULTS)}")
        rise = re.fullmatch(r"(laser|dma)(\d*)\+([0-9.eE+-]+)", when)
        self.fault_plan = kind
        if rise:
            self.fault_on_rise = (rise[1], int(rise[2] or 1), float(rise[3]))
        else:
            self._schedule_fault(int(float(when) * HZ))

    def _schedule_fault(self, cycle: int) -> None:
        kind, self.fault_on_rise = self.fault_plan, None
        assert kind is not None
        self.clock.at(cycle, lambda: self._strike(kind))

    def _strike(self, kind: str) -> None:
        self.fault_at = self.clock.now
        if kind == "hardfault":
            self.core.request_fault("injected bus error")
        elif kind == "stack-overflow":
            floor = (self.uc.reg_read(arm.UC_ARM_REG_SP) - STACK_LEFT) & ~7
            self.core.stack_floor = floor
            self.uc.hook_add(UC_HOOK_MEM_WRITE, self._below_stack, begin=CCM_BASE, end=floor - 1)
        elif kind == "estop-pulse":
            self.set_input("PB12", 1, self.clock.now / HZ)
            self.set_input("PB12", 0, self.clock.now / HZ + ESTOP_PULSE_S)
        elif kind == "dma-freeze":
            self.adc._advance()
            self.dma.frozen = True
        elif kind == "adc-overrun":
            self.adc._advance()
            self.adc.overrun()
        elif kind in ("usb-suspend", "usb-replug"):
            assert self.host is not None, f"{kind} needs the USB host (--usb or --pty)"
            # The fault is the bus going idle, at the host's next turn.
            if kind == "usb-suspend":
                self.host.suspend_for = int(USB_SUSPEND_S * HZ)
            else:
                self.host.pull_for = int(USB_UNPLUGGED_S * HZ)
            self.host.on_suspend = lambda: setattr(self, "fault_at", self.clock.now)
        elif kind == "usb-in-nak":
            assert self.host is not None, f"{kind} needs the USB host (--usb or --pty)"
            self.host.reading = False
        elif kind == "crystal-stop":
            self.rcc.stop_crystal()
        elif kind == "stray-irq":
            self.nvic.enabled[STRAY_IRQ] = True
            self.nvic.line(STRAY_IRQ, True)
            self.nvic.line(STRAY_IRQ, False)
        elif kind in ("serve-hang", "estop-hung"):
            if kind == "estop-hung":
                self.set_input("PB12", 1, self.clock.now / HZ)
            self.uc.mem_write(HANG_AT, b"\xfe\xe7")  # b .
            self.core.request_hang(HANG_AT)

    def _below_stack(self, uc: Uc, access: int, address: int, size: int, value: int, _user: object) -> None:
        self.core.request_fault(f"a write at {address:#010x}, below the stack's memory")

    def _fault_report(self) -> dict[str, Any] | None:
        """When the laser enable went low and every driver's enable high
        after the fault (None: not by the end): after the core faulted, for
        a fault that makes it fault (a stack overflow does when the stack
        next grows into the missing memory), else after the fault struck."""
        if self.fault_at is None:
            return None if self.fault_plan is None else {"kind": self.fault_plan, "struck": False}
        faulted = [c for c, *_ in self.core.faults if c >= self.fault_at]
        at = (faulted[0] if faulted else self.fault_at) / HZ
        level: dict[str, int] = {}
        for t, pin, v in self.pins:
            if t > at:
                break
            level[pin] = v
        safe_at: dict[str, float | None] = {}
        for pin in ("PB0", "PC2", "PC6", "PC10"):
            want = SAFE[pin]
            if level.get(pin, want) == want:
                safe_at[pin] = at
            else:
                safe_at[pin] = next((t for t, p, v in self.pins if t > at and p == pin and v == want), None)
        safe_at["PA6"] = self._chop_off(at)
        after = {p: None if t is None else round(t - at, 9) for p, t in safe_at.items()}
        drivers = [after[p] for p in ("PC2", "PC6", "PC10")]
        return {
            "kind": self.fault_plan,
            "struck": True,
            "struck_s": round(self.fault_at / HZ, 9),
            "faulted_s": round(faulted[0] / HZ, 9) if faulted else None,
            "laser_off_after_s": after["PB0"],
            "chop_off_after_s": after["PA6"],
            "chop_high_at_fault": level.get("PA6", 0) == 1,
            "drivers_off_after_s": None if None in drivers else max(d for d in drivers if d is not None),
            "reset_after_s": None if self.reset_at is None else round(self.reset_at / HZ - at, 9),
        }

    def _cycles_per_instruction(self) -> tuple[int, int]:
        """The board's 168 MHz cycles per instruction at the current SYSCLK."""
        sysclk = self.rcc.sysclk_hz()
        ratio = Fraction(HZ, sysclk) if sysclk else Fraction(1)
        return ratio.numerator, ratio.denominator

    def _clocks(self) -> dict[str, Any]:
        """The crystal fitted, every SYSCLK the image selected with the USB
        clock beside it, and the clock security system's state."""
        cr = self.rcc.regs.get(0x00, 0)
        return {
            "crystal_hz": self.rcc.crystal_hz,
            "crystal_oscillating": self.rcc.oscillating,
            "selected": [{"sysclk_hz": s, "usb_hz": u} for s, u in self.rcc.selected],
            "sysclk_hz": self.rcc.sysclk_hz(),
            "usb_hz": self.rcc.usb_hz(),
            "pll_source": "HSE" if self.rcc.pll_from_hse() else "HSI",
            "css_on": bool(cr >> 19 & 1),
            "css_flag": bool(self.rcc.regs.get(0x0C, 0) >> 7 & 1),
        }

    def _chop_off(self, at: float) -> float | None:
        """When the chop (PA6) went low after `at` for good: low from then
        until the laser enable next rises (a measurement after the fault may
        chop again), or to the end; None if it was still chopping."""
        until = next((t for t, p, v in self.pins if t > at and p == "PB0" and v == 1), float("inf"))
        level = next((v for t, p, v in reversed(self.pins) if t <= at and p == "PA6"), 0)
        off: float | None = at if level == 0 else None
        for t, p, v in self.pins:
            if at < t < until and p == "PA6":
                off = (off if off is not None else t) if v == 0 else None
        return off

    def driven_pins(self) -> dict[str, int]:
        """Every pin driven at the end (output or alternate function), its level."""
        return {f"P{p.letter}{n}": p.level[n] for p in self.ports.values() for n in range(16) if p.mode(n) in (1, 2)}

    def _wait(self, cycles: int, why: Blocked | None, taken_at: int) -> dict[str, Any]:
        """An interrupt's wait, in the report: where it pended and what
        masked it, where it was taken."""
        blocked = None
        if why is not None:
            pc, primask, basepri, exception = why
            blocked = {
                "in": self.elf.function_at(pc),
                "primask": primask,
                "basepri": basepri,
                "exception": IRQ_NAMES.get(exception - 16, exception) if exception else None,
            }
        return {"cycles": cycles, "masked": blocked, "taken_in": self.elf.function_at(taken_at)}

    def _watchdog(self) -> None:
        self._reset()
        raise WatchdogReset()

    def _reset(self) -> None:
        """A system reset: every pin lets go (the image does not run again
        here)."""
        self.reset_at = self.clock.now
        for p in self.ports.values():
            p.reset()

    def run(self, seconds: float, paced: bool = False, pace: float = 1.0) -> dict[str, Any]:
        """Runs to `seconds` of virtual time; `paced`: never more than
        `pace` times ahead of the wall clock (a program on the
        pseudo-terminal times its requests in real time)."""
        started = time.monotonic()
        reason = "time"
        trail: list[dict[str, Any]] | None = None
        registers: dict[str, str] | None = None
        try:
            if paced:
                step = HZ // 200
                while self.clock.now < int(seconds * HZ) and not self.stop_requested:
                    self.core.run(min(self.clock.now + step, int(seconds * HZ)))
                    # The host reads the terminal at its own steps; a closed
                    # terminal reads as ready at once, so this sleeps.
                    ahead = self.clock.now / HZ / pace - (time.monotonic() - started)
                    if ahead > 0:
                        time.sleep(ahead)
            else:
                self.core.run(int(seconds * HZ))
        except WatchdogReset:
            reason = "watchdog reset"
        except SystemResetRequest:
            self._reset()
            reason = "system reset request"
        except Fault as e:
            reason = f"fault: {e}"
            registers = {
                name: f"{self.uc.reg_read(getattr(arm, 'UC_ARM_REG_' + name.upper())):#010x}"
                for name in FAULT_REGISTERS
            }
            trail = [
                {
                    "t": c / HZ,
                    "what": w,
                    "irq": IRQ_NAMES.get(i, i),
                    "sp": f"{sp:#010x}" if sp else None,
                    "pc": f"{pc:#010x}" if pc is not None else None,
                }
                for c, w, i, sp, pc in e.trail
            ]
        if self.stop_requested and reason == "time":
            reason = "stopped (SIGTERM)"
        reloads = self.iwdg.reloads
        driven = self.driven_pins()
        gaps = [b - a for a, b in itertools.pairwise(reloads)]
        return {
            "stopped": reason,
            "exceptions_before_fault": trail,
            "registers_at_fault": registers,
            "virtual_seconds": self.clock.now / HZ,
            "host_seconds": round(time.monotonic() - started, 3),
            "instructions": self.core.instructions,
            "interrupts": {IRQ_NAMES.get(i, str(i)): n for i, n in enumerate(self.nvic.taken) if n},
            # The longest wait of each interrupt from its pending to its
            # handler's first instruction (its latency), and what the core
            # was doing meanwhile.
            "interrupt_worst_wait": {IRQ_NAMES.get(i, str(i)): self._wait(*w) for i, w in self.core.worst_wait.items()},
            # Each handler's runs, entry to return, what pre-empted it
            # included: how many, their cycles in all and the longest.
            "interrupt_runs": {
                IRQ_NAMES.get(i, str(i)): {"count": n, "cycles": total, "longest_cycles": longest}
                for i, (n, total, longest) in self.core.handler_runs.items()
            },
            "step_edges": self.steps,
            # Cycles from the tick the step timer's compare was set for to the STEP edge it raised.
            "step_edge_lateness_cycles": {
                "max": max(self.step_lateness, default=None),
                "latest": self.step_latest,
                "histogram": dict(sorted(self.step_lateness.items())),
            },
            "step_pulse_us": {
                "shortest": None if self.step_high[0] is None else round(self.step_high[0] / HZ * 1e6, 3),
                "longest": None if self.step_high[1] is None else round(self.step_high[1] / HZ * 1e6, 3),
            },
            # Each output's fastest slew rate over its edges (RM0090 §8.4.3).
            "output_speeds": {
                p: ("low", "medium", "high", "very high")[v] for p, v in sorted(self.output_speed.items())
            },
            "watchdog": {
                "running": self.iwdg.running,
                "reloads": len(reloads),
                "longest_gap_s": max(gaps) / HZ if gaps else None,
                "timeout_s": self.iwdg._period() / HZ,
            },
            "pins": [{"t": round(t, 9), "pin": p, "level": v} for t, p, v in self.pins],
            "driven_at_end": driven,
            "unsafe": [{"t": round(t, 9), "pin": p, "level": v} for t, p, v in self.pins if SAFE.get(p, v) != v],
            "safe_at_end": all(self.ports[p[1]].level[int(p[2:])] == v for p, v in SAFE.items()),
            "faults_taken": [
                {"t": c / HZ, "why": w, "in": self.elf.function_at(pc), "pc": f"{pc:#010x}", "stacked": st}
                for c, w, pc, st in self.core.faults
            ],
            "locked_up": self.core.locked,
            "clocks": self._clocks(),
            "fault": self._fault_report(),
            "first_sleep_instructions": self.core.first_sleep,
            # The longest the thread stayed awake without turning its loop
            # (one poll of the executor and what pre-empted it), µs.
            "thread_turn_longest_us": round(self.turn_longest / HZ * 1e6, 1),
            "thread_turn_longest_laser_on_us": round(self.turn_longest_laser_on / HZ * 1e6, 1),
            # The stack is the 64 KiB of CCM RAM below 0x1001_0000 (memory.x).
            "stack_bytes_max": CCM_END - self.machine.counter.lowest_sp,
            "stack_deepest_in": self.elf.function_at(self.machine.counter.lowest_at),
            "busiest_functions": dict(by_function(self.elf, self.machine.profile(), top=8)),
            "busiest_registers": {
                f"{a:#010x}": n for a, n in sorted(self.bus.accesses.items(), key=lambda kv: -kv[1])[:8]
            },
            "usb_pullup_without_vbus": self.otg.pullup_without_vbus,
            "usb": None
            if self.host is None
            else {
                "state": self.host.state,
                "sessions": self.host.sessions,
                "pty_full": self.host.pty_full,
                "error": self.host.error,
                "address": self.otg.address,
                "log": self.host.log,
                "device_descriptor": self.host.descriptor.hex() if self.host.descriptor else None,
                "configuration_bytes": len(self.host.configuration or b""),
                **bus_power(self.host.configuration),
            },
            "conversions": {
                "ended": self.adc.conversions,
                "lost": self.adc.lost,
                "moved_by_dma": self.dma.moved,
                "forbidden_dma_writes": [
                    {"t": c / HZ, "register": r, "value": f"{v:#x}"} for c, r, v in self.dma.forbidden
                ],
            },
            "exti_edges": [{"line": n, "rising": r, "latched": l} for n, r, l in self.exti.edges],
        }


def main(prog: str | None = None) -> None:
    """The command line; `prog`: how the usage names the command."""
    ap = argparse.ArgumentParser(prog=prog, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("image")
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--set", action="append", default=[], metavar="PIN=LEVEL@SECONDS")
    ap.add_argument("--usb", action="store_true", help="a USB host enumerates the device and opens its port")
    ap.add_argument(
        "--pty",
        action="store_true",
        help="bridge the open port to a pseudo-terminal (its path on stderr first), paced to the wall clock",
    )
    ap.add_argument(
        "--fault",
        metavar="KIND@WHEN",
        help="inject a fault at WHEN (seconds, or laser+S: S seconds after the laser enable first rises, or "
        "laserN+S: after its N-th rise, or dmaN+S: after DMA2 stream 0's N-th enable); KIND: "
        + "; ".join(f"{k}: {v}" for k, v in FAULTS.items()),
    )
    ap.add_argument(
        "--crystal",
        default="8e6",
        metavar="HZ|none",
        help="the crystal fitted (Hz, default the board's 8 MHz), or none",
    )
    ap.add_argument("--replug", action="store_true", help="after each session, the cable pulled and plugged back")
    ap.add_argument(
        "--pace",
        type=float,
        default=1.0,
        help="with --pty: virtual time runs at most this many times faster than the wall clock "
        "(the host's heartbeat every 5 s must reach the head's 20 s watch: at most 3)",
    )
    ap.add_argument(
        "--plant",
        metavar="COMMAND",
        help="the head behind the pins: `board-plant` and its options (`gonio simulate`'s head options), one string",
    )
    args = ap.parse_args()
    crystal = None if args.crystal == "none" else round(float(args.crystal))
    board = Board(args.image, shlex.split(args.plant) if args.plant else None, crystal)
    # SIGTERM ends a paced run where it is, and the report is printed.
    signal.signal(signal.SIGTERM, lambda *_: setattr(board, "stop_requested", True))
    if args.pty:
        master, slave = os.openpty()
        tty.setraw(slave)
        os.set_blocking(master, False)
        print(f"pty {os.ttyname(slave)}", file=sys.stderr, flush=True)
        # Held by the programs that open it only: its closing is seen.
        os.close(slave)
        board.plug(master, replug=args.replug)
    elif args.usb:
        board.plug()
    if args.fault:
        kind, when = args.fault.split("@")
        board.inject(kind, when)
    for spec in args.set:
        pin, rest = spec.split("=")
        level, at = rest.split("@")
        board.set_input(pin, int(level), float(at))
    print(json.dumps(board.run(args.seconds, paced=args.pty, pace=args.pace)))
