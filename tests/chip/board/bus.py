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

from collections.abc import Iterable
from typing import TypeVar

from unicorn import Uc
from unicorn import arm_const as arm

from .registers import Registers

PAGE = 0x1000
B = TypeVar("B", bound="Block")
# A store replayed: nothing to do.
STORED = object()


class Block:
    """A peripheral's registers: `read(offset)` and `write(offset, value)`
    on 32-bit words; byte and half-word accesses are merged into words."""

    name = "block"

    def read(self, offset: int) -> int:
        raise NotImplementedError

    def write(self, offset: int, value: int) -> None:
        raise NotImplementedError

    def write_narrow(self, offset: int, size: int, value: int) -> None:
        """A byte or half-word write: merged into the word it is part of
        (a block with byte registers handles them itself)."""
        shift = 8 * (offset & 3)
        mask = ((1 << (8 * size)) - 1) << shift
        value = (self.read(offset & ~3) & ~mask) | ((value << shift) & mask)
        self.write(offset & ~3, value & 0xFFFF_FFFF)


class Plain(Block):
    """Registers that hold what is written (unmodelled, or without side
    effects), with optional reset values."""

    def __init__(self, name: str, reset: dict[int, int] | None = None) -> None:
        self.name = name
        self.regs = dict(reset or {})

    def read(self, offset: int) -> int:
        return self.regs.get(offset, 0)

    def write(self, offset: int, value: int) -> None:
        self.regs[offset] = value


class Bus:
    def __init__(self, uc: Uc) -> None:
        self.uc = uc
        self.reg = Registers(uc)
        self.blocks: list[tuple[int, int, Block]] = []  # (base, size, block)
        self.pages: dict[int, list[tuple[int, int, Block]]] = {}
        self.fallback: dict[int, Plain] = {}
        self.accesses: dict[int, int] = {}  # address → reads and writes: where the image polls
        self._accessing = False
        self._stopped = False  # the run was ended during the access in progress
        self._replay: dict[tuple[int, int], object] = {}  # (PC, address) → what the access gave the first time

    def stop(self) -> None:
        """Ends the core's current run (at this access, if one is in progress)."""
        self.uc.emu_stop()
        if self._accessing:
            self._stopped = True

    def _replayed(self, address: int) -> object:
        key = (self.reg.read(arm.UC_ARM_REG_PC), address)
        return self._replay.pop(key, None)

    def _record(self, address: int, what: object) -> None:
        self._replay[(self.reg.read(arm.UC_ARM_REG_PC), address)] = what

    def attach(self, base: int, size: int, block: B) -> B:
        self.blocks.append((base, size, block))
        return block

    def map(self, regions: Iterable[tuple[int, int]]) -> None:
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

    def _find(self, address: int) -> tuple[Block, int]:
        page = address & ~(PAGE - 1)
        for b, s, blk in self.pages[page]:
            if b <= address < b + s:
                return blk, address - b
        return self.fallback[page], address - page

    def _read(self, uc: Uc, offset: int, size: int, page: int) -> int:
        address = page + offset
        if self._replay:
            replayed = self._replayed(address)
            if isinstance(replayed, int):
                return replayed
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

    def _write(self, uc: Uc, offset: int, size: int, value: int, page: int) -> None:
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

    def _store(self, address: int, size: int, value: int) -> None:
        blk, off = self._find(address)
        if size < 4:
            # A narrower write: the block's own handling if it has one (byte
            # registers), else merged into the word it is part of.
            blk.write_narrow(off, size, value)
            return
        blk.write(off & ~3, value & 0xFFFF_FFFF)
