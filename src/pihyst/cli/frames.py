"""The frame of a desired displacement (compensate, track, rig track): the model's own
output frame (absolute, the default: a model fitted on a sensor's absolute readings
lives there, e.g. -119 ... -75 um), or ``--relative``: from the model's rest point at
the lowest voltage of its input range, as a user writes a 0-40 um trajectory. And the
reach rule: a trajectory with more than 10 % of its samples out of reach is an error
(exit status 2, nothing written) unless ``--saturate`` says that is intended."""

import numpy as np

from pihyst.cli.errors import UsageError
from pihyst.model._units import output_unit

MAX_OUT_OF_REACH = 0.10


def add_frame_options(p):
    g = p.add_argument_group("the desired displacement's frame")
    g.add_argument("--relative", action="store_true",
                   help="the desired displacement is relative to the model's rest point at "
                        "the lowest voltage of its input range (0 = the actuator at rest "
                        "there); default: in the model's own output frame (absolute)")
    g.add_argument("--saturate", action="store_true",
                   help="accept a trajectory with more than 10 %% of its samples out of "
                        "reach (saturated at a voltage limit); by default that is an error")


def rest_point(model):
    """The model's output at rest at the bottom of its input range after a full cycle."""
    from pihyst.cli.model_inputs import initial_state
    lo = model.input_range[0]
    plain = model.replace(delay=0)
    state = initial_state(plain, "bottom")
    return float(np.asarray(plain.predict(np.array([lo]), initial_state=state))[-1])


def frame(args, model):
    """(offset, line): the desired displacement plus ``offset`` is in the model's frame;
    the line says which frame was used."""
    unit = output_unit(model)
    if getattr(args, "relative", False):
        y0 = rest_point(model)
        return y0, (f"frame: relative, desired displacement from the model's rest point at "
                    f"{model.input_range[0]:g} V ({y0:.6g} {unit} in the model's frame; "
                    f"--relative)")
    return 0.0, (f"frame: absolute, the desired displacement in the model's own output "
                 f"frame (the default; --relative for one from its rest point at "
                 f"{model.input_range[0]:g} V)")


def check_reach(args, out_of_reach, n, where, hint):
    """A UsageError when more than 10 % of the ``n`` samples are out of reach and
    ``--saturate`` is not given."""
    if n and out_of_reach > MAX_OUT_OF_REACH * n and not getattr(args, "saturate", False):
        raise UsageError(f"{where}: {out_of_reach} of {n} samples "
                         f"({100 * out_of_reach / n:.1f} %) of the desired displacement are "
                         f"out of the model's reach, more than "
                         f"{100 * MAX_OUT_OF_REACH:g} %: {hint}; --saturate if that is "
                         f"intended")
