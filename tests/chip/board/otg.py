"""The USB OTG_FS core in device mode (RM0090 §34, slave mode: the CPU
moves the data through the FIFOs), as a host on its bus sees it and as
its driver programs it.

Registers (offsets from 0x5000_0000): the global ones (GOTGCTL's
connector ID and B-session valid, GOTGINT's session end, GCCFG's VBUS
sensing, GAHBCFG,
GRSTCTL with self-clearing resets and flushes and AHBIDL, GINTSTS with
its write-1-to-clear flags and the read-only RXFLVL/IEPINT/OEPINT
summaries, GINTMSK, GRXSTSR/GRXSTSP, GRXFSIZ, DIEPTXF0–3, CID = 0x1200),
the device ones (DCFG's address, DCTL's soft disconnect, DSTS's speed and
frame number, the endpoint masks, DAINT) and per endpoint DIEPCTL/DOEPCTL
(EPENA, STALL, NAK set and cleared by SNAK/CNAK, USBAEP), DIEPINT/DOEPINT
(written 1 to clear), DIEPTSIZ/DOEPTSIZ (packet count, transfer size,
STUPCNT) and DTXFSTS (the free words of the endpoint's TX FIFO). Reading
any FIFO address pops the shared RX FIFO; writing FIFO n pushes to IN
endpoint n's TX FIFO.

The host's side (`Host` in usb_host.py calls these):
- `bus_reset()`: USBRST, then ENUMDNE with full speed when the reset ends;
- `setup(data)`: always accepted (a control endpoint cannot NAK a SETUP):
  the 8 bytes and a "SETUP done" entry enter the RX FIFO; popping the
  latter sets DOEPINT0.STUP; it clears EP0's STALL;
- `out(ep, data)`: ACK when the endpoint does not NAK (NAK is set after each
  SETUP and each completed transfer, cleared by CNAK) and the RX FIFO has
  room; the data and, at the end of the transfer (packet count 0 or a
  short packet), an "OUT done" entry enter the RX FIFO; STALL if stalled;
- `in_(ep)`: the next packet if the endpoint is enabled, not NAKing and its
  TX FIFO holds the whole packet; then XFRC when the packet count reaches
  0 and EPENA clears; else NAK or STALL;
- `suspend()`/`resume()`: USBSUSP, WKUPINT;
- `vbus(on)`: the cable's VBUS on PA9 (RM0090 §34.5.3, peripheral
  states): while the PHY is powered (GCCFG.PWRDWN) and sensing B-device
  VBUS (VBUSBSEN, NOVBUSSENS clear), a B-session valid rising sets
  GINTSTS.SRQINT and connects the pull-up on D+, its fall sets
  GOTGINT.SEDET (seen as GINTSTS.OTGINT) and removes it; with NOVBUSSENS
  the session is always valid and the pull-up stays on, so a pulled cable
  leaves an idle bus the device takes for a suspend.

Two readings of RM0090 are choices here. The session-valid comparator
acts at once (its debounce is a matter of microseconds, the host's
timings of milliseconds), and its edge when the PHY is powered with VBUS
already present counts as a rising one. With VBUS sensing, a pulled cable
gives a session end only: with no pull-up and no host, the lines sit at
SE0, which the core does not take for a reset or suspend outside a
valid session.

One more reading is a choice: an OUT endpoint here takes data when it
does not NAK, whatever EPENA says. embassy-usb-synopsys-otg arms every
read after the first by CNAK alone, and works on silicon; RM0090 says EPENA
clears at transfer completion, and does not say that a disabled endpoint
NAKs."""

from .bus import Block
from .nvic import Nvic

OTG_FS_BASE = 0x5000_0000
OTG_FS_IRQ = 67
ENDPOINTS = 4
RX_FIFO_WORDS = 320  # 1.25 KiB of shared FIFO RAM (RM0090 §34.11)

# GINTSTS bits
CMOD, MMIS, OTGINT, SOF, RXFLVL, NPTXFE = 0, 1, 2, 3, 4, 5
USBSUSP, USBRST, ENUMDNE, EOPF, IEPINT, OEPINT, SRQINT, WKUPINT = 11, 12, 13, 15, 18, 19, 30, 31
W1C = sum(1 << bit for bit in (MMIS, SOF, USBSUSP, USBRST, ENUMDNE, EOPF, SRQINT, WKUPINT, 10, 14, 20, 21, 28, 29))
# GCCFG bits, GOTGCTL's, GOTGINT's
PWRDWN, VBUSBSEN, NOVBUSSENS = 1 << 16, 1 << 19, 1 << 21
CIDSTS, BSVLD = 1 << 16, 1 << 19
SEDET = 1 << 2
# GRXSTSP packet status
OUT_DATA, OUT_DONE, SETUP_DONE, SETUP_DATA = 2, 3, 4, 6
# D*EPCTL bits
EPENA, EPDIS, SNAK, CNAK, STALL, NAKSTS, USBAEP = 1 << 31, 1 << 30, 1 << 27, 1 << 26, 1 << 21, 1 << 17, 1 << 15
XFRC, EPDISD, STUP = 1, 2, 8


class Endpoint:
    def __init__(self) -> None:
        self.ctl = 0
        self.int = 0
        self.tsiz = 0


class OtgFs(Block):
    name = "OTG_FS"

    def __init__(self, nvic: Nvic) -> None:
        self.nvic = nvic
        self.regs = {0x3C: 0x0000_1200}
        self.gintsts = 1 << NPTXFE | 1 << 26
        self.gintmsk = 0
        self.gahbcfg = 0
        self.dcfg = 0
        self.dctl = 1 << 1  # SDIS: soft-disconnected until the driver connects
        self.frame = 0
        self.ins = [Endpoint() for _ in range(ENDPOINTS)]
        self.outs = [Endpoint() for _ in range(ENDPOINTS)]
        self.rx: list[tuple[int, list[int]]] = []  # entries (status word, [data words])
        self.rx_data: list[int] = []  # words of the popped entry still to read
        self.tx: list[list[int]] = [[] for _ in range(ENDPOINTS)]  # words pushed per IN endpoint
        self.dieptxf = [0] * ENDPOINTS
        self.diepmsk = self.doepmsk = self.daintmsk = self.diepempmsk = 0
        self.gccfg = 0
        self.gotgint = 0
        self.vbus_on = False  # the cable's VBUS
        self.session_valid = False  # the B-session valid comparator's output
        # Whether the pull-up on D+ was ever on with no VBUS: current into
        # an unpowered host's D+ (USB 2.0 §7.1.5.1 forbids it).
        self.pullup_without_vbus = False

    # --- derived state -----------------------------------------------------
    @property
    def connected(self) -> bool:
        """The pull-up on D+ (DCTL.SDIS clear, in a valid session): a host
        sees the device."""
        return not self.dctl & 2 and self.session_valid

    def _sense(self) -> None:
        """The B-session valid comparator after a change of VBUS or of
        GCCFG, and the interrupt its edge raises."""
        powered = self.gccfg & PWRDWN
        valid = bool(powered and (self.gccfg & NOVBUSSENS or (self.gccfg & VBUSBSEN and self.vbus_on)))
        if valid and not self.session_valid:
            self.gintsts |= 1 << SRQINT
        if self.session_valid and not valid:
            self.gotgint |= SEDET
        self.session_valid = valid
        self._pullup_check()

    def daint(self) -> int:
        v = 0
        for n in range(ENDPOINTS):
            # TXFE (bit 7) is the FIFO's state, enabled by DIEPEMPMSK.
            ints = self.ins[n].int | (1 << 7 if not self.tx[n] else 0)
            if ints & (self.diepmsk | (1 << 7 if self.diepempmsk >> n & 1 else 0)):
                v |= 1 << n
            if self.outs[n].int & self.doepmsk:
                v |= 1 << (16 + n)
        return v

    def _gintsts(self) -> int:
        v = self.gintsts & ~(1 << RXFLVL | 1 << IEPINT | 1 << OEPINT | 1 << OTGINT)
        if self.gotgint:
            v |= 1 << OTGINT
        if self.rx:
            v |= 1 << RXFLVL
        d = self.daint() & self.daintmsk
        if d & 0xFFFF:
            v |= 1 << IEPINT
        if d >> 16:
            v |= 1 << OEPINT
        return v

    def _pullup_check(self) -> None:
        """After a change of what `connected` depends on (SDIS, the
        session) or of VBUS."""
        if self.connected and not self.vbus_on:
            self.pullup_without_vbus = True

    def update(self) -> None:
        self.nvic.line(OTG_FS_IRQ, bool(self.gahbcfg & 1 and self._gintsts() & self.gintmsk))

    def tx_depth(self, n: int) -> int:
        word = self.regs.get(0x28, 0) if n == 0 else self.dieptxf[n]
        return word >> 16 or 16

    def rx_used(self) -> int:
        return sum(1 + len(d) for _, d in self.rx)

    # --- the host's side -----------------------------------------------------
    def bus_reset(self) -> None:
        """A reset ends every transfer: the IN endpoints' EPENA and the
        FIFOs are cleared (a choice: RM0090 leaves them to the driver, whose
        reset handling flushes the FIFOs but would wait on a stale EPENA)."""
        self.dcfg &= ~(0x7F << 4)
        for n in range(ENDPOINTS):
            self.ins[n].ctl &= ~EPENA
            self.tx[n].clear()
        self.rx.clear()
        self.rx_data.clear()
        self.gintsts |= 1 << USBRST
        self.update()

    def reset_done(self) -> None:
        self.gintsts |= 1 << ENUMDNE
        self.update()

    def suspend(self) -> None:
        self.gintsts |= 1 << USBSUSP
        self.update()

    def resume(self) -> None:
        self.gintsts |= 1 << WKUPINT
        self.update()

    def vbus(self, on: bool) -> None:
        """The cable plugged (VBUS on) or pulled; pulled without VBUS
        sensing, the bus idles with the device's pull-up on: a suspend."""
        self.vbus_on = on
        self._sense()
        if not on and self.connected:
            self.gintsts |= 1 << USBSUSP
        self.update()

    def start_of_frame(self) -> None:
        self.frame = (self.frame + 1) & 0x3FFF

    @property
    def address(self) -> int:
        return self.dcfg >> 4 & 0x7F

    def _push(self, status: int, payload: bytes) -> None:
        words = [int.from_bytes(payload[i : i + 4].ljust(4, b"\0"), "little") for i in range(0, len(payload), 4)]
        self.rx.append((status, words))

    def setup(self, data: bytes) -> str:
        if self.rx_used() + 4 > self.rx_depth():
            return "NAK"  # the FIFO is full: the packet is lost, the host retries
        ep = self.outs[0]
        self.ins[0].ctl &= ~STALL
        ep.ctl &= ~STALL
        ep.ctl |= NAKSTS
        stupcnt = ep.tsiz >> 29 & 3
        ep.tsiz = (ep.tsiz & ~(3 << 29)) | (max(stupcnt - 1, 0) << 29)
        self._push(SETUP_DATA << 17 | 8 << 4 | 0, data)
        self._push(SETUP_DONE << 17, b"")
        self.update()
        return "ACK"

    def rx_depth(self) -> int:
        return self.regs.get(0x24, 0) & 0xFFFF or RX_FIFO_WORDS

    def out(self, n: int, data: bytes) -> str:
        ep = self.outs[n]
        if ep.ctl & STALL:
            return "STALL"
        if (n and not ep.ctl & USBAEP) or ep.ctl & NAKSTS:
            return "NAK"
        if self.rx_used() + 2 + (len(data) + 3) // 4 > self.rx_depth():
            return "NAK"
        self._push(OUT_DATA << 17 | len(data) << 4 | n, data)
        mps = self._mps(self.outs, n)
        pktcnt = ep.tsiz >> 19 & (1 if n == 0 else 0x3FF)
        xfrsiz = ep.tsiz & (0x7F if n == 0 else 0x7FFFF)
        pktcnt = max(pktcnt - 1, 0)
        xfrsiz = max(xfrsiz - len(data), 0)
        ep.tsiz = (ep.tsiz & ~(0x3FF << 19 | 0x7FFFF)) | pktcnt << 19 | xfrsiz
        # The driver takes one packet per transfer: each completes it, and
        # the endpoint NAKs until the driver's next CNAK.
        ep.ctl |= NAKSTS
        if pktcnt == 0 or len(data) < mps:
            self._push(OUT_DONE << 17 | n, b"")
            ep.ctl &= ~EPENA
        self.update()
        return "ACK"

    def in_(self, n: int) -> tuple[str, bytes | None]:
        ep = self.ins[n]
        if ep.ctl & STALL:
            return "STALL", None
        if not ep.ctl & EPENA or ep.ctl & NAKSTS:
            return "NAK", None
        mps = self._mps(self.ins, n)
        xfrsiz = ep.tsiz & (0x7F if n == 0 else 0x7FFFF)
        size = min(mps, xfrsiz)
        words = (size + 3) // 4
        if len(self.tx[n]) < words:
            return "NAK", None  # the driver is still filling the FIFO
        data = b"".join(w.to_bytes(4, "little") for w in self.tx[n][:words])[:size]
        del self.tx[n][:words]
        pktcnt = max((ep.tsiz >> 19 & (3 if n == 0 else 0x3FF)) - 1, 0)
        ep.tsiz = (ep.tsiz & ~(0x3FF << 19 | 0x7FFFF)) | pktcnt << 19 | (xfrsiz - size)
        if pktcnt == 0:
            ep.ctl &= ~EPENA
            ep.int |= XFRC
        self.update()
        return "ACK", data

    def _mps(self, eps: list[Endpoint], n: int) -> int:
        m = eps[n].ctl & 0x7FF
        return {0: 64, 1: 32, 2: 16, 3: 8}[m & 3] if n == 0 else m

    # --- registers ------------------------------------------------------------
    def _ep(self, offset: int) -> tuple[list[Endpoint], int, int] | None:
        """(endpoints, index, register offset within the endpoint's 0x20)."""
        if 0x900 <= offset < 0x900 + 0x20 * ENDPOINTS:
            return self.ins, (offset - 0x900) // 0x20, offset & 0x1F
        if 0xB00 <= offset < 0xB00 + 0x20 * ENDPOINTS:
            return self.outs, (offset - 0xB00) // 0x20, offset & 0x1F
        return None

    def read(self, offset: int) -> int:
        if offset >= 0x1000:  # any FIFO address pops the RX FIFO
            return self.rx_data.pop(0) if self.rx_data else 0
        if offset == 0x00:  # GOTGCTL: a B-device (ID pin open)
            return CIDSTS | (BSVLD if self.session_valid else 0)
        if offset == 0x04:
            return self.gotgint
        if offset == 0x38:
            return self.gccfg
        if offset == 0x10:  # GRSTCTL: the AHB idle, resets and flushes done
            return 1 << 31
        if offset == 0x14:
            return self._gintsts()
        if offset == 0x18:
            return self.gintmsk
        if offset == 0x08:
            return self.gahbcfg
        if offset in (0x1C, 0x20):  # GRXSTSR, GRXSTSP
            if not self.rx:
                return 0
            status, words = self.rx[0]
            if offset == 0x20:
                self.rx.pop(0)
                self.rx_data = list(words)
                kind, n = status >> 17 & 0xF, status & 0xF
                if kind == SETUP_DONE:
                    self.outs[0].int |= STUP
                elif kind == OUT_DONE:
                    self.outs[n].int |= XFRC
                self.update()
            return status
        if 0x104 <= offset < 0x104 + 4 * (ENDPOINTS - 1):
            return self.dieptxf[(offset - 0x104) // 4 + 1]
        if offset == 0x800:
            return self.dcfg
        if offset == 0x804:
            return self.dctl
        if offset == 0x808:  # DSTS: full speed on the 48 MHz PHY, the frame
            return 3 << 1 | self.frame << 8
        if offset == 0x810:
            return self.diepmsk
        if offset == 0x814:
            return self.doepmsk
        if offset == 0x818:
            return self.daint()
        if offset == 0x81C:
            return self.daintmsk
        if offset == 0x834:
            return self.diepempmsk
        ep = self._ep(offset)
        if ep:
            eps, n, r = ep
            e = eps[n]
            if r == 0x00:
                return e.ctl | (USBAEP if n == 0 else 0)
            if r == 0x08:
                txfe = 1 << 7 if eps is self.ins and not self.tx[n] else 0
                return e.int | txfe
            if r == 0x10:
                return e.tsiz
            if r == 0x18 and eps is self.ins:
                return max(self.tx_depth(n) - len(self.tx[n]), 0)
            return 0
        return self.regs.get(offset, 0)

    def write(self, offset: int, value: int) -> None:
        ep = self._ep(offset)
        if offset >= 0x1000:
            n = offset // 0x1000 - 1
            if n < ENDPOINTS:
                self.tx[n].append(value)
            self.update()
            return
        if offset == 0x10:  # GRSTCTL: flushes happen at once
            if value & 1 << 5:
                target = value >> 6 & 0x1F
                for n in range(ENDPOINTS):
                    if target == 0x10 or target == n:
                        self.tx[n].clear()
                        self.ins[n].ctl &= ~EPENA
            if value & 1 << 4:
                self.rx.clear()
                self.rx_data.clear()
        elif offset == 0x04:
            self.gotgint &= ~value
        elif offset == 0x38:
            self.gccfg = value
            self._sense()
        elif offset == 0x14:
            self.gintsts &= ~(value & W1C)
        elif offset == 0x18:
            self.gintmsk = value
        elif offset == 0x08:
            self.gahbcfg = value
        elif 0x104 <= offset < 0x104 + 4 * (ENDPOINTS - 1):
            self.dieptxf[(offset - 0x104) // 4 + 1] = value
        elif offset == 0x800:
            self.dcfg = value
        elif offset == 0x804:
            self.dctl = value & ~(1 << 11 | 0xF << 7)  # the global NAK commands act at once
            self._pullup_check()
        elif offset == 0x810:
            self.diepmsk = value
        elif offset == 0x814:
            self.doepmsk = value
        elif offset == 0x81C:
            self.daintmsk = value
        elif offset == 0x834:
            self.diepempmsk = value
        elif ep:
            eps, n, r = ep
            e = eps[n]
            if r == 0x00:
                keep = e.ctl & (NAKSTS | EPENA)
                ctl = value & ~(SNAK | CNAK | EPDIS | 1 << 28 | 1 << 29) | keep
                if value & EPENA:
                    ctl |= EPENA
                if value & SNAK:
                    ctl |= NAKSTS
                if value & CNAK:
                    ctl &= ~NAKSTS
                if value & EPDIS and ctl & EPENA:
                    ctl &= ~EPENA
                    e.int |= EPDISD
                e.ctl = ctl
            elif r == 0x08:
                e.int &= ~value
            elif r == 0x10:
                e.tsiz = value
        else:
            self.regs[offset] = value
        self.update()
