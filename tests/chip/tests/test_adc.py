"""ADC1 against RM0090 §13 (ADC): conversion time, EOC, overrun, and
conversions triggered by TIM2's TRGO reaching memory through DMA2."""

import pytest

from board.adc import ADC_IRQ, Adc
from board.dma import EN
from board.timer import Timer

from .support import TIMER_CYCLES, Chip
from .test_dma import MINC, MSIZE_16, PSIZE_16, S0CR, S0M0AR, S0NDTR, S0PAR, SRAM, Stream

SR, CR1, CR2, SMPR2, DR, CCR = 0x00, 0x04, 0x08, 0x10, 0x4C, 0x304
EOC, STRT, OVR = 1 << 1, 1 << 4, 1 << 5
ADON, DMA, SWSTART = 1, 1 << 8, 1 << 30
EXTEN_RISING, EXTSEL_TIM2_TRGO = 0b01 << 28, 0b0110 << 24
EOCIE = 1 << 5
# ADCPRE = 01: ADCCLK = PCLK2 / 4 = 21 MHz, 8 core cycles a clock.
ADCPRE_4 = 0b01 << 16
ADC_CYCLES = 8


class Converter:
    """ADC1 with TIM2 as its trigger and DMA2 stream 0 behind it."""

    def __init__(self, chip: Chip) -> None:
        self.stream = Stream(chip)
        self.tim2 = Timer("TIM2", 28, 32, chip.clock, chip.nvic, chip.rcc)
        self.adc = Adc(chip.clock, chip.nvic, chip.rcc, self.tim2, self.stream.dma)
        self.tim2.slaves.append(self.adc)
        self.adc.write(CCR, ADCPRE_4)


@pytest.fixture
def conv(chip: Chip) -> Converter:
    return Converter(chip)


@pytest.mark.parametrize(("smp", "sampling"), [(0b000, 3), (0b011, 56), (0b111, 480)])
def test_conversion_takes_sampling_time_plus_12_clocks(chip: Chip, conv: Converter, smp: int, sampling: int) -> None:
    # Tconv = sampling time + 12 cycles of ADCCLK (§13.5).
    adc = conv.adc
    adc.write(SMPR2, smp)  # channel 0's SMP0
    adc.write(CR2, ADON)
    adc.write(CR2, ADON | SWSTART)
    assert not adc.read(CR2) & SWSTART  # cleared by hardware
    chip.run((sampling + 12) * ADC_CYCLES - 1)
    assert not adc.read(SR) & EOC
    chip.run(1)
    assert adc.read(SR) & (EOC | STRT) == EOC | STRT


def test_reading_dr_clears_eoc(chip: Chip, conv: Converter) -> None:
    adc = conv.adc
    adc.write(CR1, EOCIE)
    adc.write(CR2, ADON | SWSTART)
    chip.run(1000)
    assert adc.read(SR) & EOC
    assert chip.nvic.level[ADC_IRQ]
    assert adc.read(DR) == 0  # no plant: the input at ground
    assert not adc.read(SR) & EOC
    assert not chip.nvic.level[ADC_IRQ]


def test_overrun_with_dma_loses_the_result_and_ignores_triggers(chip: Chip, conv: Converter) -> None:
    # A result not taken when the next ends: OVR (with DMA = 1), and
    # "further regular triggers are ignored" until software clears it.
    adc = conv.adc
    adc.write(CR2, ADON | DMA)
    adc.write(CR2, ADON | DMA | SWSTART)
    chip.run(1000)
    adc.write(CR2, ADON | DMA | SWSTART)
    chip.run(1000)
    assert adc.read(SR) & OVR
    assert (adc.conversions, adc.lost) == (2, 1)
    adc.write(CR2, ADON | DMA | SWSTART)
    chip.run(1000)
    adc.read(SR)  # the model converts up to now when it is accessed
    assert adc.conversions == 2
    adc.write(SR, ~OVR & 0xFFFF_FFFF)  # rc_w0
    adc.read(DR)
    adc.write(CR2, ADON | DMA | SWSTART)
    chip.run(1000)
    assert adc.read(SR) & (EOC | OVR) == EOC
    assert adc.conversions == 3


def test_tim2_trgo_conversions_reach_memory_through_the_dma(chip: Chip, conv: Converter) -> None:
    dma = conv.stream.dma
    dma.write(S0PAR, 0x4001_204C)
    dma.write(S0M0AR, SRAM)
    dma.write(S0NDTR, 100)
    dma.write(S0CR, PSIZE_16 | MSIZE_16 | MINC)
    dma.write(S0CR, dma.read(S0CR) | EN)
    conv.adc.write(CR2, ADON | DMA | EXTEN_RISING | EXTSEL_TIM2_TRGO)
    # TIM2: an update (its TRGO with MMS = 010) every 500 timer clocks.
    tim2 = conv.tim2
    tim2.write(0x04, 0b010 << 4)
    tim2.write(0x2C, 499)
    tim2.write(0x00, 1)
    period = 500 * TIMER_CYCLES
    chip.run(10 * period)
    # Ten triggers; the tenth's conversion (15 ADC clocks) has not ended.
    assert dma.read(S0NDTR) == 91
    chip.run(15 * ADC_CYCLES)
    assert dma.read(S0NDTR) == 90
    assert dma.moved == conv.adc.conversions == 10
    assert not conv.adc.read(SR) & OVR
