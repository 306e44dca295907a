"""The NVIC and SCB against the ARMv7-M Architecture Reference Manual
(B3.4 NVIC, B3.2 SCB) and PM0214 §4.2–4.4 (the STM32F4's 4 priority bits)."""

import pytest

from board.nvic import EXTERNAL, Nvic, SystemResetRequest

from .support import Chip

ISER, ICER, ISPR, ICPR, IABR, IPR = 0x100, 0x180, 0x200, 0x280, 0x300, 0x400
ICSR, VTOR, AIRCR, STIR = 0xD04, 0xD08, 0xD0C, 0xF00
VECTKEY = 0x05FA << 16
TIM2, TIM5, DMA2_STREAM0, OTG_FS = 28, 50, 56, 67


def test_set_and_clear_enable_are_written_one_to_act() -> None:
    n = Nvic()
    n.write(ISER, 1 << TIM2)
    n.write(ISER + 4, 1 << (DMA2_STREAM0 - 32))
    assert n.read(ISER) == 1 << TIM2 == n.read(ICER)
    assert n.read(ISER + 4) == 1 << (DMA2_STREAM0 - 32)
    n.write(ISER, 0)  # zeros have no effect
    n.write(ICER, 0)
    assert n.enabled[TIM2]
    n.write(ICER, 1 << TIM2)
    assert not n.enabled[TIM2]
    assert n.enabled[DMA2_STREAM0]


def test_set_and_clear_pending() -> None:
    n = Nvic()
    n.write(ISPR + 8, 1 << (OTG_FS - 64))
    assert n.pending[OTG_FS]
    assert n.read(ICPR + 8) == 1 << (OTG_FS - 64)
    n.write(ICPR + 8, 1 << (OTG_FS - 64))
    assert not n.pending[OTG_FS]


def test_stir_pends_the_interrupt_it_names() -> None:
    n = Nvic()
    n.write(STIR, TIM5)
    assert n.pending[TIM5]


def test_priorities_keep_their_upper_four_bits() -> None:
    # "Each priority field holds a priority value, 0-255"; the STM32F4
    # implements bits [7:4], the rest read as zero.
    n = Nvic()
    n.write(IPR + TIM2 // 4 * 4, 0xFF << 8 * (TIM2 % 4))
    assert n.priority[TIM2] == 0xF0
    assert n.read(IPR + TIM2 // 4 * 4) == 0xF0 << 8 * (TIM2 % 4)
    n.write_narrow(IPR + DMA2_STREAM0, 1, 0x5A)  # a byte store
    assert n.priority[DMA2_STREAM0] == 0x50
    assert n.priority[DMA2_STREAM0 + 1] == 0


def test_asserted_line_pends_once_until_its_handler_returns() -> None:
    # B1.5.6: an interrupt whose signal is still asserted when its handler
    # returns is pended again.
    n = Nvic()
    n.line(TIM2, True)
    assert n.pending[TIM2]
    n.enter(TIM2)
    n.line(TIM2, True)  # still asserted: not a new rising level
    assert not n.pending[TIM2]
    assert n.read(IABR) == 1 << TIM2
    n.leave(TIM2)
    assert n.pending[TIM2]
    assert n.read(IABR) == 0
    n.enter(TIM2)
    n.line(TIM2, False)
    n.leave(TIM2)
    assert not n.pending[TIM2]


def test_clearing_the_pending_state_of_an_asserted_line_fails() -> None:
    n = Nvic()
    n.line(TIM2, True)
    n.write(ICPR, 1 << TIM2)
    assert n.pending[TIM2]
    n.line(TIM2, False)
    n.write(ICPR, 1 << TIM2)
    assert not n.pending[TIM2]


def test_pending_is_timed_by_the_clock(chip: Chip) -> None:
    chip.run(1234)
    chip.nvic.line(TIM2, True)
    assert chip.nvic.pended_at[TIM2] == 1234


def test_best_pending_is_the_enabled_lowest_priority_value_then_lowest_number() -> None:
    n = Nvic()
    for irq, priority in ((TIM2, 0x20), (TIM5, 0x10), (DMA2_STREAM0, 0x10), (OTG_FS, 0x00)):
        n.priority[irq] = priority
        n.write(ISPR + irq // 32 * 4, 1 << irq % 32)
    assert n.best_pending() is None  # none enabled
    n.write(ISER, 1 << TIM2)
    n.write(ISER + 4, 1 << (TIM5 - 32) | 1 << (DMA2_STREAM0 - 32))
    assert n.best_pending() == (0x10, TIM5)
    # ICSR: VECTPENDING is its exception number, ISRPENDING set.
    assert n.read(ICSR) == (TIM5 + EXTERNAL) << 12 | 1 << 22


@pytest.mark.parametrize(("prigroup", "group"), [(0, 0xB0), (3, 0xB0), (4, 0xA0), (5, 0x80), (7, 0)])
def test_prigroup_splits_group_priority_from_subpriority(prigroup: int, group: int) -> None:
    n = Nvic()
    n.write(AIRCR, VECTKEY | prigroup << 8)
    assert n.read(AIRCR) == 0xFA05_0000 | prigroup << 8
    assert n.group(0xB0) == group


def test_aircr_needs_its_key() -> None:
    n = Nvic()
    n.write(AIRCR, 5 << 8)
    assert n.prigroup == 0
    n.write(AIRCR, 5 << 8 | 1 << 2)  # SYSRESETREQ without the key: ignored


def test_sysresetreq_resets_the_system() -> None:
    n = Nvic()
    with pytest.raises(SystemResetRequest):
        n.write(AIRCR, VECTKEY | 1 << 2)


def test_running_priority_is_the_active_exceptions_highest() -> None:
    n = Nvic()
    assert n.running_priority() == 256
    n.priority[TIM2], n.priority[TIM5] = 0x40, 0x20
    n.enter(TIM2)
    n.enter(TIM5)
    assert n.running_priority() == 0x20
    assert n.running_priority(excluding=TIM5) == 0x40


def test_vtor_is_aligned() -> None:
    n = Nvic()
    n.write(VTOR, 0x0800_40FF)
    assert n.read(VTOR) == 0x0800_4080
