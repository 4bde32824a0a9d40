"""Faults the emulated instruments can be told to make (fault injection)."""

import math
from collections.abc import Container, Iterable
from dataclasses import dataclass

from pihyst.exceptions import InvalidArgumentError

#: Every kind of fault, and the devices it applies to.
FAULT_KINDS = {
    "no-reply": ("supply", "sensor"),      # the request is ignored
    "late-reply": ("supply", "sensor"),    # the reply comes delay_s late
    "truncated": ("supply", "sensor"),     # only the first half of the reply
    "garbled": ("supply", "sensor"),       # one byte of the reply corrupted
    "bad-crc": ("supply",),                # Modbus: a wrong CRC
    "error-code": ("supply", "sensor"),    # Keyence ER,<cmd>,<code>; Modbus exception <code>
    "stuck": ("supply", "sensor"),         # sensor: the value freezes; supply: the output does
    "over-range": ("sensor",),             # +FFFFFFF
    "vanish": ("supply", "sensor"),        # the port disappears (unplugged adapter)
}


@dataclass
class Fault:
    """One injected fault.

    Parameters
    ----------
    kind : str
        One of :data:`FAULT_KINDS`.
    device : str
        'supply' or 'sensor'.
    start_s : float
        Emulator time (s since the emulators started) from which it acts.
    count : int or None
        Replies it affects (None: all from ``start_s`` on).
    code : int
        The error code of 'error-code' (Keyence ER code, or Modbus exception code).
    delay_s : float
        Extra delay of 'late-reply'.

    Raises
    ------
    InvalidArgumentError
        An unknown kind, a kind the device cannot make, a start that is not finite or a
        count below 1.

    Examples
    --------
    >>> from pihyst.rig import Fault
    >>> fault = Fault("no-reply", "sensor", start_s=2.0, count=1)
    >>> fault.active(1.0), fault.active(2.5), fault.active(3.0)
    (False, True, False)
    """

    kind: str
    device: str
    start_s: float = 0.0
    count: int | None = None
    code: int | None = None
    delay_s: float = 1.0

    def __post_init__(self) -> None:
        if self.kind not in FAULT_KINDS:
            raise InvalidArgumentError(f"unknown fault {self.kind!r}; choose one of "
                             f"{', '.join(FAULT_KINDS)}")
        if self.device not in FAULT_KINDS[self.kind]:
            raise InvalidArgumentError(f"fault {self.kind!r} does not apply to the "
                                       f"{self.device}")
        if not math.isfinite(self.start_s):
            raise InvalidArgumentError(f"the start must be a finite time in seconds, got "
                                       f"{self.start_s}")
        if self.count is not None and self.count < 1:
            raise InvalidArgumentError(f"count must be >= 1 or None, got {self.count}")
        if self.code is None:
            self.code = 50 if self.device == "sensor" else 4
        self.used = 0

    def active(self, t: float) -> bool:
        """Whether the fault acts on a reply at emulator time ``t`` (and count it if so).

        Parameters
        ----------
        t : float
            Emulator time (s).

        Returns
        -------
        bool
            True from ``start_s`` on, while fewer than ``count`` replies were affected.

        Examples
        --------
        >>> from pihyst.rig import Fault
        >>> fault = Fault("garbled", "supply", count=2)
        >>> [fault.active(t) for t in (0.0, 0.1, 0.2)]
        [True, True, False]
        """
        if t < self.start_s or (self.count is not None and self.used >= self.count):
            return False
        self.used += 1
        return True


class FaultSet:
    """The faults of one device; :meth:`pick` finds the one acting on a reply."""

    def __init__(self, faults: Iterable[Fault] = ()) -> None:
        self.faults = list(faults)

    def add(self, fault: Fault) -> None:
        self.faults.append(fault)

    def pick(self, t: float, kinds: Container[str] | None = None) -> Fault | None:
        for fault in self.faults:
            if (kinds is None or fault.kind in kinds) and fault.active(t):
                return fault
        return None

    def vanished(self, t: float) -> bool:
        return any(f.kind == "vanish" and t >= f.start_s for f in self.faults)

    def stuck(self, t: float) -> bool:
        return any(f.kind == "stuck" and t >= f.start_s for f in self.faults)
