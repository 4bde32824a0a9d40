"""Simulated instruments that speak the real protocols byte for byte, coupled through one
simulated beam: the supply's output voltage drives the beam, the sensor reads its
displacement.

A device sees whole chunks of bytes at the time their last byte arrives
(:meth:`Device.receive`) and answers with ``(ready_time, bytes)`` pairs; the link in
between (:mod:`pihyst.rig._serial_handlers`, :mod:`pihyst.rig._pty`) adds the time the
bytes take on the wire. Times are seconds of the emulators' clock.
"""

import re
import struct
from abc import ABC, abstractmethod
from collections.abc import Container, Iterable
from typing import Any

import numpy as np

from pihyst.rig._codecs import (
    KEYENCE_COMMAND_ERROR,
    KEYENCE_PARAMETER_ERROR,
    crc_ok,
    decode_registers,
    encode_registers,
    format_value,
    register_count,
    request_length,
    with_crc,
)
from pihyst.rig._config import char_bits
from pihyst.rig._faults import Fault, FaultSet
from pihyst.rig._plants import make_plant


class SimulatedBeam:
    """A pihyst plant driven by a piecewise-constant voltage in continuous time.

    The voltage is clipped to the beam's drive range (a supply can give 1000 V; the
    beam is rated for its range). ``pollers`` are called with the time before every
    interaction, so time-driven events (a supply's watchdog) take effect in order.
    """

    def __init__(self, plant, t0=0.0):
        self.plant = plant
        self.t0 = t0
        self.voltage = 0.0
        self._t = 0.0
        self.pollers = []
        self.displacement = float(plant.run(np.array([0.0]), np.array([0.0]))[0])

    def _at(self, t):
        return max(self._t, t - self.t0)

    def _run(self, t):
        self._t = self._at(t)
        u = min(max(self.voltage, self.plant.u_min), self.plant.u_max)
        self.displacement = float(self.plant.run(np.array([u]), np.array([self._t]))[0])
        return self.displacement

    def poll(self, t: float) -> None:
        for poll in self.pollers:
            poll(t)

    def apply(self, volts: float, t: float) -> None:
        """The voltage across the beam changes to ``volts`` at time ``t``."""
        # one sample at the new voltage: the plant interpolates from its last sample
        if volts != self.voltage:
            self.voltage = float(volts)
            self._run(t)

    def measure(self, t: float) -> float:
        """Displacement (um, with the plant's sensor noise) at time ``t``."""
        self.poll(t)
        return self._run(t)


class Device(ABC):
    """Base of the emulated instruments: framing by terminator, faults, timing."""

    name = "device"

    def __init__(self, port_config, delay_s, faults=None):
        self.baudrate = port_config.baudrate
        self.parity, self.stopbits = port_config.parity, port_config.stopbits
        self.char_bits = char_bits(port_config)
        self.delay_s = delay_s
        self.faults = faults if faults is not None else FaultSet()
        self.requests = 0
        self.t0 = 0.0

    def vanished(self, t: float) -> bool:
        return self.faults.vanished(t - self.t0)

    def poll(self, t: float) -> None:
        """Time passes without a request (what a device does on its own, e.g. a supply's
        watchdog switching the output off); nothing by default."""
        return None

    @abstractmethod
    def receive(self, data: bytes, t: float) -> list[tuple[float, bytes]]:
        """Bytes ``data`` arrived complete at time ``t``: the replies, as a list of
        ``(ready_time, bytes)``."""

    def _answer(self, reply: bytes, t: float,
                kinds: Container[str]) -> list[tuple[float, bytes]]:
        """Apply the reply faults of ``kinds`` to ``reply`` sent at ``t``."""
        ready = t + self.delay_s
        fault = self.faults.pick(t - self.t0, kinds)
        if fault is None:
            return [(ready, reply)]
        if fault.kind == "no-reply":
            return []
        if fault.kind == "late-reply":
            return [(ready + fault.delay_s, reply)]
        if fault.kind == "truncated":
            return [(ready, reply[:max(1, len(reply) // 2)])]
        if fault.kind == "garbled":
            i = len(reply) // 2
            return [(ready, reply[:i] + bytes([reply[i] ^ 0x5A]) + reply[i + 1:])]
        if fault.kind == "bad-crc":
            return [(ready, reply[:-1] + bytes([reply[-1] ^ 0xFF]))]
        raise AssertionError(fault.kind)


_REPLY_FAULTS = ("no-reply", "late-reply", "truncated", "garbled", "bad-crc")


class SupplyState:
    """What the emulated supply does: setpoint, output switch, output voltage, and its
    own communication watchdog (output off after ``watchdog_s`` without a request)."""

    def __init__(self, beam, max_V, step_V, watchdog_s=0.0, output_switch=True):
        self.beam = beam
        self.max_V = max_V
        self.step_V = step_V
        self.watchdog_s = watchdog_s
        self.setpoint_V = 0.0
        self.output_on = not output_switch   # without an output switch the output is live
        self.commands = []                   # (time, setpoint) of every accepted setpoint
        self.last_request = None
        self.stuck = False
        self.watchdog_tripped = False
        beam.pollers.append(self.poll)

    @property
    def last_setpoint_V(self):
        return self.commands[-1][1] if self.commands else 0.0

    @property
    def output_V(self):
        if not self.output_on:
            return 0.0
        # u_q = step round(u / step): the supply's resolution
        return round(self.setpoint_V / self.step_V) * self.step_V if self.step_V else \
            self.setpoint_V

    def poll(self, t: float) -> None:
        if (self.watchdog_s > 0 and self.last_request is not None and self.output_on
                and t > self.last_request + self.watchdog_s):
            self.output_on = False
            self.watchdog_tripped = True
            self.beam.apply(0.0, self.last_request + self.watchdog_s)

    def touch(self, t):
        self.poll(t)
        self.last_request = t

    def set_watchdog(self, seconds):
        """The controller armed (``seconds`` > 0) or disarmed (0) the watchdog."""
        self.watchdog_s = float(seconds)

    def set_voltage(self, volts, t):
        self.commands.append((t, volts))
        if self.stuck:
            return
        self.setpoint_V = volts
        self.beam.apply(self.output_V, t)

    def set_output(self, on, t):
        if self.stuck:
            return
        self.output_on = bool(on)
        self.beam.apply(self.output_V, t)


class ModbusSupply(Device):
    """A supply that is a Modbus RTU server with the register map of the configuration:
    03 read holding registers, 06 write single register, 16 write multiple registers,
    CRC-16/Modbus, exceptions 01/02/03; frames with a bad CRC or another address are
    ignored, as the standard requires."""

    name = "supply"

    def __init__(self, cfg, state, faults=None, delay_s=0.005):
        super().__init__(cfg, delay_s, faults)
        self.cfg = cfg
        self.state = state
        self._buffer = b""
        self._last_byte_t = None
        n = register_count(cfg.setpoint_format)
        self.setpoint_regs = list(range(cfg.setpoint_register, cfg.setpoint_register + n))
        self.readback_regs = ([] if cfg.readback_register is None else
                              list(range(cfg.readback_register, cfg.readback_register + n)))
        self._setpoint_words = encode_registers(0.0, cfg.setpoint_format, cfg.word_order)

    def _read(self, address):
        cfg, st = self.cfg, self.state
        if address in self.setpoint_regs:
            return self._setpoint_words[self.setpoint_regs.index(address)]
        if address in self.readback_regs:
            words = encode_registers(min(st.output_V * cfg.scale, _max_value(cfg)),
                                     cfg.setpoint_format, cfg.word_order)
            return words[self.readback_regs.index(address)]
        if address == cfg.output_register:
            return int(st.output_on)
        if cfg.watchdog_register is not None and address == cfg.watchdog_register:
            return min(0xFFFF, int(round(st.watchdog_s * cfg.watchdog_scale)))
        raise _ModbusException(2)

    def _write(self, start, words, t):
        cfg, st = self.cfg, self.state
        regs = list(range(start, start + len(words)))
        if regs == [cfg.output_register]:
            if words[0] not in (0, 1):
                raise _ModbusException(3)
            st.set_output(words[0] == 1, t)
            return
        if cfg.watchdog_register is not None and regs == [cfg.watchdog_register]:
            st.set_watchdog(words[0] / cfg.watchdog_scale)
            return
        if regs != self.setpoint_regs:
            raise _ModbusException(2)
        volts = decode_registers(words, cfg.setpoint_format, cfg.word_order) / cfg.scale
        if not (np.isfinite(volts) and 0 <= volts <= st.max_V):
            raise _ModbusException(3)
        self._setpoint_words = list(words)
        st.set_voltage(volts, t)

    def poll(self, t: float) -> None:
        self.state.poll(t)

    def receive(self, data: bytes, t: float) -> list[tuple[float, bytes]]:
        char = self.char_bits / self.baudrate
        # a silence of more than 3.5 characters ends a frame (Modbus over serial line 2.5.1.1)
        if self._last_byte_t is not None and t - len(data) * char - self._last_byte_t > 3.5 * char:
            self._buffer = b""
        self._last_byte_t = t
        self._buffer += data
        replies = []
        while True:
            n = request_length(self._buffer)
            if n is None or len(self._buffer) < n:
                break
            if n < 0:                       # unknown function: resynchronise on silence
                self._buffer = b""
                break
            frame, self._buffer = self._buffer[:n], self._buffer[n:]
            replies += self._frame(frame, t)
        return replies

    def _frame(self, frame, t):
        cfg, st = self.cfg, self.state
        if self.vanished(t) or not crc_ok(frame) or frame[0] not in (0, cfg.address):
            return []
        self.requests += 1
        st.touch(t)
        if self.faults.stuck(t - self.t0):
            st.stuck = True
        function = frame[1]
        fault = self.faults.pick(t - self.t0, ("error-code",))
        try:
            if fault is not None:
                raise _ModbusException(fault.code)
            start, value = struct.unpack(">HH", frame[2:6])
            if function == 3:
                if not 1 <= value <= 125:
                    raise _ModbusException(3)
                words = [self._read(a) for a in range(start, start + value)]
                body = bytes([frame[0], 3, 2 * value]) + struct.pack(f">{value}H", *words)
            elif function == 6:
                self._write(start, [value], t)
                body = frame[:6]
            else:
                count = value
                if frame[6] != 2 * count or not 1 <= count <= 123:
                    raise _ModbusException(3)
                self._write(start, list(struct.unpack(f">{count}H", frame[7:7 + 2 * count])),
                            t)
                body = frame[:6]
        except _ModbusException as exc:
            body = bytes([frame[0], function | 0x80, exc.code])
        if frame[0] == 0:                   # broadcast: no reply
            return []
        return self._answer(with_crc(body), t, _REPLY_FAULTS)


class _ModbusException(Exception):
    def __init__(self, code):
        self.code = code


def _max_value(cfg):
    return {"uint16": 0xFFFF, "uint32": 0xFFFFFFFF, "float32": 3.4e38}[cfg.setpoint_format]


def template_regex(template: str, name: str = "volts") -> re.Pattern[str]:
    """A regular expression matching what a command template produces, with one group
    for the number ``name``: 'VOLT {volts:.2f}' -> 'VOLT\\ ([-+]?[0-9.eE+-]+)'."""
    parts = re.split(r"\{" + name + r"(?::[^}]*)?\}", template)
    number = r"\s*([-+]?[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*"
    return re.compile(number.join(re.escape(p) for p in parts))


class AsciiSupply(Device):
    """A supply with an ASCII line protocol built from the configuration's templates
    (SCPI-like or Thorlabs-MDT693B-like: echo and prompt)."""

    name = "supply"

    def __init__(self, cfg, state, faults=None, delay_s=0.005, reply_template="{volts:.3f}"):
        super().__init__(cfg, delay_s, faults)
        self.cfg = cfg
        self.state = state
        self.reply_template = reply_template
        self._set = template_regex(cfg.set_command)
        self._watchdog = (None if cfg.watchdog_command is None else
                          template_regex(cfg.watchdog_command, "seconds"))
        self._buffer = b""

    def poll(self, t: float) -> None:
        self.state.poll(t)

    def receive(self, data: bytes, t: float) -> list[tuple[float, bytes]]:
        term = self.cfg.terminator.encode()
        self._buffer += data
        replies = []
        while term in self._buffer:
            line, self._buffer = self._buffer.split(term, 1)
            replies += self._line(line.decode("ascii", "replace"), t)
        return replies

    def _line(self, line, t):
        cfg, st = self.cfg, self.state
        if self.vanished(t):
            return []
        self.requests += 1
        st.touch(t)
        if self.faults.stuck(t - self.t0):
            st.stuck = True
        # echo, then for a query the prompt, the reply and the terminator, then the prompt
        # (a Thorlabs MDT693B answers 'xvoltage?' with 'xvoltage?\r*[  24.8]\r' and is
        # ready again after '*'); an SCPI-like supply answers queries only
        term = cfg.terminator
        out = line + term if cfg.echo else ""
        m = self._set.fullmatch(line)
        if m:
            volts = float(m.group(1))
            if 0 <= volts <= st.max_V:
                st.set_voltage(volts, t)
            else:
                out += "ERROR" + term
        elif cfg.query_command and line == cfg.query_command:
            out += cfg.prompt + self.reply_template.format(volts=st.output_V) + term
        elif self._watchdog is not None and self._watchdog.fullmatch(line):
            st.set_watchdog(float(self._watchdog.fullmatch(line).group(1)))
        elif cfg.output_on_command and line == cfg.output_on_command:
            st.set_output(True, t)
        elif cfg.output_off_command and line == cfg.output_off_command:
            st.set_output(False, t)
        else:
            out += "ERROR" + term
        out += cfg.prompt
        if not out:
            return []
        return self._answer(out.encode("ascii"), t, _REPLY_FAULTS[:-1])


class KeyenceSensor(Device):
    """A KEYENCE LK-G5000/LK-HD (``MS,01``, ``MM,<mask>``, ``MA``) or LK-G3000 (``M1``,
    ``M2``, ``M0``) controller with two outputs; output ``cfg.output`` measures the beam,
    the other one has no head (``XXXXXXXX``). Replies end with CR."""

    name = "sensor"

    def __init__(self, cfg, beam, faults=None, delay_s=0.001, decimals=4, range_um=300.0):
        super().__init__(cfg, delay_s, faults)
        self.cfg = cfg
        self.beam = beam
        self.decimals = decimals
        self.range_um = range_um
        self.n_outputs = 2 if cfg.protocol == "keyence-lk-g3000" else max(2, cfg.output)
        self._stuck_text = None
        self._buffer = b""

    def _value(self, output, t, over_range):
        if output != self.cfg.output:
            return "XXXXXXXX"
        y = self.beam.measure(t)
        if over_range or abs(y) > self.range_um:
            return "+FFFFFFF" if (over_range or y > 0) else "-FFFFFFF"
        # the LK-G3000 prints a sign and 7 characters (digits and point), right-aligned;
        # a value that does not fit is over-range
        width = 7 if self.cfg.protocol == "keyence-lk-g3000" else None
        text = format_value(self.cfg.sign * y / self.cfg.scale_um, self.decimals, width)
        if width is not None and len(text) > width + 1:
            return "+FFFFFFF" if text[0] == "+" else "-FFFFFFF"
        if self.faults.stuck(t - self.t0):
            self._stuck_text = self._stuck_text or text
            return self._stuck_text
        return text

    def receive(self, data: bytes, t: float) -> list[tuple[float, bytes]]:
        self._buffer += data
        replies = []
        while b"\r" in self._buffer:
            line, self._buffer = self._buffer.split(b"\r", 1)
            replies += self._line(line.decode("ascii", "replace"), t)
        return replies

    def _outputs(self, command):
        """The outputs a measurement command asks for, or None if it is not one."""
        if self.cfg.protocol == "keyence-lk-g3000":
            m = re.fullmatch(r"M([0-2])", command)
            if not m:
                return None
            k = int(m.group(1))
            return [1, 2] if k == 0 else [k]
        m = re.fullmatch(r"MS,(\d\d)", command)
        if m:
            k = int(m.group(1))
            return [k] if 1 <= k <= self.n_outputs else []
        m = re.fullmatch(r"MM,([01]{%d})" % self.n_outputs, command)
        if m:
            return [i + 1 for i, c in enumerate(m.group(1)) if c == "1"] or []
        if command == "MA":
            return list(range(1, self.n_outputs + 1))
        return None

    def _line(self, command, t):
        if self.vanished(t):
            return []
        self.requests += 1
        outputs = self._outputs(command)
        fault = self.faults.pick(t - self.t0, ("error-code",))
        if fault is not None:
            code = fault.code
        elif outputs is None:
            code = KEYENCE_COMMAND_ERROR[self.cfg.protocol]
        elif not outputs:
            code = KEYENCE_PARAMETER_ERROR[self.cfg.protocol]
        else:
            code = None
        if code is not None:
            reply = f"ER,{command.split(',')[0][:2]},{code:02d}\r"
        else:
            over = self.faults.pick(t - self.t0, ("over-range",)) is not None
            values = [self._value(k, t, over) for k in outputs]
            reply = command + "," + ",".join(values) + "\r"
        return self._answer(reply.encode("ascii"), t, _REPLY_FAULTS[:-1])


class Emulators:
    """The emulated supply and sensor of a configuration, coupled through one beam.

    Parameters
    ----------
    config : RigConfig
        The instruments to emulate ([supply], [sensor], [emulator]).
    plant : str, optional
        Simulated beam (default: ``config.emulator.plant``).
    faults : iterable of Fault
        Faults to inject.
    t0 : float
        The emulators' clock at start (fault times count from there).

    Examples
    --------
    A Modbus request to the emulated supply, as bytes (write 50.0 V as float32 to the
    setpoint registers 10-11 of slave 1):

    >>> from pihyst.rig import Emulators, parse_config
    >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\n'
    ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
    >>> emulators = Emulators(config)
    >>> from pihyst.rig._codecs import with_crc
    >>> request = with_crc(bytes.fromhex("0110000a00020442480000"))
    >>> replies = emulators.supply.receive(request, t=0.0)
    >>> emulators.supply_state.last_setpoint_V, replies[0][1].hex()
    (50.0, '0110000a000261ca')
    """

    def __init__(self, config: Any, plant: str | None = None, faults: Iterable[Fault] = (),
                 t0: float = 0.0) -> None:
        e = config.emulator
        self.config = config
        self.plant = make_plant(plant or e.plant, seed=e.seed)
        self.beam = SimulatedBeam(self.plant, t0=t0)
        s = config.supply
        switch = s.output_register is not None if s.protocol == "modbus-rtu" else \
            s.output_on_command is not None
        self.supply_state = SupplyState(self.beam, e.supply_max_V, e.supply_step_V,
                                        e.supply_watchdog_s, output_switch=switch)
        supply_faults = FaultSet(f for f in faults if f.device == "supply")
        sensor_faults = FaultSet(f for f in faults if f.device == "sensor")
        self.supply: ModbusSupply | AsciiSupply
        if s.protocol == "modbus-rtu":
            self.supply = ModbusSupply(s, self.supply_state, supply_faults, e.supply_delay_s)
        else:
            self.supply = AsciiSupply(s, self.supply_state, supply_faults, e.supply_delay_s,
                                      reply_template=e.supply_reply)
        self.sensor = KeyenceSensor(config.sensor, self.beam, sensor_faults, e.sensor_delay_s,
                                    e.sensor_decimals, e.sensor_range_um)
        self.supply.t0 = self.sensor.t0 = t0

    def add_fault(self, fault: Fault) -> None:
        """Inject ``fault`` from now on (into the supply or the sensor, by its device).

        Parameters
        ----------
        fault : Fault
            The fault.

        Examples
        --------
        >>> from pihyst.rig import Emulators, Fault, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> emulators = Emulators(config)
        >>> emulators.add_fault(Fault("no-reply", "sensor"))
        >>> emulators.sensor.receive(b"MS,01\\r", t=0.0)
        []
        """
        (self.supply if fault.device == "supply" else self.sensor).faults.add(fault)

    @property
    def devices(self) -> dict[str, "Device"]:
        """The emulated devices by role: ``{"supply": ..., "sensor": ...}``."""
        return {"supply": self.supply, "sensor": self.sensor}
