"""End to end through the emulated instruments in virtual time: the loop, its log, and
the safety on every exit path."""

import errno
import math
import os
import signal

import numpy as np
import pytest
from rig_helpers import make_config

from pihyst.cli import main as pihyst_main
from pihyst.rig import Fault, Rig, VoltageProgram, WallClock, _session, read_run_log
from pihyst.rig._log import CsvRunLog
from pihyst.sim.signals import triangle


def record(tmp_path, config=None, faults=(), period_s=20.0, program=None, **rig_kwargs):
    config = config or make_config()
    if program is None:
        _, u = triangle(period_s=period_s, dt=1.0 / config.rig.rate_hz)
        program = VoltageProgram(u)
    log = tmp_path / "run.csv"
    with Rig(config, faults=faults, **rig_kwargs) as rig:
        result = rig.run(program, log, handle_signals=True)
    return result, rig.emulators, log


def assert_safe_stop(result, emu, log, why):
    assert emu.supply_state.last_setpoint_V == 0.0
    assert not emu.supply_state.output_on
    assert why in result.reason
    notes = read_run_log(log)[1]
    assert any(n.startswith("stopped: ") and why in n for n in notes), notes[-3:]


def assert_every_tick_logged(result, log):
    columns, _ = read_run_log(log)
    ticks = columns["tick"]
    assert ticks.tolist() == list(range(len(result.records)))


def test_record_fits_as_it_is(tmp_path):
    result, emu, log = record(tmp_path, period_s=30.0)
    assert result.completed and result.zeroed and result.reason == "end of the program"
    assert result.overruns == 0
    assert emu.supply_state.last_setpoint_V == 0.0 and not emu.supply_state.output_on
    assert_every_tick_logged(result, log)
    y = result.column("displacement_um", "run")
    assert 40 < y.max() < 50 and abs(y[0]) < 0.1
    out = tmp_path / "model.json"
    assert pihyst_main(["fit", str(log), "--model", "multislope", "--thresholds",
                        "0,20,30,40", "-o", str(out)]) == 0
    assert out.exists()


def test_loop_timing_in_virtual_time(tmp_path):
    result, _, _ = record(tmp_path, period_s=4.0)
    t = result.column("time_s")
    # absolute deadlines: tick k starts at k / rate exactly (virtual time, no overrun)
    assert np.allclose(np.diff(t), 0.05, atol=1e-9)
    busy = result.column("busy_s", "run")
    # per tick: sensor 6 + 17 bytes at 115 200, write float (13 + 8) and readback (8 + 9)
    # at 19 200 with 5 ms processing each, 1 ms for the sensor, and the Modbus silence
    wire = 23 * 10 / 115200 + 0.001 + 38 * 10 / 19200 + 2 * 0.005
    assert wire < busy.min() and busy.max() < wire + 0.004


def test_start_ramp_and_readback(tmp_path):
    config = make_config(rig={"slew_V_per_s": 100.0})
    program = VoltageProgram(np.full(20, 30.0))
    result, emu, log = record(tmp_path, config, program=program)
    ramp = result.column("voltage_V", "ramp-up")
    assert ramp.tolist() == pytest.approx([5.0, 10.0, 15.0, 20.0, 25.0, 30.0])
    down = result.column("voltage_V", "shutdown")
    assert down.tolist() == pytest.approx([25.0, 20.0, 15.0, 10.0, 5.0, 0.0])
    rb = result.column("readback_V", "run")
    assert np.allclose(rb, 30.0)
    times = [t for t, _ in emu.supply_state.commands]
    assert times == sorted(times)


def test_limits_and_slew_hold_for_any_command(tmp_path):
    program = VoltageProgram(np.array([0.0, 500.0, 500.0, 80.0, 0.0, 160.0]))
    config = make_config(rig={"u_max": 120.0, "slew_V_per_s": 400.0},
                         emulator={"supply_max_V": 1000.0})
    result, emu, _ = record(tmp_path, config, program=program)
    sent = result.column("voltage_V")
    assert sent.max() <= 120.0 and np.all(np.abs(np.diff(np.r_[0.0, sent])) <= 20.0 + 1e-9)
    assert result.column("command_V", "run")[1] == 500.0


# ----------------------------------------------------------------------------- faults
SENSOR_FAULTS = [("no-reply", "communication errors"), ("late-reply", "communication errors"),
                 ("truncated", "communication errors"), ("garbled", "communication errors"),
                 ("error-code", "communication errors"), ("vanish", "communication errors"),
                 ("over-range", "invalid sensor readings"), ("stuck", "stuck")]


@pytest.mark.parametrize("kind, why", SENSOR_FAULTS)
def test_sensor_faults_stop_at_zero(tmp_path, kind, why):
    result, emu, log = record(tmp_path, faults=[Fault(kind, "sensor", start_s=3.0)])
    assert not result.completed
    assert_safe_stop(result, emu, log, why)
    assert_every_tick_logged(result, log)
    assert result.column("time_s")[-1] < 10


SUPPLY_FAULTS = [("no-reply", "communication errors"), ("late-reply", "communication errors"),
                 ("truncated", "communication errors"), ("garbled", "communication errors"),
                 ("bad-crc", "communication errors"), ("error-code", "communication errors")]


@pytest.mark.parametrize("kind, why", SUPPLY_FAULTS)
def test_supply_faults_stop_at_zero(tmp_path, kind, why):
    # three failed exchanges in a row stop the run; the supply answers again afterwards
    result, emu, log = record(tmp_path, faults=[Fault(kind, "supply", start_s=3.0, count=3)])
    assert not result.completed
    assert_safe_stop(result, emu, log, why)
    assert_every_tick_logged(result, log)


def test_stuck_supply_is_caught_by_the_readback(tmp_path):
    result, emu, log = record(tmp_path, faults=[Fault("stuck", "supply", start_s=3.0)])
    assert "readback" in result.reason
    assert emu.supply_state.last_setpoint_V == 0.0
    # the supply took neither 0 V nor output off: the run must not say it is at 0 V
    assert emu.supply_state.output_V > 1.0
    assert not result.zeroed and math.isnan(result.final_voltage_V)
    stopped = [n for n in read_run_log(log)[1] if n.startswith("stopped: readback")]
    assert len(stopped) == 1 and "WARNING: the supply reads back" in stopped[0], stopped
    assert "the beam may still be charged" in stopped[0]


def test_an_echoing_ascii_supply_with_a_prompt_ends_at_zero(tmp_path):
    # MDT693B-like: echo, '*' prompt, a readback query every tick; the shutdown's 0 V
    # follows the last tick's query at once, before that query's closing prompt arrived
    config = make_config(supply={
        "protocol": "ascii", "baudrate": 115200, "terminator": "\r",
        "set_command": "xvoltage={volts:.2f}", "query_command": "xvoltage?", "echo": True,
        "prompt": "*", "setpoint_register": None, "setpoint_format": None,
        "word_order": None, "scale": None, "output_register": None,
        "readback_register": None, "address": None})
    result, emu, log = record(tmp_path, config, period_s=5.0)
    assert result.completed and result.zeroed, result.reason
    assert emu.supply_state.output_V == 0.0
    assert not any("WARNING" in n for n in read_run_log(log)[1])


class _FullDiskLog(CsvRunLog):
    """A CSV log whose disk fills up after ``budget`` flushes."""

    budget = 0

    def _flush(self):
        type(self).budget -= 1
        if type(self).budget < 0:
            raise OSError(errno.ENOSPC, "No space left on device")
        super()._flush()


@pytest.mark.parametrize("budget", [3, 150])     # at the start ramp, in the run
def test_a_log_that_cannot_be_written_stops_the_run_at_zero(tmp_path, monkeypatch, budget):
    # the shutdown writes to the log too: a full disk raised out of it before 0 V was
    # sent, and the supply stayed at 76 V with its output on
    monkeypatch.setattr(_FullDiskLog, "budget", budget)
    monkeypatch.setattr(_session, "CsvRunLog", _FullDiskLog)
    result, emu, log = record(tmp_path)
    assert not result.completed and result.zeroed
    assert result.reason == "the log could not be written (OSError: [Errno 28] No space " \
                            "left on device)"
    assert emu.supply_state.last_setpoint_V == 0.0 and not emu.supply_state.output_on
    assert emu.supply_state.output_V == 0.0


@pytest.mark.parametrize("where", ["ramp", "zero"])
def test_a_driver_error_that_is_no_oserror_does_not_stop_the_shutdown(tmp_path, where):
    # the sensor goes over-range at 5 s (about 75 V); then the supply driver raises a
    # ValueError (a driver bug, a value it cannot encode) for some setpoints on the way
    # down: those were not caught, the shutdown left at once and the supply stayed on
    config = make_config()
    _, u = triangle(period_s=20.0, dt=1.0 / config.rig.rate_hz)
    with Rig(config, faults=[Fault("over-range", "sensor", start_s=5.0)]) as rig:
        send = rig.supply.set_voltage
        seen = []

        def refusing(volts):
            seen.append(volts)
            down = seen[seen.index(max(seen)):] if max(seen) > 70.0 else []
            if down and ((where == "ramp" and 10.0 < volts < 60.0) or
                         (where == "zero" and volts == 0.0 and down.count(0.0) < 3)):
                raise ValueError(f"cannot encode {volts} V")
            send(volts)
        rig.supply.set_voltage = refusing
        result = rig.run(VoltageProgram(u), tmp_path / "run.csv")
        state = rig.emulators.supply_state
    assert "invalid sensor readings" in result.reason
    assert result.zeroed and state.output_V == 0.0 and not state.output_on


def test_readback_after_the_end_confirms_0_V(tmp_path):
    result, emu, log = record(tmp_path)
    assert result.completed and result.zeroed
    assert emu.supply_state.output_V == 0.0
    assert not any("WARNING" in n for n in read_run_log(log)[1])


def test_vanished_supply_port(tmp_path):
    config = make_config(emulator={"supply_watchdog_s": 1.5})
    result, emu, log = record(tmp_path, config, faults=[Fault("vanish", "supply", start_s=3.0)])
    assert "communication errors" in result.reason and not result.zeroed
    notes = read_run_log(log)[1]
    assert any("WARNING: could not send 0 V" in n for n in notes)
    # nothing reaches the supply any more: its own communication watchdog switches it off
    emu.beam.poll(emu.supply_state.last_request + 2.0)
    assert emu.supply_state.output_V == 0.0 and emu.beam.voltage == 0.0


def test_overruns_stop_the_run(tmp_path):
    config = make_config(sensor={"timeout_s": 0.5}, rig={"max_overruns": 4})
    result, emu, log = record(tmp_path, config,
                              faults=[Fault("late-reply", "sensor", start_s=2.0, delay_s=0.06)])
    assert_safe_stop(result, emu, log, "consecutive overruns")
    flags = result.column("overrun", "run")
    assert flags[-4:].tolist() == [1, 1, 1, 1] and result.overruns >= 4
    t = result.column("time_s", "run")
    assert np.all(np.diff(t) > 0)


def test_a_few_invalid_readings_are_logged_and_the_log_still_fits(tmp_path):
    faults = [Fault("over-range", "sensor", start_s=5.0, count=2),
              Fault("no-reply", "sensor", start_s=8.0, count=1)]
    result, emu, log = record(tmp_path, faults=faults)
    assert result.completed
    columns, _ = read_run_log(log)
    assert set(columns["sensor_status"]) >= {"ok", "over-range+"}
    assert np.isnan(columns["displacement_um"][columns["sensor_status"] != "ok"]).all()
    assert_every_tick_logged(result, log)
    assert pihyst_main(["fit", str(log), "--model", "classical", "--thresholds", "0,10,30",
                        "-o", str(tmp_path / "m.json")]) == 0


class Raising(VoltageProgram):
    def __init__(self, at, action):
        super().__init__(triangle(period_s=20.0, dt=0.05)[1])
        self.at, self.action = at, action

    def command(self, k, measured_um):
        if k == self.at:
            self.action()
        return super().command(k, measured_um)


def test_exception_stops_at_zero_and_is_raised(tmp_path):
    def fail():
        raise RuntimeError("model blew up")
    with pytest.raises(RuntimeError, match="blew up"):
        record(tmp_path, program=Raising(60, fail))
    notes = read_run_log(tmp_path / "run.csv")[1]
    assert any(n.startswith("stopped: error: RuntimeError: model blew up; 0 V sent")
               for n in notes)


@pytest.mark.parametrize("sig, why", [(signal.SIGINT, "interrupted (SIGINT"),
                                      (signal.SIGTERM, "terminated (SIGTERM")])
def test_signals_stop_at_zero(tmp_path, sig, why):
    old = signal.getsignal(sig)
    result, emu, log = record(tmp_path, program=Raising(60, lambda: os.kill(os.getpid(), sig)))
    assert signal.getsignal(sig) is old
    assert_safe_stop(result, emu, log, why)
    assert result.column("voltage_V", "shutdown").size > 0     # ramped down


def test_non_finite_command_is_refused(tmp_path):
    result, emu, log = record(tmp_path, program=VoltageProgram(np.array([0.0, 1.0, 2.0])))
    assert result.completed

    class Nan(VoltageProgram):
        def command(self, k, measured_um):
            return 0.0, (math.nan if k == 2 else 1.0)
    result, emu, log = record(tmp_path, program=Nan(np.zeros(5)))
    assert_safe_stop(result, emu, log, "non-finite setpoint")
    assert not np.isnan(emu.supply_state.last_setpoint_V)


def test_watchdog_zeroes_a_stalled_loop(tmp_path):
    import time
    config = make_config(rig={"rate_hz": 20.0, "watchdog_periods": 6.0,
                              "slew_V_per_s": 100.0}, supply={"baudrate": 115200})
    stalled = []

    def stall():
        stalled.append(time.monotonic())
        time.sleep(1.5)
    program = Raising(5, stall)
    program.voltages = np.full(40, 20.0)
    program.n_ticks = 40
    result, emu, log = record(tmp_path, config, program=program, clock=WallClock)
    assert "watchdog" in result.reason
    st = emu.supply_state
    assert st.last_setpoint_V == 0.0 and not st.output_on
    # the watchdog thread sent 0 V while the loop was stuck: 6 periods into the stall
    t_zero = min(t for t, u in st.commands if u == 0.0 and t > stalled[0])
    # (the tick was busy a few ms before the stall began)
    assert stalled[0] + 0.25 < t_zero < stalled[0] + 1.5
    # and the shutdown knew it: no ramp down from 20 V (a step back up from 0 V) followed
    assert all(u == 0.0 for t, u in st.commands if t >= t_zero)


# ----------------------------------------------------------------------------- tracking
def tracking_runs(tmp_path, desired, gains=(1.0, 10.0)):
    import pihyst
    from pihyst.rig import FeedbackProgram, FeedforwardProgram
    config = make_config(rig={"rate_hz": 10.0})
    _, u = triangle(period_s=40.0, dt=0.1)
    loop, _, _ = record(tmp_path, config, program=VoltageProgram(u))
    y = loop.column("displacement_um", "run")
    model = pihyst.fit(u, y, family="multislope", thresholds=[0, 20, 30, 40]).model
    out = {}
    for name, program in (
            ("open", FeedforwardProgram(model, desired, 0.0, 150.0, 20.0)),
            ("feedback", FeedbackProgram(model, desired, 0.0, 150.0, 0.1, *gains,
                                         max_step=20.0))):
        result, emu, _ = record(tmp_path, config, program=program)
        assert result.completed
        e = result.column("displacement_um", "run") - result.column("reference", "run")
        out[name] = (e, result, program)
    return out


def test_feedback_removes_what_feedforward_cannot(tmp_path):
    _, desired = triangle(u_max=35.0, period_s=40.0, dt=0.1)
    runs = tracking_runs(tmp_path, np.r_[desired, np.full(300, 20.0)])
    e_open, e_fb = runs["open"][0], runs["feedback"][0]
    assert np.mean(np.abs(e_fb)) < 0.3 * np.mean(np.abs(e_open))
    # holding 20 um for 30 s: creep moves the open-loop beam, feedback holds it
    assert np.mean(np.abs(e_fb[-100:])) < 0.05 < np.mean(np.abs(e_open[-100:]))


def test_anti_windup_at_the_voltage_limit(tmp_path):
    # 60 um is out of reach (the beam gives ~45 um at 150 V): the voltage saturates and
    # the integral must not wind up, or the way back to 20 um would overshoot for long
    desired = np.r_[np.linspace(0, 60, 100), np.full(100, 60.0), np.full(100, 20.0)]
    runs = tracking_runs(tmp_path, desired)
    e, result, program = runs["feedback"]
    u = result.column("voltage_V", "run")
    assert u[150:200].max() == 150.0
    assert abs(program.integral) < 50.0
    assert np.mean(np.abs(e[-50:])) < 0.05


def test_hdf5_log(tmp_path):
    h5py = pytest.importorskip("h5py")
    config = make_config()
    with Rig(config, faults=[Fault("over-range", "sensor", start_s=2.0)]) as rig:
        result = rig.run(VoltageProgram(triangle(period_s=20.0, dt=0.05)[1]),
                         tmp_path / "run.h5", handle_signals=False)
    with h5py.File(tmp_path / "run.h5") as f:
        assert f["tick"][:].tolist() == list(range(len(result.records)))
        assert f["sensor_status"].asstr()[-1] in ("over-range+", "not read")
        assert any(n.startswith("stopped: 5 consecutive invalid") for n in
                   f.attrs["notes"])
        assert any("rig run log" in m for m in f.attrs["metadata"])


def test_a_creep_model_runs_its_lags_at_the_rigs_tick(tmp_path):
    # fitted on a 200 Hz record (creep.dt 5 ms), tracked through the Python API on the
    # 20 Hz rig: the lags move 50 ms per tick, as pihyst.compensate at the ticks' times
    import pihyst
    from pihyst.model import Creep
    from pihyst.rig import FeedforwardProgram

    model = pihyst.ClassicalPI([0, 10, 30, 60], [0.2, 0.05, 0.03, 0.01],
                               creep=Creep([1.0, 10.0], [0.1, 0.1], dt=0.005))
    desired = np.r_[np.linspace(0.0, 20.0, 20), np.full(400, 20.0)]
    program = FeedforwardProgram(model, desired, 0.0, 150.0, max_step=10.0)
    result, _, _ = record(tmp_path, program=program)
    assert result.completed
    sent, ref = result.column("command_V", "run"), result.column("reference", "run")
    expected = pihyst.compensate(model, ref, t=0.05 * np.arange(ref.size), u_min=0.0,
                                 u_max=150.0, slew_rate=10.0, sample_period=1.0,
                                 initial_voltage=sent[0])
    np.testing.assert_allclose(sent, expected.voltage, rtol=0, atol=1e-6)
    assert program.model.creep.dt == pytest.approx(0.05)
