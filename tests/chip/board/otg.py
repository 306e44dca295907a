"""The USB OTG_FS core (RM0090 §34), as far as a device with no host on its
bus: the core ID embassy-usb-synopsys-otg checks, resets that complete at
once with the AHB idle, and a GINTSTS whose flags are written 1 to clear.
Enumeration, FIFOs and transfers are not modelled yet: without a host, no
bus event ever comes."""

from bus import Block

OTG_FS_BASE = 0x5000_0000
OTG_FS_IRQ = 67


class OtgFs(Block):
    name = "OTG_FS"

    def __init__(self):
        # GINTSTS resets with CMOD = 0 (device) and PTXFE/NPTXFE set.
        self.regs = {0x14: 0x0400_0020, 0x3C: 0x0000_1200}

    def read(self, offset):
        v = self.regs.get(offset, 0)
        if offset == 0x10:  # GRSTCTL: AHB idle, the resets done
            v = (v | 1 << 31) & ~0x3F
        return v

    def write(self, offset, value):
        if offset == 0x14:
            self.regs[0x14] = self.regs.get(0x14, 0) & ~(value & 0xF030_FC0A)
        elif offset == 0x3C:
            pass
        else:
            self.regs[offset] = value
