"""TIM2–TIM5 against RM0090 §18 (general-purpose timers, upcounting)."""

import pytest

from board.gpio import Port
from board.timer import Timer

from .support import TIMER_CYCLES, Chip, Recorder

CR1, CR2, SMCR, DIER, SR, EGR, CCMR1, CCER, CNT, PSC, ARR, CCR1, CCR2 = (
    0x00,
    0x04,
    0x08,
    0x0C,
    0x10,
    0x14,
    0x18,
    0x20,
    0x24,
    0x28,
    0x2C,
    0x34,
    0x38,
)
CEN, UDIS, URS, ARPE = 1, 1 << 1, 1 << 2, 1 << 7
UIF, CC1IF, CC2IF = 1, 1 << 1, 1 << 2
UIE, CC1IE = 1, 1 << 1
UG = 1
TIM2_IRQ, TIM3_IRQ = 28, 29


def tim2(chip: Chip) -> Timer:
    return Timer("TIM2", TIM2_IRQ, 32, chip.clock, chip.nvic, chip.rcc)


def tim3(chip: Chip) -> Timer:
    return Timer("TIM3", TIM3_IRQ, 16, chip.clock, chip.nvic, chip.rcc)


def started(chip: Chip, t: Timer, psc: int, arr: int) -> Timer:
    """`t` counting at the timer clock over PSC+1, to ARR: the prescaler
    loaded by an update (UG), its UIF cleared, then CEN."""
    t.write(PSC, psc)
    t.write(ARR, arr)
    t.write(EGR, UG)
    t.write(SR, 0)
    t.write(CR1, t.read(CR1) | CEN)
    return t


def test_reset_values_auto_reload_is_the_counters_width(chip: Chip) -> None:
    # TIMx_ARR resets to 0xFFFF, and to 0xFFFF_FFFF on the 32-bit TIM2 and TIM5.
    assert tim3(chip).read(ARR) == 0xFFFF
    assert tim2(chip).read(ARR) == 0xFFFF_FFFF
    t = tim3(chip)
    t.write(ARR, 0x1_2345)
    assert t.read(ARR) == 0x2345


def test_counter_stands_until_cen(chip: Chip) -> None:
    t = tim2(chip)
    chip.run(10_000)
    assert t.read(CNT) == 0
    t.write(CR1, CEN)
    chip.run(10 * TIMER_CYCLES)
    assert t.read(CNT) == 10


def test_prescaler_divides_the_timer_clock(chip: Chip) -> None:
    # CK_CNT = CK_PSC / (PSC + 1): PSC 83 counts at 1 MHz, 168 core cycles a tick.
    t = started(chip, tim2(chip), psc=83, arr=0xFFFF_FFFF)
    chip.run(168 * 100 - 1)
    assert t.read(CNT) == 99
    chip.run(1)
    assert t.read(CNT) == 100


def test_prescaler_is_preloaded_until_an_update_event(chip: Chip) -> None:
    # "The new prescaler ratio is taken into account at the next update event."
    t = tim2(chip)
    t.write(CR1, CEN)
    t.write(PSC, 83)
    assert t.read(PSC) == 83  # the preload register reads back at once
    chip.run(100 * TIMER_CYCLES)
    assert t.read(CNT) == 100  # still counting at the undivided clock
    t.write(EGR, UG)
    assert t.read(CNT) == 0
    chip.run(100 * 84 * TIMER_CYCLES)
    assert t.read(CNT) == 100


def test_ug_restarts_the_counter_and_sets_uif(chip: Chip) -> None:
    t = started(chip, tim3(chip), psc=0, arr=1000)
    chip.run(500 * TIMER_CYCLES)
    assert t.read(CNT) == 500
    assert not t.read(SR) & UIF
    t.write(EGR, UG)
    assert t.read(CNT) == 0
    assert t.read(SR) & UIF


def test_ug_with_urs_sets_no_uif(chip: Chip) -> None:
    # URS = 1: "only counter overflow/underflow generates an update interrupt".
    t = tim3(chip)
    t.write(CR1, URS)
    t.write(EGR, UG)
    assert not t.read(SR) & UIF
    t.write(ARR, 9)
    t.write(CR1, URS | CEN)
    chip.run(10 * TIMER_CYCLES)
    assert t.read(SR) & UIF


def test_overflow_at_arr_wraps_to_zero_and_sets_uif(chip: Chip) -> None:
    # Upcounting: from 0 to ARR, then an overflow event and a restart from 0.
    t = started(chip, tim3(chip), psc=0, arr=999)
    chip.run(999 * TIMER_CYCLES)
    assert t.read(CNT) == 999
    assert not t.read(SR) & UIF
    chip.run(TIMER_CYCLES)
    assert t.read(CNT) == 0
    assert t.read(SR) & UIF


def test_uif_is_cleared_by_writing_zero(chip: Chip) -> None:
    # SR's flags are rc_w0: a 1 written leaves them, a 0 clears them.
    t = started(chip, tim3(chip), psc=0, arr=9)
    t.write(CCR1, 5)
    chip.run(10 * TIMER_CYCLES)
    assert t.read(SR) & (UIF | CC1IF) == UIF | CC1IF
    t.write(SR, 0xFFFF)
    assert t.read(SR) & (UIF | CC1IF) == UIF | CC1IF
    t.write(SR, ~UIF & 0xFFFF)
    assert t.read(SR) & (UIF | CC1IF) == CC1IF


def test_udis_suppresses_the_update_event(chip: Chip) -> None:
    t = started(chip, tim3(chip), psc=0, arr=99)
    t.write(CR1, CEN | UDIS)
    chip.run(150 * TIMER_CYCLES)
    assert t.read(CNT) == 50
    assert not t.read(SR) & UIF


def test_arr_without_arpe_takes_effect_at_once(chip: Chip) -> None:
    t = started(chip, tim3(chip), psc=0, arr=999)
    chip.run(10 * TIMER_CYCLES)
    t.write(ARR, 19)
    chip.run(10 * TIMER_CYCLES)
    assert t.read(SR) & UIF
    assert t.read(CNT) == 0


def test_arr_with_arpe_waits_for_the_update_event(chip: Chip) -> None:
    # ARPE = 1: ARR is buffered, its shadow loaded at the update event.
    t = started(chip, tim3(chip), psc=0, arr=99)
    t.write(CR1, CEN | ARPE)
    t.write(ARR, 49)
    assert t.read(ARR) == 49
    chip.run(60 * TIMER_CYCLES)
    assert t.read(CNT) == 60  # past the new ARR: the old one still counts
    assert not t.read(SR) & UIF
    chip.run(40 * TIMER_CYCLES)
    assert t.read(SR) & UIF
    t.write(SR, 0)
    chip.run(50 * TIMER_CYCLES)  # the next period is the new ARR's
    assert t.read(SR) & UIF
    assert t.read(CNT) == 0


def test_compare_match_sets_ccxif_without_its_interrupt_enabled(chip: Chip) -> None:
    # "CCxIF is set by hardware ... when the counter matches the compare value."
    t = started(chip, tim2(chip), psc=0, arr=999)
    t.write(CCR1, 300)
    t.write(CCR2, 700)
    chip.run(299 * TIMER_CYCLES)
    assert t.read(SR) & (CC1IF | CC2IF) == 0
    chip.run(TIMER_CYCLES)
    assert t.read(SR) & (CC1IF | CC2IF) == CC1IF
    chip.run(400 * TIMER_CYCLES)
    assert t.read(SR) & (CC1IF | CC2IF) == CC1IF | CC2IF
    assert not chip.nvic.pending[TIM2_IRQ]


def test_compare_beyond_arr_never_matches(chip: Chip) -> None:
    t = started(chip, tim3(chip), psc=0, arr=99)
    t.write(CCR1, 200)
    chip.run(1000 * TIMER_CYCLES)
    assert not t.read(SR) & CC1IF


def test_enabled_compare_interrupt_pends_at_the_match(chip: Chip) -> None:
    # No register access in between: the interrupt must pend by itself, at
    # the cycle the counter reaches CCR1.
    t = started(chip, tim2(chip), psc=83, arr=0xFFFF_FFFF)
    start = chip.now
    t.write(CCR1, 1000)
    t.write(DIER, CC1IE)
    chip.run(2000 * 168)
    assert chip.nvic.pending[TIM2_IRQ]
    assert chip.nvic.pended_at[TIM2_IRQ] == start + 1000 * 168


def test_enabled_update_interrupt_pends_at_each_overflow(chip: Chip) -> None:
    t = started(chip, tim3(chip), psc=0, arr=999)
    start = chip.now
    t.write(DIER, UIE)
    chip.run(1500 * TIMER_CYCLES)
    assert chip.nvic.pended_at[TIM3_IRQ] == start + 1000 * TIMER_CYCLES
    # The handler clears UIF: the line falls, and the next overflow pends it again.
    chip.nvic.enter(TIM3_IRQ)
    t.write(SR, 0)
    chip.nvic.leave(TIM3_IRQ)
    assert not chip.nvic.pending[TIM3_IRQ]
    chip.run(1000 * TIMER_CYCLES)
    assert chip.nvic.pending[TIM3_IRQ]
    assert chip.nvic.pended_at[TIM3_IRQ] == start + 2000 * TIMER_CYCLES


def test_flag_without_its_enable_raises_no_interrupt(chip: Chip) -> None:
    t = started(chip, tim3(chip), psc=0, arr=9)
    chip.run(100 * TIMER_CYCLES)
    assert t.read(SR) & UIF
    assert not chip.nvic.pending[TIM3_IRQ]
    t.write(DIER, UIE)  # enabling it with the flag set asserts the line
    assert chip.nvic.pending[TIM3_IRQ]


def test_cnt_is_writable(chip: Chip) -> None:
    t = started(chip, tim3(chip), psc=0, arr=999)
    t.write(CNT, 990)
    chip.run(10 * TIMER_CYCLES)
    assert t.read(CNT) == 0
    assert t.read(SR) & UIF


def test_slave_counts_the_masters_updates(chip: Chip) -> None:
    # TIM3 in external clock mode 1 (SMS = 111) on ITR1, TIM2's TRGO being
    # its update event (MMS = 010): TIM3 counts TIM2's overflows.
    master, slave = tim2(chip), tim3(chip)
    slave.triggers[1] = master
    master.slaves.append(slave)
    master.write(CR2, 0b010 << 4)
    started(chip, master, psc=0, arr=99)
    slave.write(SMCR, 1 << 4 | 0b111)
    slave.write(CR1, CEN)
    chip.run(1050 * TIMER_CYCLES)
    assert slave.read(CNT) == 10
    assert master.read(CNT) == 50
    # An update by software (UG) is an update event too: one more edge.
    master.write(EGR, UG)
    assert slave.read(CNT) == 11


@pytest.mark.parametrize(("mode", "high_below"), [(0b110, True), (0b111, False)])
def test_pwm_output_follows_the_compare(chip: Chip, mode: int, high_below: bool) -> None:
    # PWM mode 1 (OC1M = 110): OC1REF high while CNT < CCR1; mode 2 the
    # opposite. CC1E drives the pin (PA6, alternate function).
    wiring = Recorder(chip.clock)
    port = Port("A", wiring)
    port.write(0x00, 0b10 << 12)  # PA6 alternate function
    t = tim3(chip)
    t.outputs[0] = (port, 6)
    t.write(CCMR1, mode << 4)
    t.write(CCR1, 25)
    t.write(CCER, 1)
    started(chip, t, psc=0, arr=99)
    assert port.level[6] == int(high_below)
    chip.run(30 * TIMER_CYCLES)
    assert port.level[6] == int(not high_below)
    # The edge at CNT = CCR1 is scheduled, not found at the next access.
    edges = [(cycle, level) for cycle, pin, level in wiring.edges if pin == "PA6"]
    assert edges[-1] == (chip.now - 5 * TIMER_CYCLES, int(not high_below))
    t.write(CCER, 0)  # CC1E clear: the timer lets go of the pin
    assert 6 not in port.alternate
