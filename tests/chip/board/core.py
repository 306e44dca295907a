"""The Cortex-M4F core on unicorn, with what unicorn leaves out of M-class
mode: taking exceptions (stacking, preemption by priority, tail-chaining,
the FPU's extended frame), returning from them, and sleeping in WFE.

unicorn 2.1 executes Thumb-2 and the FPU, and reports a handler's
`bx lr` to an EXC_RETURN value as interrupt 8 with PC at that value (less
its low bit); everything else an exception does is done here, as the
ARMv7-M Architecture Reference Manual describes it (B1.5.6 entry, B1.5.7
return, B1.5.18 WFE):

- entry pushes `r0–r3, r12, lr, pc, xPSR` (and `s0–s15, FPSCR` when
  CONTROL.FPCA says the thread used the FPU) on the current stack, 8-byte
  aligned (xPSR bit 9 records the padding), sets IPSR, LR = EXC_RETURN
  and PC = the vector;
- an exception preempts when its group priority is lower than the
  running one (the active exceptions', or PRIMASK's 0);
- on return a pending exception that would preempt the context returned to
  is taken at once without unstacking (tail-chaining);
- WFE clears the event register if set, else sleeps until an exception is
  taken; SEV and every exception return set it;
- a pending interrupt masked by PRIMASK is taken right after the `cpsie i`
  or `msr PRIMASK` that unmasks it;
- a fault (an access outside the memory map, an undefined instruction)
  enters HardFault at priority −1, the configurable faults being disabled
  (B1.5.8 escalation); a stacking that fails sets CFSR.STKERR and
  HFSR.FORCED, leaves SP where the frame would have gone and enters the
  handler all the same (B1.5.6, "derived exceptions on exception entry");
  a fault in the HardFault handler locks the core up (B1.5.15): it executes
  nothing more, every pin as it was, until a reset;
- the NMI (`request_nmi`: the clock security system's) is taken at the
  next instruction at priority −2, above everything; a fault in it locks
  the core up; its handler is not expected to return.

Time: one instruction per SYSCLK cycle, counted per translated block
(count.c), so `speed()` core cycles of the board's 168 MHz clock per
instruction (10.5 on the HSI's 16 MHz before the PLL is up, 1 after);
SYSCLK is read at the start of each run of the core, so a switch takes
effect within a slice (at most 100 µs). Sleep skips to the next event of
the clock."""

import collections
import struct
from collections.abc import Callable, Iterable

from unicorn import UC_HOOK_CODE, UC_HOOK_INTR, Uc, UcError
from unicorn import arm_const as arm

from .clock import Clock
from .emulate import Elf, Machine
from .nvic import EXTERNAL, Nvic
from .registers import Batch, Registers

WFE, WFI, SEV, CPSIE_I = 0xBF20, 0xBF30, 0xBF40, 0xB662
FRAME = tuple(getattr(arm, f"UC_ARM_REG_{r}") for r in ("R0", "R1", "R2", "R3", "R12", "LR"))
FP_FRAME = [getattr(arm, f"UC_ARM_REG_S{i}") for i in range(16)] + [arm.UC_ARM_REG_FPSCR]
# What an exception entry reads first.
STATE = (arm.UC_ARM_REG_CONTROL, arm.UC_ARM_REG_IPSR, arm.UC_ARM_REG_XPSR, arm.UC_ARM_REG_MSP)
# unicorn's interrupt number for an exception return (QEMU's EXCP_EXCEPTION_EXIT).
EXCEPTION_EXIT = 8
NMI, HARDFAULT = 2, 3
# The SCB's fault status registers (PM0214 §4.4.14, §4.4.16).
CFSR, HFSR = 0xD28, 0xD2C
STKERR, FORCED = 1 << 12, 1 << 30
# Cycles a run of the core lasts at most: a pending interrupt masked by
# PRIMASK is taken at the `cpsie` that unmasks it, by BASEPRI at the end of
# a run at the latest.
SLICE = 16_800

# An exception entry or return: (cycle, "enter"/"return"/"chain"/"fault",
# IRQ, SP, PC).
TrailEntry = tuple[int, str, int, int | None, int | None]
# What kept an interrupt waiting: (PC, PRIMASK, BASEPRI, the running exception).
Blocked = tuple[int, int, int, int]
# An exception entry's stacking: (SP, EXC_RETURN, whether the frame was written).
Stacking = tuple[int, int, bool]


class Fault(Exception):
    """The core stopped where real silicon would fault or lock up; `trail`:
    the last exception entries and returns before it."""

    def __init__(self, message: str, trail: Iterable[TrailEntry] = ()) -> None:
        super().__init__(message)
        self.trail = list(trail)


class Core:
    def __init__(self, machine: Machine, elf: Elf, nvic: Nvic, clock: Clock) -> None:
        self.m = machine
        self.uc = machine.uc
        self.nvic = nvic
        self.clock = clock
        self.event = False  # the event register
        self.sleeping = False
        # Since when the thread has been awake without a turn of its loop
        # (a WFE executed in thread mode), and who hears of each turn:
        # `on_thread_turn(since, now)`.
        self.awake_since: int | None = 0
        self.on_thread_turn: Callable[[int, int], None] | None = None
        self._running = False  # inside `emu_start`
        self.instructions = 0
        # (cycle, "enter"/"return"/"chain", IRQ, SP, PC) of the last
        # exceptions, for the report of a fault.
        self.trail: collections.deque[TrailEntry] = collections.deque(maxlen=24)
        # Per IRQ, what kept it waiting when it could not be taken at once
        # (where the core was, PRIMASK, BASEPRI, the running exception),
        # until it is taken; and its longest wait: (cycles, that, where it
        # was taken).
        self.blocked: dict[int, Blocked] = {}
        self.worst_wait: dict[int, tuple[int, Blocked | None, int]] = {}
        # Per IRQ, when its handler was entered, and its runs: [count,
        # total cycles, longest] (what pre-empted it included).
        self.entered: dict[int, int] = {}
        self.handler_runs: dict[int, list[int]] = {}
        self.first_sleep: int | None = None  # instructions from reset to the first idle wait
        # HardFault active; the core locked up; a fault to take at the next
        # instruction (a test's); the faults taken: (cycle, why, PC, stacked).
        self.in_hardfault = False
        self.in_nmi = False
        self.nmi_request = False
        self.locked = False
        self.fault_request: str | None = None
        self.faults: list[tuple[int, str, int, bool | None]] = []
        # Where the thread is sent to loop for ever (a test's stuck serve loop).
        self.hang_at: int | None = None
        # Where the stack's memory ends (a test moves it up: an overflow).
        self.stack_floor = 0
        # Board cycles per instruction, as a fraction (numerator,
        # denominator), and the fraction of a cycle carried between runs.
        self.speed: Callable[[], tuple[int, int]] = lambda: (1, 1)
        self._speed = (1, 1)
        self._carry = 0
        clock.executed = lambda: (self.m.executed - self._run_start) * self._speed[0] // self._speed[1]
        clock.shorten_run = self._shorten_run
        # Ends the current run from a peripheral's access (the board's bus,
        # which replays the access unicorn will execute again).
        self.stop_run: Callable[[], None] = self.uc.emu_stop
        self._run_start = 0
        nvic.on_change = self._interrupts_changed
        text = [(a, b) for a, b in elf.segments if 0x0800_0000 <= a < 0x0810_0000]
        hooks: dict[int, Callable[[Uc, int, int, object], None]] = {
            WFE: self._on_wfe,
            WFI: self._on_wfe,
            SEV: self._on_sev,
            CPSIE_I: self._on_cpsie,
        }
        for base, blob in text:
            for off in range(0, len(blob) - 1, 2):
                half = blob[off] | blob[off + 1] << 8
                hook = hooks.get(half)
                # `msr PRIMASK, rN` (F38n 8810): how cortex-m's critical
                # sections end, restoring the mask they found.
                if half & 0xFFF0 == 0xF380 and off + 3 < len(blob) and blob[off + 2] | blob[off + 3] << 8 == 0x8810:
                    hook = self._on_msr_primask
                # A half-word inside a 32-bit instruction is never where an
                # instruction starts, so its hook never fires.
                if hook:
                    self.uc.hook_add(UC_HOOK_CODE, hook, begin=base + off, end=base + off)
        self.uc.hook_add(UC_HOOK_INTR, self._on_interrupt)
        self.reg = Registers(self.uc)
        self._state = Batch(self.uc, STATE)
        self._frame = Batch(self.uc, FRAME)
        self._fp_frame = Batch(self.uc, FP_FRAME)
        self.pc = machine.reset() | 1

    # --- hooks -------------------------------------------------------------
    def _on_sev(self, uc: Uc, address: int, size: int, _user: object) -> None:
        self.event = True

    def _on_wfe(self, uc: Uc, address: int, size: int, _user: object) -> None:
        if self._current_exception() == 0 and self.awake_since is not None and self.on_thread_turn:
            self.on_thread_turn(self.awake_since, self.clock.now)
        self.awake_since = self.clock.now
        if self.event:
            self.event = False
        else:
            self.awake_since = None
            self.sleeping = True
            if self.first_sleep is None:
                self.first_sleep = self.instructions + self.m.executed - self._run_start
            uc.emu_stop()
        self.reg.write(arm.UC_ARM_REG_PC, (address + 2) | 1)

    def _on_cpsie(self, uc: Uc, address: int, size: int, _user: object) -> None:
        if self.nvic.best_pending() is not None:
            self.reg.write(arm.UC_ARM_REG_PRIMASK, 0)
            self.reg.write(arm.UC_ARM_REG_PC, (address + 2) | 1)
            uc.emu_stop()

    def _on_msr_primask(self, uc: Uc, address: int, size: int, _user: object) -> None:
        """Unmasking with a pending interrupt: done here, and the interrupt
        taken right after the instruction, as on silicon."""
        rn = uc.mem_read(address, 2)[0] & 0xF
        value = self.reg.read(arm.UC_ARM_REG_R0 + rn) if rn < 13 else 0
        if not value & 1 and self.nvic.best_pending() is not None:
            self.reg.write(arm.UC_ARM_REG_PRIMASK, 0)
            self.reg.write(arm.UC_ARM_REG_PC, (address + 4) | 1)
            uc.emu_stop()

    def _on_interrupt(self, uc: Uc, intno: int, _user: object) -> None:
        if intno != EXCEPTION_EXIT:
            # QEMU's EXCP_UDEF (1), EXCP_SWI (2), ...: a usage fault, escalated.
            self.pc = self.reg.read(arm.UC_ARM_REG_PC) | 1
            self.fault(f"exception {intno} (undefined instruction: 1)")
            uc.emu_stop()
            return
        self._return(self.reg.read(arm.UC_ARM_REG_PC) | 1)

    def request_hang(self, address: int) -> None:
        """The thread continues at `address` (a loop) the next time the core
        is in thread mode."""
        self.hang_at = address
        if self._running:
            self.stop_run()

    def request_fault(self, why: str) -> None:
        """A fault at the instruction the core is at (a test injects a bus
        error): taken before the next one."""
        self.fault_request = why
        if self._running:
            self.uc.emu_stop()

    def request_nmi(self) -> None:
        """The NMI pends: taken before the next instruction."""
        self.nmi_request = True
        if self._running:
            self.uc.emu_stop()

    def _enter_nmi(self) -> None:
        sp, exc_return, stacked = self._stack()
        if not stacked:
            self.faults.append((self.clock.now, "lockup: stacking for the NMI", self.pc & ~1, False))
            self.locked = True
            return
        self.trail.append((self.clock.now, "nmi", -14, sp, self.pc & ~1))
        self.in_nmi = True
        self.reg.write(arm.UC_ARM_REG_IPSR, NMI)
        self.reg.write(arm.UC_ARM_REG_LR, exc_return)
        self.pc = self._vector(NMI) | 1
        self.reg.write(arm.UC_ARM_REG_PC, self.pc)
        self.sleeping = False

    def _shorten_run(self) -> None:
        """An event now falls due before the current run's end: the run
        ends here, and the next one ends at the event."""
        if self._running:
            self.stop_run()

    def _interrupts_changed(self) -> None:
        """A peripheral or a register write changed what may be taken: end
        the current run so that what may preempt now is taken at this
        instruction (what PRIMASK masks is taken where it is unmasked, what
        BASEPRI masks at the end of the run)."""
        if self._running:
            best = self.nvic.best_pending()
            if best is not None and best[0] < self._execution_priority():
                self.stop_run()

    # --- exceptions ----------------------------------------------------------
    def _current_exception(self) -> int:
        return self.reg.read(arm.UC_ARM_REG_IPSR) & 0x1FF

    def _execution_priority(self, active_excluding: int | None = None) -> int:
        if self.in_nmi:
            return -2
        if self.in_hardfault:
            return -1
        p = self.nvic.running_priority(active_excluding)
        if self.reg.read(arm.UC_ARM_REG_PRIMASK) & 1:
            p = min(p, 0)
        basepri = self.reg.read(arm.UC_ARM_REG_BASEPRI) & 0xF0
        if basepri:
            p = min(p, self.nvic.group(basepri))
        return p

    def _vector(self, exception: int) -> int:
        address = self.nvic.vtor + 4 * exception
        if address < 0x10_0000:
            # Address 0 aliases the boot memory: main flash, BOOT0 low (RM0090 §2.4).
            address += 0x0800_0000
        vector: int = struct.unpack("<I", self.uc.mem_read(address, 4))[0]
        return vector

    def take_pending(self) -> None:
        """Takes the pending exception that may preempt now, if any."""
        best = self.nvic.best_pending()
        if best is None:
            return
        if best[0] < self._execution_priority():
            self._enter(best[1])
        elif best[1] not in self.blocked:
            self.blocked[best[1]] = (
                self.pc & ~1,
                self.reg.read(arm.UC_ARM_REG_PRIMASK) & 1,
                self.reg.read(arm.UC_ARM_REG_BASEPRI) & 0xFF,
                self._current_exception(),
            )

    def _stack(self) -> Stacking:
        """Exception entry's stacking; returns EXC_RETURN and whether the
        frame was written (a stack overflow: it was not, SP moved all the same)."""
        uc = self.uc
        control, ipsr, xpsr, sp = self._state.read()
        handler = ipsr & 0x1FF != 0
        if control & 2 and not handler:
            raise Fault("thread mode on the process stack: not modelled (the image uses MSP only)")
        fp = bool(control & 4)
        words = 26 if fp else 8
        pad = (sp - 4 * words) & 4
        sp = sp - 4 * words - pad
        values = [*self._frame.read(), self.pc & ~1, xpsr | (pad and 1 << 9) | 1 << 24]
        if fp:
            values += [*self._fp_frame.read(), 0]
        frame = struct.pack(f"<{words}I", *values)
        stacked = sp >= self.stack_floor
        try:
            if stacked:
                uc.mem_write(sp, frame)
        except UcError:
            stacked = False
        self.reg.write(arm.UC_ARM_REG_MSP, sp)
        exc_return = 0xFFFF_FFF1 if handler else 0xFFFF_FFF9
        if fp:
            exc_return &= ~0x10
        self.reg.write(arm.UC_ARM_REG_CONTROL, control & ~4)
        return sp, exc_return, stacked

    def _enter(self, irq: int) -> None:
        entry = sp, exc_return, stacked = self._stack()
        if not stacked:
            # A derived fault of the entry: HardFault instead, which preempts.
            self.fault(f"stacking for IRQ {irq} at {sp:#010x}", entry)
            return
        self.trail.append((self.clock.now, "enter", irq, sp, self.pc & ~1))
        self._dispatch(irq, exc_return)

    def fault(self, why: str, entry: Stacking | None = None) -> None:
        """A fault at `self.pc`: HardFault entered (`entry`: the stacking
        an interrupt's entry already did), or the core locked up if it
        faulted in HardFault."""
        if self.in_hardfault or self.in_nmi or self.locked:
            self.faults.append((self.clock.now, f"lockup: {why}", self.pc & ~1, None))
            self.locked = True
            return
        sp, exc_return, stacked = entry or self._stack()
        self.faults.append((self.clock.now, why, self.pc & ~1, stacked))
        scb = self.nvic.scb
        scb[HFSR] = scb.get(HFSR, 0) | FORCED
        if not stacked:
            scb[CFSR] = scb.get(CFSR, 0) | STKERR
        self.trail.append((self.clock.now, "fault", -1, sp, self.pc & ~1))
        self.in_hardfault = True
        self.reg.write(arm.UC_ARM_REG_IPSR, HARDFAULT)
        self.reg.write(arm.UC_ARM_REG_LR, exc_return)
        self.pc = self._vector(HARDFAULT) | 1
        self.reg.write(arm.UC_ARM_REG_PC, self.pc)
        self.sleeping = False

    def _dispatch(self, irq: int, exc_return: int) -> None:
        waited = self.clock.now - self.nvic.pended_at[irq]
        why = self.blocked.pop(irq, None)
        if waited > self.worst_wait.get(irq, (-1,))[0]:
            self.worst_wait[irq] = (waited, why, self.pc & ~1)
        self.reg.write(arm.UC_ARM_REG_IPSR, irq + EXTERNAL)
        self.reg.write(arm.UC_ARM_REG_LR, exc_return)
        self.nvic.enter(irq)
        self.entered[irq] = self.clock.now
        self.pc = self._vector(irq + EXTERNAL) | 1
        self.reg.write(arm.UC_ARM_REG_PC, self.pc)
        if self.sleeping:
            self.awake_since = self.clock.now
        self.sleeping = False

    def _return(self, exc_return: int) -> None:
        uc = self.uc
        leaving = self._current_exception() - EXTERNAL
        if leaving < 0:
            raise Fault(f"return from exception {leaving + EXTERNAL}: only interrupts are taken here")
        self.nvic.leave(leaving)
        ran = self.clock.now - self.entered.pop(leaving, self.clock.now)
        runs = self.handler_runs.setdefault(leaving, [0, 0, 0])
        runs[0] += 1
        runs[1] += ran
        runs[2] = max(runs[2], ran)
        # An exception return sets the event register (B1.5.18).
        self.event = True
        # Tail-chaining: the next exception would preempt what is returned
        # to (its active exceptions, PRIMASK, BASEPRI); a new entry clears
        # FPCA, the stacked frame staying the one EXC_RETURN describes.
        best = self.nvic.best_pending()
        if best is not None and best[0] < self._execution_priority():
            self.reg.write(arm.UC_ARM_REG_CONTROL, self.reg.read(arm.UC_ARM_REG_CONTROL) & ~4)
            self.trail.append((self.clock.now, "chain", best[1], None, None))
            self._dispatch(best[1], exc_return)
            uc.emu_stop()
            return
        fp = not exc_return & 0x10
        sp = self.reg.read(arm.UC_ARM_REG_MSP)
        words = 26 if fp else 8
        frame = struct.unpack(f"<{words}I", uc.mem_read(sp, 4 * words))
        self._frame.write(frame[:6])
        pc, xpsr = frame[6], frame[7]
        self.trail.append((self.clock.now, "return", leaving, sp, pc))
        if fp:
            self._fp_frame.write(frame[8:25])
        sp += 4 * words + (4 if xpsr >> 9 & 1 else 0)
        self.reg.write(arm.UC_ARM_REG_MSP, sp)
        self.reg.write(arm.UC_ARM_REG_XPSR, xpsr & ~(1 << 9))
        control = self.reg.read(arm.UC_ARM_REG_CONTROL)
        self.reg.write(arm.UC_ARM_REG_CONTROL, control | 4 if fp else control & ~4)
        self.pc = pc | 1
        self.reg.write(arm.UC_ARM_REG_PC, self.pc)
        # What the return unmasked may be taken now.
        if self.nvic.best_pending() is not None:
            uc.emu_stop()

    # --- running -------------------------------------------------------------
    def run(self, until: int) -> None:
        """Runs the core to cycle `until` (virtual time), taking exceptions
        and sleeping as events come."""
        clock = self.clock
        while clock.now < until:
            clock.fire_due()
            if self.nmi_request and not self.locked:
                self.nmi_request = False
                self._enter_nmi()
            if self.fault_request is not None and not self.locked:
                why, self.fault_request = self.fault_request, None
                self.fault(why)
            if self.hang_at is not None and self._current_exception() == 0:
                self.pc, self.hang_at = self.hang_at | 1, None
                self.reg.write(arm.UC_ARM_REG_PC, self.pc)
                self.sleeping = False
            if not self.locked:
                self.take_pending()
            if self.sleeping or self.locked:
                nxt = clock.next()
                if nxt is None or nxt >= until:
                    clock.base = until
                    return
                clock.base = max(nxt, clock.now)
                continue
            nxt = clock.next()
            budget = min(until, nxt if nxt is not None else until, clock.now + SLICE) - clock.now
            self._run_start = self.m.executed
            self._running = True
            clock.run_end = clock.now + budget
            num, den = self._speed = self.speed()
            try:
                self.uc.emu_start(self.pc, 0xFFFF_FFFF, count=max(budget * den // num, 1))
            except UcError as e:
                # A bus or usage fault on silicon (this image enables none of
                # the configurable faults): HardFault at the faulting instruction.
                self.pc = self.reg.read(arm.UC_ARM_REG_PC) | 1
                self.fault(str(e))
                continue
            finally:
                self._running = False
                clock.run_end = 0
                executed = self.m.executed - self._run_start
                self._run_start = self.m.executed
                charged, self._carry = divmod(executed * num + self._carry, den)
                clock.base += max(charged, 1)
                self.instructions += executed
            self.pc = self.reg.read(arm.UC_ARM_REG_PC) | 1
