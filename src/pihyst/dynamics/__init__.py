"""Rate-dependent models: pihyst's static hysteresis followed by identified discrete
linear dynamics (Hammerstein), and the linear-only references (docs/theory/hammerstein.md).

- :func:`fit_state_space` / :class:`StateSpace`: a stable MIMO state-space model from
  periodic multisine records (the best linear approximation, frequency-domain subspace
  identification, the order chosen by validation on held-back records);
  :func:`estimate_bla` the nonparametric frequency response it starts from;
- :func:`fit_hammerstein_ss` / :class:`StateSpaceHammerstein`: classical PI per input,
  then those MIMO dynamics;
- :func:`fit_scheduled_state_space` / :class:`ScheduledStateSpace`: one model for
  several drive amplitudes, its modes interpolated in the running input amplitude
  (:func:`running_amplitude`); :func:`fit_feedback_state_space` the same kind of model
  with the amplitude dependence a feedback loop around fixed dynamics;
- :func:`fit_hammerstein` / :class:`HammersteinModel`: classical PI per input, then
  A_j(q) y_j = sum_i B_ji(q) h_i per output (any records, e.g. sweeps);
- :func:`fit_dynamics`: a given static model (``pihyst.fit``, any family) followed by
  unit-static-gain dynamics fitted on periodic records (a SISO HammersteinModel);
- :func:`fit_linear` / :func:`predict_linear`: the same polynomial structure on the
  input itself;
- :func:`compensate_hammerstein`: zero-phase error tracking inverse of the dynamics (for
  a periodic trajectory, the exact inverse per harmonic), then the exact hysteresis
  inverse with voltage and slew limits (SISO); below the band the dynamics were
  measured in, :func:`trust_weight` fades their correction out, and on a periodic
  trajectory's harmonics :func:`periodic_weight` leaves it out where the identification's
  held-back records showed it not to help, and :func:`held_mean` moves the voltage's
  mean only as far as the static model's known mean error allows;
- :func:`compensate_mimo`: the same for a square MIMO StateSpaceHammerstein and a
  periodic trajectory (the dynamics inverted per harmonic);
- :func:`compensate_scheduled`: the same for a square ScheduledStateSpace (its schedule
  a fixed point of the voltages it produces; voltage limits per input), also reached
  through :func:`compensate_mimo`;
- :func:`load_hammerstein`: a HammersteinModel from its JSON file
  (:meth:`HammersteinModel.save`); :func:`load_scheduled_state_space` and
  :func:`save_scheduled_state_space` the same for a ScheduledStateSpace.
"""

from pihyst.dynamics._bla import FrequencyResponse, estimate_bla
from pihyst.dynamics._compensate import (
    compensate_hammerstein,
    compensate_mimo,
    held_mean,
    mean_error_share,
    periodic_inverse_dynamics,
    periodic_weight,
    trust_weight,
    zpetc,
)
from pihyst.dynamics._compensate_scheduled import (
    ScheduledCompensation,
    compensate_scheduled,
)
from pihyst.dynamics._fit_feedback import fit_feedback_state_space
from pihyst.dynamics._fit_scheduled import fit_scheduled_state_space
from pihyst.dynamics._fit_state_space import OrderSelection, fit_state_space
from pihyst.dynamics._hammerstein import (
    HammersteinModel,
    default_thresholds,
    fit_hammerstein,
    fit_linear,
    predict_linear,
)
from pihyst.dynamics._hammerstein_io import load_hammerstein
from pihyst.dynamics._hammerstein_ss import StateSpaceHammerstein, fit_hammerstein_ss
from pihyst.dynamics._on_static import fit_dynamics
from pihyst.dynamics._scheduled import ScheduledStateSpace, running_amplitude
from pihyst.dynamics._scheduled_io import (
    load_scheduled_state_space,
    save_scheduled_state_space,
)
from pihyst.dynamics._statespace import StateSpace, fsid

__all__ = ["FrequencyResponse", "HammersteinModel", "OrderSelection", "ScheduledCompensation",
           "ScheduledStateSpace", "StateSpace",
           "StateSpaceHammerstein", "compensate_hammerstein", "compensate_mimo",
           "compensate_scheduled",
           "default_thresholds",
           "estimate_bla", "fit_dynamics", "fit_feedback_state_space", "fit_hammerstein",
           "fit_hammerstein_ss", "fit_linear",
           "fit_scheduled_state_space", "fit_state_space", "fsid", "load_hammerstein",
           "load_scheduled_state_space",
           "held_mean", "mean_error_share", "periodic_inverse_dynamics", "periodic_weight",
           "predict_linear", "running_amplitude", "save_scheduled_state_space", "trust_weight",
           "zpetc"]
