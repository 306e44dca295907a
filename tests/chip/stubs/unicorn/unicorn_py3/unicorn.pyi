import ctypes
from collections.abc import Callable
from typing import Any

# The engine's C library, and its hook handle type (the board calls the C
# API directly where the binding's per-call cost is too high).
uclib: ctypes.CDLL
uc_hook_h = ctypes.c_size_t

class UcError(Exception):
    errno: int

class Uc:
    _uch: ctypes.c_void_p
    def __init__(self, arch: int, mode: int, cpu: int | None = None) -> None: ...
    def ctl_set_cpu_model(self, model: int) -> None: ...
    def mem_map(self, address: int, size: int, perms: int = ...) -> None: ...
    def mmio_map(
        self,
        address: int,
        size: int,
        read_cb: Callable[[Uc, int, int, Any], int] | None,
        read_ud: object,
        write_cb: Callable[[Uc, int, int, int, Any], None] | None,
        write_ud: object,
    ) -> None: ...
    def mem_read(self, address: int, size: int) -> bytearray: ...
    def mem_write(self, address: int, data: bytes) -> None: ...
    # The 32-bit core and FPU registers only: ints.
    def reg_read(self, reg_id: int, aux: object = None) -> int: ...
    def reg_write(self, reg_id: int, value: int) -> None: ...
    def hook_add(
        self,
        htype: int,
        callback: Callable[..., object],
        user_data: object = None,
        begin: int = 1,
        end: int = 0,
        aux1: int = 0,
        aux2: int = 0,
    ) -> int: ...
    def emu_start(self, begin: int, until: int, timeout: int = 0, count: int = 0) -> None: ...
    def emu_stop(self) -> None: ...
