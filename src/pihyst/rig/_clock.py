"""Clocks: the monotonic wall clock, and a virtual clock for tests and fast simulations.

A clock is two callables, ``now()`` (seconds, never decreasing) and ``sleep(seconds)``.
With :class:`VirtualClock`, sleeping advances time at once, so a 300 s run through the
emulated instruments takes the time its computations take.
"""

import threading
import time


class WallClock:
    """time.monotonic and time.sleep."""

    virtual = False

    @staticmethod
    def now():
        return time.monotonic()

    @staticmethod
    def sleep(seconds):
        if seconds > 0:
            time.sleep(seconds)


class VirtualClock:
    """Time that moves only when someone sleeps.

    Examples
    --------
    >>> clock = VirtualClock()
    >>> clock.sleep(2.5); clock.now()
    2.5
    """

    virtual = True

    def __init__(self, start=0.0):
        self._t = float(start)
        self._lock = threading.Lock()

    def now(self):
        return self._t

    def sleep(self, seconds):
        if seconds > 0:
            with self._lock:
                self._t += seconds

    def advance_to(self, t):
        with self._lock:
            self._t = max(self._t, t)
