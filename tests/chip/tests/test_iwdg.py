"""The independent watchdog against RM0090 §21 (IWDG) and its Table 107
of timeouts on the 32 kHz LSI."""

import pytest

from board.clock import HZ
from board.system import Iwdg

from .support import Chip

KR, PR, RLR = 0x00, 0x04, 0x08
START, RELOAD, UNLOCK = 0xCCCC, 0xAAAA, 0x5555


class Watchdog:
    """An IWDG and the resets it causes (the clock's cycle of each)."""

    def __init__(self, chip: Chip) -> None:
        self.chip = chip
        self.resets: list[int] = []
        self.iwdg = Iwdg(chip.clock, lambda: self.resets.append(chip.clock.instant()))

    def configure(self, pr: int, rlr: int) -> None:
        self.iwdg.write(KR, UNLOCK)
        self.iwdg.write(PR, pr)
        self.iwdg.write(KR, UNLOCK)
        self.iwdg.write(RLR, rlr)


def seconds(s: float) -> int:
    return round(s * HZ)


@pytest.fixture
def dog(chip: Chip) -> Watchdog:
    return Watchdog(chip)


def test_counts_nothing_until_started(chip: Chip, dog: Watchdog) -> None:
    chip.run(seconds(60))
    assert dog.resets == []
    assert not dog.iwdg.running


def test_start_counts_down_from_0xfff(chip: Chip, dog: Watchdog) -> None:
    # PR 0 (/4), from 0xFFF: Table 107's longest timeout at /4, 512 ms.
    dog.iwdg.write(KR, START)
    chip.run(seconds(0.512) - 1)
    assert dog.resets == []
    chip.run(1)
    assert dog.resets == [seconds(0.512)]


def test_start_counts_from_0xfff_whatever_rlr_holds(chip: Chip, dog: Watchdog) -> None:
    # "the counter starts counting down from the reset value of 0xFFF"
    dog.configure(pr=0, rlr=99)
    dog.iwdg.write(KR, START)
    chip.run(seconds(0.5))
    assert dog.resets == []
    chip.run(seconds(0.1))
    assert dog.resets == [seconds(0.512)]


@pytest.mark.parametrize(
    ("pr", "rlr", "timeout_ms"),
    [(0, 0, 0.125), (0, 0xFFF, 512), (3, 0xFFF, 4096), (6, 0, 8), (6, 0xFFF, 32768), (7, 0xFFF, 32768)],
)
def test_reload_timeouts_follow_table_107(chip: Chip, dog: Watchdog, pr: int, rlr: int, timeout_ms: float) -> None:
    dog.configure(pr, rlr)
    dog.iwdg.write(KR, START)
    chip.run(1000)
    dog.iwdg.write(KR, RELOAD)  # from RLR now
    reloaded = chip.now
    chip.run(seconds(timeout_ms / 1000) - 1)
    assert dog.resets == []
    chip.run(1)
    assert dog.resets == [reloaded + seconds(timeout_ms / 1000)]


def test_reload_postpones_the_reset(chip: Chip, dog: Watchdog) -> None:
    dog.configure(pr=1, rlr=999)  # /8: 250 µs a count, 250 ms in all
    dog.iwdg.write(KR, START)
    dog.iwdg.write(KR, RELOAD)
    for _ in range(10):
        chip.run(seconds(0.2))
        dog.iwdg.write(KR, RELOAD)
    assert dog.resets == []
    assert len(dog.iwdg.reloads) == 11
    last = chip.now
    chip.run(seconds(1))
    assert dog.resets == [last + seconds(0.25)]


def test_pr_and_rlr_are_write_protected_until_0x5555(dog: Watchdog) -> None:
    iwdg = dog.iwdg
    iwdg.write(PR, 4)
    iwdg.write(RLR, 0x123)
    assert (iwdg.read(PR), iwdg.read(RLR)) == (0, 0xFFF)  # reset values
    iwdg.write(KR, UNLOCK)
    iwdg.write(PR, 4)
    assert iwdg.read(PR) == 4
    iwdg.write(KR, RELOAD)  # any other key protects them again
    iwdg.write(RLR, 0x123)
    assert iwdg.read(RLR) == 0xFFF


def test_registers_keep_their_width(dog: Watchdog) -> None:
    dog.configure(pr=0xFF, rlr=0xFFFF)
    assert (dog.iwdg.read(PR), dog.iwdg.read(RLR)) == (7, 0xFFF)


def test_reload_before_start_starts_nothing(chip: Chip, dog: Watchdog) -> None:
    dog.iwdg.write(KR, RELOAD)
    chip.run(seconds(60))
    assert dog.resets == []
