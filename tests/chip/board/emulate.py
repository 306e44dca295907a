"""Runs a Cortex-M4F image on the unicorn engine and counts its instructions.

Used by `chip-bench` (bench/src/bin/chip_bench.rs); the unicorn engine comes
from PyPI (`pip install unicorn`), a prebuilt wheel: the `unicorn-engine`
crate would build the engine's C sources with cmake on every clean machine.
Run from tests/chip (or with the package installed):

    python3 -m board.emulate costs IMAGE
                   run `gonio-cost` from reset to its `done` mark; print
                   {name: {count, max, min, total}} as JSON, instructions
                   between each pair of marks, less the marks' own cost (the
                   `overhead` bracket).
    python3 -m board.emulate costs IMAGE NAME
                   the same, and on stderr the functions the longest stretch
                   called NAME ran in.

The unmodified `gonio-head` image runs on the virtual board (the rest of
this package), which takes this module's ELF loader and instruction counter.

Instructions are counted per translated block by a hook in C (count.c, built
here with `cc`): the first time a block runs, its Thumb-2 instructions are
decoded for their length (16 or 32 bits) and counted; every later run adds
that count. Execution is in order and without exceptions, so a block always
runs to its end.
"""

import bisect
import ctypes
import json
import os
import struct
import subprocess
import sys
import tempfile
from collections.abc import Iterable
from typing import Any

import unicorn
from unicorn import (
    UC_ARCH_ARM,
    UC_HOOK_BLOCK,
    UC_HOOK_CODE,
    UC_MODE_MCLASS,
    UC_MODE_THUMB,
    Uc,
    UcError,
)
from unicorn import arm_const as arm
from unicorn.unicorn_py3.unicorn import uc_hook_h, uclib

FLASH = (0x0800_0000, 1 << 20)
SRAM = (0x2000_0000, 128 << 10)
CCM = (0x1000_0000, 64 << 10)
# Peripherals (APB, AHB1/2) and the core's system control space, as plain
# memory for the probes: they touch neither, but cortex-m-rt enables the FPU
# there.
PERIPHERALS = (0x4000_0000, 0x1000_0000)
SYSTEM = (0xE000_0000, 0x0010_0000)
# A run that has not reached its end after this long is stuck.
TIME_LIMIT_US = 1800 * 1_000_000
# `cost_mark`'s phases (firmware/src/bin/cost/probes.rs).
BEGIN, END, VALUE = 0, 1, 2


class Elf:
    """The loadable segments and the symbols of a 32-bit little-endian ELF."""

    def __init__(self, path: str) -> None:
        with open(path, "rb") as f:
            self.data = f.read()
        d = self.data
        if d[:4] != b"\x7fELF" or d[4] != 1 or d[5] != 1:
            raise SystemExit(f"{path}: not a 32-bit little-endian ELF")
        (self.entry, phoff, shoff) = struct.unpack_from("<III", d, 24)
        (phentsize, phnum, shentsize, shnum) = struct.unpack_from("<HHHH", d, 42)
        self.segments: list[tuple[int, bytes]] = []
        for i in range(phnum):
            p_type, off, _vaddr, paddr, filesz, _memsz = struct.unpack_from("<IIIIII", d, phoff + i * phentsize)
            if p_type == 1 and filesz:
                self.segments.append((paddr, d[off : off + filesz]))
        sections = [struct.unpack_from("<IIIIIIIIII", d, shoff + i * shentsize) for i in range(shnum)]
        self.symbols: dict[str, int] = {}
        self.functions: list[tuple[int, int, str]] = []
        for s in sections:
            if s[1] != 2:  # SHT_SYMTAB
                continue
            strtab = sections[s[6]]
            for k in range(s[5] // 16):
                name_off, value, size, info, _other, _shndx = struct.unpack_from("<IIIBBH", d, s[4] + k * 16)
                start = strtab[4] + name_off
                name = d[start : d.index(b"\0", start)].decode()
                self.symbols[name] = value
                if info & 0xF == 2 and size:  # STT_FUNC
                    self.functions.append((value & ~1, size, name))
        self.functions.sort()
        self._starts = [f[0] for f in self.functions]

    def function_at(self, addr: int) -> str:
        """The name of the function holding `addr`, or the address."""
        i = bisect.bisect_right(self._starts, addr) - 1
        f = self.functions[i] if i >= 0 else None
        return f[2] if f and addr < f[0] + f[1] else f"{addr:#x}"


class Counter(ctypes.Structure):
    """`struct counter` of count.c."""

    # The fields' types, for mypy (ctypes makes them from `_fields_`).
    executed: int
    lowest_sp: int
    stretch_lowest: int
    lowest_at: int
    profiling: int

    _fields_ = [
        ("executed", ctypes.c_uint64),
        ("lowest_sp", ctypes.c_uint32),
        ("stretch_lowest", ctypes.c_uint32),
        ("lowest_at", ctypes.c_uint32),
        ("pad", ctypes.c_uint32),
        ("reg_read", ctypes.c_void_p),
        ("mem_read", ctypes.c_void_p),
        ("sp_reg", ctypes.c_int32),
        ("profiling", ctypes.c_int32),
    ]


def counter_library() -> ctypes.CDLL:
    """count.c built with the system's C compiler (the one Rust links with)."""
    source = os.path.join(os.path.dirname(os.path.abspath(__file__)), "count.c")
    with tempfile.TemporaryDirectory() as tmp:
        lib = os.path.join(tmp, "count.so")
        subprocess.run([os.environ.get("CC", "cc"), "-O2", "-shared", "-fPIC", "-o", lib, source], check=True)
        return ctypes.CDLL(lib)


class Machine:
    def __init__(self, elf: Elf, plain: Iterable[tuple[int, int]] = (PERIPHERALS, SYSTEM)) -> None:
        """`plain`: the regions beside memory mapped as plain memory (the
        virtual board maps its own registers there instead)."""
        self.uc = Uc(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
        self.uc.ctl_set_cpu_model(arm.UC_CPU_ARM_CORTEX_M4)
        for base, size in (FLASH, SRAM, CCM, *plain):
            self.uc.mem_map(base, size)
        for addr, blob in elf.segments:
            self.uc.mem_write(addr, blob)
        self.lib = counter_library()
        self.counter = Counter(
            executed=0,
            lowest_sp=0xFFFF_FFFF,
            stretch_lowest=0xFFFF_FFFF,
            lowest_at=0,
            pad=0,
            reg_read=ctypes.cast(uclib.uc_reg_read, ctypes.c_void_p),
            mem_read=ctypes.cast(uclib.uc_mem_read, ctypes.c_void_p),
            sp_reg=arm.UC_ARM_REG_SP,
            profiling=0,
        )
        hook = uc_hook_h()
        status = uclib.uc_hook_add(
            self.uc._uch,
            ctypes.byref(hook),
            UC_HOOK_BLOCK,
            ctypes.cast(self.lib.count_block, ctypes.c_void_p),
            ctypes.cast(ctypes.pointer(self.counter), ctypes.c_void_p),
            1,
            0,
        )
        if status != 0:
            raise SystemExit(f"uc_hook_add failed: {status}")
        # Per open stretch, innermost last: its start SP and the lowest SP
        # of the stretch outside it (count.c follows the innermost one).
        self.open_start: list[int] = []
        self.open_outer: list[int] = []
        self.stack_top = 0  # the initial SP, from the vector table at `reset`

    @property
    def executed(self) -> int:
        return self.counter.executed

    def start_profile(self) -> None:
        """Counts instructions per block from here until `stop_profile`."""
        self.lib.profile_reset()
        self.counter.profiling = 1

    def stop_profile(self) -> None:
        self.counter.profiling = 0

    def profile(self) -> dict[int, int]:
        """{block address: instructions} from `start_profile` to `stop_profile`."""
        n = ctypes.c_uint32.in_dll(self.lib, "profile_len").value
        used = (ctypes.c_uint32 * n).in_dll(self.lib, "profile_used")
        address = (ctypes.c_uint64 * (1 << 16)).in_dll(self.lib, "profile_address")
        count = (ctypes.c_uint64 * (1 << 16)).in_dll(self.lib, "profile_instructions")
        return {address[i]: count[i] for i in used}

    def open_stretch(self) -> None:
        sp = self.uc.reg_read(arm.UC_ARM_REG_SP)
        self.open_start.append(sp)
        self.open_outer.append(self.counter.stretch_lowest)
        self.counter.stretch_lowest = sp

    def close_stretch(self) -> int:
        """The stack the stretch just closed used: from its start to its
        deepest point (stretches nest: an inner one's depth is its outer
        one's too)."""
        lowest = self.counter.stretch_lowest
        self.counter.stretch_lowest = min(self.open_outer.pop(), lowest)
        return self.open_start.pop() - lowest

    def reset(self) -> int:
        sp: int
        pc: int
        sp, pc = struct.unpack("<II", self.uc.mem_read(FLASH[0], 8))
        self.uc.reg_write(arm.UC_ARM_REG_SP, sp)
        self.stack_top = sp
        return pc

    def read_str(self, ptr: int, length: int) -> str:
        return bytes(self.uc.mem_read(ptr, length)).decode()


def by_function(elf: Elf, profile: dict[int, int], top: int = 40) -> list[tuple[str, int]]:
    """The functions a profile's instructions ran in, largest first."""
    totals: dict[str, int] = {}
    for addr, n in profile.items():
        name = elf.function_at(addr)
        totals[name] = totals.get(name, 0) + n
    return sorted(totals.items(), key=lambda kv: -kv[1])[:top]


def costs(path: str, profile_name: str | None = None) -> dict[str, Any]:
    elf = Elf(path)
    m = Machine(elf)
    mark = elf.symbols["cost_mark"] & ~1
    open_at: dict[str, int] = {}
    figures: dict[str, dict[str, Any]] = {}
    values: dict[str, int] = {}
    state: dict[str, Any] = {"done": False, "panic": None}

    def on_mark(uc: Uc, _address: int, _size: int, _user: object) -> None:
        r0, r1, r2, r3 = (
            uc.reg_read(r) for r in (arm.UC_ARM_REG_R0, arm.UC_ARM_REG_R1, arm.UC_ARM_REG_R2, arm.UC_ARM_REG_R3)
        )
        name = m.read_str(r0, r1)
        if r2 == VALUE:
            values[name] = r3
            return
        if name in ("done", "panic") or name.endswith(("_failed", "_refused", "_stalled")):
            state["done"] = name == "done"
            state["panic"] = None if name == "done" else name
            uc.emu_stop()
            return
        if r2 == BEGIN:
            open_at[name] = m.executed
            m.open_stretch()
            if name == profile_name:
                m.start_profile()
        else:
            n = m.executed - open_at.pop(name)
            stack = m.close_stretch()
            if name == profile_name:
                m.stop_profile()
                if n > state.get("profiled", 0):
                    state["profiled"] = n
                    state["profile"] = m.profile()
            f = figures.setdefault(name, {"count": 0, "max": 0, "min": None, "total": 0})
            f["count"] += 1
            f["max"] = max(f["max"], n)
            f["min"] = n if f["min"] is None else min(f["min"], n)
            f["total"] += n
            f["stack_max"] = max(f.get("stack_max", 0), stack)

    m.uc.hook_add(UC_HOOK_CODE, on_mark, begin=mark, end=mark)
    pc = m.reset()
    try:
        # No instruction limit (unicorn would count with a hook of its own
        # on every instruction): the image ends at its `done` mark, a stall
        # or a panic at theirs, anything else at the time limit.
        m.uc.emu_start(pc, 0xFFFF_FFFF, timeout=TIME_LIMIT_US)
    except UcError as e:
        at = m.uc.reg_read(arm.UC_ARM_REG_PC)
        sp = m.uc.reg_read(arm.UC_ARM_REG_SP)
        inside = ", ".join(open_at) or "no stretch"
        raise SystemExit(
            f"emulation failed at pc {at:#010x}, sp {sp:#010x}, after {m.executed} instructions, in {inside}: {e}"
        ) from e
    if not state["done"]:
        partial = {k: (v["count"], v["max"]) for k, v in figures.items()}
        raise SystemExit(f"the image stopped before its end: {state['panic'] or 'no done mark'} (so far: {partial})")
    if profile_name and "profile" in state:
        print(f"longest {profile_name}: {state['profiled']} instructions", file=sys.stderr)
        for name, n in by_function(elf, state["profile"]):
            print(f"  {n:>9}  {name}", file=sys.stderr)
    overhead = figures.pop("overhead")["min"]
    for f in figures.values():
        for k in ("max", "min", "total"):
            f[k] -= overhead * (f["count"] if k == "total" else 1)
    return {
        "emulator": f"unicorn {unicorn.__version__} (Cortex-M4, Thumb-2, instructions counted per translated block)",
        "overhead_instructions": overhead,
        "executed_instructions": m.executed,
        "stack_bytes_max": m.stack_top - m.counter.lowest_sp,
        "values": values,
        "probes": figures,
    }


def main() -> None:
    if len(sys.argv) not in (3, 4) or sys.argv[1] != "costs":
        raise SystemExit(__doc__)
    print(json.dumps(costs(sys.argv[2], sys.argv[3] if len(sys.argv) == 4 else None)))


if __name__ == "__main__":
    main()
