"""The rig loop: achievable tick rate through the emulated instruments at 19 200 and
115 200 baud (and the link budget behind it), timing jitter in real time, and the
controller's own overhead per tick.

1. Link budget: bytes per tick and their time on the wire (10 bits per byte, 8N1), plus
   the devices' processing, from the emulators in virtual time (exactly what the
   emulated wire costs), asked to run far faster than they can: every tick overruns, so
   the busy time per tick is the shortest achievable period.
2. Jitter in real time: the loop through the in-process emulators on the wall clock;
   reference: a bare loop that sleeps to the same absolute deadlines and does nothing.
3. Overhead: the controller with instruments that answer instantly (virtual time);
   reference: a bare Python loop making the same driver calls.

Run: python benchmarks/bench_rig.py
"""

import time

import numpy as np

from pihyst.rig import (
    Controller,
    LoopSettings,
    Reading,
    Rig,
    VirtualClock,
    VoltageProgram,
    parse_config,
)
from pihyst.sim.signals import triangle


def config(supply_baud, rate_hz, readback=True):
    return parse_config(f"""
[rig]
rate_hz = {rate_hz}
slew_V_per_s = 1e6
max_overruns = 1000000
[supply]
port = "pihystsim://supply"
baudrate = {supply_baud}
output_register = 9
{"readback_register = 12" if readback else ""}
[sensor]
port = "pihystsim://sensor"
baudrate = 115200
""", source="bench")


def link_budget():
    print("1. link budget per tick (Modbus float32 setpoint write, optional float32 "
          "readback; KEYENCE MS,01 at 115 200 baud; processing 5 ms supply, 1 ms sensor)")
    print(f"{'supply baud':>12} {'readback':>9} {'bytes':>6} {'wire ms':>8} "
          f"{'busy ms':>8} {'max rate Hz':>12}")
    for baud in (19200, 115200):
        for readback in (True, False):
            cfg = config(baud, 1000.0, readback)
            u = np.linspace(0.0, 100.0, 200)
            with Rig(cfg) as rig:
                result = rig.run(VoltageProgram(u), handle_signals=False)
            busy = result.column("busy_s", "run")
            supply_bytes = 13 + 8 + ((8 + 9) if readback else 0)
            sensor_bytes = 6 + 17
            wire = supply_bytes * 10 / baud + sensor_bytes * 10 / 115200
            print(f"{baud:>12} {str(readback):>9} {supply_bytes + sensor_bytes:>6} "
                  f"{1000 * wire:>8.2f} {1000 * np.mean(busy):>8.2f} "
                  f"{1 / np.mean(busy):>12.1f}")


def bare_deadline_loop(rate_hz, n):
    period = 1.0 / rate_hz
    t0 = deadline = time.monotonic()
    late = []
    for _ in range(n):
        now = time.monotonic()
        if deadline > now:
            time.sleep(deadline - now)
        late.append(time.monotonic() - deadline)
        deadline += period
    del t0
    return np.array(late)


def jitter():
    print("\n2. jitter in real time through the in-process emulators (2 s per row)")
    print(f"{'supply baud':>12} {'rate Hz':>8} {'mean ms':>8} {'p99 ms':>7} {'max ms':>7} "
          f"{'overruns':>9} {'bare p99 ms':>12} {'p99 ratio':>10}")
    for baud, rate in ((19200, 20.0), (115200, 50.0)):
        cfg = config(baud, rate)
        n = int(2 * rate)
        with Rig(cfg, real_time=True) as rig:
            result = rig.controller(handle_signals=False, watchdog=False).run(
                VoltageProgram(np.linspace(0, 50, n)))
        late = result.column("late_s", "run")
        bare = bare_deadline_loop(rate, n)
        p99, bare_p99 = np.percentile(late, 99), np.percentile(bare, 99)
        print(f"{baud:>12} {rate:>8g} {1000 * late.mean():>8.3f} {1000 * p99:>7.3f} "
              f"{1000 * late.max():>7.3f} {result.overruns:>9} {1000 * bare_p99:>12.3f} "
              f"{p99 / bare_p99 if bare_p99 > 0 else float('nan'):>10.2f}")


class InstantSupply:
    has_readback = False

    def set_voltage(self, volts):
        self.volts = volts

    def read_voltage(self):
        return None

    def output_on(self):
        pass

    def output_off(self):
        pass


class InstantSensor:
    def read(self):
        return Reading(1.0)


def overhead():
    print("\n3. controller overhead per tick (instruments that answer at once, virtual time)")
    n = 20000
    _, u = triangle(period_s=n / 1000.0, dt=1e-3)
    settings = LoopSettings(rate_hz=1000.0, slew_V_per_s=1e6)
    supply, sensor = InstantSupply(), InstantSensor()
    best = np.inf
    for _ in range(3):
        controller = Controller(supply, sensor, settings, clock=VirtualClock(),
                                handle_signals=False)
        t0 = time.perf_counter()
        controller.run(VoltageProgram(u))
        best = min(best, time.perf_counter() - t0)
    ref = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        for v in u:
            sensor.read()
            supply.set_voltage(float(v))
        ref = min(ref, time.perf_counter() - t0)
    ticks = u.size
    print(f"controller: {1e6 * best / ticks:.1f} us per tick; bare loop with the same "
          f"driver calls: {1e6 * ref / ticks:.2f} us per tick; ratio {best / ref:.0f}")
    print(f"at 20 Hz the controller takes {100 * best / ticks * 20:.3f} % of a period")


if __name__ == "__main__":
    link_budget()
    jitter()
    overhead()
