"""The memory map: flash and RAM as plain memory, the peripherals as
register blocks. unicorn maps MMIO by 4 KiB pages, and one page can hold
several peripherals (TIM2–TIM5, GPIOA–GPIOD, RCC and FLASH), so a page
dispatches each access to the block at its address; an address no block
models reads back what was written there, as a register without side
effects would.

A run of the core may have to end in the middle of an access (it made an
interrupt pend that must be taken at this instruction, or an event due
sooner). unicorn then executes the accessing instruction again when the
core resumes: a load's result is dropped and a store has already reached
the block. So that the block sees each access once, as on silicon, that
access is recorded and replayed when the instruction comes again: the
value first read, or nothing for a store.
"""

from unicorn import arm_const as arm
from registers import Registers

PAGE = 0x1000
# A store replayed: nothing to do.
STORED = object()


class Block:
    """A peripheral's registers: `read(offset)` and `write(offset, value)`
    on 32-bit words; byte and half-word accesses are merged into words."""

    name = "block"

    def read(self, offset):
        raise NotImplementedError

    def write(self, offset, value):
        raise NotImplementedError


class Plain(Block):
    """Registers that hold what is written (unmodelled, or without side
    effects), with optional reset values."""

    def __init__(self, name, reset=None):
        self.name = name
        self.regs = dict(reset or {})

    def read(self, offset):
        return self.regs.get(offset, 0)

    def write(self, offset, value):
        self.regs[offset] = value


class Bus:
    def __init__(self, uc):
        self.uc = uc
        self.reg = Registers(uc)
        self.blocks = []  # (base, size, block)
        self.pages = {}
        self.accesses = {}  # address → reads and writes: where the image polls
        self._accessing = False
        self._stopped = False  # the run was ended during the access in progress
        self._replay = {}  # (PC, address) → what the access gave the first time

    def stop(self):
        """Ends the core's current run (at this access, if one is in progress)."""
        self.uc.emu_stop()
        if self._accessing:
            self._stopped = True

    def _replayed(self, address):
        key = (self.reg.read(arm.UC_ARM_REG_PC), address)
        return self._replay.pop(key, None)

    def _record(self, address, what):
        self._replay[(self.reg.read(arm.UC_ARM_REG_PC), address)] = what

    def attach(self, base, size, block):
        self.blocks.append((base, size, block))
        return block

    def map(self, regions):
        """Maps the blocks' pages as MMIO and the rest of `regions` ((base,
        size)) as plain memory."""
        pages = sorted({(b + o) & ~(PAGE - 1) for b, s, _ in self.blocks for o in range(0, s, PAGE)})
        for page in pages:
            self.uc.mmio_map(page, PAGE, self._read, page, self._write, page)
        taken = set(pages)
        for base, size in regions:
            run = None
            for page in range(base, base + size + PAGE, PAGE):
                free = page < base + size and page not in taken
                if free and run is None:
                    run = page
                elif not free and run is not None:
                    self.uc.mem_map(run, page - run)
                    run = None
        self.pages = {p: [(b, s, blk) for b, s, blk in self.blocks if b < p + PAGE and b + s > p] for p in pages}
        self.fallback = {p: Plain(f"unmodelled {p:#x}") for p in pages}

    def _find(self, address):
        page = address & ~(PAGE - 1)
        for b, s, blk in self.pages[page]:
            if b <= address < b + s:
                return blk, address - b
        return self.fallback[page], address - page

    def _read(self, uc, offset, size, page):
        address = page + offset
        if self._replay:
            value = self._replayed(address)
            if value is not None:
                return value
        self.accesses[address] = self.accesses.get(address, 0) + 1
        self._accessing = True
        try:
            blk, off = self._find(address)
            word = blk.read(off & ~3)
            shift = 8 * (off & 3)
            value = (word >> shift) & ((1 << (8 * size)) - 1)
        finally:
            self._accessing = False
        if self._stopped:
            self._stopped = False
            self._record(address, value)
        return value

    def _write(self, uc, offset, size, value, page):
        address = page + offset
        if self._replay and self._replayed(address) is STORED:
            return
        self.accesses[address] = self.accesses.get(address, 0) + 1
        self._accessing = True
        try:
            self._store(address, size, value)
        finally:
            self._accessing = False
        if self._stopped:
            self._stopped = False
            self._record(address, STORED)

    def _store(self, address, size, value):
        blk, off = self._find(address)
        if size < 4:
            # A narrower write: the block's own handling if it has one (byte
            # registers), else merged into the word it is part of.
            if hasattr(blk, "write_narrow"):
                blk.write_narrow(off, size, value)
                return
            shift = 8 * (off & 3)
            mask = ((1 << (8 * size)) - 1) << shift
            value = (blk.read(off & ~3) & ~mask) | ((value << shift) & mask)
        blk.write(off & ~3, value & 0xFFFF_FFFF)
