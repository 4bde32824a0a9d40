"""pihyst's rig in PyMeasure (``pip install 'pihyst[pymeasure]'``).

Instrument classes that speak exactly the bytes of ``pihyst rig``'s drivers (they hold
those drivers, on the PyMeasure adapter): :class:`KeyenceLKG5000`,
:class:`KeyenceLKG3000`, :class:`ModbusHVSupply`, :class:`AsciiHVSupply` and
:class:`MDT693BLikeSupply`. Procedures for ``record`` and ``track``
(:class:`RecordProcedure`, :class:`TrackProcedure`, on the base :class:`RigProcedure`)
that run pihyst's controller with its safety and emit every tick, so that PyMeasure's
ManagedWindow plots a run live; ``learn`` is built on :class:`RigProcedure` in
``examples/pymeasure_learn.py`` (the learning sits beside the rig, not under it). See
docs/rig.md and ``examples/pymeasure_record.py``.
"""

try:
    import pymeasure  # noqa: F401
except ImportError:  # pragma: no cover - the extra is in the test environment
    raise ImportError("pihyst.rig.pymeasure needs PyMeasure: pip install "
                      "'pihyst[pymeasure]'") from None

from pihyst.rig.pymeasure._instruments import (
    MDT693B_DIALECT,
    AsciiHVSupply,
    KeyenceLKG3000,
    KeyenceLKG5000,
    MDT693BLikeSupply,
    ModbusHVSupply,
)
from pihyst.rig.pymeasure._port import AdapterPort
from pihyst.rig.pymeasure._procedures import (
    RecordProcedure,
    RigProcedure,
    RunStopped,
    TrackProcedure,
)

__all__ = ["MDT693B_DIALECT", "AdapterPort", "AsciiHVSupply", "KeyenceLKG3000",
           "KeyenceLKG5000", "MDT693BLikeSupply", "ModbusHVSupply", "RecordProcedure",
           "RigProcedure", "RunStopped", "TrackProcedure"]
