"""The USB OTG_FS core in device mode against RM0090 §34 (slave mode: the
CPU moves the data through the FIFOs), the host's side played by hand."""

import pytest

from board.otg import OTG_FS_IRQ, OtgFs

from .support import Chip

GAHBCFG, GRSTCTL, GINTSTS, GINTMSK, GRXSTSR, GRXSTSP, DIEPTXF1 = 0x08, 0x10, 0x14, 0x18, 0x1C, 0x20, 0x104
DIEPCTL1, DIEPINT1, DIEPTSIZ1, DTXFSTS1 = 0x920, 0x928, 0x930, 0x938
DOEPINT0, DOEPCTL1, DOEPINT1, DOEPTSIZ1 = 0xB08, 0xB20, 0xB28, 0xB30
FIFO0, FIFO1 = 0x1000, 0x2000
RXFLVL = 1 << 4
EPENA, CNAK, SNAK, NAKSTS, USBAEP = 1 << 31, 1 << 26, 1 << 27, 1 << 17, 1 << 15
XFRC, STUP = 1, 1 << 3
RXFFLSH = 1 << 4
# GRXSTSP's packet status (PKTSTS, bits 20:17).
OUT_DATA, OUT_DONE, SETUP_DONE, SETUP_DATA = 0b0010, 0b0011, 0b0100, 0b0110


def status(pktsts: int, bcnt: int, ep: int) -> int:
    """A receive status word: PKTSTS, BCNT (bits 14:4), EPNUM (bits 3:0)."""
    return pktsts << 17 | bcnt << 4 | ep


@pytest.fixture
def otg(chip: Chip) -> OtgFs:
    return OtgFs(chip.nvic)


def armed_out(otg: OtgFs) -> None:
    """Bulk OUT endpoint 1 active, 64-byte packets, armed for one packet."""
    otg.write(DOEPCTL1, USBAEP | EPENA | CNAK | 64)
    otg.write(DOEPTSIZ1, 1 << 19 | 64)


def test_rx_fifo_empty_has_no_rxflvl(otg: OtgFs) -> None:
    assert not otg.read(GINTSTS) & RXFLVL
    assert otg.read(GRXSTSP) == 0


def test_received_packet_is_popped_status_then_data(otg: OtgFs) -> None:
    armed_out(otg)
    assert otg.out(1, b"hello") == "ACK"
    assert otg.read(GINTSTS) & RXFLVL
    # GRXSTSR reads the top of the receive FIFO without popping it.
    assert otg.read(GRXSTSR) == status(OUT_DATA, 5, 1)
    assert otg.read(GRXSTSR) == status(OUT_DATA, 5, 1)
    # GRXSTSP pops it; the packet's words are then read from the FIFO.
    assert otg.read(GRXSTSP) == status(OUT_DATA, 5, 1)
    assert otg.read(FIFO0) == int.from_bytes(b"hell", "little")
    assert otg.read(FIFO0) == int.from_bytes(b"o\0\0\0", "little")
    # A short packet completes the transfer: its own entry, which sets XFRC when popped.
    assert otg.read(GINTSTS) & RXFLVL
    assert not otg.read(DOEPINT1) & XFRC
    assert otg.read(GRXSTSP) == status(OUT_DONE, 0, 1)
    assert otg.read(DOEPINT1) & XFRC
    assert not otg.read(GINTSTS) & RXFLVL
    assert otg.read(GRXSTSP) == 0


def test_rxflvl_is_read_only(otg: OtgFs) -> None:
    armed_out(otg)
    otg.out(1, b"x")
    otg.write(GINTSTS, 0xFFFF_FFFF)
    assert otg.read(GINTSTS) & RXFLVL


def test_rxflvl_raises_the_interrupt_while_the_fifo_holds_entries(chip: Chip, otg: OtgFs) -> None:
    otg.write(GINTMSK, RXFLVL)
    otg.write(GAHBCFG, 1)  # GINTMSK: the core's interrupt line unmasked
    armed_out(otg)
    otg.out(1, b"abc")
    assert chip.nvic.pending[OTG_FS_IRQ]
    otg.read(GRXSTSP)
    assert chip.nvic.level[OTG_FS_IRQ]  # the completion entry is still there
    otg.read(GRXSTSP)
    assert not chip.nvic.level[OTG_FS_IRQ]


def test_endpoint_naks_after_a_transfer_until_cnak(otg: OtgFs) -> None:
    armed_out(otg)
    otg.out(1, b"a")
    assert otg.read(DOEPCTL1) & NAKSTS
    assert otg.out(1, b"b") == "NAK"
    otg.write(DOEPCTL1, otg.read(DOEPCTL1) | CNAK)
    assert otg.out(1, b"b") == "ACK"
    otg.write(DOEPCTL1, otg.read(DOEPCTL1) | SNAK)
    assert otg.out(1, b"c") == "NAK"


def test_setup_packet_then_setup_done_sets_stup(otg: OtgFs) -> None:
    request = bytes([0x80, 6, 0, 1, 0, 0, 18, 0])  # GET_DESCRIPTOR (device)
    assert otg.setup(request) == "ACK"
    assert otg.read(GRXSTSP) == status(SETUP_DATA, 8, 0)
    words = [otg.read(FIFO0), otg.read(FIFO0)]
    assert b"".join(w.to_bytes(4, "little") for w in words) == request
    assert not otg.read(DOEPINT0) & STUP
    assert otg.read(GRXSTSP) == status(SETUP_DONE, 0, 0)
    assert otg.read(DOEPINT0) & STUP
    otg.write(DOEPINT0, STUP)  # written 1 to clear
    assert not otg.read(DOEPINT0) & STUP


def test_rx_fifo_flush_empties_it(otg: OtgFs) -> None:
    armed_out(otg)
    otg.out(1, b"abc")
    otg.write(GRSTCTL, RXFFLSH)
    assert not otg.read(GINTSTS) & RXFLVL
    assert otg.read(GRXSTSP) == 0


def test_tx_fifo_status_counts_free_words_and_in_sends_the_packet(otg: OtgFs) -> None:
    otg.write(DIEPTXF1, 64 << 16 | 0x200)  # 64 words deep
    assert otg.read(DTXFSTS1) == 64
    otg.write(DIEPCTL1, USBAEP | 64)
    otg.write(DIEPTSIZ1, 1 << 19 | 10)
    for word in (b"0123", b"4567", b"89\0\0"):
        otg.write(FIFO1, int.from_bytes(word, "little"))
    assert otg.read(DTXFSTS1) == 61
    assert otg.in_(1) == ("NAK", None)  # not enabled yet
    otg.write(DIEPCTL1, otg.read(DIEPCTL1) | EPENA | CNAK)
    assert otg.in_(1) == ("ACK", b"0123456789")
    assert otg.read(DTXFSTS1) == 64
    assert otg.read(DIEPINT1) & XFRC
    assert not otg.read(DIEPCTL1) & EPENA
