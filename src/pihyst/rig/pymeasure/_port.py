"""A pyserial-like port over a PyMeasure adapter, so that pihyst's own drivers
(:mod:`pihyst.rig._supply`, :mod:`pihyst.rig._sensor`) speak through PyMeasure: the
bytes on the wire are the drivers' bytes, whatever the adapter (a ``SerialAdapter``, a
``VISAAdapter`` over ``ASRL``/``TCPIP::...::SOCKET``, or the ``ProtocolAdapter`` of
``pymeasure.test.expected_protocol``).

The drivers write whole requests and read replies by count (Modbus RTU) or up to a
terminator or prompt (the ASCII dialects); the adapter's own terminations are not used.
"""

import pyvisa
from pymeasure.adapters import VISAAdapter

from pihyst.rig._ports import RigError


class AdapterPort:
    """What the drivers use of a pyserial port (``write``, ``read``, ``read_until``,
    ``reset_input_buffer``, ``timeout``, ``baudrate``), over ``adapter``.

    ``baudrate`` and ``timeout_s`` are the configured ones (the Modbus driver times the
    3.5-character silence from the baud rate); reads time out as the adapter's
    connection does. A read that times out returns what came (pyserial's behaviour), so
    the drivers raise their own no-reply or cut-short errors.
    """

    def __init__(self, adapter, baudrate, timeout_s, name):
        self.adapter = adapter
        self.baudrate = baudrate
        self.timeout = timeout_s
        self.port = name
        self.is_open = True
        # pyvisa's read_bytes(n) drops what came before a timeout: read a byte at a time
        self._bytewise = isinstance(adapter, VISAAdapter)

    def _read_bytes(self, count):
        try:
            return self.adapter.read_bytes(count)
        except pyvisa.errors.VisaIOError as err:
            if err.error_code == pyvisa.constants.StatusCode.error_timeout:
                return b""
            raise RigError(f"{self.port}: {err}") from None

    def write(self, data):
        data = bytes(data)
        try:
            self.adapter.write_bytes(data)
        except pyvisa.errors.VisaIOError as err:
            raise RigError(f"{self.port}: {err}") from None
        return len(data)

    def read(self, size=1):
        if not self._bytewise:
            return bytes(self._read_bytes(size))
        out = bytearray()
        while len(out) < size:
            byte = self._read_bytes(1)
            if not byte:
                break
            out += byte
        return bytes(out)

    def read_until(self, expected=b"\n", size=None):
        out = bytearray()
        while not out.endswith(expected) and (size is None or len(out) < size):
            byte = self._read_bytes(1)
            if not byte:
                break
            out += byte
        return bytes(out)

    def open(self):
        self.is_open = True

    def reset_input_buffer(self):
        try:
            self.adapter.flush_read_buffer()
        except pyvisa.errors.VisaIOError as err:
            raise RigError(f"{self.port}: {err}") from None

    def reset_output_buffer(self):
        pass

    def flush(self):
        pass

    def close(self):
        self.is_open = False
        self.adapter.close()
