"""The NVIC and the parts of the SCB the image touches, as the ARMv7-M
Architecture Reference Manual (B3.4, B1.5) and the STM32F4 programming
manual PM0214 (4.2–4.4) describe them: 82 external interrupts with 4
priority bits (the upper nibble of each byte), set/clear-enable and
set/clear-pending registers written 1-to-act, active bits, priority
grouping from AIRCR.PRIGROUP.

Interrupt lines are levels: a peripheral reports whether its request is
asserted (`line`), and the NVIC latches a rising level as pending, and
pends again on exception return while the level stays (B1.5.6 "the
interrupt is pended again when its handler returns if the signal is still
asserted")."""

from collections.abc import Callable

from .bus import Block
from .clock import Clock

IRQS = 82
EXTERNAL = 16  # exception number of IRQ 0


class Nvic(Block):
    name = "NVIC/SCB"

    def __init__(self) -> None:
        self.enabled = [False] * IRQS
        self.pending = [False] * IRQS
        self.active = [False] * IRQS
        self.level = [False] * IRQS
        self.priority = [0] * IRQS
        self.prigroup = 0
        self.vtor = 0
        self.scb: dict[int, int] = {}  # other SCB/SCS registers, held as written
        self.on_change: Callable[[], None] = lambda: None  # the core re-checks what it can take
        self.taken = [0] * IRQS  # exceptions entered, per IRQ
        # When each line last pended (the core times the wait to its
        # handler's entry from there: the interrupt's latency).
        self.clock: Clock | None = None
        self.pended_at = [0] * IRQS

    # --- what peripherals do -------------------------------------------
    def line(self, irq: int, asserted: bool) -> None:
        if asserted and not self.level[irq]:
            if not self.pending[irq] and self.clock:
                self.pended_at[irq] = self.clock.instant()
            self.pending[irq] = True
            self.level[irq] = True
            self.on_change()
        self.level[irq] = asserted

    # --- what the core does --------------------------------------------
    def group(self, priority: int) -> int:
        """The preempting part of a priority (PRIGROUP splits the byte)."""
        shift = self.prigroup + 1 if self.prigroup < 7 else 8
        return priority >> shift << shift

    def best_pending(self) -> tuple[int, int] | None:
        """The pending, enabled IRQ to take next: lowest priority value, then
        lowest number; (group priority, irq) or None."""
        if not any(self.pending):
            return None
        best: tuple[int, int] | None = None
        for irq in range(IRQS):
            if self.pending[irq] and self.enabled[irq]:
                key = (self.priority[irq], irq)
                if best is None or key < best:
                    best = key
        return None if best is None else (self.group(best[0]), best[1])

    def running_priority(self, excluding: int | None = None) -> int:
        """The group priority of the active exceptions (256: none)."""
        p = 256
        if not any(self.active):
            return p
        for irq in range(IRQS):
            if self.active[irq] and irq != excluding:
                p = min(p, self.group(self.priority[irq]))
        return p

    def enter(self, irq: int) -> None:
        self.pending[irq] = False
        self.active[irq] = True
        self.taken[irq] += 1

    def leave(self, irq: int) -> None:
        self.active[irq] = False
        if self.level[irq]:
            self.pending[irq] = True
            if self.clock:
                self.pended_at[irq] = self.clock.now

    # --- registers (offsets from 0xE000E000) ----------------------------
    def _bits(self, array: list[bool], offset: int, base: int) -> int:
        i = (offset - base) // 4 * 32
        return sum(1 << k for k in range(32) if i + k < IRQS and array[i + k])

    def _apply(self, array: list[bool], offset: int, base: int, value: int, state: bool) -> None:
        i = (offset - base) // 4 * 32
        for k in range(32):
            if value >> k & 1 and i + k < IRQS:
                array[i + k] = state

    def read(self, offset: int) -> int:
        for base, array in (
            (0x100, self.enabled),
            (0x180, self.enabled),
            (0x200, self.pending),
            (0x280, self.pending),
            (0x300, self.active),
        ):
            if base <= offset < base + 0x20:
                return self._bits(array, offset, base)
        if 0x400 <= offset < 0x400 + IRQS:
            i = offset - 0x400
            return sum(self.priority[i + k] << (8 * k) for k in range(4) if i + k < IRQS)
        if offset == 0xD00:
            return 0x410F_C241  # CPUID: Cortex-M4 r0p1
        if offset == 0xD04:  # ICSR: VECTPENDING, ISRPENDING
            b = self.best_pending()
            return ((b[1] + EXTERNAL) << 12 | 1 << 22) if b else 0
        if offset == 0xD08:
            return self.vtor
        if offset == 0xD0C:
            return 0xFA05_0000 | self.prigroup << 8
        return self.scb.get(offset, 0)

    def write(self, offset: int, value: int) -> None:
        if 0x100 <= offset < 0x120:
            self._apply(self.enabled, offset, 0x100, value, True)
        elif 0x180 <= offset < 0x1A0:
            self._apply(self.enabled, offset, 0x180, value, False)
        elif 0x200 <= offset < 0x220:
            self._apply(self.pending, offset, 0x200, value, True)
        elif 0x280 <= offset < 0x2A0:
            self._apply(self.pending, offset, 0x280, value, False)
            # A line still asserted stays pending (PM0214 §4.2.4).
            for irq in range(IRQS):
                self.pending[irq] = self.pending[irq] or self.level[irq]
        elif 0x400 <= offset < 0x400 + IRQS:
            for k in range(4):
                if offset - 0x400 + k < IRQS:
                    self.priority[offset - 0x400 + k] = value >> (8 * k) & 0xF0
        elif offset == 0xD08:
            self.vtor = value & ~0x7F
        elif offset == 0xD0C:
            if value >> 16 == 0x05FA:
                self.prigroup = value >> 8 & 7
                if value & 4:
                    raise SystemResetRequest()
        elif offset == 0xF00:  # STIR
            self.pending[value & 0x1FF] = True
        else:
            self.scb[offset] = value
        self.on_change()

    def write_narrow(self, offset: int, size: int, value: int) -> None:
        """Priority bytes are written one at a time (`set_priority`)."""
        if 0x400 <= offset < 0x400 + IRQS:
            for k in range(size):
                if offset - 0x400 + k < IRQS:
                    self.priority[offset - 0x400 + k] = value >> (8 * k) & 0xF0
            self.on_change()
            return
        shift = 8 * (offset & 3)
        mask = ((1 << (8 * size)) - 1) << shift
        word = offset & ~3
        self.write(
            word, (self.read(word) & ~mask) | ((value << shift) & mask) if word >= 0xD00 else (value << shift) & mask
        )


class SystemResetRequest(Exception):
    """AIRCR.SYSRESETREQ: the core asked for a reset."""
