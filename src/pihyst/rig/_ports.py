"""Opening serial ports from any pyserial URL (a device path, ``spy://``, ``socket://``,
``pihystsim://`` for the emulated instruments, ...)."""

import functools
import sys
from collections.abc import Callable
from typing import Any, TypeVar

import serial

_TERMIOS_ERRORS: tuple[type[Exception], ...]
try:
    import termios
    _TERMIOS_ERRORS = (termios.error,)
except ImportError:  # pragma: no cover - not on Windows
    _TERMIOS_ERRORS = ()

_Method = TypeVar("_Method", bound=Callable[..., Any])

from pihyst.rig import _serial_handlers  # noqa: E402  (after the platform's termios)


class RigError(IOError):
    """The rig could not do what it was asked (a port that does not open, a device that
    does not answer as the protocol says); the message is one line.

    Examples
    --------
    >>> from pihyst.rig import RigError, open_port
    >>> try:
    ...     open_port("/nonexistent/tty", 9600, 0.1, "supply")
    ... except RigError as err:
    ...     print(str(err).split(":")[:2])
    ['supply', ' cannot open port /nonexistent/tty']
    """


class NoReplyError(RigError, TimeoutError):
    """A device did not answer within its timeout.

    Examples
    --------
    >>> from pihyst.rig import NoReplyError, RigError
    >>> issubclass(NoReplyError, RigError) and issubclass(NoReplyError, TimeoutError)
    True
    """


def open_port(url: str, baudrate: int, timeout_s: float, what: str, parity: str = "N",
              stopbits: int = 1) -> Any:
    """An open pyserial port, from a device path or any pyserial URL.

    Parameters
    ----------
    url : str
        A device (``/dev/ttyUSB0``, ``COM3``) or a pyserial URL (``socket://host:port``,
        ``spy://...``, ``pihystsim://supply`` for the emulated instruments).
    baudrate : int
        Bits per second.
    timeout_s : float
        The read timeout (s); writes time out after the larger of this and 1 s.
    what : str
        What is on the port (``"supply"``, ``"sensor"``), for error messages.
    parity : str
        ``"N"``, ``"E"`` or ``"O"``.
    stopbits : int
        1 or 2.

    Returns
    -------
    serial.SerialBase
        The open port.

    Raises
    ------
    RigError
        The port does not open (one line naming ``what`` and ``url``).

    Examples
    --------
    >>> from pihyst.rig import open_port
    >>> port = open_port("loop://", 115200, 0.1, "sensor")
    >>> port.write(b"MS,01\\r"); port.read_until(b"\\r")
    6
    b'MS,01\\r'
    >>> port.close()
    """
    if _serial_handlers.url_name(url) is not None and \
            "pihyst.rig" not in serial.protocol_handler_packages:
        serial.protocol_handler_packages.append("pihyst.rig")
    try:
        return serial.serial_for_url(url, baudrate=baudrate, timeout=timeout_s,
                                     write_timeout=max(1.0, timeout_s), parity=parity,
                                     stopbits=stopbits)
    except (serial.SerialException, ValueError, OSError) as err:
        raise RigError(f"{what}: cannot open port {url}: {err}") from None


def read_line(port: Any, terminator: bytes, what: str) -> bytes:
    """Bytes up to and including ``terminator``; raises :class:`NoReplyError` when
    nothing came and :class:`RigError` for a reply cut short."""
    data = port.read_until(terminator)
    if not data.endswith(terminator):
        if not data:
            raise NoReplyError(f"{what}: no reply within {port.timeout:g} s")
        raise RigError(f"{what}: reply cut short: {data!r}")
    return data


def port_errors(what: str) -> Callable[[_Method], _Method]:
    """Decorator: errors of the port that are not OSError (pyserial lets termios.error out
    of a vanished device) become :class:`RigError`, so the loop counts them."""
    def wrap(method: _Method) -> _Method:
        @functools.wraps(method)
        def call(*args: Any, **kwargs: Any) -> Any:
            try:
                return method(*args, **kwargs)
            except _TERMIOS_ERRORS as err:
                raise RigError(f"{what}: port error: {err}") from None
        return call  # type: ignore[return-value]  # functools.wraps keeps the signature
    return wrap


def close_port(port: Any) -> None:
    """Close ``port``; for a ``spy://`` port also the file its log goes to (pyserial
    leaves it open), and for a ``socket://`` port its socket (pyserial does not close it
    when the other side has gone: its shutdown() fails first)."""
    sock = getattr(port, "_socket", None)
    port.close()
    if sock is not None:
        sock.close()
    output = getattr(getattr(port, "formatter", None), "output", None)
    if output is not None and hasattr(output, "close") and output not in (sys.stdout,
                                                                          sys.stderr):
        output.close()
