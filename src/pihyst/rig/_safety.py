"""Safety pieces of the loop: the setpoint check, signal handling and the watchdog."""

import math
import signal
import threading
import time


class StopRun(Exception):
    """Raised inside the loop to stop the run safely; the message says why."""


class Terminated(BaseException):
    """SIGTERM arrived (a BaseException, like KeyboardInterrupt, so that no ``except
    Exception`` swallows it)."""


class SetpointGuard:
    """Every setpoint passes here before it is sent:

        u = clip(command, u_min, u_max),  |u - v| <= slew / rate for every voltage v the
                                          supply may be at

    After a send that failed (no reply, bad reply) the supply may or may not have taken
    the new value, so the guard keeps the range [lo, hi] of voltages it may be at and
    keeps the next setpoint within one step of both ends. A non-finite command is
    refused (:class:`StopRun`): it is a fault upstream, not a value to clip."""

    def __init__(self, u_min, u_max, max_step=None):
        self.u_min, self.u_max = u_min, u_max
        self.max_step = max_step
        self.lo = self.hi = 0.0

    @property
    def last(self):
        """The highest voltage the supply may be at."""
        return self.hi

    def check(self, command):
        if not math.isfinite(command):
            raise StopRun(f"refused a non-finite setpoint ({command})")
        u = min(max(command, self.u_min), self.u_max)
        if self.max_step is not None:
            u = min(max(u, self.hi - self.max_step), self.lo + self.max_step)
        return u

    def sent(self, u):
        """``u`` was sent and acknowledged."""
        self.lo = self.hi = u

    def failed(self, u):
        """Sending ``u`` failed: the supply may be at ``u`` or where it was."""
        self.lo, self.hi = min(self.lo, u), max(self.hi, u)


class SignalGuard:
    """SIGTERM raises :class:`Terminated` and SIGINT KeyboardInterrupt in the main thread
    while the loop runs; :meth:`hold` defers both while the output is being zeroed.
    Outside the main thread (where Python cannot install handlers) it does nothing."""

    def __init__(self):
        self._old = {}
        self.pending = None
        self._holding = False

    def _handler(self, signum, frame):
        name = signal.Signals(signum).name
        if self._holding:
            self.pending = name
            return
        if signum == signal.SIGINT:
            raise KeyboardInterrupt
        raise Terminated(name)

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                self._old[sig] = signal.signal(sig, self._handler)
        return self

    def hold(self):
        self._holding = True

    def __exit__(self, *exc):
        for sig, old in self._old.items():
            signal.signal(sig, old)
        self._old.clear()
        return False


class Watchdog:
    """A thread that calls ``trip()`` once when the loop has been busy (not waiting for
    its next deadline) for more than ``limit_s`` of wall-clock time: a stalled loop must
    not leave a voltage on the beam."""

    def __init__(self, limit_s, trip, poll_s=None):
        self.limit_s = limit_s
        self._trip = trip
        self._poll = poll_s if poll_s is not None else max(0.001, limit_s / 5)
        self._busy_since = None
        self._stop = threading.Event()
        self.tripped = None                 # the stall (s) when it tripped
        self._thread = threading.Thread(target=self._watch, name="pihyst-rig-watchdog",
                                         daemon=True)

    def start(self):
        self._thread.start()
        return self

    def busy(self):
        self._busy_since = time.monotonic()

    def idle(self):
        self._busy_since = None

    def _watch(self):
        while not self._stop.wait(self._poll):
            since = self._busy_since
            if since is not None and self.tripped is None:
                stall = time.monotonic() - since
                if stall > self.limit_s:
                    self.tripped = stall
                    self._trip()

    def stop(self):
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()
