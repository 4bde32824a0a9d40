"""Iterative learning of a repeated scan (``pihyst rig learn``) as a PyMeasure Procedure,
built on pihyst's RigProcedure: each learning trial is one rig run (0 V to 0 V, the
controller's limits, slew and safety) whose every tick is emitted with a ``trial``
column, so PyMeasure's ManagedWindow plots the trials live.

    python examples/pymeasure_learn.py MODEL.json PERIOD.csv --trials 5 -o learn.csv

PERIOD.csv holds one period of the desired displacement (time_s, displacement_um). The
procedure lives here, not in pihyst.rig.pymeasure, because it joins the rig and
pihyst.learn, which sit side by side in pihyst's layers. Needs 'pihyst[pymeasure]'.
"""

import argparse
import logging
import os
import sys

import numpy as np
from pymeasure.experiment import IntegerParameter, Parameter

from pihyst.cli.learn import desired_period
from pihyst.learn import learn_periodic
from pihyst.rig import COLUMNS
from pihyst.rig.pymeasure import RigProcedure, RunStopped
from pihyst.rig.pymeasure._inputs import model_at_tick

HERE = os.path.dirname(os.path.abspath(__file__))
log = logging.getLogger(__name__)


class LearnProcedure(RigProcedure):
    """``pihyst rig learn``: learn one period of voltages for the periodic desired
    displacement of a CSV (one period), starting from the model's inverse. Each trial
    plays the period ``periods`` times and measures the last one."""

    model = Parameter("Model (JSON)", default="model.json")
    desired = Parameter("Desired period (CSV)", default="period.csv")
    periods = IntegerParameter("Periods per trial", minimum=2, maximum=1000, default=2)
    trials = IntegerParameter("Learning trials", minimum=1, maximum=1000, default=5)

    DATA_COLUMNS = list(COLUMNS) + ["trial"]

    learning = None

    def startup(self):
        config = self.load_config()
        self.loop = config.rig
        self.model_ = model_at_tick(self.model, self.loop.rate_hz)
        self.desired_ = desired_period(self.desired, self.loop.rate_hz)
        self.open_rig(config)

    def run_period(self, u):
        """One trial (learn_periodic's ``run_period``): the last period measured."""
        trial = len(self.results_of_runs or [])
        if self.should_stop():
            raise _Aborted()
        n = self.trials + 1
        program = self.program_for(u, trial)
        result = self.run_program(program, {"trial": trial},
                                  (100.0 * trial / n, 100.0 * (trial + 1) / n))
        if not result.completed:                       # the abort button
            raise _Aborted()
        y = result.column("displacement_um", phase="run")[-u.size:]
        if y.size != u.size or not np.all(np.isfinite(y)):
            raise RunStopped(f"learning trial {trial}: no valid reading on some tick of the "
                             "measured period; 0 V, output off")
        return y

    def program_for(self, u, trial):
        from pihyst.rig import VoltageProgram
        return VoltageProgram(np.tile(u, self.periods),
                              f"learning trial {trial}: {self.periods} periods of {u.size} "
                              f"ticks for {self.desired}")

    def execute(self):
        r = self.loop
        try:
            self.learning = learn_periodic(self.run_period, self.desired_, 1.0 / r.rate_hz,
                                           model=self.model_, u_min=r.u_min, u_max=r.u_max,
                                           slew_rate=r.slew_V_per_s, trials=self.trials,
                                           keep_trials=True)
        except _Aborted:
            log.info("learning aborted after %d trial(s)", len(self.results_of_runs or []))
            return
        log.info("learning: RMS error per trial %s um",
                 ", ".join(f"{e:.4g}" for e in self.learning.rms))


class _Aborted(Exception):
    """The abort button during learning (the trial's run has zeroed the supply)."""


def main(argv=None):
    from pymeasure.experiment import Results, Worker
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("model")
    p.add_argument("desired")
    p.add_argument("--config", default=os.path.join(HERE, "rig", "emulated.toml"))
    p.add_argument("--trials", type=int, default=5)
    p.add_argument("--periods", type=int, default=2)
    p.add_argument("-o", "--output", default="learn.csv", help="PyMeasure Results file")
    args = p.parse_args(argv)
    procedure = LearnProcedure(config=args.config, model=args.model, desired=args.desired,
                               trials=args.trials, periods=args.periods)
    worker = Worker(Results(procedure, args.output))
    worker.start()
    worker.join(timeout=24 * 3600)
    if procedure.learning is None:
        print("learning did not finish (see the log)", file=sys.stderr)
        return 1
    print("RMS error per trial (um): " + ", ".join(f"{e:.4g}" for e in procedure.learning.rms))
    print(f"{len(procedure.results_of_runs)} trials, every one ended at 0 V, output off; "
          f"PyMeasure results in {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
