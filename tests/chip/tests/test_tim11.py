"""TIM11 against RM0090 §19: its counter and update flag, and channel 1
capturing HSE_RTC, as the image's crystal check uses them."""

import itertools

from board.clock import HZ, Clock
from board.system import Rcc
from board.tim11 import Tim11

CR1, SR, EGR, CCMR1, CCER, CNT, PSC, ARR, CCR1, OR = 0x00, 0x10, 0x14, 0x18, 0x20, 0x24, 0x28, 0x2C, 0x34, 0x50
UIF, CC1IF = 1, 2


def timer(crystal: int | None) -> tuple[Clock, Rcc, Tim11]:
    """TIM11 on the HSI (16 MHz, reset clocks), the crystal on, RTCPRE 31."""
    clock, rcc = Clock(), Rcc(crystal)
    rcc.write(0x00, rcc.read(0x00) | 1 << 16)
    rcc.write(0x08, 31 << 16)
    t = Tim11(clock, rcc)
    t.write(EGR, 1)
    t.write(SR, 0)
    t.write(CR1, 1)
    return clock, rcc, t


def test_the_counter_counts_the_hsi_and_flags_its_overflows() -> None:
    clock, _, t = timer(8_000_000)
    # 10.5 core cycles per HSI tick.
    clock.base = 1000 * HZ // 16_000_000 + 5
    assert t.read(CNT) == 1000
    assert not t.read(SR) & UIF
    clock.base = 65_536 * HZ // 16_000_000
    assert t.read(SR) & UIF and t.read(CNT) == 0
    t.write(SR, ~UIF & 0xFFFF)
    assert not t.read(SR) & UIF


def capture_ticks(crystal: int, captures: int = 16) -> int:
    """HSI ticks over `captures` captures, polled as the image polls."""
    clock, _, t = timer(crystal)
    t.write(OR, 0b10)
    t.write(CCMR1, 0b01 | 0b11 << 2)
    t.write(CCER, 1)
    values: list[int] = []
    while len(values) < captures + 1:
        clock.base += 40
        if t.read(SR) & CC1IF:
            values.append(t.read(CCR1))
            assert not t.read(SR) & CC1IF, "reading CCR1 clears CC1IF"
    return sum((b - a) & 0xFFFF for a, b in itertools.pairwise(values))


def test_captures_count_the_crystal_against_the_hsi() -> None:
    # 16 captures of 8 edges of the crystal ÷31, in 16 MHz ticks.
    assert abs(capture_ticks(8_000_000) - 7936) <= 1
    assert abs(capture_ticks(12_000_000) - 5291) <= 1


def test_nothing_is_captured_without_a_crystal_or_its_route() -> None:
    clock, _, t = timer(None)
    t.write(OR, 0b10)
    t.write(CCMR1, 0b01 | 0b11 << 2)
    t.write(CCER, 1)
    clock.base = HZ // 100
    assert not t.read(SR) & CC1IF
    clock, _, t = timer(8_000_000)
    t.write(CCMR1, 0b01 | 0b11 << 2)
    t.write(CCER, 1)  # TI1 left on its GPIO
    clock.base = HZ // 100
    assert not t.read(SR) & CC1IF
