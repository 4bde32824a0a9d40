"""Simulated actuators and test signals: the stand-in for the paper's rig.

- :func:`make_plant` / :data:`PLANT_NAMES`: simulated piezo beams (Preisach or Bouc-Wen
  hysteresis, creep, supply quantisation, sensor noise, optional dynamics); none is a PI
  model, so fitting PI models to their data proves something
  (docs/theory/simulated-beams.md);
- :func:`make_stage` / :class:`Stage`: scanning stages, hysteresis and creep followed by
  lightly damped modes, a converter delay and an amplifier slew limit at a fixed clock;
- :func:`random_plant`: a random actuator from a seed, for population benchmarks (a
  stage with ``dynamics=True``);
- :mod:`pihyst.sim.signals`: the paper's triangle, sines, decaying triangles, random
  ramps, staircases.
"""

from pihyst.sim import signals
from pihyst.sim._plant import PLANT_NAMES, Plant, make_plant
from pihyst.sim._population import random_plant
from pihyst.sim._stage import Stage, make_stage

__all__ = ["PLANT_NAMES", "Plant", "Stage", "make_plant", "make_stage", "random_plant",
           "signals"]
