"""The PyMeasure Procedures (pihyst.rig.pymeasure) run headless against the emulated
instruments: through PyMeasure's Worker into a Results file (what ManagedWindow does,
without the window), and by calling startup/execute/shutdown. Every way a run ends
leaves the emulated supply at 0 V with the output off; the example script records a
loop that 'pihyst fit' reads as it is."""

import os
import subprocess
import sys

import numpy as np
import pytest
from rig_helpers import config_text

pytest.importorskip("pymeasure")

from pymeasure.experiment import Procedure, Results, Worker  # noqa: E402

from pihyst.exceptions import InvalidArgumentError  # noqa: E402
from pihyst.rig import COLUMNS, Fault  # noqa: E402
from pihyst.rig.pymeasure import (  # noqa: E402
    RecordProcedure,
    RunStopped,
    TrackProcedure,
)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


@pytest.fixture
def rig_toml(tmp_path):
    path = tmp_path / "rig.toml"
    path.write_text(config_text())
    return str(path)


@pytest.fixture
def model_json(tmp_path):
    path = tmp_path / "model.json"
    path.write_text('{"family": "classical", "thresholds": [0, 10, 30], '
                    '"weights": [0.22, 0.06, 0.03]}')
    return str(path)


def desired_csv(tmp_path, seconds, name="desired.csv"):
    t = np.arange(int(seconds * 20)) / 20.0
    y = 20 - 12 * np.cos(2 * np.pi * t / seconds)
    path = tmp_path / name
    path.write_text("time_s,displacement_um\n"
                    + "".join(f"{a:g},{b:.6f}\n" for a, b in zip(t, y)))
    return str(path)


def assert_zeroed(procedure):
    st = procedure.emulators.supply_state
    assert st.last_setpoint_V == 0.0 and st.setpoint_V == 0.0 and not st.output_on
    assert procedure.result.zeroed and procedure.rig is None      # closed by shutdown()


def run_in_worker(procedure, path):
    results = Results(procedure, str(path))
    worker = Worker(results)
    worker.start()
    worker.join(timeout=120)
    assert not worker.is_alive()
    return results


def test_record_through_worker_and_results(tmp_path, rig_toml):
    procedure = RecordProcedure(config=rig_toml, period=10.0, u_max=120.0)
    results = run_in_worker(procedure, tmp_path / "loop.csv")
    assert procedure.status == Procedure.FINISHED
    assert procedure.result.completed and procedure.result.reason == "end of the program"
    assert_zeroed(procedure)
    data = results.data
    assert list(data.columns) == list(COLUMNS)
    assert len(data) == len(procedure.result.records)          # every tick, shutdown too
    run = data[data["phase"] == "run"]
    assert len(run) == 201                                      # 10 s at 20 Hz, both ends
    assert run["voltage_V"].max() == pytest.approx(120.0)
    assert 30 < run["displacement_um"].max() < 40
    # the Results file is read back by PyMeasure and fitted by pihyst as it is
    again = Results.load(str(tmp_path / "loop.csv"), RecordProcedure)
    assert len(again.data) == len(data)


def test_abort_stops_the_run_at_zero(rig_toml):
    procedure = RecordProcedure(config=rig_toml, period=300.0)
    emitted = []

    def emit(topic, record):
        if topic == "results":
            emitted.append(record)
    procedure.emit = emit
    procedure.should_stop = lambda: len(emitted) >= 100        # the abort button
    procedure.startup()
    try:
        procedure.execute()                                     # an abort is not a failure
    finally:
        procedure.shutdown()
    assert procedure.result.reason == "stop requested" and not procedure.result.completed
    assert_zeroed(procedure)
    assert emitted[-1]["phase"] == "shutdown" and emitted[-1]["voltage_V"] == 0.0
    steps = np.diff([r["voltage_V"] for r in emitted])
    assert np.all(np.abs(steps) <= 200.0 / 20 + 1e-9)             # the slew limit holds


def test_a_fault_fails_the_procedure_after_zeroing(tmp_path, rig_toml):
    procedure = RecordProcedure(config=rig_toml, period=60.0)
    procedure.faults = [Fault("over-range", "sensor", start_s=5.0)]
    run_in_worker(procedure, tmp_path / "loop.csv")
    assert procedure.status == Procedure.FAILED
    assert "consecutive invalid sensor readings" in procedure.result.reason
    assert_zeroed(procedure)
    with pytest.raises(RunStopped, match="stopped early.*0 V, output off"):
        p = RecordProcedure(config=rig_toml, period=60.0)
        p.faults = procedure.faults
        p.emit = lambda *a: None
        p.startup()
        try:
            p.execute()
        finally:
            p.shutdown()


def test_limits_beyond_the_rig_are_refused_before_anything_is_sent(rig_toml):
    procedure = RecordProcedure(config=rig_toml, u_max=151.0)
    with pytest.raises(InvalidArgumentError, match="within the rig's limits"):
        procedure.startup()
    assert procedure.rig is None


def test_track_open_loop_and_with_feedback(tmp_path, rig_toml, model_json):
    desired = desired_csv(tmp_path, 10.0)
    errors = {}
    for name, gains in (("open", {}), ("feedback", {"kp": 1.0, "ki": 10.0})):
        procedure = TrackProcedure(config=rig_toml, model=model_json, desired=desired,
                                   **gains)
        results = run_in_worker(procedure, tmp_path / f"{name}.csv")
        assert procedure.status == Procedure.FINISHED, procedure.result
        assert_zeroed(procedure)
        run = results.data[results.data["phase"] == "run"]
        assert len(run) == 200
        assert run["reference"].to_numpy() == pytest.approx(
            np.loadtxt(desired, delimiter=",", skiprows=1)[:, 1])
        errors[name] = procedure.errors()
    assert errors["feedback"]["rms"] < errors["open"]["rms"] / 2


def test_learn_example_runs_trials_that_each_end_at_zero(tmp_path, rig_toml, model_json):
    desired = desired_csv(tmp_path, 2.0)
    LearnProcedure = load_example("pymeasure_learn").LearnProcedure
    procedure = LearnProcedure(config=rig_toml, model=model_json, desired=desired, trials=2)
    results = run_in_worker(procedure, tmp_path / "learn.csv")
    assert procedure.status == Procedure.FINISHED
    assert len(procedure.results_of_runs) == 3
    assert all(r.completed and r.zeroed for r in procedure.results_of_runs)
    assert_zeroed(procedure)
    assert sorted(set(results.data["trial"])) == [0, 1, 2]
    assert min(procedure.learning.rms) < procedure.learning.rms[0]


def test_learn_example_script(tmp_path, rig_toml, model_json, capsys):
    desired = desired_csv(tmp_path, 2.0)
    out = tmp_path / "learn.csv"
    main = load_example("pymeasure_learn").main
    assert main([model_json, desired, "--config", rig_toml, "--trials", "1", "-o",
                 str(out)]) == 0
    text = capsys.readouterr().out
    assert "RMS error per trial (um): " in text
    assert "2 trials, every one ended at 0 V, output off" in text and out.exists()


def load_example(name="pymeasure_record"):
    import importlib.util
    path = os.path.join(ROOT, "examples", f"{name}.py")
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_example_records_a_loop_that_fit_reads(tmp_path, capsys):
    out = tmp_path / "loop.csv"
    assert load_example().main(["--period", "10", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "recorded 201 ticks: voltage 0 .. 150 V" in text
    assert "stopped: end of the program; 0 V, output off" in text
    from pihyst.cli import main
    assert main(["fit", str(out), "--model", "multislope", "-o",
                 str(tmp_path / "model.json")]) == 0


@pytest.mark.slow
def test_example_as_a_script(tmp_path):
    out = tmp_path / "loop.csv"
    proc = subprocess.run([sys.executable, os.path.join(ROOT, "examples", "pymeasure_record.py"),
                           "--period", "20", "-o", str(out)], capture_output=True, text=True,
                          timeout=300, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "recorded 401 ticks: voltage 0 .. 150 V" in proc.stdout
    assert "stopped: end of the program; 0 V, output off" in proc.stdout


@pytest.mark.slow
def test_managed_window_plots_the_run_live(tmp_path, monkeypatch):
    """The example's ManagedWindow (offscreen): Queue runs a record, and the loop's curve
    grows while the run goes. Needs a Qt binding (not in the test extra: PyQt5 or
    PySide6 installed by hand)."""
    import importlib.util
    import time
    if not any(importlib.util.find_spec(m) for m in ("PyQt5", "PySide6", "PyQt6", "PySide2")):
        pytest.skip("no Qt binding installed (pip install PyQt5)")
    monkeypatch.setenv("QT_QPA_PLATFORM", "offscreen")
    monkeypatch.chdir(tmp_path)
    from pymeasure.display.Qt import QtWidgets
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication([])
    window = load_example().make_window(os.path.join(ROOT, "examples", "rig", "emulated.toml"),
                                        10.0, 1)
    window.queue()
    sizes = []
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        app.processEvents()
        curve = window.manager.experiments.queue[0].curve_list[0]
        sizes.append(0 if curve.xData is None else len(curve.xData))
        if not window.manager.is_running() and sizes[-1] > 0:
            break
        time.sleep(0.02)
    experiment = window.manager.experiments.queue[0]
    assert experiment.procedure.result.reason == "end of the program"
    assert experiment.procedure.result.zeroed
    assert sizes[-1] == 201 and 30 < max(curve.yData) < 50     # the whole loop, plotted
    assert len({s for s in sizes if 0 < s < 201}) >= 2          # ... while it was recorded
    assert (tmp_path / "loop-1.csv").exists()
    window.close()


def test_a_procedure_that_fails_outside_a_run_still_ends_at_zero(tmp_path, rig_toml):
    class Broken(RecordProcedure):
        def execute(self):                      # a procedure of one's own with a bug
            self.rig.supply.output_on()
            self.rig.supply.set_voltage(20.0)
            raise RuntimeError("a bug between opening the rig and running")

    procedure = Broken(config=rig_toml, period=10.0)
    run_in_worker(procedure, tmp_path / "broken.csv")
    assert procedure.status == Procedure.FAILED
    st = procedure.emulators.supply_state
    assert st.last_setpoint_V == 0.0 and not st.output_on and procedure.rig is None
