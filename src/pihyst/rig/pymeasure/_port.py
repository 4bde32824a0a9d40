"""A pyserial-like port over a PyMeasure adapter, so that pihyst's own drivers
(:mod:`pihyst.rig._supply`, :mod:`pihyst.rig._sensor`) speak through PyMeasure: the
bytes on the wire are the drivers' bytes, whatever the adapter (a ``SerialAdapter``, a
``VISAAdapter`` over ``ASRL``/``TCPIP::...::SOCKET``, or the ``ProtocolAdapter`` of
``pymeasure.test.expected_protocol``).

The drivers write whole requests and read replies by count (Modbus RTU) or up to a
terminator or prompt (the ASCII dialects); the adapter's own terminations are not used.
"""

from typing import Any

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

    Parameters
    ----------
    adapter : pymeasure Adapter
        The connection (``SerialAdapter``, ``VISAAdapter``, ``ProtocolAdapter``).
    baudrate : int
        The configured baud rate.
    timeout_s : float
        The configured timeout (s), as pyserial's ``timeout``.
    name : str
        What is on the port, for error messages.

    Examples
    --------
    >>> from pymeasure.adapters import ProtocolAdapter
    >>> from pihyst.rig import SensorConfig
    >>> from pihyst.rig._sensor import KeyenceSensor
    >>> from pihyst.rig.pymeasure import AdapterPort
    >>> adapter = ProtocolAdapter([(b"MS,01\\r", b"MS,01,+0001.5000\\r")])
    >>> port = AdapterPort(adapter, baudrate=115200, timeout_s=0.1, name="sensor")
    >>> KeyenceSensor(port, SensorConfig()).read()
    Reading(value=1.5, status='ok')
    """

    def __init__(self, adapter: Any, baudrate: int, timeout_s: float, name: str) -> None:
        self.adapter = adapter
        self.baudrate = baudrate
        self.timeout = timeout_s
        self.port = name
        self.is_open = True
        # pyvisa's read_bytes(n) drops what came before a timeout: read a byte at a time
        self._bytewise = isinstance(adapter, VISAAdapter)

    def _read_bytes(self, count: int) -> bytes:
        try:
            return self.adapter.read_bytes(count)
        except pyvisa.errors.VisaIOError as err:
            if err.error_code == pyvisa.constants.StatusCode.error_timeout:
                return b""
            raise RigError(f"{self.port}: {err}") from None

    def write(self, data: bytes) -> int:
        """Write ``data`` through the adapter.

        Parameters
        ----------
        data : bytes
            The bytes.

        Returns
        -------
        int
            How many were written (all).

        Raises
        ------
        RigError
            A VISA error.

        Examples
        --------
        >>> from pymeasure.adapters import ProtocolAdapter
        >>> from pihyst.rig.pymeasure import AdapterPort
        >>> adapter = ProtocolAdapter([(b"M1\\r", None)])
        >>> port = AdapterPort(adapter, baudrate=115200, timeout_s=0.1, name="sensor")
        >>> port.write(b"M1\\r")
        3
        """
        data = bytes(data)
        try:
            self.adapter.write_bytes(data)
        except pyvisa.errors.VisaIOError as err:
            raise RigError(f"{self.port}: {err}") from None
        return len(data)

    def read(self, size: int = 1) -> bytes:
        """Up to ``size`` bytes; fewer when the adapter's read times out.

        Parameters
        ----------
        size : int
            How many bytes.

        Returns
        -------
        bytes
            What came.

        Raises
        ------
        RigError
            A VISA error other than a timeout.

        Examples
        --------
        >>> from pymeasure.adapters import ProtocolAdapter
        >>> from pihyst.rig.pymeasure import AdapterPort
        >>> adapter = ProtocolAdapter([(None, b"\\x01\\x03")])
        >>> port = AdapterPort(adapter, baudrate=115200, timeout_s=0.1, name="sensor")
        >>> port.read(2)
        b'\\x01\\x03'
        """
        if not self._bytewise:
            return bytes(self._read_bytes(size))
        out = bytearray()
        while len(out) < size:
            byte = self._read_bytes(1)
            if not byte:
                break
            out += byte
        return bytes(out)

    def read_until(self, expected: bytes = b"\n", size: int | None = None) -> bytes:
        """Bytes up to and including ``expected`` (or ``size`` bytes, or what came
        before a timeout).

        Parameters
        ----------
        expected : bytes
            The terminator.
        size : int or None
            The most bytes to read; None: no limit.

        Returns
        -------
        bytes
            What came.

        Raises
        ------
        RigError
            A VISA error other than a timeout.

        Examples
        --------
        >>> from pymeasure.adapters import ProtocolAdapter
        >>> from pihyst.rig.pymeasure import AdapterPort
        >>> adapter = ProtocolAdapter([(None, b"12.5\\r\\n")])
        >>> port = AdapterPort(adapter, baudrate=115200, timeout_s=0.1, name="sensor")
        >>> port.read_until(b"\\r\\n")
        b'12.5\\r\\n'
        """
        out = bytearray()
        while not out.endswith(expected) and (size is None or len(out) < size):
            byte = self._read_bytes(1)
            if not byte:
                break
            out += byte
        return bytes(out)

    def open(self) -> None:
        """Mark the port open (the adapter is opened by PyMeasure).

        Examples
        --------
        >>> from pymeasure.adapters import ProtocolAdapter
        >>> from pihyst.rig.pymeasure import AdapterPort
        >>> adapter = ProtocolAdapter([])
        >>> port = AdapterPort(adapter, baudrate=115200, timeout_s=0.1, name="sensor")
        >>> port.open(); port.is_open
        True
        """
        self.is_open = True

    def reset_input_buffer(self) -> None:
        """Drop what the adapter has received and not read.

        Raises
        ------
        RigError
            A VISA error.

        Examples
        --------
        >>> from pymeasure.adapters import ProtocolAdapter
        >>> from pihyst.rig.pymeasure import AdapterPort
        >>> adapter = ProtocolAdapter([])
        >>> port = AdapterPort(adapter, baudrate=115200, timeout_s=0.1, name="sensor")
        >>> port.reset_input_buffer()
        """
        try:
            self.adapter.flush_read_buffer()
        except pyvisa.errors.VisaIOError as err:
            raise RigError(f"{self.port}: {err}") from None

    def reset_output_buffer(self) -> None:
        """Nothing to do: writes go out at once.

        Examples
        --------
        >>> from pymeasure.adapters import ProtocolAdapter
        >>> from pihyst.rig.pymeasure import AdapterPort
        >>> adapter = ProtocolAdapter([])
        >>> port = AdapterPort(adapter, baudrate=115200, timeout_s=0.1, name="sensor")
        >>> port.reset_output_buffer()
        """

    def flush(self) -> None:
        """Nothing to do: writes go out at once.

        Examples
        --------
        >>> from pymeasure.adapters import ProtocolAdapter
        >>> from pihyst.rig.pymeasure import AdapterPort
        >>> adapter = ProtocolAdapter([])
        >>> port = AdapterPort(adapter, baudrate=115200, timeout_s=0.1, name="sensor")
        >>> port.flush()
        """

    def close(self) -> None:
        """Close the adapter.

        Examples
        --------
        >>> from pymeasure.adapters import ProtocolAdapter
        >>> from pihyst.rig.pymeasure import AdapterPort
        >>> adapter = ProtocolAdapter([])
        >>> port = AdapterPort(adapter, baudrate=115200, timeout_s=0.1, name="sensor")
        >>> port.close(); port.is_open
        False
        """
        self.is_open = False
        self.adapter.close()
