"""Emulated instruments as pyserial ports: ``pihystsim://NAME`` opens the device
registered under NAME (see :func:`register`), in this process.

The port emulates the wire: bytes take their bit times (start, 8 data, parity, stop) at
the port's baud rate, in both directions, one byte after the other; a device answers
``delay_s`` after the last byte of a request. Time is the registered clock's, so with a
:class:`~pihyst.rig._clock.VirtualClock` a read that waits for a reply advances virtual
time instead of sleeping. A port whose baud rate differs from the device's gets no
replies (the device sees garbage), as on a real line.
"""

import threading
import urllib.parse
from collections import deque
from typing import Any

import serial
from serial.serialutil import PortNotOpenError, SerialBase, SerialException

SCHEME = "pihystsim"
_REGISTRY: dict[str, tuple[Any, Any]] = {}  # name -> (device, clock)
_LOCK = threading.Lock()


def register(name, device, clock):
    """Make ``device`` reachable as ``pihystsim://name`` (replaces an earlier one)."""
    with _LOCK:
        _REGISTRY[name] = (device, clock)
    if "pihyst.rig" not in serial.protocol_handler_packages:
        serial.protocol_handler_packages.append("pihyst.rig")


def unregister(name, device=None):
    with _LOCK:
        if name in _REGISTRY and (device is None or _REGISTRY[name][0] is device):
            del _REGISTRY[name]


def url_name(url):
    """NAME of a ``pihystsim://NAME`` URL, None for any other port."""
    parts = urllib.parse.urlsplit(url)
    if parts.scheme.lower() != SCHEME:
        return None
    return (parts.netloc + parts.path).strip("/")


class Serial(SerialBase):
    """pyserial port to an emulated device (see the module notes)."""

    def open(self):
        if self.is_open:
            raise SerialException("port is already open")
        if self._port is None:
            raise SerialException("port must be configured before it can be used")
        name = url_name(self._port)
        with _LOCK:
            entry = _REGISTRY.get(name)
        if entry is None:
            raise SerialException(f"could not open port {self._port}: no emulated device "
                                  f"{name!r} is running in this process")
        self.device, self.clock = entry
        self._rx = deque()               # (arrival time, byte) from the device
        self._tx_free = self._rx_free = self.clock.now()
        self.is_open = True

    def close(self):
        # as pyserial's own ports: io.RawIOBase.close would flush, which raises
        # PortNotOpenError on a closed port (so every close raised, and a second one too)
        self.is_open = False

    def _reconfigure_port(self):
        pass

    def from_url(self, url):
        return url

    @property
    def _char_s(self):
        bits = 1 + self._bytesize + (self._parity != "N") + self._stopbits
        return bits / self._baudrate

    def _check(self):
        if not self.is_open:
            raise PortNotOpenError()
        if self.device.vanished(self.clock.now()):
            self.is_open = False
            raise SerialException(f"{self._port}: device disconnected")

    @property
    def in_waiting(self):
        self._check()
        now = self.clock.now()
        return sum(1 for t, _ in self._rx if t <= now)

    def write(self, data):
        self._check()
        data = bytes(data)
        if not data:
            return 0
        start = max(self.clock.now(), self._tx_free)
        self._tx_free = start + len(data) * self._char_s
        if (self._baudrate, self._parity, self._stopbits) != \
                (self.device.baudrate, self.device.parity, self.device.stopbits):
            return len(data)
        for ready, reply in self.device.receive(data, self._tx_free):
            begin = max(ready, self._rx_free)
            for i, byte in enumerate(reply):
                self._rx.append((begin + (i + 1) * self._char_s, byte))
            self._rx_free = begin + len(reply) * self._char_s
        return len(data)

    def read(self, size=1):
        self._check()
        now = self.clock.now()
        deadline = float("inf") if self._timeout is None else now + self._timeout
        taken = [b for t, b in list(self._rx)[:size] if t <= deadline]
        if len(taken) == size and size:
            done = self._rx[size - 1][0]
        elif deadline == float("inf"):
            raise SerialException(f"{self._port}: read without timeout would wait forever")
        else:
            done = deadline
        self.clock.sleep(max(0.0, done - now))
        self._check()
        for _ in taken:
            self._rx.popleft()
        return bytes(taken)

    def read_until(self, expected=b"\n", size=None):
        """Bytes up to and including ``expected`` (or ``size`` bytes), within one timeout
        of the emulators' clock (pyserial's own read_until times out on the wall clock,
        which is wrong in virtual time)."""
        self._check()
        now = self.clock.now()
        deadline = float("inf") if self._timeout is None else now + self._timeout
        taken = bytearray()
        done = None
        for t, byte in self._rx:
            if t > deadline:
                break
            taken.append(byte)
            done = t
            if taken.endswith(expected) or (size is not None and len(taken) >= size):
                break
        else:
            if deadline == float("inf"):
                raise SerialException(f"{self._port}: read without timeout would wait "
                                      "forever")
        if not (taken.endswith(expected) or (size is not None and len(taken) >= size)):
            done = deadline
        self.clock.sleep(max(0.0, done - now))
        self._check()
        for _ in taken:
            self._rx.popleft()
        return bytes(taken)

    def reset_input_buffer(self):
        self._check()
        now = self.clock.now()
        while self._rx and self._rx[0][0] <= now:
            self._rx.popleft()

    def reset_output_buffer(self):
        self._check()

    def flush(self):
        self._check()
        self.clock.sleep(max(0.0, self._tx_free - self.clock.now()))

    def send_break(self, duration=0.25):
        self._check()

    def _update_break_state(self):
        pass

    def _update_rts_state(self):
        pass

    def _update_dtr_state(self):
        pass

    @property
    def cts(self):
        return True

    @property
    def dsr(self):
        return True

    @property
    def ri(self):
        return False

    @property
    def cd(self):
        return True
