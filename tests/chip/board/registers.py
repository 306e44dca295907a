"""Reading and writing the core's registers without unicorn's per-call
dispatch.

unicorn's `reg_read`, `reg_write` and `reg_read_batch` pick a value type
per register and build their arguments on every call: some 20 µs for the
26 registers of an exception frame, several µs for one register. With tens
of thousands of step and guard interrupts a second, each touching some
twenty registers, that cost more than the emulation itself. A `Batch`
builds a fixed set's arrays once, `Registers` one value for every single
access, and both call the engine directly; the registers are the 32-bit
core and FPU registers only."""

import ctypes
from collections.abc import Sequence

from unicorn import Uc
from unicorn.unicorn_py3.unicorn import uclib


class Batch:
    def __init__(self, uc: Uc, registers: Sequence[int]) -> None:
        self.uc = uc
        n = len(registers)
        self.n = ctypes.c_int(n)
        self.ids = (ctypes.c_int * n)(*registers)
        self.values = (ctypes.c_uint32 * n)()
        base = ctypes.addressof(self.values)
        self.pointers = (ctypes.c_void_p * n)(*(base + 4 * i for i in range(n)))

    def read(self) -> list[int]:
        if uclib.uc_reg_read_batch(self.uc._uch, self.ids, self.pointers, self.n):
            raise RuntimeError("uc_reg_read_batch failed")
        return list(self.values)

    def write(self, values: Sequence[int]) -> None:
        self.values[:] = [v & 0xFFFF_FFFF for v in values]
        if uclib.uc_reg_write_batch(self.uc._uch, self.ids, self.pointers, self.n):
            raise RuntimeError("uc_reg_write_batch failed")


class Registers:
    """Single 32-bit registers, read and written through one reused value."""

    def __init__(self, uc: Uc) -> None:
        self.uch = uc._uch
        self.value = ctypes.c_uint32()
        self.ref = ctypes.byref(self.value)

    def read(self, register: int) -> int:
        if uclib.uc_reg_read(self.uch, register, self.ref):
            raise RuntimeError(f"uc_reg_read({register}) failed")
        return self.value.value

    def write(self, register: int, value: int) -> None:
        self.value.value = value & 0xFFFF_FFFF
        if uclib.uc_reg_write(self.uch, register, self.ref):
            raise RuntimeError(f"uc_reg_write({register}) failed")
