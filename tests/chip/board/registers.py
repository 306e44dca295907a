"""Reading and writing a fixed set of the core's registers in one call.

unicorn's `reg_read_batch` picks a value type per register and builds its
argument arrays on every call, some 20 µs for the 26 registers of an
exception frame: with tens of thousands of step interrupts a second, more
than the emulation itself. A `Batch` builds them once and calls the engine
directly; the registers are the 32-bit core and FPU registers only."""

import ctypes

from unicorn.unicorn_py3.unicorn import uclib


class Batch:
    def __init__(self, uc, registers):
        self.uc = uc
        n = len(registers)
        self.n = ctypes.c_int(n)
        self.ids = (ctypes.c_int * n)(*registers)
        self.values = (ctypes.c_uint32 * n)()
        base = ctypes.addressof(self.values)
        self.pointers = (ctypes.c_void_p * n)(*(base + 4 * i for i in range(n)))

    def read(self):
        if uclib.uc_reg_read_batch(self.uc._uch, self.ids, self.pointers, self.n):
            raise RuntimeError("uc_reg_read_batch failed")
        return list(self.values)

    def write(self, values):
        self.values[:] = [v & 0xFFFF_FFFF for v in values]
        if uclib.uc_reg_write_batch(self.uc._uch, self.ids, self.pointers, self.n):
            raise RuntimeError("uc_reg_write_batch failed")
