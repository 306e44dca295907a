"""DMA2 stream 0 against RM0090 §10 (DMA controller), peripheral to
memory as ADC1's results reach memory."""

import struct

import pytest
from unicorn import UC_ARCH_ARM, UC_MODE_MCLASS, UC_MODE_THUMB, Uc

from board.adc import DR
from board.dma import STREAM0_IRQ, Dma

from .support import Chip

LISR, HISR, LIFCR, HIFCR = 0x00, 0x04, 0x08, 0x0C
S0CR, S0NDTR, S0PAR, S0M0AR, S0FCR = 0x10, 0x14, 0x18, 0x1C, 0x24
EN, TEIE, HTIE, TCIE, CIRC, MINC = 1, 1 << 2, 1 << 3, 1 << 4, 1 << 8, 1 << 10
PSIZE_16, MSIZE_16 = 1 << 11, 1 << 13
FEIF0, DMEIF0, TEIF0, HTIF0, TCIF0 = 1, 1 << 2, 1 << 3, 1 << 4, 1 << 5
SRAM = 0x2000_0000
BUFFER = SRAM + 0x100


class Stream:
    """DMA2 stream 0 with SRAM behind it."""

    def __init__(self, chip: Chip) -> None:
        self.uc = Uc(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
        self.uc.mem_map(SRAM, 0x1000)
        self.nvic = chip.nvic
        self.dma = Dma(self.uc, chip.nvic, chip.clock)

    def program(self, items: int, cr: int = 0) -> None:
        """Channel 0, peripheral (ADC1's DR) to memory, 16-bit items, the
        memory address incremented; then enabled."""
        self.dma.write(S0PAR, DR)
        self.dma.write(S0M0AR, BUFFER)
        self.dma.write(S0NDTR, items)
        self.dma.write(S0CR, PSIZE_16 | MSIZE_16 | MINC | cr)
        self.dma.write(S0CR, self.dma.read(S0CR) | EN)

    def request(self, *items: int) -> int:
        """The ADC's requests, one item each: how many the stream took."""
        return self.dma.receive(struct.pack(f"<{len(items)}H", *items))

    def memory(self, items: int) -> list[int]:
        return list(struct.unpack(f"<{items}H", self.uc.mem_read(BUFFER, 2 * items)))


@pytest.fixture
def stream(chip: Chip) -> Stream:
    return Stream(chip)


def test_each_transfer_decrements_ndtr(stream: Stream) -> None:
    stream.program(8)
    assert stream.dma.accepts(DR)
    assert stream.request(0x111) == 1
    assert stream.dma.read(S0NDTR) == 7
    assert stream.request(0x222, 0x333) == 2
    assert stream.dma.read(S0NDTR) == 5
    assert stream.memory(3) == [0x111, 0x222, 0x333]


def test_half_transfer_then_transfer_complete(stream: Stream) -> None:
    # HTIF when half the items have moved, TCIF when NDTR reaches 0.
    stream.program(8)
    stream.request(1, 2, 3)
    assert stream.dma.read(LISR) == 0
    stream.request(4)
    assert stream.dma.read(LISR) == HTIF0
    stream.request(5, 6, 7)
    assert stream.dma.read(LISR) == HTIF0
    stream.request(8)
    assert stream.dma.read(LISR) == HTIF0 | TCIF0
    assert stream.dma.read(S0NDTR) == 0


def test_normal_mode_stops_at_the_end(stream: Stream) -> None:
    # Non-circular: EN cleared at the end, later requests not served.
    stream.program(4)
    assert stream.request(1, 2, 3, 4, 5, 6) == 4
    assert not stream.dma.read(S0CR) & EN
    assert not stream.dma.accepts(DR)
    assert stream.memory(5) == [1, 2, 3, 4, 0]


def test_circular_mode_reloads_ndtr_and_the_address(stream: Stream) -> None:
    # "the content of the DMA_SxNDTR register is automatically reloaded with
    # the initially programmed value" and the pointer returns to SxM0AR.
    stream.program(4, CIRC)
    assert stream.request(*range(1, 7)) == 6
    assert stream.dma.read(S0CR) & EN
    assert stream.dma.read(S0NDTR) == 2
    assert stream.memory(4) == [5, 6, 3, 4]
    assert stream.dma.read(LISR) == HTIF0 | TCIF0
    stream.dma.write(LIFCR, HTIF0 | TCIF0)
    stream.request(7)
    assert stream.dma.read(LISR) == 0
    stream.request(8)  # the second round's end
    assert stream.dma.read(LISR) == TCIF0
    assert stream.dma.read(S0NDTR) == 4
    assert stream.memory(4) == [5, 6, 7, 8]
    stream.dma.write(LIFCR, TCIF0)
    stream.request(9, 10)  # the third round's half
    assert stream.dma.read(LISR) == HTIF0
    assert stream.memory(4) == [9, 10, 7, 8]


def test_lifcr_clears_the_flags_written_one(stream: Stream) -> None:
    stream.program(2)
    stream.request(1, 2)
    assert stream.dma.read(LISR) == HTIF0 | TCIF0
    stream.dma.write(LIFCR, 0)
    assert stream.dma.read(LISR) == HTIF0 | TCIF0
    stream.dma.write(LIFCR, TCIF0)
    assert stream.dma.read(LISR) == HTIF0
    stream.dma.write(LIFCR, HTIF0)
    assert stream.dma.read(LISR) == 0


def test_lisr_is_read_only_and_hifcr_is_streams_4_to_7s(stream: Stream) -> None:
    stream.program(2)
    stream.request(1, 2)
    stream.dma.write(LISR, 0)
    stream.dma.write(HIFCR, 0x0F7D_0F7D)  # every flag of streams 4–7
    assert stream.dma.read(LISR) == HTIF0 | TCIF0
    assert stream.dma.read(HISR) == 0


def test_flag_with_its_enable_raises_the_interrupt(stream: Stream) -> None:
    stream.program(4, TCIE)
    stream.request(1, 2)  # HTIF, not enabled
    assert not stream.nvic.pending[STREAM0_IRQ]
    stream.request(3, 4)
    assert stream.nvic.pending[STREAM0_IRQ]
    assert stream.nvic.level[STREAM0_IRQ]
    stream.dma.write(LIFCR, TCIF0)
    assert not stream.nvic.level[STREAM0_IRQ]


def test_until_flag_counts_items_to_the_next_enabled_flag(stream: Stream) -> None:
    stream.program(10, HTIE | TCIE)
    assert stream.dma.until_flag() == 5
    stream.request(1, 2, 3, 4, 5, 6)
    assert stream.dma.until_flag() == 4


def test_disabling_the_stream_ends_the_transfer_with_tcif(stream: Stream) -> None:
    # §10.3.14: clearing EN mid-transfer sets TCIF.
    stream.program(8)
    stream.request(1)
    stream.dma.write(S0CR, stream.dma.read(S0CR) & ~EN)
    assert stream.dma.read(LISR) == TCIF0
    assert stream.dma.read(S0NDTR) == 7  # what is left, for software to read


def test_configuration_is_write_protected_while_enabled(stream: Stream) -> None:
    # "it is forbidden to write these registers when the EN bit is read as 1"
    stream.program(8)
    stream.dma.write(S0NDTR, 100)
    stream.dma.write(S0M0AR, SRAM)
    stream.dma.write(S0CR, stream.dma.read(S0CR) & ~MINC)
    assert stream.dma.read(S0NDTR) == 8
    assert stream.dma.read(S0M0AR) == BUFFER
    assert stream.dma.read(S0CR) & MINC
    assert [register for _, register, _ in stream.dma.forbidden] == ["S0NDTR", "S0M0AR", "S0CR"]
    # The interrupt enables are not protected.
    stream.dma.write(S0CR, stream.dma.read(S0CR) | TCIE)
    assert stream.dma.read(S0CR) & TCIE


def test_re_enabled_stream_starts_at_m0ar(stream: Stream) -> None:
    stream.program(8)
    stream.request(1, 2)
    stream.dma.write(S0CR, stream.dma.read(S0CR) & ~EN)
    stream.dma.write(S0CR, stream.dma.read(S0CR) | EN)
    stream.request(9)
    assert stream.memory(3) == [9, 2, 0]
    assert stream.dma.read(S0NDTR) == 5


def test_fcr_resets_to_direct_mode_with_the_fifo_empty(stream: Stream) -> None:
    assert stream.dma.read(S0FCR) == 0x21
