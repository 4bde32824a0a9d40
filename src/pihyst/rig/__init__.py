"""The rig: drivers for the high-voltage supply (Modbus RTU or ASCII) and the KEYENCE
laser displacement sensor, a fixed-rate controller with its safety, run logs, and
emulated instruments that speak the same bytes, coupled through a simulated beam.

Examples
--------
Record the paper's loop through the emulated instruments, in virtual time:

>>> from pihyst.rig import Rig, VoltageProgram, parse_config
>>> from pihyst.sim.signals import triangle
>>> config = parse_config('''
... [rig]
... rate_hz = 10.0
... slew_V_per_s = 200.0
... [supply]
... port = "pihystsim://supply"
... readback_register = 12
... output_register = 9
... [sensor]
... port = "pihystsim://sensor"
... ''')
>>> t, u = triangle(period_s=30.0, dt=0.1)
>>> with Rig(config) as rig:
...     result = rig.run(VoltageProgram(u), handle_signals=False)
>>> result.reason, result.zeroed, rig.emulators.supply_state.last_setpoint_V
('end of the program', True, 0.0)
>>> y = result.column("displacement_um", phase="run")
>>> bool(40 < y.max() < 50)
True
"""

from pihyst.rig._clock import VirtualClock, WallClock
from pihyst.rig._codecs import KeyenceError, Reading, ReplyError, crc16_modbus, crc_ok
from pihyst.rig._config import (
    ConfigError,
    EmulatorConfig,
    LoopSettings,
    RigConfig,
    SensorConfig,
    SupplyConfig,
    load_config,
    parse_config,
)
from pihyst.rig._controller import Controller, RunResult
from pihyst.rig._emulators import Emulators
from pihyst.rig._faults import FAULT_KINDS, Fault
from pihyst.rig._log import COLUMNS, CsvRunLog, TickRecord, read_run_log
from pihyst.rig._ports import NoReplyError, RigError, open_port
from pihyst.rig._programs import FeedbackProgram, FeedforwardProgram, VoltageProgram
from pihyst.rig._sensor import KeyenceSensor, open_sensor
from pihyst.rig._session import Rig, is_emulated
from pihyst.rig._supply import AsciiSupply, ModbusRtuSupply, open_supply

__all__ = [
    "COLUMNS", "FAULT_KINDS", "AsciiSupply", "ConfigError", "Controller", "CsvRunLog",
    "EmulatorConfig", "Emulators", "Fault", "FeedbackProgram", "FeedforwardProgram",
    "KeyenceError", "KeyenceSensor", "LoopSettings", "ModbusRtuSupply", "NoReplyError",
    "Reading", "ReplyError", "Rig", "RigConfig", "RigError", "RunResult", "SensorConfig",
    "SupplyConfig", "TickRecord", "VirtualClock", "VoltageProgram", "WallClock",
    "crc16_modbus", "crc_ok", "is_emulated", "load_config", "open_port", "open_sensor",
    "open_supply", "parse_config", "read_run_log",
]
