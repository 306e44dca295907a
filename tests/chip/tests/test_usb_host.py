"""What the board's USB host reads of a device's configuration (USB 2.0
§9.6.3)."""

from board.usb_host import bus_power


def test_a_configuration_says_whether_the_device_powers_itself() -> None:
    # bLength, bDescriptorType, wTotalLength, bNumInterfaces,
    # bConfigurationValue, iConfiguration, bmAttributes, bMaxPower.
    self_powered = bytes([9, 2, 67, 0, 2, 1, 0, 0xC0, 1])
    bus_powered = bytes([9, 2, 67, 0, 2, 1, 0, 0x80, 50])
    assert bus_power(self_powered) == {"self_powered": True, "max_power_ma": 2}
    assert bus_power(bus_powered) == {"self_powered": False, "max_power_ma": 100}
    assert bus_power(None) == {"self_powered": None, "max_power_ma": None}
    assert bus_power(b"\x09\x02") == {"self_powered": None, "max_power_ma": None}
