"""The GPIO ports against RM0090 §8 (GPIO registers)."""

import pytest

from board.gpio import Port

from .support import Chip, Recorder

MODER, OTYPER, OSPEEDR, PUPDR, IDR, ODR, BSRR = 0x00, 0x04, 0x08, 0x0C, 0x10, 0x14, 0x18
INPUT, OUTPUT, ALTERNATE = 0b00, 0b01, 0b10


def port(letter: str = "C", chip: Chip | None = None) -> tuple[Port, Recorder]:
    wiring = Recorder(chip.clock if chip else None)
    return Port(letter, wiring), wiring


def outputs(p: Port, *pins: int) -> None:
    p.write(MODER, p.read(MODER) | sum(OUTPUT << (2 * n) for n in pins))


@pytest.mark.parametrize(
    ("letter", "moder", "ospeedr", "pupdr"),
    [("A", 0xA800_0000, 0x0C00_0000, 0x6400_0000), ("B", 0x0000_0280, 0x0000_00C0, 0x0000_0100), ("C", 0, 0, 0)],
)
def test_reset_values(letter: str, moder: int, ospeedr: int, pupdr: int) -> None:
    # §8.4: port A and B's debug pins are alternate functions out of reset.
    p, _ = port(letter)
    assert (p.read(MODER), p.read(OSPEEDR), p.read(PUPDR), p.read(ODR)) == (moder, ospeedr, pupdr, 0)


def test_bsrr_sets_and_resets_odr_bits() -> None:
    p, _ = port()
    outputs(p, 0, 1, 2)
    p.write(BSRR, 0b111)
    assert p.read(ODR) == 0b111
    p.write(BSRR, 0b101 << 16)
    assert p.read(ODR) == 0b010
    p.write(BSRR, 0)  # a 0 written has no effect
    assert p.read(ODR) == 0b010


def test_bsrr_set_wins_over_reset() -> None:
    # "If both BSx and BRx are set, BSx has priority."
    p, _ = port()
    outputs(p, 4)
    p.write(BSRR, 1 << 4 | 1 << (16 + 4))
    assert p.read(ODR) == 1 << 4


def test_bsrr_reads_as_zero() -> None:
    p, _ = port()
    p.write(BSRR, 0xFFFF)
    assert p.read(BSRR) == 0


def test_idr_reads_the_pins_an_output_drives() -> None:
    p, _ = port()
    outputs(p, 3)
    p.write(ODR, 1 << 3 | 1 << 5)  # pin 5 is an input: its ODR bit drives nothing
    assert p.read(IDR) & (1 << 3 | 1 << 5) == 1 << 3
    p.write(BSRR, 1 << (16 + 3))
    assert not p.read(IDR) & 1 << 3


def test_idr_reads_an_inputs_pull_and_what_drives_it() -> None:
    p, wiring = port()
    p.write(PUPDR, 0b01 << 2 * 7 | 0b10 << 2 * 8)  # PC7 pull-up, PC8 pull-down
    assert p.read(IDR) & (1 << 7 | 1 << 8) == 1 << 7
    p.set_input(7, 0)  # driven from outside: stronger than the pull
    p.set_input(8, 1)
    assert p.read(IDR) & (1 << 7 | 1 << 8) == 1 << 8
    assert wiring.readings == 2  # the board hears of each IDR read


def test_otyper_is_16_bits() -> None:
    p, _ = port()
    p.write(OTYPER, 0xFFFF_FFFF)
    assert p.read(OTYPER) == 0xFFFF


def test_output_changes_are_logged_and_every_change_is_an_edge(chip: Chip) -> None:
    p, wiring = port("C", chip)
    outputs(p, 0)
    assert wiring.logged == [(0, "PC0", 0)]  # driven from now on, low
    chip.run(100)
    p.write(BSRR, 1)
    p.write(BSRR, 1)  # no change: nothing more
    chip.run(100)
    p.write(BSRR, 1 << 16)
    assert wiring.logged == [(0, "PC0", 0), (100, "PC0", 1), (200, "PC0", 0)]
    assert wiring.edges == [(100, "PC0", 1), (200, "PC0", 0)]


def test_alternate_function_pin_follows_its_peripheral() -> None:
    p, _ = port("A")
    p.write(MODER, p.read(MODER) | ALTERNATE << 2 * 6)
    p.drive(6, 1)
    assert p.read(IDR) & 1 << 6
    p.drive(6, None)  # the peripheral lets go: the pin floats, keeping its level
    assert p.read(IDR) & 1 << 6
    p.write(PUPDR, p.read(PUPDR) | 0b10 << 2 * 6)
    assert not p.read(IDR) & 1 << 6


def test_reset_lets_the_pins_go_to_their_resistors() -> None:
    p, wiring = port()
    p.resistors[2] = 1
    outputs(p, 2)
    assert p.level[2] == 0
    p.reset()
    assert p.read(MODER) == 0
    assert p.level[2] == 1
    assert wiring.logged[-1] == (0, "PC2", 1)
