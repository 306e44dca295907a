"""A synthetic USB host on the board's bus: it resets the bus, enumerates
the device (descriptors, address, configuration), opens the CDC-ACM port
(line coding, DTR) as an operating system's driver does when a program
opens the port, moves bytes between a byte stream (a pseudo-terminal's
master side) and the bulk endpoints, and drops DTR when the program
closes the port, raising it again for the next program that opens it;
optionally the cable is pulled and plugged back after each session.

It runs as a coroutine on the virtual clock: each transaction is one call
into the OTG model, and a NAK is retried a little later, the firmware
running in between, as a host controller retries. Control transfers are
always finished (status stage included): the driver does not poll its bus
while one is open."""

import os
import struct
from collections.abc import Callable, Generator
from typing import TypeVar

from .clock import HZ, Clock
from .otg import OtgFs

US = HZ // 1_000_000
MS = HZ // 1000
RETRY = 20 * US  # after a NAK
PACKET_TIME = 50 * US  # a 64-byte full-speed packet on the wire
CDC_OUT, CDC_IN = 1, 2
GIVE_UP = 2 * HZ  # a transaction NAKed this long is an error of the device

# The host's life and its transfers: generators that yield the cycles to
# wait before they go on (and return what a transfer read).
Steps = Generator[int, None, None]
T = TypeVar("T", bound=tuple[object, ...])


def bus_power(configuration: bytes | None) -> dict[str, bool | int | None]:
    """What a configuration descriptor says of the device's power (USB 2.0
    §9.6.3): bmAttributes' bit 6, self-powered, and bMaxPower in 2 mA
    units; None for both before the host has read it."""
    if configuration is None or len(configuration) < 9:
        return {"self_powered": None, "max_power_ma": None}
    return {"self_powered": bool(configuration[7] & 0x40), "max_power_ma": 2 * configuration[8]}


class HostError(Exception):
    pass


class Host:
    def __init__(self, otg: OtgFs, clock: Clock, stream: int | None = None, replug: bool = False) -> None:
        self.otg = otg
        self.clock = clock
        self.stream = stream  # a file descriptor, read and written raw
        self.to_device = bytearray()
        # What the device sent that the pseudo-terminal has not taken yet
        # (its buffer full: the program is not reading). While any waits, no
        # IN is polled, as a tty's driver stops reading its USB endpoint
        # when its buffer fills: nothing is dropped. `pty_full` counts the
        # writes it did not take whole.
        self.to_host = bytearray()
        self.pty_full = 0
        self.log: list[tuple[float, str]] = []  # (seconds, what)
        self.descriptor: bytes | None = None
        self.configuration: bytes | None = None
        self.state = "detached"
        self.error: str | None = None
        self.sessions = 0
        # After each session, unplug the cable and plug it back in.
        self.replug = replug
        # A test's fault: the host suspends the bus for this long (cycles)
        # in the middle of a session, then resumes it without a reset; told
        # when it suspends.
        self.suspend_for: int | None = None
        self.on_suspend: Callable[[], object] = lambda: None
        # A test's fault: the cable pulled in the middle of a session for
        # this long (cycles), then plugged back: the bus reset and the
        # device enumerated again, the port reopened (the program holding
        # it open meanwhile); what was on its way is lost. Told when the
        # cable goes, as for a suspend.
        self.pull_for: int | None = None
        # A test's fault: the host keeps the port open but stops reading
        # (every IN NAKed from then on).
        self.reading = True

    def start(self) -> None:
        self.otg.vbus(True)
        self.proc = self._run()
        self.clock.at(self.clock.now + MS, self._step)

    def _step(self) -> None:
        try:
            delay = next(self.proc)
        except StopIteration:
            return
        except HostError as e:
            self.error = str(e)
            self.state = "error"
            return
        self.clock.at(self.clock.now + delay, self._step)

    def _note(self, what: str) -> None:
        self.log.append((round(self.clock.now / HZ, 6), what))

    # --- transactions, retried while NAKed -------------------------------------
    def _until(self, attempt: Callable[[], T], what: str) -> Generator[int, None, T]:
        since = self.clock.now
        while True:
            result = attempt()
            if result[0] != "NAK":
                return result
            if self.clock.now - since > GIVE_UP:
                raise HostError(f"{what}: NAKed for {GIVE_UP / HZ} s")
            yield RETRY

    def _setup(self, packet: bytes) -> Steps:
        yield from self._until(lambda: (self.otg.setup(packet),), "SETUP")
        yield PACKET_TIME

    def control_in(
        self, request_type: int, request: int, value: int, index: int, length: int
    ) -> Generator[int, None, bytes]:
        """A control read: SETUP, IN data until short or complete, OUT status."""
        yield from self._setup(struct.pack("<BBHHH", request_type, request, value, index, length))
        data = bytearray()
        while True:
            status, chunk = yield from self._until(lambda: self.otg.in_(0), f"control IN {request:#x} data")
            if status == "STALL":
                raise HostError(f"control IN {request:#x} {value:#x} stalled")
            assert chunk is not None  # an ACK's data
            data += chunk
            yield PACKET_TIME
            if len(chunk) < 64 or len(data) >= length:
                break
        (status,) = yield from self._until(lambda: (self.otg.out(0, b""),), "control IN status")
        if status == "STALL":
            raise HostError(f"control IN {request:#x} status stalled")
        yield PACKET_TIME
        return bytes(data)

    def control_out(self, request_type: int, request: int, value: int, index: int, payload: bytes = b"") -> Steps:
        """A control write: SETUP, OUT data if any, IN status (a ZLP)."""
        yield from self._setup(struct.pack("<BBHHH", request_type, request, value, index, len(payload)))
        if payload:
            (status,) = yield from self._until(lambda: (self.otg.out(0, payload),), f"control OUT {request:#x} data")
            if status == "STALL":
                raise HostError(f"control OUT {request:#x} stalled")
            yield PACKET_TIME
        status, chunk = yield from self._until(lambda: self.otg.in_(0), f"control OUT {request:#x} status")
        if status == "STALL":
            raise HostError(f"control OUT {request:#x} {value:#x} stalled")
        if chunk:
            raise HostError(f"control OUT {request:#x}: a status stage with {len(chunk)} bytes")
        yield PACKET_TIME

    # --- the host's life --------------------------------------------------------
    def _run(self) -> Steps:
        while True:
            while not (self.otg.connected and self.otg.gahbcfg & 1):
                yield MS
            self._note("attached")
            yield from self._enumerate()
            # Sessions, one per program that opens the port, until the
            # cable is pulled (a test's fault, or `replug` after each).
            while True:
                pulled = yield from self._session()
                if pulled:
                    break
                if self.replug:
                    yield from self._unplug(100 * MS)
                    break

    def _unplug(self, cycles: int) -> Steps:
        """The cable out for `cycles`, then back in."""
        self._note("unplugged")
        self.otg.vbus(False)
        yield cycles
        self._note("plugged")
        self.otg.vbus(True)

    def _enumerate(self) -> Steps:
        self.otg.bus_reset()
        yield 10 * MS
        self.otg.reset_done()
        yield MS
        self.descriptor = yield from self.control_in(0x80, 6, 0x0100, 0, 64)
        vid, pid = struct.unpack_from("<HH", self.descriptor, 8)
        self._note(f"device {vid:04x}:{pid:04x}")
        yield from self.control_out(0x00, 5, 5, 0)
        if self.otg.address != 5:
            raise HostError(f"SET_ADDRESS 5: the device answers at {self.otg.address}")
        header = yield from self.control_in(0x80, 6, 0x0200, 0, 9)
        total = struct.unpack_from("<H", header, 2)[0]
        self.configuration = yield from self.control_in(0x80, 6, 0x0200, 0, total)
        yield from self.control_out(0x00, 9, 1, 0)
        self._note("configured")

    def _port_open(self) -> bool:
        """Whether a program holds the pseudo-terminal open (reading its
        master side fails with EIO when none does); without a stream, the
        port is open from the start."""
        if self.stream is None:
            return True
        try:
            self.to_device += os.read(self.stream, 4096)
        except BlockingIOError:
            pass
        except OSError:
            return False
        return True

    def _to_pty(self) -> None:
        """Hands the pseudo-terminal what it takes of the device's bytes."""
        assert self.stream is not None  # only a stream's bytes wait for it
        try:
            del self.to_host[: os.write(self.stream, self.to_host)]
        except BlockingIOError:
            pass
        except OSError:
            self.to_host.clear()  # the program closed the port: `_port_open` sees it
        if self.to_host:
            self.pty_full += 1

    def _set_dtr(self, on: bool) -> Steps:
        """What an operating system's CDC-ACM driver does when a program
        opens the port (115 200 8N1, then DTR and RTS) and closes it."""
        if on:
            yield from self.control_out(0x21, 0x20, 0, 0, struct.pack("<IBBB", 115_200, 0, 0, 8))
        yield from self.control_out(0x21, 0x22, 3 if on else 0, 0)
        self.state = "open" if on else "closed"
        self._note("port open (DTR)" if on else "port closed (DTR dropped)")

    def _session(self) -> Generator[int, None, bool]:
        """Waits for a program to open the port, bridges the bulk endpoints
        while it is open, and drops DTR when it closes the port; True when
        the cable was pulled instead."""
        while not self._port_open():
            yield MS
        yield from self._set_dtr(True)
        self.sessions += 1
        while True:
            if not self._port_open():
                self.to_host.clear()
                yield from self._set_dtr(False)
                return False
            if self.pull_for is not None:
                pulled, self.pull_for = self.pull_for, None
                self.on_suspend()
                self.to_device.clear()
                self.to_host.clear()
                yield from self._unplug(pulled)
                return True
            busy = False
            if self.to_device:
                chunk = bytes(self.to_device[:64])
                status = self.otg.out(CDC_OUT, chunk)
                if status == "ACK":
                    del self.to_device[:64]
                    busy = True
                elif status == "STALL":
                    raise HostError("bulk OUT stalled")
            if self.to_host:
                self._to_pty()
            polling = self.reading and not self.to_host
            status, data = self.otg.in_(CDC_IN) if polling else ("NAK", b"")
            if status == "ACK":
                busy = True
                # Without a stream, what the device sends is dropped.
                if self.stream is not None and data is not None:
                    self.to_host += data
                    self._to_pty()
            elif status == "STALL":
                raise HostError("bulk IN stalled")
            self.otg.start_of_frame()
            if self.suspend_for is not None:
                # The bus idles (no SOF, no transactions): the device
                # suspends; then the host signals resume, with no reset.
                idle, self.suspend_for = self.suspend_for, None
                self._note("bus suspended")
                self.on_suspend()
                self.otg.suspend()
                yield idle
                self._note("bus resumed")
                self.otg.resume()
            yield PACKET_TIME if busy else MS
