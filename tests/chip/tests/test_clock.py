"""The virtual clock the models schedule their events on."""

from fractions import Fraction

from board.clock import Clock, cycles

from .support import Chip


def test_cycles_are_whole_when_they_can_be() -> None:
    assert cycles(168, 84) == 2
    assert isinstance(cycles(168, 84), int)
    assert cycles(168_000_000, 16_000_000) == Fraction(21, 2)


def test_events_fire_in_time_order_at_their_own_instant(chip: Chip) -> None:
    fired: list[tuple[str, int]] = []
    chip.clock.at(300, lambda: fired.append(("b", chip.clock.instant())))
    chip.clock.at(100, lambda: fired.append(("a", chip.clock.instant())))
    late = chip.clock.at(200, lambda: fired.append(("cancelled", 0)))
    late.cancel()
    chip.run_to(250)
    assert fired == [("a", 100)]
    chip.run_to(1000)
    assert fired == [("a", 100), ("b", 300)]
    assert chip.clock.next() is None


def test_an_event_in_the_past_fires_now() -> None:
    clock = Clock()
    clock.base = 500
    event = clock.at(100, lambda: None)
    assert event.cycle == 500


def test_an_event_before_the_runs_end_shortens_the_run() -> None:
    clock = Clock()
    shortened: list[int] = []
    clock.shorten_run = lambda: shortened.append(clock.now)
    clock.run_end = 1000
    clock.at(2000, lambda: None)
    assert shortened == []
    clock.at(999, lambda: None)
    assert shortened == [0]
