"""Clocks: the monotonic wall clock, and a virtual clock for tests and fast simulations.

A clock is two callables, ``now()`` (seconds, never decreasing) and ``sleep(seconds)``.
With :class:`VirtualClock`, sleeping advances time at once, so a 300 s run through the
emulated instruments takes the time its computations take.
"""

import threading
import time


class WallClock:
    """time.monotonic and time.sleep: the clock of a run on real instruments.

    Examples
    --------
    >>> from pihyst.rig import WallClock
    >>> clock = WallClock()
    >>> t0 = clock.now(); clock.sleep(0.001); clock.now() >= t0 + 0.001
    True
    """

    virtual = False

    @staticmethod
    def now() -> float:
        """The time (s) of the monotonic clock.

        Returns
        -------
        float
            Seconds since an arbitrary start; never decreases.

        Examples
        --------
        >>> from pihyst.rig import WallClock
        >>> WallClock.now() <= WallClock.now()
        True
        """
        return time.monotonic()

    @staticmethod
    def sleep(seconds: float) -> None:
        """Wait ``seconds`` (nothing for 0 or less).

        Parameters
        ----------
        seconds : float
            How long to wait (s).

        Examples
        --------
        >>> from pihyst.rig import WallClock
        >>> WallClock.sleep(-1.0)    # returns at once
        """
        if seconds > 0:
            time.sleep(seconds)


class VirtualClock:
    """Time that moves only when someone sleeps.

    Parameters
    ----------
    start : float
        The time (s) it starts at.

    Examples
    --------
    >>> from pihyst.rig import VirtualClock
    >>> clock = VirtualClock()
    >>> clock.sleep(2.5); clock.now()
    2.5
    """

    virtual = True

    def __init__(self, start: float = 0.0) -> None:
        self._t = float(start)
        self._lock = threading.Lock()

    def now(self) -> float:
        """The virtual time (s).

        Returns
        -------
        float
            The start plus every sleep so far.

        Examples
        --------
        >>> from pihyst.rig import VirtualClock
        >>> VirtualClock(start=10.0).now()
        10.0
        """
        return self._t

    def sleep(self, seconds: float) -> None:
        """Advance the time by ``seconds`` at once (nothing for 0 or less).

        Parameters
        ----------
        seconds : float
            How far to advance (s).

        Examples
        --------
        >>> from pihyst.rig import VirtualClock
        >>> clock = VirtualClock()
        >>> clock.sleep(0.5); clock.sleep(-3.0); clock.now()
        0.5
        """
        if seconds > 0:
            with self._lock:
                self._t += seconds

    def advance_to(self, t: float) -> None:
        """Advance the time to ``t`` (nothing if it is already later).

        Parameters
        ----------
        t : float
            The time (s) to advance to.

        Examples
        --------
        >>> from pihyst.rig import VirtualClock
        >>> clock = VirtualClock(start=1.0)
        >>> clock.advance_to(3.0); clock.advance_to(2.0); clock.now()
        3.0
        """
        with self._lock:
            self._t = max(self._t, t)
