"""Emulated instruments on pseudo-terminals: any program opens the printed device path
(``/dev/pts/N``) as it would open the real instrument's serial port.

One thread per device reads the master side, hands complete chunks to the device at the
time their last byte would have arrived at the baud rate, and writes the reply when it
would have been sent, byte timing included (wall clock). A 'vanish' fault closes the
pseudo-terminal, as an unplugged USB adapter does.
"""

import os
import select
import threading
import tty

from pihyst.rig._clock import WallClock
from pihyst.rig._emulators import Emulators
from pihyst.rig._serve import answer


class _PtyDevice:
    def __init__(self, device):
        self.device = device
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)               # no echo, no CR/LF translation
        tty.setraw(self.master)
        self.path = os.ttyname(self.slave)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, daemon=True,
                                        name=f"pihyst-emulated-{device.name}")

    def start(self):
        self._thread.start()

    def _serve(self):
        while not self._stop.is_set():
            if self.device.vanished(WallClock.now()):
                break
            self.device.poll(WallClock.now())   # its watchdog trips without a request
            try:
                ready, _, _ = select.select([self.master], [], [], 0.02)
                if not ready:
                    continue
                data = os.read(self.master, 4096)
            except OSError:
                break
            if not data:
                continue
            try:
                answer(self.device, data, lambda b: os.write(self.master, b))
            except OSError:
                return
        self.close()

    def close(self):
        self._stop.set()
        for fd in ("master", "slave"):
            f = getattr(self, fd)
            if f is not None:
                try:
                    os.close(f)
                except OSError:
                    pass
                setattr(self, fd, None)

    def stop(self):
        self._stop.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout=2.0)
        self.close()


class PtyEmulators:
    """The emulated supply and sensor of ``config`` on pseudo-terminals; ``paths`` maps
    'supply' and 'sensor' to their device paths. A context manager."""

    def __init__(self, config, plant=None, faults=()):
        self.emulators = Emulators(config, plant=plant, faults=faults, t0=WallClock.now())
        self._ptys = {what: _PtyDevice(dev) for what, dev in self.emulators.devices.items()}
        self.paths = {what: p.path for what, p in self._ptys.items()}
        for p in self._ptys.values():
            p.start()

    def close(self):
        for p in self._ptys.values():
            p.stop()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
