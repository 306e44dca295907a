# The part of unicorn 2.1's Python binding the board uses, typed: the
# package's own hints leave most of `Uc` untyped to mypy.
from . import arm_const as arm_const
from .unicorn_py3.unicorn import Uc as Uc
from .unicorn_py3.unicorn import UcError as UcError

__version__: str

UC_ARCH_ARM: int
UC_MODE_THUMB: int
UC_MODE_MCLASS: int
UC_HOOK_BLOCK: int
UC_HOOK_CODE: int
UC_HOOK_INTR: int
UC_HOOK_MEM_WRITE: int
