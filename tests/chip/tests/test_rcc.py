"""RCC against RM0090 §7 (reset and clock control for the STM32F405)."""

from board.clock import HZ
from board.system import Rcc

from .support import CFGR, TIMER_HZ

CR, CFGR_OFFSET, BDCR, CSR = 0x00, 0x08, 0x70, 0x74
HSEON, HSERDY, PLLON, PLLRDY = 1 << 16, 1 << 17, 1 << 24, 1 << 25
LSION, LSIRDY = 1, 1 << 1
RMVF, BORRSTF, PINRSTF, PORRSTF, IWDGRSTF = 1 << 24, 1 << 25, 1 << 26, 1 << 27, 1 << 29


def test_reset_values() -> None:
    r = Rcc()
    assert r.read(CR) == 0x0000_0083  # HSION, HSIRDY, HSITRIM 16
    assert r.read(0x04) == 0x2400_3010  # PLLCFGR
    assert r.read(CSR) == PORRSTF | PINRSTF | BORRSTF  # a power-on reset's flags


def test_ready_flags_follow_their_enables() -> None:
    r = Rcc()
    r.write(CR, r.read(CR) | HSEON | PLLON)
    assert r.read(CR) & (HSERDY | PLLRDY) == HSERDY | PLLRDY
    r.write(CR, r.read(CR) & ~PLLON)
    assert r.read(CR) & (HSERDY | PLLRDY) == HSERDY
    r.write(CSR, LSION)
    assert r.read(CSR) & LSIRDY


def test_sws_reports_the_selected_clock() -> None:
    r = Rcc()
    r.write(CFGR_OFFSET, 0b10)
    assert r.read(CFGR_OFFSET) >> 2 & 3 == 0b10


def test_bus_clocks_from_the_prescalers() -> None:
    r = Rcc()
    assert r.apb1_timer_hz() == r.apb2_hz() == 16_000_000  # HSI, undivided
    r.write(CFGR_OFFSET, CFGR)
    # APB1 divided by 4: its timers run at twice PCLK1 (§7.2, "timer clock").
    assert r.apb1_timer_hz() == TIMER_HZ == 2 * HZ // 4
    assert r.apb2_hz() == HZ // 2


def test_reset_flags_are_cleared_by_rmvf_and_kept_over_a_reset() -> None:
    r = Rcc()
    r.write(CSR, RMVF)
    assert r.read(CSR) & 0xFF00_0000 == 0
    r.write(BDCR, 1)  # LSEON: the backup domain survives a system reset
    r.write(CFGR_OFFSET, CFGR)
    r.reset(cause_bit=29)  # the watchdog's
    assert r.read(CSR) & 0xFF00_0000 == IWDGRSTF | PINRSTF
    assert r.read(BDCR) & 1
    assert r.read(CFGR_OFFSET) == 0
