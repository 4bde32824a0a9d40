"""Record a hysteresis loop from the emulated instruments with PyMeasure.

    python examples/pymeasure_record.py -o loop.csv            # headless: Worker + Results
    python examples/pymeasure_record.py --gui                  # PyMeasure's ManagedWindow

pihyst's RecordProcedure runs ``pihyst rig record`` (the controller, its limits, slew and
safety: 0 V and output off however the run ends) on the rig of --config (default: the
emulated rig of examples/rig/emulated.toml, in virtual time) and emits every tick; PyMeasure
writes them to its Results file and, with --gui, plots the loop live. The GUI needs a Qt
binding (pip install PyQt5 or PySide6). The Results file has pihyst's log columns
(voltage_V, displacement_um, ...). Needs ``pip install 'pihyst[pymeasure]'``.
"""

import argparse
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def record(config, output, period, cycles, u_max=0.0):
    """Run the RecordProcedure headless into the Results file ``output``; returns the
    procedure (its ``result`` is pihyst's RunResult) and PyMeasure's Results."""
    from pymeasure.experiment import Results, Worker

    from pihyst.rig.pymeasure import RecordProcedure
    procedure = RecordProcedure(config=config, period=period, cycles=cycles, u_max=u_max)
    results = Results(procedure, output)
    worker = Worker(results)
    worker.start()
    worker.join(timeout=3600)
    return procedure, results


def make_window(config, period, cycles):
    """PyMeasure's ManagedWindow for the RecordProcedure: the loop (displacement against
    voltage) plotted live; Queue runs one record into loop-N.csv. Needs a QApplication."""
    from pymeasure.display.windows import ManagedWindow
    from pymeasure.experiment import Results

    from pihyst.rig.pymeasure import RecordProcedure

    class RecordWindow(ManagedWindow):
        def __init__(self):
            super().__init__(procedure_class=RecordProcedure,
                             inputs=["config", "signal", "u_min", "u_max", "period", "cycles",
                                     "real_time"],
                             displays=["signal", "period", "cycles"],
                             x_axis="voltage_V", y_axis="displacement_um")
            self.setWindowTitle("pihyst rig record")

        def queue(self, procedure=None):
            procedure = procedure or self.make_procedure()
            self.runs = getattr(self, "runs", 0) + 1
            filename = os.path.abspath(f"loop-{self.runs}.csv")
            self.manager.queue(self.new_experiment(Results(procedure, filename)))

    window = RecordWindow()
    window.set_parameters(RecordProcedure(config=config, period=period,
                                          cycles=cycles).parameter_objects())
    return window


def window(config, period, cycles):
    from pymeasure.display.Qt import QtWidgets
    app = QtWidgets.QApplication(sys.argv)
    w = make_window(config, period, cycles)
    w.show()
    return app.exec()


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--config", default=os.path.join(HERE, "rig", "emulated.toml"))
    p.add_argument("--period", type=float, default=300.0, help="triangle period, s")
    p.add_argument("--cycles", type=int, default=1)
    p.add_argument("-o", "--output", default="loop.csv", help="PyMeasure Results file")
    p.add_argument("--gui", action="store_true", help="PyMeasure's ManagedWindow")
    args = p.parse_args(argv)
    if args.gui:
        return window(args.config, args.period, args.cycles)
    procedure, results = record(args.config, args.output, args.period, args.cycles)
    result = procedure.result
    if result is None:
        print("the procedure failed before the run (see the log above)", file=sys.stderr)
        return 1
    data = results.data
    run = data[data["phase"] == "run"]
    print(f"recorded {len(run)} ticks: voltage {run['voltage_V'].min():.4g} .. "
          f"{run['voltage_V'].max():.4g} V, displacement {run['displacement_um'].min():.4g} "
          f".. {run['displacement_um'].max():.4g} um")
    final = "0 V, output off" if result.zeroed else "WARNING: the supply could not be zeroed"
    print(f"stopped: {result.reason}; {final}; PyMeasure results in {args.output}")
    return 0 if result.completed and result.zeroed else 1


if __name__ == "__main__":
    sys.exit(main())
