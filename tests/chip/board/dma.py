"""DMA2 (RM0090 §10): stream 0 modelled, peripheral to memory in direct
mode, the way the ADC's conversions reach memory; the other streams'
registers hold what is written.

What the manual states and this model does:
- a request moves one data item from SxPAR to the memory pointer and
  decrements NDTR; HTIF is set when half the programmed items have moved,
  TCIF when NDTR reaches 0 (§10.3.17); in circular mode NDTR is then
  reloaded with the value software programmed and the pointer returns to
  SxM0AR (§10.3.8);
- clearing EN stops the stream and sets TCIF (§10.3.14: "the transfer
  complete interrupt flag is set in order to indicate the end of
  transfer");
- the address registers hold base addresses; the running pointer is
  internal. To restart where it stopped "the software has to read the
  DMA_SxNDTR register ... the peripheral and/or memory addresses have to
  be updated ... the SxNDTR register has to be updated" (§10.3.14). A
  stream enabled again without that therefore starts at SxM0AR, with the
  items NDTR still counts, which is what this model does; the manual does
  not say whether NDTR is reloaded then, and it is not here;
- SxCR's configuration bits, NDTR, PAR, M0AR, M1AR and FCR's DMDIS/FTH are
  write-protected while EN is set ("it is forbidden to write these
  registers when the EN bit is read as 1"): such writes are ignored and
  listed in `forbidden`;
- LIFCR/HIFCR clear flags written 1; the stream's interrupt line is
  asserted while a flag and its enable are both set.

Not modelled: FIFO mode, double-buffer mode, memory-to-memory, bursts,
transfer and FIFO errors, stream priorities (one stream is active)."""

from collections.abc import Callable

from unicorn import Uc

from .bus import Block
from .clock import Clock
from .nvic import Nvic

DMA2_BASE = 0x4002_6400
STREAM0_IRQ = 56

TCIF, HTIF, TEIF, DMEIF, FEIF = 1 << 5, 1 << 4, 1 << 3, 1 << 2, 1 << 0
EN, DMEIE, TEIE, HTIE, TCIE, CIRC = 1, 1 << 1, 1 << 2, 1 << 3, 1 << 4, 1 << 8
# SxCR bits software may change while EN is set (the manual marks the rest
# "protected").
CR_FREE = EN | DMEIE | TEIE | HTIE | TCIE | CIRC


class Dma(Block):
    name = "DMA2"

    def __init__(self, uc: Uc, nvic: Nvic, clock: Clock) -> None:
        self.uc = uc
        self.nvic = nvic
        self.clock = clock
        self.lisr = 0
        self.cr = 0
        self.ndtr = 0  # items left in this round
        self.programmed = 0  # what software last wrote to NDTR: the reload
        self.par = self.m0ar = self.m1ar = 0
        self.fcr = 0x21  # reset value: FS empty, DMDIS 0
        self.pointer = 0  # items moved since the pointer left SxM0AR
        self.others: dict[int, int] = {}  # the other streams' registers
        # The requester brings its requests up to now before an access, and
        # plans again after a write.
        self.before_access: Callable[[], None] = lambda: None
        self.after_write: Callable[[], None] = lambda: None
        # Told when software enables the stream (a test times a fault by it).
        self.on_enable: Callable[[], None] = lambda: None
        self.forbidden: list[tuple[int, str, int]] = []  # (cycle, register, value): writes the manual forbids
        self.moved = 0  # items moved in all, for the board's report
        # A test's fault: the stream stops serving requests (NDTR frozen)
        # until software disables and enables it again.
        self.frozen = False

    # --- what the requester does -----------------------------------------
    def accepts(self, source: int) -> bool:
        """Whether stream 0 takes requests from the peripheral register at
        `source` now (enabled, channel 0, peripheral to memory)."""
        return bool(self.cr & EN) and self.cr >> 25 & 7 == 0 and self.cr >> 6 & 3 == 0 and self.par == source

    def receive(self, data: bytes) -> int:
        """Moves the items of `data` (16-bit, little-endian bytes) in order;
        returns how many the stream took (it stops at the end of a
        non-circular transfer)."""
        if self.cr >> 11 & 3 != 1 or self.cr >> 13 & 3 != 1 or not self.cr >> 10 & 1:
            raise NotImplementedError(f"DMA2 stream 0: only 16-bit, memory-incremented transfers (CR {self.cr:#x})")
        items = len(data) // 2
        taken = 0
        while taken < items and self.cr & EN and not self.frozen:
            if self.ndtr == 0:
                break
            n = min(items - taken, self.ndtr)
            half = self.programmed - self.programmed // 2
            before = self.programmed - self.ndtr
            self.uc.mem_write(self.m0ar + 2 * self.pointer, bytes(data[2 * taken : 2 * (taken + n)]))
            self.pointer += n
            self.ndtr -= n
            taken += n
            if before < half <= self.programmed - self.ndtr:
                self.lisr |= HTIF
            if self.ndtr == 0:
                self.lisr |= TCIF
                if self.cr & CIRC:
                    self.ndtr = self.programmed
                    self.pointer = 0
                else:
                    self.cr &= ~EN
        self.moved += taken
        self._line()
        return taken

    def until_flag(self) -> int | None:
        """Items until an enabled half or complete flag is next set (None:
        none will be)."""
        if not self.cr & EN or self.frozen:
            return None
        done = self.programmed - self.ndtr
        half = self.programmed - self.programmed // 2
        ahead = []
        if self.cr & HTIE and done < half:
            ahead.append(half - done)
        if self.cr & TCIE and self.ndtr:
            ahead.append(self.ndtr)
        return min(ahead) if ahead else None

    # --- registers -----------------------------------------------------------
    def _line(self) -> None:
        enabled = (TCIF if self.cr & TCIE else 0) | (HTIF if self.cr & HTIE else 0) | (TEIF if self.cr & TEIE else 0)
        enabled |= (DMEIF if self.cr & DMEIE else 0) | (FEIF if self.fcr & 0x80 else 0)
        self.nvic.line(STREAM0_IRQ, bool(self.lisr & enabled))

    def read(self, offset: int) -> int:
        self.before_access()
        return {
            0x00: self.lisr,
            0x10: self.cr,
            0x14: self.ndtr,
            0x18: self.par,
            0x1C: self.m0ar,
            0x20: self.m1ar,
            0x24: self.fcr,
        }.get(offset, self.others.get(offset, 0))

    def write(self, offset: int, value: int) -> None:
        self.before_access()
        running = self.cr & EN
        if offset == 0x08:  # LIFCR: stream 0's flags are its bits 0–5
            self.lisr &= ~(value & 0x3D)
        elif offset == 0x10:
            if running and (value ^ self.cr) & ~CR_FREE:
                self.forbidden.append((self.clock.now, "S0CR", value))
                value = value & CR_FREE | self.cr & ~CR_FREE
            if running and not value & EN:
                self.lisr |= TCIF  # the stream stops: "end of transfer"
            if not running and value & EN:
                self.pointer = 0  # the pointer starts at the base address
                self.frozen = False
            self.cr = value
            if not running and value & EN:
                self.on_enable()
        elif offset in (0x14, 0x18, 0x1C, 0x20) and running:
            self.forbidden.append(
                (self.clock.now, {0x14: "S0NDTR", 0x18: "S0PAR", 0x1C: "S0M0AR", 0x20: "S0M1AR"}[offset], value)
            )
        elif offset == 0x14:
            self.ndtr = self.programmed = value & 0xFFFF
        elif offset == 0x18:
            self.par = value
        elif offset == 0x1C:
            self.m0ar = value
        elif offset == 0x20:
            self.m1ar = value
        elif offset == 0x24:
            self.fcr = value & 0x87 if not running else self.fcr & 0x07 | value & 0x80
        else:
            self.others[offset] = value
        self._line()
        self.after_write()
