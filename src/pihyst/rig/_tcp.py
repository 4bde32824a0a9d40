"""Emulated instruments on TCP ports of this computer, for any client: pyserial's
``socket://127.0.0.1:PORT``, PyVISA's ``TCPIP::127.0.0.1::PORT::SOCKET``, LabVIEW's TCP
functions. Each instrument listens on its own port and speaks the bytes of its serial
protocol over the connection, as behind a serial device server (Modbus RTU frames with
their CRC, not Modbus TCP), timed as on its serial line at the configured baud rate
(wall clock).

One client at a time per instrument (a serial line has one master); the next one is
accepted when it hangs up. A 'vanish' fault closes the port and the connection, as an
unplugged device server does.
"""

import select
import socket
import threading

from pihyst.exceptions import InvalidArgumentError
from pihyst.rig._clock import WallClock
from pihyst.rig._emulators import Emulators
from pihyst.rig._serve import answer

LOOPBACK = "127.0.0.1"


class _TcpDevice:
    def __init__(self, device, host, port):
        self.device = device
        self.server = socket.create_server((host, port), backlog=1)
        self.address = self.server.getsockname()[:2]
        self._stop = threading.Event()
        self._client = None
        self._thread = threading.Thread(target=self._serve, daemon=True,
                                        name=f"pihyst-emulated-{device.name}-tcp")

    def start(self):
        self._thread.start()

    def _idle(self, sock):
        """Wait a little for ``sock`` to be readable; False when the device is gone."""
        if self.device.vanished(WallClock.now()):
            return None
        self.device.poll(WallClock.now())   # its watchdog trips without a request
        ready, _, _ = select.select([sock], [], [], 0.02)
        return bool(ready)

    def _serve(self):
        try:
            while not self._stop.is_set():
                ready = self._idle(self.server)
                if ready is None:
                    break
                if ready:
                    conn, _ = self.server.accept()
                    self._talk(conn)
        except OSError:
            pass
        self.close()

    def _talk(self, conn):
        self._client = conn
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        try:
            while not self._stop.is_set():
                ready = self._idle(conn)
                if ready is None:
                    return
                if not ready:
                    continue
                data = conn.recv(4096)
                if not data:                 # the client hung up
                    return
                answer(self.device, data, conn.sendall, bytewise=False)
        finally:
            self._client = None
            conn.close()

    def close(self):
        self._stop.set()
        for sock in (self._client, self.server):
            if sock is not None:
                try:
                    sock.close()
                except OSError:
                    pass

    def stop(self):
        self._stop.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout=2.0)
        self.close()


class TcpEmulators:
    """The emulated supply and sensor of ``config`` on TCP ports of ``host``: the supply
    on ``port`` and the sensor on ``port + 1`` (``port`` 0: two free ports). ``paths``
    maps 'supply' and 'sensor' to pyserial URLs (``socket://127.0.0.1:PORT``) and
    ``visa`` to PyVISA resource names (``TCPIP::127.0.0.1::PORT::SOCKET``). A context
    manager."""

    def __init__(self, config, port=0, host=LOOPBACK, plant=None, faults=()):
        if not 0 <= port <= 65534:
            raise InvalidArgumentError(f"TCP port must be 0 .. 65534 (the sensor takes port "
                                       f"+ 1), got {port}")
        self.emulators = Emulators(config, plant=plant, faults=faults, t0=WallClock.now())
        self._servers = {}
        try:
            for i, (what, dev) in enumerate(self.emulators.devices.items()):
                self._servers[what] = _TcpDevice(dev, host, port + i if port else 0)
        except OSError:
            self.close()
            raise
        self.addresses = {what: s.address for what, s in self._servers.items()}
        self.paths = {what: f"socket://{h}:{p}" for what, (h, p) in self.addresses.items()}
        self.visa = {what: f"TCPIP::{h}::{p}::SOCKET" for what, (h, p) in self.addresses.items()}
        for s in self._servers.values():
            s.start()

    def close(self):
        for s in self._servers.values():
            s.stop()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
