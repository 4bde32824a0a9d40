"""Learning feedforward for periodic trajectories (docs/theory/learning.md).

- :func:`learn_periodic`: inversion-based iterative learning of one period of voltages:
  each trial plays a period, measures one, and updates the next through the model's
  exact hysteresis inverse and the dynamics' inverse per harmonic (the model's, or
  estimated from the trials), with a robustness filter that learns only where that
  response is trusted; limits and slew round the cycle on every trial; a trial that
  makes the error grow is undone and the gain halved.
- :func:`feasible_periodic`: any periodic drive made feasible (limits, cyclic slew).
"""

from pihyst.learn._feasible import cyclic_steps, feasible_periodic
from pihyst.learn._learn import LearningResult, learn_periodic

__all__ = ["LearningResult", "cyclic_steps", "feasible_periodic", "learn_periodic"]
