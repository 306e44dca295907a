"""RCC against RM0090 §7 (reset and clock control for the STM32F405)."""

from board.clock import HZ
from board.system import Rcc

from .support import CFGR, CR_ON, PLLCFGR, TIMER_HZ

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
    r.write(0x04, PLLCFGR)
    r.write(CR, CR_ON)
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


def test_the_clocks_follow_the_crystal_and_pllcfgr() -> None:
    for crystal, sysclk, usb in ((8_000_000, HZ, 48_000_000), (12_000_000, 252_000_000, 72_000_000)):
        r = Rcc(crystal)
        r.write(0x04, PLLCFGR)
        r.write(CR, CR_ON)
        r.write(CFGR_OFFSET, CFGR)
        assert (r.sysclk_hz(), r.usb_hz()) == (sysclk, usb)
        assert r.selected == [(sysclk, usb)]
    # From the HSI: /8 *168 /2 and /7, whatever the crystal.
    r = Rcc(None)
    r.write(0x04, 8 | 168 << 6 | 7 << 24)
    r.write(CR, 1 | 1 << 24)
    r.write(CFGR_OFFSET, CFGR)
    assert (r.sysclk_hz(), r.usb_hz()) == (HZ, 48_000_000)


def test_no_crystal_never_gets_ready_nor_does_a_pll_on_it() -> None:
    r = Rcc(None)
    r.write(0x04, PLLCFGR)
    r.write(CR, CR_ON)
    assert not r.read(CR) & HSERDY
    assert not r.read(CR) & PLLRDY
    assert r.usb_hz() is None


def test_a_stopped_crystal_raises_the_css_and_falls_back_to_the_hsi() -> None:
    r = Rcc(8_000_000)
    nmis: list[int] = []
    lost: list[int] = []
    r.on_css = lambda: nmis.append(1)
    r.on_clock_lost = lambda: lost.append(1)
    r.write(0x04, PLLCFGR)
    r.write(CR, CR_ON | 1 << 19)  # CSSON
    r.write(CFGR_OFFSET, CFGR)
    r.stop_crystal()
    assert nmis == [1] and not lost
    assert r.read(0x0C) & 1 << 7  # CSSF
    assert not r.read(CR) & (HSEON | HSERDY | PLLON | PLLRDY)
    assert r.read(CR) & 1 << 19, "CSSON stays as software set it"
    assert r.sysclk_hz() == 16_000_000 and r.read(CFGR_OFFSET) & 0xF == 0
    r.write(0x0C, 1 << 23)  # CSSC
    assert not r.read(0x0C) & 1 << 7
    # Without the clock security system the core loses its clock.
    r = Rcc(8_000_000)
    r.on_css = lambda: nmis.append(2)
    r.on_clock_lost = lambda: lost.append(2)
    r.write(0x04, PLLCFGR)
    r.write(CR, CR_ON)
    r.write(CFGR_OFFSET, CFGR)
    r.stop_crystal()
    assert lost == [2] and nmis == [1]
