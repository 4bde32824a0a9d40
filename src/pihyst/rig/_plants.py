"""The simulated beams the emulated instruments drive: the one place the rig imports them
(they are moving to ``pihyst.sim``)."""

from pihyst.sim import PLANT_NAMES, make_plant

__all__ = ["PLANT_NAMES", "make_plant"]
