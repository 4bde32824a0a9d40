"""Opening serial ports from any pyserial URL (a device path, ``spy://``, ``socket://``,
``pihystsim://`` for the emulated instruments, ...)."""

import functools
import sys

import serial

try:
    import termios
    _TERMIOS_ERRORS = (termios.error,)
except ImportError:  # pragma: no cover - not on Windows
    _TERMIOS_ERRORS = ()

from pihyst.rig import _serial_handlers


class RigError(IOError):
    """The rig could not do what it was asked (a port that does not open, a device that
    does not answer as the protocol says); the message is one line."""


class NoReplyError(RigError, TimeoutError):
    """A device did not answer within its timeout."""


def open_port(url, baudrate, timeout_s, what, parity="N", stopbits=1):
    """An open pyserial port; ``what`` ('supply', 'sensor') names it in errors."""
    if _serial_handlers.url_name(url) is not None and \
            "pihyst.rig" not in serial.protocol_handler_packages:
        serial.protocol_handler_packages.append("pihyst.rig")
    try:
        return serial.serial_for_url(url, baudrate=baudrate, timeout=timeout_s,
                                     write_timeout=max(1.0, timeout_s), parity=parity,
                                     stopbits=stopbits)
    except (serial.SerialException, ValueError, OSError) as err:
        raise RigError(f"{what}: cannot open port {url}: {err}") from None


def read_line(port, terminator, what):
    """Bytes up to and including ``terminator``; raises :class:`NoReplyError` when
    nothing came and :class:`RigError` for a reply cut short."""
    data = port.read_until(terminator)
    if not data.endswith(terminator):
        if not data:
            raise NoReplyError(f"{what}: no reply within {port.timeout:g} s")
        raise RigError(f"{what}: reply cut short: {data!r}")
    return data


def port_errors(what):
    """Decorator: errors of the port that are not OSError (pyserial lets termios.error out
    of a vanished device) become :class:`RigError`, so the loop counts them."""
    def wrap(method):
        @functools.wraps(method)
        def call(*args, **kwargs):
            try:
                return method(*args, **kwargs)
            except _TERMIOS_ERRORS as err:
                raise RigError(f"{what}: port error: {err}") from None
        return call
    return wrap


def close_port(port):
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
