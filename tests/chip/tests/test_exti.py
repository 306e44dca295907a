"""The EXTI and SYSCFG's routing against RM0090 §9.2.3–9.2.6 (EXTICR)
and §12 (EXTI), the edges coming from a GPIO port's pins."""

from board.gpio import EXTI_IRQ, Exti, Port, Syscfg

from .support import Chip, Recorder

IMR, EMR, RTSR, FTSR, SWIER, PR = 0x00, 0x04, 0x08, 0x0C, 0x10, 0x14
EXTICR1, EXTICR4 = 0x08, 0x14
PORT_A, PORT_B = 0, 1
EXTI15_10_IRQ, EXTI0_IRQ = 40, 6


def exti(chip: Chip) -> tuple[Exti, Syscfg, dict[str, Port]]:
    syscfg = Syscfg()
    e = Exti(chip.nvic, syscfg)
    wiring = Recorder(chip.clock, e)
    ports = {letter: Port(letter, wiring) for letter in "AB"}
    return e, syscfg, ports


def pb12_rising(chip: Chip) -> tuple[Exti, Port]:
    """Line 12 routed to port B (EXTICR4's EXTI12 = 0001), rising trigger."""
    e, syscfg, ports = exti(chip)
    syscfg.write(EXTICR4, PORT_B)
    e.write(RTSR, 1 << 12)
    return e, ports["B"]


def test_line_irqs_follow_the_vector_table() -> None:
    # EXTI0–4 have a vector each, 5–9 and 10–15 share one (RM0090 Table 61).
    assert EXTI_IRQ[:5] == [6, 7, 8, 9, 10]
    assert set(EXTI_IRQ[5:10]) == {23}
    assert set(EXTI_IRQ[10:]) == {40}


def test_selected_edge_sets_the_pending_bit(chip: Chip) -> None:
    e, pb = pb12_rising(chip)
    pb.set_input(12, 1)
    assert e.read(PR) == 1 << 12


def test_edge_not_selected_sets_nothing(chip: Chip) -> None:
    e, pb = pb12_rising(chip)
    pb.set_input(12, 1)
    e.write(PR, 1 << 12)
    pb.set_input(12, 0)  # falling, and only the rising trigger is selected
    assert e.read(PR) == 0
    e.write(FTSR, 1 << 12)
    pb.set_input(12, 1)
    pb.set_input(12, 0)
    assert e.read(PR) == 1 << 12


def test_a_line_hears_the_port_exticr_routes_to_it_only(chip: Chip) -> None:
    e, syscfg, ports = exti(chip)
    syscfg.write(EXTICR4, PORT_B)
    e.write(RTSR, 1 << 12)
    ports["A"].set_input(12, 1)  # PA12: line 12 is port B's
    assert e.read(PR) == 0
    ports["B"].set_input(12, 1)
    assert e.read(PR) == 1 << 12


def test_pending_bit_is_cleared_by_writing_one(chip: Chip) -> None:
    e, pb = pb12_rising(chip)
    pb.set_input(12, 1)
    e.write(PR, 0)  # a 0 written leaves it
    assert e.read(PR) == 1 << 12
    e.write(PR, 1 << 12)
    assert e.read(PR) == 0


def test_pending_unmasked_line_raises_its_interrupt(chip: Chip) -> None:
    e, pb = pb12_rising(chip)
    pb.set_input(12, 1)  # masked: pending, no interrupt
    assert e.read(PR) == 1 << 12
    assert not chip.nvic.pending[EXTI15_10_IRQ]
    e.write(IMR, 1 << 12)  # unmasked with PR set: the request goes out
    assert chip.nvic.pending[EXTI15_10_IRQ]
    # The handler clears PR: the line falls and no new request pends.
    chip.nvic.enter(EXTI15_10_IRQ)
    e.write(PR, 1 << 12)
    chip.nvic.leave(EXTI15_10_IRQ)
    assert not chip.nvic.pending[EXTI15_10_IRQ]


def test_software_interrupt_sets_pr_on_an_unmasked_line(chip: Chip) -> None:
    # SWIER: "sets the corresponding pending bit in EXTI_PR if the interrupt
    # is enabled on this line on the EXTI_IMR".
    e, _, _ = exti(chip)
    e.write(SWIER, 1 << 3)
    assert e.read(PR) == 0
    e.write(IMR, 1)
    e.write(SWIER, 1)
    assert e.read(PR) == 1
    assert chip.nvic.pending[EXTI0_IRQ]


def test_line_0_reset_routing_is_port_a(chip: Chip) -> None:
    e, syscfg, ports = exti(chip)
    assert syscfg.read(EXTICR1) == 0
    e.write(IMR, 1)
    e.write(RTSR, 1)
    ports["A"].set_input(0, 1)
    assert chip.nvic.pending[EXTI0_IRQ]
    assert e.edges == [(0, True, True)]
