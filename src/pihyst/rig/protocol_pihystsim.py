"""pyserial URL handler ``pihystsim://NAME`` (pyserial finds it by this module's name):
the emulated instruments running in this process."""

from pihyst.rig._serial_handlers import Serial

__all__ = ["Serial"]
